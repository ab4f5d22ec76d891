//! The command line used as nobody meant it to be: a closed or full
//! standard output, a signal in mid-run, an output folder that holds
//! something else, names that lead out of `out/`, absurd flags. Every case
//! ends with a clear exit code and leaves no half-written output.

use crate::common::{ehservo, repo};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn fig2() -> PathBuf {
    repo().join("scenarios/paper/fig2.toml")
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The names in a directory, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// No staging (`.ehservo.tmp-…`) or set-aside (`.ehservo.old-…`) folder.
fn assert_no_leftovers(dir: &Path) {
    let left: Vec<String> = names(dir)
        .into_iter()
        .filter(|n| n.starts_with(".ehservo."))
        .collect();
    assert!(
        left.is_empty(),
        "left behind in {}: {left:?}",
        dir.display()
    );
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The write end of a pipe whose read end is closed for good: the reader
/// (`true`) has exited and this process never held the read end.
fn closed_pipe() -> Stdio {
    let mut reader = Command::new("true")
        .stdin(Stdio::piped())
        .spawn()
        .expect("true");
    let write_end = reader.stdin.take().unwrap();
    reader.wait().unwrap();
    Stdio::from(write_end)
}

/// A small study: 2 runs of the Fig. 8 case over 1 s.
fn small_study(dir: &Path) -> PathBuf {
    write(
        dir,
        "study.toml",
        &format!(
            "name = \"tiny\"\nbase = \"{}\"\nset = [\"simulation.horizon=1\", \"simulation.settle=0.5\"]\n\n[[axis]]\nkey = \"controller.eta\"\nvalues = [0.0, 0.25]\n",
            repo()
                .join("scenarios/paper/fig8.toml")
                .canonicalize()
                .unwrap()
                .display()
        ),
    )
}

/// Every command that prints, with the files it needs under `dir`.
fn printing_commands(dir: &Path) -> Vec<Vec<String>> {
    let f = fig2().display().to_string();
    let study = small_study(dir).display().to_string();
    let shard = dir.join("shard").display().to_string();
    let o = ehservo()
        .args(["sweep", &study, "-q", "--no-plot", "--out", &shard])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let d = |s: &str| dir.join(s).display().to_string();
    [
        vec!["defaults".to_string()],
        vec!["analyze".into(), f.clone()],
        vec!["analyze".into(), f.clone(), "--json".into()],
        vec!["check".into(), f.clone()],
        vec![
            "run".into(),
            f,
            "--no-plot".into(),
            "--out".into(),
            d("run"),
        ],
        vec![
            "sweep".into(),
            study,
            "--no-plot".into(),
            "--out".into(),
            d("sweep"),
        ],
        vec!["merge".into(), shard, "--out".into(), d("merged")],
        vec!["--help".into()],
    ]
    .into()
}

#[test]
fn a_closed_stdout_ends_every_command_quietly_with_exit_1() {
    let tmp = tempfile::tempdir().unwrap();
    for args in printing_commands(tmp.path()) {
        let o = ehservo()
            .args(&args)
            .stdout(closed_pipe())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(o.stderr.is_empty(), "{args:?}: {}", stderr(&o));
    }
    assert_no_leftovers(tmp.path());
}

#[test]
fn a_full_stdout_is_one_line_and_exit_1() {
    let tmp = tempfile::tempdir().unwrap();
    for args in printing_commands(tmp.path()) {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = ehservo().args(&args).stdout(full).output().unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        // `check` says "ok" on stderr only once the scenario is printed.
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: writing to stdout: "),
            "{args:?}: {err}"
        );
    }
    assert_no_leftovers(tmp.path());
}

/// A scenario that runs for many seconds even on a fast machine (20 million
/// steps; it is always interrupted long before).
fn long_scenario(dir: &Path) -> PathBuf {
    write(
        dir,
        "long.toml",
        "name = \"long\"\n[simulation]\nhorizon = 2000.0\nstep = 0.0001\n[output]\ndecimate = 100\nplot = false\n",
    )
}

/// Starts a long run into `out`, waits until its staging folder exists
/// (in `staging_in`), sends `signal` and returns the exit code.
fn interrupt(scenario: &Path, out: &Path, staging_in: &Path, signal: &str) -> Option<i32> {
    let mut child = ehservo()
        .arg("run")
        .arg(scenario)
        .arg("-q")
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let staged = staging_in.is_dir()
            && names(staging_in)
                .iter()
                .any(|n| n.starts_with(".ehservo.tmp-"));
        if staged {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no staging folder"
        );
        assert!(child.try_wait().unwrap().is_none(), "the run ended early");
        std::thread::sleep(Duration::from_millis(20));
    }
    // Mid-run: trace.csv is being written into the staging folder.
    std::thread::sleep(Duration::from_millis(500));
    let k = Command::new("kill")
        .arg(format!("-{signal}"))
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(k.success());
    child.wait().unwrap().code()
}

#[test]
fn sigterm_in_mid_run_leaves_no_staging_folder_and_no_output() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = long_scenario(tmp.path());
    let out = tmp.path().join("out");
    let code = interrupt(&sc, &out, tmp.path(), "TERM");
    assert_eq!(code, Some(130));
    assert_eq!(names(tmp.path()), ["long.toml"]);
}

