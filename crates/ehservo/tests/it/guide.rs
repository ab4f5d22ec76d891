//! The guide (`docs/guide/*.md`) and the README, executed: every fenced
//! block is run or checked, so the pages cannot drift from the program.
//! The convention (also stated at the top of docs/guide/README.md):
//!
//! - ```` ```console ````: lines `$ CMD` are commands, the lines after one
//!   (up to the next `$ `) its expected output, stdout then stderr. A line
//!   `…` stands for any number of lines, `…` inside a line for any text; a
//!   last line `[exit N]` expects exit code N (0 otherwise). A command shown
//!   without output lines must print nothing. Commands are split like a
//!   shell's words (quotes, no pipes or variables) and run in a fresh folder
//!   per page that links every top-level entry of the repository (so
//!   `scenarios/…` is there and `out/` is the page's own); the blocks of a
//!   page share it, in order. `ehservo` (and `cargo run --release --`) is
//!   the binary these tests are built with (or `EHSERVO_GUIDE_BIN`),
//!   `python3` the interpreter of `EHSERVO_GUIDE_PYTHON` (default
//!   `python3`). `cargo test --workspace` is not run: it must be `.ci/run`'s
//!   test command, word for word.
//! - Attributes after the language: `needs=a,b` runs the block only where
//!   each need is met (`release`: a release binary given by
//!   `EHSERVO_GUIDE_BIN`; `python`: the interpreter imports `ehservo`;
//!   `fmpy`: it imports `fmpy`; `qemu`: `qemu-system-arm` and the PIL firmware
//!   built; `ffi`: `libehservo_ffi.so` beside the binary and `gcc`), and
//!   reports it as skipped elsewhere; `EHSERVO_GUIDE_REQUIRE=a,b` makes a
//!   missing need a failure (the CI steps that provide each set it).
//!   `skip="reason"` never runs the block (installing system packages,
//!   submitting to a cluster) and says why.
//! - ```` ```toml ````: loaded as a scenario (`toml study`, `toml tune`,
//!   `toml league`, `toml manifest` as those), by the library's own loaders;
//!   `save=NAME` also writes it into the page's folder, where later commands
//!   use it; `file=PATH` requires the block to be a contiguous part of that
//!   repository file (and loads the file).
//! - ```` ```python ````: syntax-checked (when a `python3` is there); with
//!   `run`, executed in the page's folder (`needs=python` implied) and must
//!   exit 0. ```` ```rust ````, ```` ```c ```` need `file=PATH`.
//!   ```` ```text ```` is shown output or a synopsis, not run.
//!
//! `EHSERVO_BLESS=1 cargo test -p ehservo --test it guide` rewrites the
//! output of every command whose output no longer matches with what it
//! printed now (trim it to an excerpt with `…` afterwards).

use crate::common::repo;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The pages, each a test of its own (a page not listed here fails
/// `every_page_is_tested`).
const PAGES: &[&str] = &[
    "README.md",
    "docs/guide/README.md",
    "docs/guide/getting-started.md",
    "docs/guide/scenarios.md",
    "docs/guide/plants.md",
    "docs/guide/plant-fmu.md",
    "docs/guide/cylinder-from-datasheets.md",
    "docs/guide/actuators-and-sensors.md",
    "docs/guide/controllers.md",
    "docs/guide/studies-and-clusters.md",
    "docs/guide/tuning-and-league.md",
    "docs/guide/reproduction.md",
    "docs/guide/python-c-fmi.md",
    "docs/guide/board.md",
    "docs/guide/troubleshooting.md",
];

/// Longest any one command may take.
const TIMEOUT: Duration = Duration::from_secs(300);

/// The wildcard of expected output.
const ANY: &str = "…";

struct Block {
    lang: String,
    attrs: Vec<(String, String)>,
    /// Index (0-based) of the first content line in the page.
    first: usize,
    lines: Vec<String>,
}

impl Block {
    fn attr(&self, k: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(a, _)| a == k)
            .map(|(_, v)| v.as_str())
    }
    fn flag(&self, k: &str) -> bool {
        self.attrs.iter().any(|(a, v)| a == k && v.is_empty())
    }
    /// Where the block starts, for messages (1-based fence line).
    fn at(&self, page: &str) -> String {
        format!("{page}:{}", self.first)
    }
}

