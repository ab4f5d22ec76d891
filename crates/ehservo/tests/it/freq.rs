//! `ehservo linearize` and `ehservo freq`: bad requests refused clearly,
//! measured responses against the computed ones on a linear case, and the
//! same numbers on any thread count.

use crate::common;
use ehservo::freq::measure::{self, Broadband, Input, Settings};
use ehservo::freq::oppoint::At;
use ehservo::freq::response::Discretisation;
use ehservo::freq::ss::C64;
use ehservo::scenario::Loop;
use std::f64::consts::PI;

fn write(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Every bad request: exit 2, one line naming the file and the flag or
/// key, nothing written.
#[test]
fn bad_requests_are_refused_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    let fig2 = common::repo().join("scenarios/paper/fig2.toml");
    let fig2 = fig2.to_str().unwrap();
    let heavy = write(
        tmp.path(),
        "heavy-load.toml",
        "[load]\namplitude = 500.0\nwavenumber = 1.0\n",
    );
    let tight = write(
        tmp.path(),
        "tight-valve.toml",
        "[load]\namplitude = 20.0\nwavenumber = 1.0\n[actuator]\nlimit = 0.01\n[controller]\nkind = \"pid\"\n",
    );
    let kink = write(
        tmp.path(),
        "no-leakage.toml",
        "[plant.params]\nKce = 0.0\n[controller]\nkind = \"pid\"\n",
    );
    let (heavy, tight, kink) = (
        heavy.to_str().unwrap().to_string(),
        tight.to_str().unwrap().to_string(),
        kink.to_str().unwrap().to_string(),
    );
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str, &str)> = vec![
        (
            vec!["freq", fig2, "--out", o, "--f-max", "60"],
            "--f-max",
            "above the Nyquist frequency 50 Hz",
        ),
        (
            vec!["freq", fig2, "--out", o, "--f-min", "10", "--f-max", "5"],
            "--f-min",
            "empty frequency range",
        ),
        (
            vec!["freq", fig2, "--out", o, "--f-min=-1"],
            "--f-min",
            "must be a frequency > 0",
        ),
        (
            vec!["freq", fig2, "--out", o, "--measure-f-max", "51"],
            "--measure-f-max",
            "above the Nyquist",
        ),
        (
            vec!["freq", fig2, "--out", o, "--measure", "bogus"],
            "--measure",
            "unknown method",
        ),
        (
            vec!["freq", fig2, "--out", o, "--measure-f-min", "1e-6"],
            "--measure-f-min",
            "below what a record can resolve",
        ),
        (
            vec!["freq", fig2, "--out", o, "--at", "20"],
            "--at",
            "within the run",
        ),
        (
            vec!["linearize", &heavy, "--trim", "57.29577951308232"],
            "--trim",
            "d(theta_ddot)/dt",
        ),
        (
            vec!["linearize", &tight, "--trim", "30"],
            "actuator.limit",
            "beyond the saturation",
        ),
        (
            vec!["freq", &kink, "--out", o, "--trim", "10"],
            "--trim",
            "not differentiable there",
        ),
    ];
    for (args, key, expect) in cases {
        let r = common::ehservo().args(&args).output().unwrap();
        let file = std::path::Path::new(args[1])
            .file_name()
            .unwrap()
            .to_str()
            .unwrap();
        let err = common::rejected_naming(file, &r, expect);
        assert!(err.contains(key), "{args:?}: names {key}: {err}");
        assert!(!out.exists(), "{args:?}: output written for bad input");
    }
    // The kink's message gives the one-sided slopes, and --side builds them.
    let r = common::ehservo()
        .args(["linearize", &kink, "--trim", "10"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("from below") && err.contains("from above"),
        "{err}"
    );
    let r = common::ehservo()
        .args(["linearize", &kink, "--trim", "10", "--side", "minus"])
        .output()
        .unwrap();
    assert_eq!(
        r.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["one_sided"], "minus");
    assert_eq!(v["kinks"].as_array().unwrap().len(), 1);
}

