//! Force and load-pressure loops, run by the binary (issue #49 items 1 and
//! 3, docs/force-control.md): the loop's quantity in its columns, metrics
//! and summary; the force PI's integral action held against the rod's
//! pressure·area balance; the velocity feed-forward measured against the
//! same PI without it.

use super::common::{ehservo, repo};

/// A run's trace (header, rows) and summary.json, of `scenario` with the
/// `--set` overrides `set`.
fn run(scenario: &str, set: &[&str]) -> (Vec<String>, Vec<Vec<f64>>, serde_json::Value) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let mut cmd = ehservo();
    cmd.arg("run")
        .arg(repo().join(scenario))
        .args(["--no-plot", "--quiet", "--out"])
        .arg(&out);
    for s in set {
        cmd.args(["--set", s]);
    }
    let o = cmd.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    (header, rows, serde_json::from_str(&summary).unwrap())
}

/// The column `name`'s index.
fn at(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no {name} in {header:?}"))
}

/// The mean of `f` over the rows at t ≥ `from` (s).
fn mean_from(rows: &[Vec<f64>], from: f64, f: &dyn Fn(&[f64]) -> f64) -> f64 {
    let tail: Vec<f64> = rows.iter().filter(|r| r[0] >= from).map(|r| f(r)).collect();
    tail.iter().sum::<f64>() / tail.len() as f64
}

/// The slide's areas by hand: A_A = π/4·0.063² = 3.1172e-3 m²,
/// A_B = π/4·(0.063² − 0.045²) = 1.5268e-3 m².
fn areas() -> (f64, f64) {
    let q = std::f64::consts::PI / 4.0;
    (q * 0.063 * 0.063, q * (0.063 * 0.063 - 0.045 * 0.045))
}

/// scenarios/force/force-pi.toml: a 20 kN step into the specimen. The
/// columns say the quantity (f_d_kN, f_kN, e_kN; the rod's motion in mm),
/// the integral drives the error to zero (|e| ≤ 20 N, 0.1 % of the step,
/// over the last second), and the force the loop holds is the one the
/// pressures make: over the last second the means of F_env and of
/// A_A·p_A − A_B·p_B agree to 0.1 % (ẏ and ÿ average out; the slide has
/// no Coulomb friction, and its viscous 2000·ẏ is in the balance).
#[test]
fn a_force_step_on_a_specimen_settles_on_the_pressure_area_balance() {
    let (h, rows, summary) = run("scenarios/force/force-pi.toml", &[]);
    assert_eq!(&h[..5], ["t_s", "f_d_kN", "f_kN", "e_kN", "u_V"]);
    assert!(h.iter().any(|c| c == "y_dot_mm_s") && h.iter().any(|c| c == "ff_V"));
    assert_eq!(summary["metrics"]["unit"], "kN");
    let last = rows.last().unwrap();
    assert!(
        (last[at(&h, "f_d_kN")] - 20.0).abs() < 1e-12,
        "the 20 kN step"
    );
    // f_kN is f_env_N shown in kN.
    let (f, f_env) = (last[at(&h, "f_kN")], last[at(&h, "f_env_N")]);
    assert!(
        (f * 1e3 - f_env).abs() <= 1e-9 * f_env,
        "{f} kN vs {f_env} N"
    );
    let tail = rows.iter().filter(|r| r[0] >= 2.0);
    let e_max = tail.map(|r| r[at(&h, "e_kN")].abs()).fold(0.0, f64::max);
    assert!(e_max <= 0.02, "|e| up to {e_max} kN over the last second");
    let (aa, ab) = areas();
    let hydraulic = mean_from(&rows, 2.0, &|r| {
        aa * r[at(&h, "p_a_Pa")] - ab * r[at(&h, "p_b_Pa")] - 2000.0 * r[at(&h, "y_dot_mm_s")] / 1e3
    });
    let env = mean_from(&rows, 2.0, &|r| r[at(&h, "f_env_N")]);
    assert!((env - 2e4).abs() <= 1e-3 * 2e4, "mean F_env {env} N");
    assert!(
        (hydraulic - env).abs() <= 1e-3 * env,
        "pressures' {hydraulic} N vs F_env {env} N"
    );
}

/// scenarios/force/load-simulator.toml: holding 10 kN while the spring's
/// mount moves 1 mm at 2 Hz. The designed velocity feed-forward cuts the
/// force error's RMS after the transient against the same PI with kv = 0
/// (measured when written: 0.1055 kN against 0.4320 kN); held here as at
/// least a halving, with both runs bounded.
#[test]
fn velocity_feedforward_reduces_the_extra_force_of_a_moving_mount() {
    let rms = |set: &[&str]| {
        let (_, _, s) = run("scenarios/force/load-simulator.toml", set);
        assert_eq!(s["metrics"]["diverged"], false);
        assert_eq!(s["behaviour"]["oscillation"]["sustained"], false);
        s["metrics"]["e_rms"].as_f64().unwrap()
    };
    let with = rms(&[]);
    let without = rms(&["controller.kv=0"]);
    eprintln!("e_rms: {with} kN with the feed-forward, {without} kN without");
    assert!(with < 0.5 * without, "{with} kN vs {without} kN");
}

/// scenarios/force/pressure.toml: the specimen's loop closed on the load
/// pressure p_L = p_A − α·p_B (α = A_B/A_A), a 50 bar step. The trace's
/// p_l_bar is p_L of its own p_a_Pa and p_b_Pa columns (α by hand from
/// the areas), and it settles on 50 bar (mean over the last second within
/// 0.05 bar, 0.1 %).
#[test]
fn a_load_pressure_loop_holds_its_step() {
    let (aa, ab) = areas();
    let (h, rows, summary) = run("scenarios/force/pressure.toml", &[]);
    assert_eq!(&h[1..4], ["p_l_d_bar", "p_l_bar", "e_bar"]);
    assert_eq!(summary["metrics"]["unit"], "bar");
    let last = rows.last().unwrap();
    let pl = (last[at(&h, "p_a_Pa")] - ab / aa * last[at(&h, "p_b_Pa")]) / 1e5;
    assert!(
        (last[at(&h, "p_l_bar")] - pl).abs() <= 1e-9 * pl,
        "{pl} bar"
    );
    let held = mean_from(&rows, 2.0, &|r| r[at(&h, "p_l_bar")]);
    assert!((held - 50.0).abs() <= 0.05, "p_L held at {held} bar");
}