/// `key=value`, `key="a value"` or a bare word (value "").
fn parse_attrs(s: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for w in words(s).unwrap_or_default() {
        match w.split_once('=') {
            Some((k, v)) => out.push((k.to_string(), v.to_string())),
            None => out.push((w, String::new())),
        }
    }
    out
}

/// The fenced blocks of a Markdown page.
fn blocks(page: &str, text: &str) -> Result<Vec<Block>, String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let l = lines[i];
        if l.trim_start().starts_with("```") && !l.starts_with("```") {
            return Err(format!(
                "{page}:{}: an indented fence (put blocks at the left margin)",
                i + 1
            ));
        }
        if let Some(info) = l.strip_prefix("```") {
            let info = info.trim();
            let (lang, rest) = info.split_once(' ').unwrap_or((info, ""));
            let start = i + 1;
            let mut j = start;
            while j < lines.len() && lines[j].trim_end() != "```" {
                j += 1;
            }
            if j == lines.len() {
                return Err(format!("{page}:{}: the block is not closed", i + 1));
            }
            out.push(Block {
                lang: lang.to_string(),
                attrs: parse_attrs(rest),
                first: start,
                lines: lines[start..j].iter().map(|s| s.to_string()).collect(),
            });
            i = j + 1;
        } else {
            i += 1;
        }
    }
    Ok(out)
}

/// A command line split into words: single and double quotes, backslash
/// escapes; `|`, `>`, `<`, `;`, `&`, `$`, backquotes outside quotes refused.
fn words(s: &str) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut any = false;
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                any = true;
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(x) => cur.push(x),
                        None => return Err(format!("unclosed ' in {s}")),
                    }
                }
            }
            '"' => {
                any = true;
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\\') => match chars.next() {
                            Some(x) => cur.push(x),
                            None => return Err(format!("trailing \\ in {s}")),
                        },
                        Some(x) => cur.push(x),
                        None => return Err(format!("unclosed \" in {s}")),
                    }
                }
            }
            '\\' => {
                any = true;
                if let Some(x) = chars.next() {
                    cur.push(x);
                }
            }
            '|' | '>' | '<' | ';' | '&' | '$' | '`' => {
                return Err(format!(
                    "{c:?} in {s}: the guide's commands are plain words (no shell)"
                ))
            }
            c if c.is_whitespace() => {
                if any {
                    out.push(std::mem::take(&mut cur));
                    any = false;
                }
            }
            c => {
                any = true;
                cur.push(c);
            }
        }
    }
    if any {
        out.push(cur);
    }
    Ok(out)
}

