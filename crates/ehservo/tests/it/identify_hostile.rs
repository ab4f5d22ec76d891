//! `identify` on logs built to break it (issue 46): periods the fits cannot
//! work with, signals that never move. Each is refused before any fit,
//! exit 2, one line naming the file and the column, nothing written, and
//! within seconds (a run past its deadline is killed and fails the test).

use crate::common::{ehservo, rejected_naming};
use std::path::Path;
use std::process::Output;
use std::time::{Duration, Instant};

/// Runs `ehservo ARGS`, killed (and the test failed) after `limit`.
pub fn run_within(args: &[&std::ffi::OsStr], limit: Duration) -> Output {
    let mut child = ehservo()
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            panic!("ehservo {args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// A log of 256 rows at times t0 + k·h with a moving command, the
/// position and (when given) the pressure from `y` and `p`.
fn log(t0: f64, h: f64, y: impl Fn(usize) -> f64, p: Option<&dyn Fn(usize) -> f64>) -> String {
    let mut s = String::from(if p.is_some() {
        "t_s,u_V,theta_rad,p_load_Pa\n"
    } else {
        "t_s,u_V,theta_rad\n"
    });
    for k in 0..256 {
        let u = 0.05 * (0.05 * k as f64).sin() + 0.03 * (0.31 * k as f64).sin();
        s += &format!("{:e},{u:e},{:e}", t0 + k as f64 * h, y(k));
        if let Some(p) = p {
            s += &format!(",{:e}", p(k));
        }
        s.push('\n');
    }
    s
}

fn identify_refuses(dir: &Path, name: &str, text: &str, expect: &str) {
    let f = dir.join(name);
    std::fs::write(&f, text).unwrap();
    let out = dir.join(format!("out-{name}"));
    let o = run_within(
        &[
            "identify".as_ref(),
            f.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ],
        Duration::from_secs(20),
    );
    let err = rejected_naming(name, &o, expect);
    assert!(err.trim().len() <= 300, "{name}: a short line: {err}");
    assert!(!out.exists(), "{name}: nothing written");
}

#[test]
fn degenerate_periods_and_still_signals_are_refused_before_any_fit() {
    let dir = tempfile::tempdir().unwrap();
    let ramp = |k: usize| 1e-4 * (0.05 * k as f64).sin();
    let cases: [(&str, f64, f64, &str); 5] = [
        // The two periods of issue 46 that hung inside nalgebra's SVD.
        (
            "h1e-200.csv",
            0.0,
            1e-200,
            "the sample period 1e-200 s is outside",
        ),
        (
            "h1e-110.csv",
            0.0,
            1e-110,
            "the sample period 1e-110 s is outside",
        ),
        // 10⁻³¹⁰ is subnormal (below f64::MIN_POSITIVE = 2.2·10⁻³⁰⁸).
        ("subnormal.csv", 0.0, 1e-310, "not a normal positive number"),
        ("slow.csv", 0.0, 1e5, "the sample period 1e5 s is outside"),
        // t ≈ 10¹² s: ulp = 10¹²·2.2·10⁻¹⁶ = 2.2·10⁻⁴ s, 22 % of h = 1 ms.
        ("epoch.csv", 1e12, 1e-3, "resolved to"),
    ];
    for (name, t0, h, expect) in cases {
        identify_refuses(dir.path(), name, &log(t0, h, ramp, None), expect);
    }
    identify_refuses(
        dir.path(),
        "still-y.csv",
        &log(0.0, 1e-3, |_| 0.25, None),
        "column `theta_rad`: the position never moves",
    );
    identify_refuses(
        dir.path(),
        "still-p.csv",
        &log(0.0, 1e-3, ramp, Some(&|_| 1e5)),
        "column `p_load_Pa`: the pressure never moves",
    );
}

/// A `--prior` that cannot serve is refused before any fit, naming the
/// flag and the user's file: a cylinder scenario for rotary data (once
/// fitted for 3.9 s, then refused under the name "identified"), and a
/// file that does not exist.
#[test]
fn a_bad_prior_is_named_before_any_fit() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("rotary.csv");
    std::fs::write(&f, log(0.0, 1e-3, |k| 1e-4 * (0.05 * k as f64).sin(), None)).unwrap();
    let slide = crate::common::repo().join("scenarios/cylinders/slide.toml");
    let missing = dir.path().join("missing.toml");
    for (prior, expect) in [
        (
            &slide,
            "a linear plant (plant.model = \"cylinder\"), where the data measure a rotary axis",
        ),
        (&missing, "cannot be read"),
    ] {
        let out = dir.path().join("out");
        let start = Instant::now();
        let o = run_within(
            &[
                "identify".as_ref(),
                f.as_os_str(),
                "--prior".as_ref(),
                prior.as_os_str(),
                "--out".as_ref(),
                out.as_os_str(),
            ],
            Duration::from_secs(20),
        );
        let err = crate::common::rejected("prior", &o, expect);
        let named = format!("--prior {}", prior.display());
        assert!(err.contains(&named), "names the flag and the file: {err}");
        assert!(start.elapsed() < Duration::from_secs(5), "before any fit");
        assert!(!out.exists(), "nothing written");
    }
}

/// `excite` on a linear axis (the slide of issue 45) writes a scenario
/// that `ehservo check` accepts, open and closed loop: no paper's
/// `uncertainty.a_bias` on a cylinder, the reference in mm (`t,y_mm`), a
/// closed loop's reference about the rod's start.
#[test]
fn excite_on_a_cylinder_writes_a_scenario_check_accepts() {
    let dir = tempfile::tempdir().unwrap();
    let slide = crate::common::repo().join("scenarios/cylinders/slide.toml");
    for (lp, amplitude) in [("open", "0.5"), ("closed", "0.01")] {
        let out = dir.path().join(lp);
        let o = ehservo()
            .args(["excite", "--loop", lp, "--duration", "2", "--period", "500"])
            .args(["--amplitude", amplitude, "--prior"])
            .arg(&slide)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{lp}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let o = ehservo()
            .arg("check")
            .arg(out.join("scenario.toml"))
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{lp}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let text = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
        assert!(!text.contains("a_bias"), "{lp}: {text}");
    }
    // The open loop's table is the command at 1 V a mm: u_V = y_d_mm.
    let o = ehservo()
        .arg("run")
        .arg(dir.path().join("open/scenario.toml"))
        .args(["--no-plot", "-q", "--out"])
        .arg(dir.path().join("run"))
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let trace = std::fs::read_to_string(dir.path().join("run/trace.csv")).unwrap();
    let mut lines = trace.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (yd, u) = (col("y_d_mm"), col("u_V"));
    for l in lines.take(50) {
        let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        assert!((v[u] - v[yd]).abs() <= 1e-9 * v[yd].abs().max(1e-3), "{l}");
    }
}