/// PID on the nominal servo (no load, no variation) at small amplitude is
/// a linear loop: the sinestream and the multisine's Welch H1 measured on
/// the simulator agree with the computed responses (θ/θd, θ/d and S) to
/// 0.1 dB and 1° wherever the quality (fundamental fraction, coherence)
/// is above 0.99 — with 10 RK4 sub-steps against the exact ZOH model, and
/// with one sub-step against the model of the simulator's RK4 map.
#[test]
fn measured_agrees_with_computed_on_a_linear_case() {
    let base = "[load]\namplitude = 0.0\nwavenumber = 0.0\n[uncertainty]\na_bias = 0.0\nb_bias = 0.0\n[controller]\nkind = \"pid\"\n";
    for (substeps, d) in [(10, Discretisation::Zoh), (1, Discretisation::Rk4)] {
        let toml = format!("{base}[simulation]\nstep = 0.01\nsubsteps = {substeps}\n");
        let s = Loop::parse(&toml).unwrap();
        let l = ehservo::freq::linearise(&s, "linear", Some(At::Trim(0.0)), None, d).unwrap();
        let settings = Settings {
            theta0: 0.0,
            amplitude: 0.01f64.to_radians(),
            disturbance: 0.002,
            settle_s: 2.0,
            settle_cycles: 2.0,
            cycles: 4,
            min_window: 64,
        };
        let freqs: Vec<f64> = (0..24)
            .map(|i| 0.2 * (225.0f64).powf(i as f64 / 23.0))
            .collect();
        let (tr, di) = rayon::join(
            || measure::sinestream(&l.setup, Input::Tracking, &freqs, &settings).unwrap(),
            || measure::sinestream(&l.setup, Input::Disturbance, &freqs, &settings).unwrap(),
        );
        let plan = measure::plan_welch(Broadband::Multisine, 0.2, 45.0, 30, 3, 0.01, 2.0).unwrap();
        // (The chirp's H1 is not held to this bound: docs/frequency.md.)
        let (wt, wd) = measure::welch_both(&l.setup, &plan, &settings);
        let mut checked = 0;
        let close = |what: &str, f: f64, got: C64, want: C64| {
            let dg = 20.0 * (got.norm() / want.norm()).log10();
            let dp = (got / want).arg().to_degrees();
            assert!(
                dg.abs() < 0.1 && dp.abs() < 1.0,
                "{what} at {f:.3} Hz ({substeps} sub-steps, {d:?}): {dg:.4} dB, {dp:.4}°"
            );
        };
        for (t, u) in tr.iter().chain(&wt).zip(di.iter().chain(&wd)) {
            let r = l.lp.at(2.0 * PI * t.f_hz);
            if t.quality > 0.99 {
                close("θ/θd", t.f_hz, t.theta_c().unwrap(), r.track.unwrap());
                checked += 1;
            }
            if u.quality > 0.99 && u.quality_s.unwrap_or(1.0) > 0.99 {
                close("θ/d", u.f_hz, u.theta_c().unwrap(), r.dist.unwrap());
                close("S", u.f_hz, u.s_c().unwrap(), r.s.unwrap());
                checked += 1;
            }
        }
        // Not vacuous: nearly every sinestream and multisine point passed
        // the quality gate.
        assert!(
            checked >= 2 * (freqs.len() + plan.bins.len()) - 4,
            "{checked} checked"
        );
    }
}

/// The same files, byte for byte, on one thread and on two.
#[test]
fn freq_is_the_same_on_any_thread_count() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = common::repo().join("docs/league/suite/scenarios/pid/fig2.toml");
    let mut outs = Vec::new();
    for t in ["1", "2"] {
        let d = tmp.path().join(format!("t{t}"));
        let r = common::ehservo()
            .arg("freq")
            .arg(&sc)
            .args([
                "--out",
                d.to_str().unwrap(),
                "--threads",
                t,
                "--no-plot",
                "-q",
            ])
            .args(["--measure", "sine,multisine", "--measure-points", "12"])
            .output()
            .unwrap();
        assert_eq!(
            r.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&r.stderr)
        );
        outs.push(d);
    }
    for f in [
        "freq.json",
        "response.csv",
        "measured_sine.csv",
        "measured_multisine.csv",
        "linearization.json",
    ] {
        let a = std::fs::read(outs[0].join(f)).unwrap();
        let b = std::fs::read(outs[1].join(f)).unwrap();
        assert!(a == b, "{f} differs between 1 and 2 threads");
    }
}