/// Whether `line` matches `pattern`, `…` standing for any text.
fn line_matches(pattern: &str, line: &str) -> bool {
    let parts: Vec<&str> = pattern.split(ANY).collect();
    if parts.len() == 1 {
        return pattern == line;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !line.starts_with(first) || line.len() < first.len() + last.len() || !line.ends_with(last) {
        return false;
    }
    let mut rest = &line[first.len()..line.len() - last.len()];
    for p in &parts[1..parts.len() - 1] {
        match rest.find(p) {
            Some(k) => rest = &rest[k + p.len()..],
            None => return false,
        }
    }
    true
}

/// Whether the output lines match the expected ones (`…` alone: any lines).
fn output_matches(expected: &[String], actual: &[String]) -> bool {
    match expected.split_first() {
        None => actual.is_empty(),
        Some((e, rest)) if e == ANY => {
            (0..=actual.len()).any(|k| output_matches(rest, &actual[k..]))
        }
        Some((e, rest)) => {
            !actual.is_empty() && line_matches(e, &actual[0]) && output_matches(rest, &actual[1..])
        }
    }
}

/// What a page's blocks run with.
struct Env {
    bin: PathBuf,
    release: bool,
    python: String,
    require: BTreeSet<String>,
    bless: bool,
}

impl Env {
    fn new() -> Env {
        let given = std::env::var_os("EHSERVO_GUIDE_BIN").map(PathBuf::from);
        let bin = given
            .clone()
            .map(|b| std::fs::canonicalize(&b).unwrap_or(b))
            .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_ehservo")));
        Env {
            release: given.is_some(),
            bin,
            python: std::env::var("EHSERVO_GUIDE_PYTHON").unwrap_or_else(|_| "python3".into()),
            require: std::env::var("EHSERVO_GUIDE_REQUIRE")
                .unwrap_or_default()
                .split(',')
                .map(|s| s.trim().to_string())
                .filter(|s| !s.is_empty())
                .collect(),
            bless: std::env::var_os("EHSERVO_BLESS").is_some_and(|v| v != "0"),
        }
    }

    fn python_imports(&self, module: &str) -> bool {
        Command::new(&self.python)
            .args(["-c", &format!("import {module}")])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    }

    fn on_path(prog: &str) -> bool {
        std::env::var_os("PATH")
            .is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(prog).is_file()))
    }

    /// Whether a need is met; `Err` names an unknown one.
    fn has(&self, need: &str) -> Result<bool, String> {
        Ok(match need {
            "release" => self.release,
            "python" => self.python_imports("ehservo"),
            "fmpy" => self.python_imports("fmpy"),
            "qemu" => {
                Self::on_path("qemu-system-arm")
                    && repo()
                        .join("target/thumbv7em-none-eabihf/release/ehservo-firmware-pil")
                        .is_file()
            }
            "ffi" => self.bin.with_file_name("libehservo_ffi.so").is_file() && Self::on_path("gcc"),
            other => return Err(format!("unknown need {other:?}")),
        })
    }

    /// `None` when the block runs here; otherwise why not (or an error when
    /// a required need is missing).
    fn skipped(&self, b: &Block, page: &str) -> Result<Option<String>, String> {
        if let Some(why) = b.attr("skip") {
            if why.is_empty() {
                return Err(format!("{}: skip needs a reason", b.at(page)));
            }
            return Ok(Some(format!("not run: {why}")));
        }
        let mut needs: Vec<&str> = b
            .attr("needs")
            .map(|n| n.split(',').collect())
            .unwrap_or_default();
        if b.lang == "python" && b.flag("run") && !needs.contains(&"python") {
            needs.push("python");
        }
        for n in needs {
            if !self.has(n).map_err(|e| format!("{}: {e}", b.at(page)))? {
                if self.require.contains(n) {
                    return Err(format!(
                        "{}: needs {n}, which EHSERVO_GUIDE_REQUIRE requires and is not here",
                        b.at(page)
                    ));
                }
                return Ok(Some(format!("needs {n}")));
            }
        }
        Ok(None)
    }
}

/// A page's working folder: every top-level entry of the repository linked
/// (but `out`, `.git`), so its paths resolve and its outputs stay here.
fn workdir() -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    let root = std::fs::canonicalize(repo()).unwrap();
    for e in std::fs::read_dir(&root).unwrap() {
        let e = e.unwrap();
        let name = e.file_name();
        if name == "out" || name == ".git" {
            continue;
        }
        std::os::unix::fs::symlink(e.path(), d.path().join(&name)).unwrap();
    }
    d
}

/// Runs one command with a time limit; its stdout then stderr as lines,
/// and its exit code.
fn execute(prog: &Path, args: &[String], dir: &Path) -> Result<(Vec<String>, i32), String> {
    let out_path = dir.join(".guide-stdout");
    let err_path = dir.join(".guide-stderr");
    let mut child = Command::new(prog)
        .args(args)
        .current_dir(dir)
        .env_remove("EHSERVO_BLESS")
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap())
        .spawn()
        .map_err(|e| format!("{}: {e}", prog.display()))?;
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("timed out after {} s", TIMEOUT.as_secs()));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut text = String::from_utf8_lossy(&std::fs::read(&out_path).unwrap()).into_owned();
    if !text.is_empty() && !text.ends_with('\n') {
        text.push('\n');
    }
    text.push_str(&String::from_utf8_lossy(&std::fs::read(&err_path).unwrap()));
    let _ = std::fs::remove_file(&out_path);
    let _ = std::fs::remove_file(&err_path);
    let lines: Vec<String> = text.lines().map(|l| l.trim_end().to_string()).collect();
    Ok((trim_blank(lines), status.code().unwrap_or(-1)))
}

fn trim_blank(mut v: Vec<String>) -> Vec<String> {
    while v.last().is_some_and(|l| l.is_empty()) {
        v.pop();
    }
    v
}

/// One command of a console block: where its `$` line is and its expected
/// output.
struct Cmd {
    /// Index in the block's lines of the `$` line, and one past its last
    /// expected line.
    at: usize,
    end: usize,
    words: Vec<String>,
    expected: Vec<String>,
    exit: i32,
}

