//! The supply's datasheet parts held against the same components in small
//! Hopsan models run by HopsanCLI (tests/data/hopsan/supply-*.csv, their
//! models and command lines in tests/data/hopsan/SOURCE.md): a flow source
//! or the pressure-compensated pump into a 1 L line, with the part, and a
//! turbulent orifice to tank whose area steps from 1e-6 to 3e-6 m². ehservo
//! steps its supply's own two states (`Supply::deriv`, RK4 at Hopsan's
//! 1e-5 s, `Supply::limit_opening` after each step) with the orifice's flow
//! as the valve's draw. The tolerances are the measured differences
//! (docs/cylinder.md, "The supply's parts against Hopsan") with a margin.

use crate::common::repo;
use ehservo::analysis::step::read_columns;
use ehservo_sim::supply::{Supply, SupplyCfg};

/// Hopsan's orifice: C_q = 0.67, ρ = 870 kg/m³ (HydraulicTurbulentOrifice).
fn orifice(area: f64, dp: f64) -> f64 {
    0.67 * area * (2.0 * dp.max(0.0) / 870.0).sqrt()
}

struct Case {
    trace: &'static str,
    /// The second column: the relief's opening, ε, or the charge.
    second: &'static str,
    supply: &'static str,
    t_step: f64,
}

/// The relief of a datasheet: cracking at 200 bar, 215 bar at 35 L/min,
/// 90 % in 10 ms; a 35 L/min flow source (1 rev/s).
const RELIEF: &str = r#"
kind = "pump"
displacement = 5.833333333333333e-4
speed = 6.283185307179586
volume = 1e-3
bulk_modulus = 1e9
relief_pressure = 2e7
relief_full_flow_pressure = 2.15e7
relief_rated_flow = 5.833333333333333e-4
relief_response_time = 0.01
tank_pressure = 1e5
initial_pressure = 1e5
"#;

fn cases() -> [Case; 3] {
    [
        Case {
            trace: "supply-relief-datasheet.csv",
            second: "relief_xv",
            supply: RELIEF,
            t_step: 0.5,
        },
        Case {
            trace: "supply-pc-pump.csv",
            second: "eps",
            supply: r#"
kind = "pc-pump"
displacement = 28e-6
speed = 157.07963267948966
leakage = 1e-12
volume = 1e-3
bulk_modulus = 1e9
compensator_pressure = 2.1e7
compensator_band = 1e6
tank_pressure = 1e5
initial_pressure = 1e5
"#,
            t_step: 1.0,
        },
        Case {
            trace: "supply-accumulator.csv",
            second: "x_charge",
            supply: "",
            t_step: 1.5,
        },
    ]
}

/// ehservo's (t, p_s, second state) at Hopsan's sample times `ts`.
fn ours(s: &Supply, pt: f64, t_step: f64, ts: &[f64]) -> Vec<[f64; 2]> {
    let h = 1e-5;
    let mut x = [
        1e5,
        match s {
            Supply::PcPump(p) => p.y_max(1e5),
            _ => 0.0,
        },
    ];
    let mut out = Vec::with_capacity(ts.len());
    let mut k = 0usize;
    for &t in ts {
        let n = (t / h).round() as usize;
        while k < n {
            let area = |t: f64| if t < t_step { 1e-6 } else { 3e-6 };
            ehservo_core::rk4::rk4_step(
                |t, y: &[f64; 2], dy: &mut [f64; 2]| {
                    let q = orifice(area(t), y[0] - pt);
                    *dy = s.deriv(y[0], y[1], pt, q, 1.0, 1.0);
                },
                k as f64 * h,
                &mut x,
                h,
            );
            x[1] = s.limit_opening(x[0], x[1]);
            k += 1;
        }
        out.push(x);
    }
    out
}

/// The largest |Δp_s| (Pa) over the trace, and over its last 0.1 s.
fn compare(case: &Case) -> (f64, f64, Vec<[f64; 2]>, Vec<Vec<f64>>) {
    let p = repo().join("tests/data/hopsan").join(case.trace);
    let c = read_columns(&p, &["t_s", "p_s_Pa", case.second]).unwrap();
    let text = if case.supply.is_empty() {
        format!("{RELIEF}accumulator = {{ precharge = 1e7, volume = 1e-3, exponent = 1.4 }}\n")
    } else {
        case.supply.to_string()
    };
    let cfg: SupplyCfg = toml::from_str(&text).unwrap();
    let (s, pt) = Supply::try_new(&cfg, 1e9).unwrap();
    let o = ours(&s, pt, case.t_step, &c[0]);
    let t_end = c[0][c[0].len() - 1];
    let (mut all, mut end, mut at) = (0.0_f64, 0.0_f64, 0.0);
    for (i, x) in o.iter().enumerate() {
        let d = (x[0] - c[1][i]).abs();
        if d > all {
            (all, at) = (d, c[0][i]);
        }
        if c[0][i] >= t_end - 0.1 {
            end = end.max(d);
        }
    }
    eprintln!("{}: largest |Δp| at t = {at} s", case.trace);
    (all, end, o, c)
}