/// With plots, a linear loop's `freq` draws Bode and Nyquist plots and the
/// measured responses, each as PNG and SVG, and a chirp measurement writes
/// its CSV with the coherence beside each bin.
#[test]
fn plots_and_the_chirp_are_written() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = common::repo().join("docs/league/suite/scenarios/pid/fig2.toml");
    let d = tmp.path().join("f");
    let r = common::ehservo()
        .arg("freq")
        .arg(&sc)
        .args(["--out", d.to_str().unwrap(), "-q"])
        .args(["--measure", "chirp", "--measure-points", "8"])
        .output()
        .unwrap();
    assert_eq!(
        r.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    for name in ["bode", "nyquist", "measured"] {
        let png = std::fs::read(d.join(format!("{name}.png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "{name}.png");
        let svg = std::fs::read_to_string(d.join(format!("{name}.svg"))).unwrap();
        assert!(svg.contains("<svg"), "{name}.svg");
    }
    let csv = std::fs::read_to_string(d.join("measured_chirp.csv")).unwrap();
    let head = csv.lines().next().unwrap();
    assert!(
        head.contains("coherence") || head.contains("quality"),
        "{head}"
    );
    assert!(csv.lines().count() > 2, "{csv}");
}

/// `--at T` linearises at the run's state at T: the operating point's
/// state is the trace's x at that sample, the command the trace's u, and
/// it is no equilibrium (its drift is θ̇, θ̈, θ⃛ of the trace).
#[test]
fn at_a_time_is_the_runs_state() {
    let s = Loop::load(&common::repo().join("scenarios/paper/fig2.toml"), &[]).unwrap();
    let l = ehservo::freq::linearise(&s, "fig2", Some(At::Time(1.37)), None, Discretisation::Zoh)
        .unwrap();
    let r = ehservo::run::run(&s, ehservo::run::Keep::Every(1));
    let smp = r.trace.iter().find(|x| x.k == 137).unwrap();
    assert_eq!(l.point.t_s, Some(1.37));
    for i in 0..3 {
        assert_eq!(l.point.plant_state[i].to_bits(), smp.x[i].to_bits(), "x{i}");
    }
    assert_eq!(l.point.u.to_bits(), smp.u.to_bits());
    assert!((l.point.drift[0] - smp.x[1]).abs() < 1e-12);
    assert!((l.point.drift[1] - smp.x[2]).abs() < 1e-12);
    assert!(l.point.drift[2].abs() > 0.0);
}

/// A measured band above the loop's gain crossover (the PID's computed one
/// is at 5.6 Hz: `freq` without `--measure`) has no crossover to measure:
/// the margins say so and name the band, rather than a bare "none".
#[test]
fn a_measured_band_without_a_crossover_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let o = crate::common::ehservo()
        .arg("freq")
        .arg(crate::common::repo().join("scenarios/frequency/pid-nominal.toml"))
        .args([
            "--measure",
            "sine",
            "--measure-f-min",
            "20",
            "--measure-f-max",
            "40",
        ])
        .args(["--measure-points", "3", "--no-plot", "--out"])
        .arg(dir.path().join("f"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("measured (sine"))
        .unwrap();
    assert!(
        line.contains("phase margin none (|L| does not cross 1 between 20.")
            && line.contains(" Hz, where L was measured)"),
        "{line}"
    );
    // The computed crossover lies below the band: the premise.
    let c = text
        .lines()
        .find(|l| l.trim_start().starts_with("L: gain margin"))
        .unwrap();
    let f: f64 = c
        .split("phase margin ")
        .nth(1)
        .unwrap()
        .split(" at ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(f < 20.0, "{c}");
}

/// Issue 46, item 2: the measurement's counts are made in checked
/// arithmetic. `--settle 1e300` once planned u64::MAX samples, the work
/// sum wrapped round below the limit, and every cell came out empty with
/// exit 0; `--measure-f-min 1e-300` was measured from 1.56 Hz. Each is now
/// refused in one short line naming its flag, nothing written.
#[test]
fn work_counts_that_cannot_be_planned_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let fig2 = common::repo().join("scenarios/paper/fig2.toml");
    let fig2 = fig2.to_str().unwrap();
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    // Fig. 2: h = 0.01 s, sampled, 1 sub-step: 2 evaluations a sample. A
    // record within 4e8 evaluations, run for both inputs, is at most
    // 4e8 / (2·2) = 1e8 samples = 1e6 s; a sinestream needs 4 cycles + 2
    // settling periods in it: 6 / 1e6 s = 6e-6 Hz, the lowest allowed.
    let cases: Vec<(Vec<&str>, &str, &str)> = vec![
        // The sinestream's settling samples: 1e300 / 0.01 = 1e302.
        (
            vec!["--settle", "1e300"],
            "--settle",
            "1.000e302 settling samples asked",
        ),
        // Welch's settling samples, the same figure.
        (
            vec!["--settle", "1e300", "--measure", "multisine"],
            "--settle",
            "1.000e302 settling samples asked",
        ),
        // Finite counts whose sum is beyond the limit: 40 frequencies × 2
        // inputs × 1e10 s / 0.01 s × 2 evaluations = 1.6e14.
        (vec!["--settle", "1e10"], "--settle", "about 1.60e14"),
        // Below what a record can resolve, with the range allowed.
        (
            vec!["--measure-f-min", "1e-300"],
            "--measure-f-min",
            "allowed: 6.000e-6 to 50 Hz",
        ),
        (
            vec!["--measure-f-min", "5.9e-6"],
            "--measure-f-min",
            "allowed: 6.000e-6 to 50 Hz",
        ),
        // Just above it the record resolves the frequency, and the work
        // of the 40 frequencies is what is refused.
        (
            vec!["--measure-f-min", "6.1e-6"],
            "--measure-f-min",
            "more than the limit of 4e8",
        ),
        // Welch: 4 periods of f in each of 4 segments: 16 / 1e6 s.
        (
            vec!["--measure-f-min", "1e-300", "--measure", "chirp"],
            "--measure-f-min",
            "allowed: 1.600e-5 to 50 Hz",
        ),
        (vec!["--f-max", "1e300"], "--f-max", "1e300 Hz is above"),
    ];
    for (extra, key, expect) in cases {
        let r = common::ehservo()
            .args(["freq", fig2, "--out", o, "--no-plot"])
            .args(&extra)
            .output()
            .unwrap();
        let err = common::rejected_naming("fig2.toml", &r, expect);
        assert!(err.contains(key), "{extra:?}: names {key}: {err}");
        assert!(err.trim().chars().count() < 300, "{extra:?}: short: {err}");
        assert!(!out.exists(), "{extra:?}: output written for bad input");
    }
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}