fn commands(b: &Block) -> Result<Vec<Cmd>, String> {
    let mut out: Vec<Cmd> = Vec::new();
    let mut i = 0;
    while i < b.lines.len() {
        let l = &b.lines[i];
        let Some(cmd) = l.strip_prefix("$ ") else {
            if out.is_empty() {
                return Err(format!(
                    "line {}: output before any `$ ` command",
                    b.first + i + 1
                ));
            }
            i += 1;
            continue;
        };
        let at = i;
        let mut text = cmd.to_string();
        while text.ends_with('\\') && i + 1 < b.lines.len() {
            text.pop();
            i += 1;
            text.push(' ');
            text.push_str(b.lines[i].trim());
        }
        i += 1;
        let body_start = i;
        while i < b.lines.len() && !b.lines[i].starts_with("$ ") {
            i += 1;
        }
        let mut expected: Vec<String> = trim_blank(
            b.lines[body_start..i]
                .iter()
                .map(|l| l.trim_end().to_string())
                .collect(),
        );
        let mut exit = 0;
        if let Some(last) = expected.last() {
            if let Some(n) = last
                .strip_prefix("[exit ")
                .and_then(|r| r.strip_suffix(']'))
            {
                exit = n
                    .parse()
                    .map_err(|_| format!("line {}: bad {last}", b.first + i))?;
                expected.pop();
            }
        }
        out.push(Cmd {
            at,
            end: i,
            words: words(&text)?,
            expected,
            exit,
        });
    }
    Ok(out)
}

/// The test command of `.ci/run`: the README shows it word for word.
fn ci_runs(line: &str) -> bool {
    std::fs::read_to_string(repo().join(".ci/run"))
        .unwrap()
        .lines()
        .any(|l| l.trim() == line)
}

/// Checks (and with bless rewrites) one page; returns the failures.
fn check_page(page: &str, env: &Env) -> Vec<String> {
    let path = repo().join(page);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{page}: {e}"));
    let bs = match blocks(page, &text) {
        Ok(b) => b,
        Err(e) => return vec![e],
    };
    let dir = workdir();
    let mut fails = Vec::new();
    // Replacements for bless: (first line index, one past the last, new lines).
    let mut edits: Vec<(usize, usize, Vec<String>)> = Vec::new();
    let tmp = std::fs::canonicalize(dir.path())
        .unwrap()
        .display()
        .to_string();
    for b in &bs {
        let at = b.at(page);
        let skipped = match env.skipped(b, page) {
            Ok(s) => s,
            Err(e) => {
                fails.push(e);
                continue;
            }
        };
        if let Some(why) = &skipped {
            eprintln!("{at}: {} block {why}", b.lang);
        }
        match b.lang.as_str() {
            "console" => {
                if skipped.is_some() {
                    continue;
                }
                let cmds = match commands(b) {
                    Ok(c) => c,
                    Err(e) => {
                        fails.push(format!("{page}: {e}"));
                        continue;
                    }
                };
                for c in cmds {
                    let shown = c.words.join(" ");
                    if shown == "cargo test --workspace" {
                        if !ci_runs(&shown) {
                            fails.push(format!("{at}: `{shown}` is not .ci/run's test command"));
                        }
                        if !c.expected.is_empty() {
                            fails.push(format!("{at}: `{shown}` is not run: show no output"));
                        }
                        continue;
                    }
                    let (prog, args): (PathBuf, &[String]) = match c.words[0].as_str() {
                        "ehservo" => (env.bin.clone(), &c.words[1..]),
                        "cargo"
                            if c.words.len() > 3 && c.words[1..4] == ["run", "--release", "--"] =>
                        {
                            (env.bin.clone(), &c.words[4..])
                        }
                        "python3" | "python" => (PathBuf::from(&env.python), &c.words[1..]),
                        "gcc" | "./ehservo_run" => (PathBuf::from(&c.words[0]), &c.words[1..]),
                        other => {
                            fails.push(format!(
                                "{at}: `{other}`: not a command the guide runs (ehservo, python3, gcc, ./ehservo_run); mark the block skip=\"why\""
                            ));
                            continue;
                        }
                    };
                    let prog = if prog.starts_with("./") {
                        dir.path().join(&prog)
                    } else {
                        prog
                    };
                    match execute(&prog, args, dir.path()) {
                        Err(e) => fails.push(format!("{at}: `{shown}`: {e}")),
                        Ok((actual, code)) => {
                            let actual: Vec<String> =
                                actual.iter().map(|l| l.replace(&tmp, ANY)).collect();
                            if code != c.exit || !output_matches(&c.expected, &actual) {
                                if env.bless {
                                    let mut new = vec![b.lines[c.at].clone()];
                                    // Keep a continued command's lines.
                                    let mut k = c.at;
                                    while b.lines[k].ends_with('\\') {
                                        k += 1;
                                        new.push(b.lines[k].clone());
                                    }
                                    new.extend(actual.iter().cloned());
                                    if code != 0 {
                                        new.push(format!("[exit {code}]"));
                                    }
                                    edits.push((b.first + c.at, b.first + c.end, new));
                                } else {
                                    fails.push(format!(
                                        "{at}: `{shown}` exited {code} (expected {}) and printed:\n{}\n--- expected:\n{}",
                                        c.exit,
                                        actual.join("\n"),
                                        c.expected.join("\n")
                                    ));
                                }
                            }
                        }
                    }
                }
            }
            "toml" => {
                if skipped.is_some() {
                    continue;
                }
                if let Err(e) = check_toml(b, dir.path()) {
                    fails.push(format!("{at}: {e}"));
                }
            }
            "python" => {
                if let Err(e) = check_python(b, env, dir.path(), skipped.is_none()) {
                    fails.push(format!("{at}: {e}"));
                }
            }
            "rust" | "c" => match b.attr("file") {
                Some(f) => {
                    if let Err(e) = part_of(b, f) {
                        fails.push(format!("{at}: {e}"));
                    }
                }
                None => fails.push(format!(
                    "{at}: a {} block needs file=PATH (the file the tests build)",
                    b.lang
                )),
            },
            "text" => {}
            other => fails.push(format!(
                "{at}: a block of {other:?}: use console, toml, python, rust/c with file=, or text"
            )),
        }
    }
    if env.bless && !edits.is_empty() {
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        edits.sort_by_key(|e| std::cmp::Reverse(e.0));
        for (a, z, new) in edits {
            lines.splice(a..z, new);
        }
        let mut out = lines.join("\n");
        out.push('\n');
        std::fs::write(&path, out).unwrap();
        eprintln!("{page}: blessed");
    }
    fails
}

