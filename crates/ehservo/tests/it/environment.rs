//! A cylinder against its environment, run by the binary (issue #49,
//! item 2): the environment's force is the trace's `f_env_N` column, right
//! after `f_stop_N`, on a cylinder that has one, and on no other.

use super::common::{ehservo, repo};

/// Runs `scenario` and returns the trace's header and rows.
fn trace(scenario: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let o = ehservo()
        .arg("run")
        .arg(repo().join(scenario))
        .args(["--no-plot", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// scenarios/force/specimen.toml: the slide (63/45 mm, B = 2000 N·s/m)
/// ends its step at 200 mm in a 2 MN/m specimen touched at 190 mm, so by
/// hand F_env = k·(y − x_c) = 2e6·0.010 = 20 000 N at rest; and the rod's
/// balance gives the same force from the pressures, A_A·p_A − A_B·p_B −
/// B·ẏ, with A_A = π/4·0.063² = 3.1172e-3 m², A_B = π/4·(0.063² − 0.045²)
/// = 1.5268e-3 m² (M·ÿ is nil at the end).
#[test]
fn the_specimen_force_is_a_trace_column_that_balances_the_pressures() {
    let (header, rows) = trace("scenarios/force/specimen.toml");
    let at = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no {name} in {header:?}"))
    };
    assert_eq!(at("f_env_N"), at("f_stop_N") + 1);
    let last = rows.last().unwrap();
    let (y, v) = (last[at("y_mm")] / 1e3, last[at("y_dot_mm_s")] / 1e3);
    let f = last[at("f_env_N")];
    assert!(
        (f - 2e6 * (y - 0.19)).abs() < 1e-6 * f,
        "F_env {f} N at y = {y} m"
    );
    assert!((f - 2e4).abs() < 0.01 * 2e4, "F_env {f} N, by hand 20 kN");
    let q = std::f64::consts::PI / 4.0;
    let (aa, ab) = (q * 0.063 * 0.063, q * (0.063 * 0.063 - 0.045 * 0.045));
    let hydraulic = aa * last[at("p_a_Pa")] - ab * last[at("p_b_Pa")] - 2000.0 * v;
    assert!(
        (f - hydraulic).abs() < 1e-3 * f,
        "F_env {f} N vs the pressures' {hydraulic} N"
    );
    // Never pulling, and nothing before contact: the rod starts at 180 mm.
    assert!(rows.iter().all(|r| r[at("f_env_N")] >= 0.0));
    // Exactly 0 out of contact: max(0, ·) is not reached, the branch returns 0.
    assert!(rows[0][at("f_env_N")].to_bits() == 0.0f64.to_bits());
}

/// Without an environment the column is not there: the cylinder's trace is
/// what it was.
#[test]
fn a_cylinder_without_an_environment_has_no_such_column() {
    let (header, _) = trace("scenarios/cylinders/slide.toml");
    assert!(!header.iter().any(|h| h == "f_env_N"), "{header:?}");
    assert_eq!(header.iter().filter(|h| h.starts_with("f_")).count(), 2);
}