/// The datasheet relief: the steady pressures before and after the
/// orifice's step (211.3 and 203.9 bar in Hopsan) and the whole transient.
#[test]
fn the_datasheet_relief_agrees_with_hopsan() {
    let [case, _, _] = cases();
    let (all, end, o, c) = compare(&case);
    eprintln!("relief: max |Δp| {all:.4e} Pa, last 0.1 s {end:.4e} Pa");
    // Before the step (t = 0.45 s, sample 900): the opening too.
    let i = 900;
    assert!((c[0][i] - 0.45).abs() < 1e-9);
    let dx = (o[i][1] - c[2][i]).abs() / c[2][i];
    eprintln!(
        "relief: opening at 0.45 s {:.4e} vs {:.4e} ({dx:.2e})",
        o[i][1], c[2][i]
    );
    // Measured: 3.15 kPa over the transient (0.016 % of the cracking
    // pressure), 7 Pa at the end, the opening to 5e-7 of itself.
    assert!(end < 20.0, "{end}");
    assert!(all < 5e3, "{all}");
    assert!(dx < 1e-5, "{dx}");
}

/// The pressure-compensated pump: its start-up overshoot (Hopsan's
/// regulator is slow with its default l_p) and the steady pressures in
/// the band before and after the draw steps up.
#[test]
fn the_pc_pump_agrees_with_hopsan() {
    let [_, case, _] = cases();
    let (all, end, o, c) = compare(&case);
    eprintln!("pc-pump: max |Δp| {all:.4e} Pa, last 0.1 s {end:.4e} Pa");
    let n = c[0].len() - 1;
    eprintln!("pc-pump: end {:.6e} vs {:.6e}", o[n][0], c[1][n]);
    // The start-up alone (t < 1 s): the overshoot to 585 bar and its decay.
    let before = (0..n)
        .filter(|&i| c[0][i] < 1.0)
        .map(|i| (o[i][0] - c[1][i]).abs())
        .fold(0.0_f64, f64::max);
    eprintln!("pc-pump: max |Δp| before the step {before:.4e} Pa");
    // Measured: 5.4 bar in the start-up (overshoot to 585 bar), 14.3 bar
    // in the swing (99 to 284 bar) after the draw steps up at 1 s, 2 Pa
    // at the end.
    assert!(end < 10.0, "{end}");
    assert!(before < 8e5, "{before}");
    assert!(all < 2e6, "{all}");
    // The same with the control valve 100 times faster (τ_v = 1e-5 s in
    // both): the pole ehservo drops (g1 = l_pe·τ_v/d) moves out of the
    // way, and the difference falls tenfold, so it is that pole's.
    let fast = Case {
        trace: "supply-pc-pump-tauv1e-5.csv",
        supply: PC_FAST,
        ..case
    };
    let (all_fast, end_fast, _, _) = compare(&fast);
    eprintln!("pc-pump, τ_v = 1e-5: max |Δp| {all_fast:.4e} Pa, last 0.1 s {end_fast:.4e} Pa");
    assert!(all_fast < 0.1 * all, "{all_fast} vs {all}");
    assert!(end_fast < 10.0, "{end_fast}");
}

const PC_FAST: &str = r#"
kind = "pc-pump"
displacement = 28e-6
speed = 157.07963267948966
leakage = 1e-12
volume = 1e-3
bulk_modulus = 1e9
compensator_pressure = 2.1e7
compensator_band = 1e6
compensator_valve_time_constant = 1e-5
tank_pressure = 1e5
initial_pressure = 1e5
"#;

/// The accumulator: the line charges it from its precharge (100 bar) to
/// the relief's pressure; its state of charge against Hopsan's.
#[test]
fn the_accumulator_agrees_with_hopsan() {
    let [_, _, case] = cases();
    let (all, end, o, c) = compare(&case);
    eprintln!("accumulator: max |Δp| {all:.4e} Pa, last 0.1 s {end:.4e} Pa");
    let Supply::Pump(p) = Supply::try_new(
        &toml::from_str(&format!(
            "{RELIEF}accumulator = {{ precharge = 1e7, volume = 1e-3, exponent = 1.4 }}\n"
        ))
        .unwrap(),
        1e9,
    )
    .unwrap()
    .0
    else {
        unreachable!()
    };
    let acc = p.acc.unwrap();
    let mut dx = 0.0_f64;
    for (i, x) in o.iter().enumerate() {
        dx = dx.max((acc.oil_volume(x[0]) / 1e-3 - c[2][i]).abs());
    }
    eprintln!("accumulator: max |Δcharge| {dx:.4e}");
    // Measured: 4.55 kPa while it charges (Hopsan's inlet K_ca = 1e-7,
    // ehservo's lossless), 7 Pa at the end, the charge to 4.5e-5.
    assert!(end < 20.0, "{end}");
    assert!(all < 7e3, "{all}");
    assert!(dx < 1e-4, "{dx}");
}
