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

/// `--free` and `--fix` that contradict themselves (issue 46, round four:
/// `--free bulk_modulus,bulk_modulus` and `--fix viscous=1000 --free
/// viscous` were fitted, exit 0) are refused with the flag and the name,
/// before the log is read: the log given does not exist, so a refusal
/// that names it would mean the flags were checked after reading.
#[test]
fn contradictory_free_and_fix_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("not-read.csv");
    let cases: [(&[&str], &str); 4] = [
        (
            &["--free", "bulk_modulus,bulk_modulus"],
            "--free bulk_modulus: named twice",
        ),
        (
            &["--free", "bulk_modulus,,viscous"],
            "--free: an empty name",
        ),
        (
            &["--fix", "viscous=1000", "--fix", "viscous=2000"],
            "--fix viscous: given twice",
        ),
        (
            &["--fix", "viscous=1000", "--free", "viscous,rated_flow"],
            "--fix viscous and --free viscous",
        ),
    ];
    for (flags, expect) in cases {
        let out = dir.path().join("out");
        let mut args: Vec<&std::ffi::OsStr> = vec!["identify".as_ref(), missing.as_os_str()];
        args.extend(flags.iter().map(std::ffi::OsStr::new));
        args.extend(["--out".as_ref(), out.as_os_str()]);
        let o = run_within(&args, Duration::from_secs(20));
        let err = crate::common::rejected("free/fix", &o, expect);
        assert!(
            !err.contains("not-read.csv"),
            "checked before the log: {err}"
        );
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
        crate::common::succeeded(lp, &o);
        let o = ehservo()
            .arg("check")
            .arg(out.join("scenario.toml"))
            .output()
            .unwrap();
        crate::common::succeeded(lp, &o);
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
    crate::common::succeeded("run of the open experiment", &o);
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

/// A plant with a load stiffness, simulated here and not by ehservo:
/// y''' + a3·y'' + a2·y' + a1·y = b·u with (a1, a2, a3, b) = (2000 s⁻³,
/// 13000 s⁻², 40 s⁻¹, 18000 rad/(V·s³)) (poles −0.154 and a pair at
/// ω_n = 114 rad/s, ζ = 0.17), by a hand-written RK4 (10 steps a sample)
/// under a held sum of 12 sines of 0.01 V from 0.25 to 43 Hz, 8 s at
/// 500 Hz, with ±10⁻⁵ rad of uniform noise from a 64-bit LCG (Knuth's
/// MMIX constants).
fn stiff_log() -> String {
    let (a1, a2, a3, b) = (2000.0, 13000.0, 40.0, 18000.0);
    let (h, n, m) = (2e-3, 4001usize, 10usize);
    let fs = [
        0.25, 0.5, 1.1, 2.3, 5.0, 9.0, 13.0, 17.0, 19.0, 23.0, 31.0, 43.0,
    ];
    let u_at = |k: usize| -> f64 {
        let t = k as f64 * h;
        fs.iter()
            .enumerate()
            .map(|(i, f)| 0.01 * (2.0 * std::f64::consts::PI * f * t + (i * i) as f64 * 0.7).sin())
            .sum()
    };
    let f = |x: [f64; 3], u: f64| [x[1], x[2], -a1 * x[0] - a2 * x[1] - a3 * x[2] + b * u];
    let add =
        |x: [f64; 3], k: [f64; 3], s: f64| [x[0] + s * k[0], x[1] + s * k[1], x[2] + s * k[2]];
    let (mut x, mut seed) = ([0.0f64; 3], 12345u64);
    let mut s = String::from("t_s,u_V,theta_rad\n");
    let hs = h / m as f64;
    for k in 0..n {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let noise = ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2e-5;
        let u = u_at(k);
        s += &format!("{:e},{u:e},{:e}\n", k as f64 * h, x[0] + noise);
        for _ in 0..m {
            let k1 = f(x, u);
            let k2 = f(add(x, k1, hs / 2.0), u);
            let k3 = f(add(x, k2, hs / 2.0), u);
            let k4 = f(add(x, k3, hs), u);
            x = std::array::from_fn(|i| {
                x[i] + hs / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
    }
    s
}

fn identify_json(dir: &Path, name: &str, extra: &[&str]) -> (Output, serde_json::Value) {
    let f = dir.join("stiff.csv");
    if !f.exists() {
        std::fs::write(&f, stiff_log()).unwrap();
    }
    let out = dir.join(name);
    let o = ehservo()
        .arg("identify")
        .arg(&f)
        .args(extra)
        .args(["--no-plot", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let j = std::fs::read_to_string(out.join("identify.json"))
        .map(|t| serde_json::from_str(&t).unwrap())
        .unwrap_or(serde_json::Value::Null);
    (o, j)
}

/// The truth has a1 = 2000 s⁻³: the linear fit finds it within 15 %,
/// free and with its standard error (it was "UNIDENTIFIABLE: held at its
/// prior" 0 at every --ident-threshold: its start grid had no a1 and its
/// scale was 10⁻⁹·a2).
#[test]
fn a_load_stiffness_is_identified() {
    let dir = tempfile::tempdir().unwrap();
    let (o, j) = identify_json(dir.path(), "lin", &["--no-greybox"]);
    crate::common::succeeded("identify", &o);
    let fit = &j["linear"]["fit"];
    assert_eq!(fit["converged"], true, "{fit}");
    let a1 = fit["estimates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["key"] == "a1")
        .unwrap();
    assert_eq!(a1["status"], "free", "{a1}");
    let v = a1["value"].as_f64().unwrap();
    assert!((v / 2000.0 - 1.0).abs() < 0.15, "a1 = {v}");
    assert!(a1["se"].as_f64().unwrap() < 0.15 * 2000.0, "{a1}");
}

/// A fit that stops without converging says so in its output, its JSON
/// and its exit status (1), with the reason and the count, is not printed
/// as a result beside the converged one, and no identified.toml is written
/// from it. Here the grey-box is given 14 evaluations (--max-evaluations;
/// it needs several hundred on these data), which the linear fit (7)
/// does not need more than.
#[test]
fn a_fit_that_does_not_converge_is_not_a_result() {
    let dir = tempfile::tempdir().unwrap();
    let (o, j) = identify_json(dir.path(), "short", &["--max-evaluations", "14"]);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(1), "{out}{err}");
    assert!(
        err.contains("the greybox fit did not converge") && err.contains("evaluations"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert_eq!(j["linear"]["fit"]["converged"], true);
    assert!(
        out.contains("linear model (") && out.contains("  a1 "),
        "{out}"
    );
    let gb = out
        .split("greybox model: DID NOT CONVERGE")
        .nth(1)
        .unwrap_or_else(|| panic!("{out}"));
    // No estimate lines under the grey-box's header.
    assert!(!gb.lines().skip(1).any(|l| l.starts_with("  ")), "{out}");
    let fit = &j["greybox"]["fit"];
    assert_eq!(fit["converged"], false, "{fit}");
    assert!(fit["evaluations"].as_u64().unwrap() >= 1, "{fit}");
    assert!(!dir.path().join("short/identified.toml").exists());
}