/// The block is a contiguous part of the repository file.
fn part_of(b: &Block, file: &str) -> Result<(), String> {
    let whole = std::fs::read_to_string(repo().join(file)).map_err(|e| format!("{file}: {e}"))?;
    let part = b.lines.join("\n");
    if whole.contains(&part) {
        Ok(())
    } else {
        Err(format!("the block is not a part of {file} as it is now"))
    }
}

fn check_toml(b: &Block, dir: &Path) -> Result<(), String> {
    let kind = ["study", "tune", "league", "manifest"]
        .into_iter()
        .find(|k| b.flag(k))
        .unwrap_or("scenario");
    let file = match (b.attr("file"), b.attr("save")) {
        (Some(f), None) => {
            part_of(b, f)?;
            repo().join(f)
        }
        (None, save) => {
            let p = dir.join(save.unwrap_or(".guide-block.toml"));
            let mut text = b.lines.join("\n");
            text.push('\n');
            std::fs::write(&p, text).unwrap();
            p
        }
        (Some(_), Some(_)) => return Err("file= and save= together".into()),
    };
    let loaded = match kind {
        "scenario" => ehservo::scenario::Loop::load(&file, &[])
            .map(|_| ())
            .map_err(|e| e.to_string()),
        "study" => ehservo::study::Plan::load(&file)
            .map(|_| ())
            .map_err(|e| e.to_string()),
        "tune" => ehservo::tune::Tune::load(&file)
            .map(|_| ())
            .map_err(|e| e.to_string()),
        "league" => ehservo::league::League::load(&file)
            .map(|_| ())
            .map_err(|e| e.to_string()),
        _ => ehservo::reproduce::manifest::Manifest::load(&file)
            .map(|_| ())
            .map_err(|e| e.to_string()),
    };
    loaded.map_err(|e| format!("does not load as a {kind}: {e}"))
}

