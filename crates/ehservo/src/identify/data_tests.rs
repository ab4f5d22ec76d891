//! Tests of `data.rs` (reading an experiment), apart from the code they test.

use super::*;

fn rows(n: usize, f: impl Fn(usize) -> String) -> String {
    (0..n).map(|k| f(k) + "\n").collect()
}

fn opts() -> ReadOptions {
    ReadOptions {
        tolerance: 0.05,
        min_rows: 4,
        window: None,
    }
}

/// A short header is quoted whole; 300 columns `c0 … c299` are quoted
/// by their first names within 120 characters and their count; one
/// name of 10 000 characters is cut.
#[test]
fn a_long_header_is_quoted_short() {
    assert_eq!(header_list(&["t_s", "u_V", "y_mm"]), "t_s, u_V, y_mm");
    let names: Vec<String> = (0..300).map(|k| format!("c{k}")).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let q = header_list(&names);
    // "c0, " … "c9, " is 40 characters, "c10, " … "c25" 16·5 − 2 = 78:
    // 118 in all; "c26" would make 123 > 120.
    assert_eq!(q, format!("{}, … (300 columns)", names[..26].join(", ")));
    let long = "x".repeat(10_000);
    let q = header_list(&[long.as_str(), "y"]);
    assert!(q.chars().count() < 150 && q.ends_with("(2 columns)"), "{q}");
    let q = header_list(&[long.as_str()]);
    assert!(q.ends_with("x, … (1 column)"), "{q}");
}

/// Degrees and millimetres are converted: 180° is π rad; bar is 1e5 Pa.
#[test]
fn units_come_from_the_suffixes() {
    let text = format!(
        "t_s,u_V,theta_deg,p_load_bar\n{}",
        rows(5, |k| format!(
            "{},{},{},{}",
            k as f64 * 0.01,
            k % 2,
            180 + k,
            2 + k
        ))
    );
    let e = parse(&text, "x.csv", &ColumnMap::default(), opts()).unwrap();
    assert_eq!(e.axis, Axis::Rotary);
    assert!((e.y.values[0] - std::f64::consts::PI).abs() < 1e-15);
    assert!((e.pressure.unwrap().values[0] - 2e5).abs() < 1e-9);
    assert!((e.h - 0.01).abs() < 1e-15);
    let text = format!(
        "t,u_V,y_mm\n{}",
        rows(5, |k| format!("{},{},{}", k, k % 2, 250 + k))
    );
    let e = parse(&text, "x.csv", &ColumnMap::default(), opts()).unwrap();
    assert_eq!(e.axis, Axis::Linear);
    assert!((e.y.values[0] - 0.25).abs() < 1e-15);
}

/// ehservo's trace.csv: the measured angle is preferred to the true one.
#[test]
fn a_trace_reads_its_measured_angle() {
    let text = format!(
        "t_s,theta_d_deg,theta_deg,e_deg,u_V,p_load_Pa,theta_meas_deg\n{}",
        rows(5, |k| format!(
            "{},0,1,0,{k},{k},{}",
            k as f64 * 0.001,
            2 + k
        ))
    );
    let e = parse(&text, "trace.csv", &ColumnMap::default(), opts()).unwrap();
    assert_eq!(e.y.column, "theta_meas_deg");
    assert_eq!(e.reference.as_ref().unwrap().column, "theta_d_deg");
    let none = ColumnMap {
        pressure: Some("none".into()),
        reference: Some("none".into()),
        ..Default::default()
    };
    let e = parse(&text, "trace.csv", &none, opts()).unwrap();
    assert!(e.pressure.is_none() && e.reference.is_none());
}

/// A Unix time stamp (1.7·10⁹ s) at 1 kHz keeps ulp = 1.7e9·2.2e-16 =
/// 3.8·10⁻⁷ s, 3.8·10⁻⁴ of a period: accepted; 10¹² s keeps 2.2·10⁻⁴ s,
/// 0.22 of a period: refused; 10⁻²⁰⁰ s and a subnormal period too.
#[test]
fn periods_the_fits_can_use() {
    assert!(check_period("f", "t_s", 1e-3, 1.7e9, 1.7e9 + 10.0).is_ok());
    let e = |h: f64, t0: f64| {
        check_period("f", "t_s", h, t0, t0 + 255.0 * h)
            .unwrap_err()
            .to_string()
    };
    assert!(e(1e-3, 1e12).contains("resolved to"));
    assert!(e(1e-200, 0.0).contains("outside"));
    assert!(e(1e-310, 0.0).contains("not a normal"));
    assert!(e(f64::INFINITY, 0.0).contains("not a normal"));
}

fn err(text: &str) -> String {
    parse(text, "d.csv", &ColumnMap::default(), opts())
        .unwrap_err()
        .to_string()
}

#[test]
fn bad_rows_are_named() {
    let head = "t_s,u_V,theta_rad\n";
    let e = err(&format!(
        "{head}0,0,0\n0.1,1,0\n0.1,0,0\n0.3,1,0\n0.4,0,0\n"
    ));
    assert!(
        e.contains("line 4 (row 3)") && e.contains("does not increase"),
        "{e}"
    );
    let e = err(&format!(
        "{head}0,0,0\n0.1,1,0\n0.2,NaN,0\n0.3,1,0\n0.4,0,0\n"
    ));
    assert!(
        e.contains("row 3") && e.contains("`u_V`") && e.contains("NaN"),
        "{e}"
    );
    let e = err(&format!(
        "{head}0,0,0\n0.1,1,0\n0.25,0,0\n0.3,1,0\n0.4,0,0\n"
    ));
    assert!(e.contains("row 3") && e.contains("non-uniform"), "{e}");
    let e = err(&format!("{head}0,1,0\n0.1,1,0\n0.2,1,0\n0.3,1,0\n"));
    assert!(e.contains("the command never moves"), "{e}");
    let e = err(&format!("{head}0,1,2\n0.1,0,2\n0.2,1,2\n0.3,0,2\n"));
    assert!(e.contains("the position never moves"), "{e}");
    let e = err(&format!("{head}0,1,0\n0.1,0,0\n"));
    assert!(e.contains("2 data rows"), "{e}");
    let e = err(&format!("{head}0,1,x\n"));
    assert!(
        e.contains("`x` is not a number") && e.contains("theta_rad"),
        "{e}"
    );
    let e = err("t_s,u_V,v\n0,1,2\n");
    assert!(e.contains("no position column"), "{e}");
    let e = err("0,0,0\n1,1,1\n");
    assert!(e.contains("not a header"), "{e}");
    // Times rounded to the printed digits stay within the tolerance.
    let t = format!(
        "{head}{}",
        rows(2048, |k| format!(
            "{:.4},{},{k}",
            3.0 * k as f64 / 2047.0,
            k % 2
        ))
    );
    assert!(parse(&t, "d.csv", &ColumnMap::default(), opts()).is_ok());
}