#[test]
fn sigint_removes_the_folders_made_for_the_output_and_keeps_the_old_one() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = long_scenario(tmp.path());
    // Parent folders the run has to create go too.
    let out = tmp.path().join("a/b/out");
    let code = interrupt(&sc, &out, &tmp.path().join("a/b"), "INT");
    assert_eq!(code, Some(130));
    assert_eq!(names(tmp.path()), ["long.toml"]);

    // An earlier output in the way stays as it was.
    let keep = tmp.path().join("keep");
    let o = ehservo()
        .arg("run")
        .arg(fig2())
        .args(["-q", "--no-plot", "--out"])
        .arg(&keep)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let before = std::fs::read(keep.join("summary.json")).unwrap();
    let code = interrupt(&sc, &keep, tmp.path(), "INT");
    assert_eq!(code, Some(130));
    assert_eq!(names(tmp.path()), ["keep", "long.toml"]);
    assert_eq!(names(&keep), ["summary.json", "trace.csv"]);
    assert_eq!(std::fs::read(keep.join("summary.json")).unwrap(), before);
}

fn run_into(out: &Path, extra: &[&str]) -> Output {
    ehservo()
        .arg("run")
        .arg(fig2())
        .arg("-q")
        .args(extra)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn a_rerun_leaves_no_stale_file() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    let o = run_into(&out, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(out.join("trace.png").is_file());
    // Whatever else an earlier run (or a person) left in it goes too.
    write(&out, "notes.txt", "old");
    let o = run_into(&out, &["--no-plot"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(names(&out), ["summary.json", "trace.csv"]);
    assert_no_leftovers(tmp.path());

    // An empty folder is taken.
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let o = run_into(&empty, &["--no-plot"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(names(&empty), ["summary.json", "trace.csv"]);

    // Old study plots go when a study is run again into its folder.
    let study = small_study(tmp.path());
    let sweep = tmp.path().join("sweep");
    for plots in [true, false] {
        let o = ehservo()
            .arg("sweep")
            .arg(&study)
            .arg("-q")
            .args(if plots { vec![] } else { vec!["--no-plot"] })
            .arg("--out")
            .arg(&sweep)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    assert_eq!(names(&sweep), ["results.csv", "study.json"]);
    assert_no_leftovers(tmp.path());
}

#[test]
fn a_folder_that_is_not_an_output_is_refused_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let mine = work.join("mine");
    std::fs::create_dir(&mine).unwrap();
    write(&mine, "thesis.tex", "years of work");
    let file = write(&work, "file", "a file");

    let refuse = |out: &str, needle: &str| {
        let o = ehservo()
            .current_dir(&work)
            .arg("run")
            .arg(fig2())
            .args(["-q", "--no-plot", "--out", out])
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "--out {out}: {err}");
        assert!(err.contains(needle), "--out {out}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    };
    refuse(
        "mine",
        &format!(
            "exists and is not an ehservo output folder (it has none of {}): refusing to replace it",
            ehservo::output::OUTPUT_MARKERS.join(", ")
        ),
    );
    refuse("file", "exists and is not a directory");
    refuse("file/out", "is not a directory");
    refuse(".", "the current directory");
    refuse("..", "the current directory");
    refuse("/", "the root");
    refuse("./", "the current directory");
    assert_eq!(names(&mine), ["thesis.tex"]);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "a file");
    assert_eq!(names(&work), ["file", "mine"]);
    assert_eq!(names(tmp.path()), ["work"]);

    // The same rule for sweep, merge and reproduce, before any work.
    let study = small_study(tmp.path());
    let shard = tmp.path().join("shard");
    let o = ehservo()
        .arg("sweep")
        .arg(&study)
        .args(["-q", "--no-plot", "--out"])
        .arg(&shard)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let m = mine.display().to_string();
    for args in [
        vec!["sweep", study.to_str().unwrap(), "--out", &m],
        vec!["merge", shard.to_str().unwrap(), "--out", &m],
        vec!["reproduce", "--out", &m],
    ] {
        let o = ehservo().current_dir(repo()).args(&args).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
    assert_eq!(names(&mine), ["thesis.tex"]);
    assert_no_leftovers(&work);
}

#[test]
fn a_long_output_name_works_and_a_failed_staging_removes_its_folders() {
    let tmp = tempfile::tempdir().unwrap();
    // 250 bytes: a legal name; the staging name beside it stays short.
    let out = tmp.path().join("new").join("a".repeat(250));
    let o = run_into(&out, &["--no-plot"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(names(&out), ["summary.json", "trace.csv"]);
    assert_no_leftovers(&tmp.path().join("new"));

    // A staging that is dropped (an error, a panic) takes the folders it
    // made with it, and only those.
    let before = ehservo::interrupt::live_staging_dirs();
    let stage = ehservo::output::Staging::new(&tmp.path().join("x/y/out")).unwrap();
    std::fs::write(stage.path().join("part.csv"), "half").unwrap();
    assert!(tmp.path().join("x/y").is_dir());
    assert_eq!(ehservo::interrupt::live_staging_dirs(), before + 1);
    drop(stage);
    assert_eq!(ehservo::interrupt::live_staging_dirs(), before);
    assert_eq!(names(tmp.path()), ["new"]);

    let stage = ehservo::output::Staging::new(&tmp.path().join("new/out")).unwrap();
    drop(stage);
    assert_eq!(names(&tmp.path().join("new")), ["a".repeat(250)]);

    // A committed one leaves its output and nothing else.
    let stage = ehservo::output::Staging::new(&tmp.path().join("p/q")).unwrap();
    std::fs::write(stage.path().join("summary.json"), "{}").unwrap();
    stage.commit().unwrap();
    assert_eq!(names(&tmp.path().join("p/q")), ["summary.json"]);
    assert_no_leftovers(&tmp.path().join("p"));
}

#[test]
fn a_scenario_name_cannot_lead_out_of_the_output_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    for (i, name) in ["../escape", "../../escape", "/tmp/escape", "a/b", "..", "."]
        .iter()
        .enumerate()
    {
        let sc = write(
            tmp.path(),
            &format!("s{i}.toml"),
            &format!("name = {name:?}\n"),
        );
        let o = ehservo()
            .current_dir(&work)
            .arg("run")
            .arg(&sc)
            .args(["-q", "--no-plot"])
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains("must be a plain name without '/' or '..' to be used as the output folder; pass --out"),
            "{name}: {err}"
        );
        assert!(names(&work).is_empty(), "{name}: {:?}", names(&work));
    }
    assert!(!tmp.path().join("escape").exists());
    // With --out the name is only a name.
    let sc = write(tmp.path(), "esc.toml", "name = \"../escape\"\n");
    let o = ehservo()
        .current_dir(&work)
        .arg("run")
        .arg(&sc)
        .args(["-q", "--no-plot", "--out", "here"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(names(&work), ["here"]);
}

#[test]
fn threads_are_checked_and_reproduce_fails_fast_on_an_unwritable_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let study = small_study(tmp.path());
    let out = tmp.path().join("o");
    for t in ["0", "1025", "18446744073709551615"] {
        let o = ehservo()
            .arg("sweep")
            .arg(&study)
            .args(["-q", "--threads", t, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{t}: {err}");
        assert!(err.contains("--threads"), "{t}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    for t in ["-1", "many"] {
        let o = ehservo()
            .arg("sweep")
            .arg(&study)
            .args(["--threads", t, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{t}: {}", stderr(&o));
    }
    assert!(!out.exists());

    // /proc takes no new folder, not even from root.
    for args in [
        vec!["reproduce", "--quiet", "--out", "/proc/ehservo-test/out"],
        vec![
            "sweep",
            study.to_str().unwrap(),
            "--quiet",
            "--out",
            "/proc/ehservo-test/out",
        ],
    ] {
        let start = Instant::now();
        let o = ehservo().current_dir(repo()).args(&args).output().unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with("error: "), "{err}");
        assert!(err.contains("/proc/ehservo-test"), "{err}");
        assert!(o.stdout.is_empty());
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "{args:?}: failed only after {:?}",
            start.elapsed()
        );
    }
}

/// This round's long commands take SIGINT as `run` does: a sinestream of
/// `ehservo freq` (400 frequencies, 60 s of settling each: minutes of
/// work) and `ehservo identify` of a 30 s experiment (tens of seconds of
/// fitting) stop promptly with exit 130, leaving no output and no staging
/// folder.
#[test]
fn sigint_stops_freq_and_identify_and_leaves_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    // identify's data: 30 s of a multisine at 1 kHz on Fig. 2's servo.
    let trace = crate::common::excited_trace(tmp.path(), &["--duration", "30"]);
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let fig2 = fig2();
    let cases: [(&str, Vec<&std::ffi::OsStr>); 2] = [
        (
            "freq",
            vec![
                "freq".as_ref(),
                fig2.as_os_str(),
                "--measure-points".as_ref(),
                "400".as_ref(),
                "--settle".as_ref(),
                "60".as_ref(),
                "--out".as_ref(),
                "o".as_ref(),
            ],
        ),
        (
            "identify",
            vec![
                "identify".as_ref(),
                trace.as_os_str(),
                "--pressure".as_ref(),
                "none".as_ref(),
                "--out".as_ref(),
                "o".as_ref(),
            ],
        ),
    ];
    for (name, args) in cases {
        let mut child = ehservo()
            .args(args)
            .current_dir(&work)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        assert!(
            child.try_wait().unwrap().is_none(),
            "{name} ended before the signal"
        );
        let k = Command::new("kill")
            .arg("-INT")
            .arg(child.id().to_string())
            .status()
            .unwrap();
        assert!(k.success());
        let sent = Instant::now();
        let code = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s.code();
            }
            assert!(
                sent.elapsed() < Duration::from_secs(10),
                "{name} still running 10 s after SIGINT"
            );
            std::thread::sleep(Duration::from_millis(20));
        };
        assert_eq!(code, Some(130), "{name}");
        assert!(names(&work).is_empty(), "{name} left {:?}", names(&work));
    }
}