fn check_python(b: &Block, env: &Env, dir: &Path, run: bool) -> Result<(), String> {
    let src = dir.join(".guide-block.py");
    std::fs::write(&src, b.lines.join("\n") + "\n").unwrap();
    if let Some(f) = b.attr("file") {
        part_of(b, f)?;
    }
    let have_python = Command::new(&env.python)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !have_python {
        if env.require.contains("python") {
            return Err(format!("{} is not there", env.python));
        }
        eprintln!("python block not syntax-checked: no {}", env.python);
        return Ok(());
    }
    let (out, code) = execute(
        Path::new(&env.python),
        &[
            "-c".into(),
            "import ast,sys; ast.parse(open(sys.argv[1]).read())".into(),
            src.display().to_string(),
        ],
        dir,
    )?;
    if code != 0 {
        return Err(format!("not valid Python:\n{}", out.join("\n")));
    }
    if run && b.flag("run") {
        let (out, code) = execute(Path::new(&env.python), &[src.display().to_string()], dir)?;
        if code != 0 {
            return Err(format!("the Python block failed:\n{}", out.join("\n")));
        }
    }
    Ok(())
}

fn page(page: &str) {
    let env = Env::new();
    let fails = check_page(page, &env);
    assert!(fails.is_empty(), "{}", fails.join("\n\n"));
}

macro_rules! pages {
    ($($name:ident => $path:literal,)*) => {
        $(#[test] fn $name() { page($path); })*
    };
}

pages! {
    readme => "README.md",
    index => "docs/guide/README.md",
    getting_started => "docs/guide/getting-started.md",
    scenarios => "docs/guide/scenarios.md",
    plants => "docs/guide/plants.md",
    plant_fmu => "docs/guide/plant-fmu.md",
    cylinder_from_datasheets => "docs/guide/cylinder-from-datasheets.md",
    actuators_and_sensors => "docs/guide/actuators-and-sensors.md",
    controllers => "docs/guide/controllers.md",
    studies_and_clusters => "docs/guide/studies-and-clusters.md",
    tuning_and_league => "docs/guide/tuning-and-league.md",
    reproduction => "docs/guide/reproduction.md",
    python_c_fmi => "docs/guide/python-c-fmi.md",
    board => "docs/guide/board.md",
    troubleshooting => "docs/guide/troubleshooting.md",
}

#[test]
fn every_page_is_tested() {
    let mut on_disk: Vec<String> = std::fs::read_dir(repo().join("docs/guide"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".md"))
        .map(|n| format!("docs/guide/{n}"))
        .collect();
    on_disk.sort();
    for p in &on_disk {
        assert!(
            PAGES.contains(&p.as_str()),
            "{p} is not in guide.rs's PAGES"
        );
    }
    assert_eq!(
        PAGES.len(),
        on_disk.len() + 1,
        "PAGES lists a page that is not there"
    );
}

#[test]
fn the_matcher_matches_what_it_says() {
    let l = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert!(output_matches(
        &l(&["a", "…", "d"]),
        &l(&["a", "b", "c", "d"])
    ));
    assert!(output_matches(&l(&["a", "…"]), &l(&["a"])));
    assert!(!output_matches(&l(&["a", "d"]), &l(&["a", "b", "d"])));
    assert!(!output_matches(&l(&[]), &l(&["x"])));
    assert!(line_matches("took … s (… runs)", "took 0.12 s (4 runs)"));
    assert!(!line_matches("took … s", "took 0.12 ms"));
    assert!(!line_matches("ab…ba", "aba"));
    assert_eq!(
        words(r#"ehservo run x.toml --set 'a="b c"' "d e""#).unwrap(),
        l(&["ehservo", "run", "x.toml", "--set", "a=\"b c\"", "d e"])
    );
    assert!(words("ehservo run x | head").is_err());
}

/// Every relative link of the pages (outside code blocks) names a file or
/// folder that is there.
#[test]
fn links_resolve() {
    let mut bad = Vec::new();
    for page in PAGES {
        let text = std::fs::read_to_string(repo().join(page)).unwrap();
        let dir = Path::new(page).parent().unwrap_or(Path::new(""));
        let mut in_code = false;
        for (n, line) in text.lines().enumerate() {
            if line.starts_with("```") {
                in_code = !in_code;
                continue;
            }
            if in_code {
                continue;
            }
            let mut rest = line;
            while let Some(k) = rest.find("](") {
                rest = &rest[k + 2..];
                let Some(end) = rest.find(')') else { break };
                let target = &rest[..end];
                let path = target.split('#').next().unwrap_or("");
                if !path.is_empty()
                    && !target.contains("://")
                    && !target.contains(char::is_whitespace)
                    && !repo().join(dir).join(path).exists()
                {
                    bad.push(format!("{page}:{}: {target}", n + 1));
                }
            }
        }
    }
    assert!(bad.is_empty(), "links to nothing:\n{}", bad.join("\n"));
}
