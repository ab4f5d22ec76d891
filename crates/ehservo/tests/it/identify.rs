//! `ehservo excite` and `ehservo identify` against known truth: ehservo's
//! own simulated experiments (a multisine, a chirp, a closed loop), logged
//! with a 16-bit encoder's quantisation and seeded sensor noise, identified
//! from their `trace.csv`; the truth is the scenario's parameters, through
//! (9) for the linear model's coefficients.
//!
//! The coverage over seeds (the true coefficients inside the stated 95 %
//! intervals in at least 90 % of seeds) runs on 40 seeds in CI
//! (`coverage_of_the_intervals`, at least 36 of 40 each).

use crate::common::ehservo;
use ehservo::core::servo::{Load, NominalModel, ServoParams};
use ehservo::identify::excite::{excite_to_dir, Loop, Phases, Signal, Spec};
use ehservo::identify::fit::Status;
use ehservo::identify::{identify, report, Options, Outcome};
use std::path::{Path, PathBuf};

/// A 16-bit encoder's step: 2π/65536 rad.
const ENCODER_16: f64 = 2.0 * std::f64::consts::PI / 65536.0;

/// The paper's servo with a linear valve: Ps raised to 10¹³ Pa and Ag
/// lowered by √(13.795e6/1e13) so that Kg, hence b, is the paper's while
/// P_l/Ps < 10⁻⁶ (the valve root's nonlinearity gone): the third-order
/// model is then exactly linear, and its (9) is the truth.
fn linear_valve() -> Vec<String> {
    let p = ServoParams::paper();
    vec![
        "plant.params.Ps=1e13".into(),
        format!("plant.params.Ag={:e}", p.ag * (p.ps / 1e13).sqrt()),
        "load.amplitude=0".into(),
    ]
}

/// The truth of [`linear_valve`]: (a1, a2, a3, b).
fn linear_truth() -> [f64; 4] {
    let mut p = ServoParams::paper();
    p.ag *= (p.ps / 1e13).sqrt();
    p.ps = 1e13;
    let c = p.coefficients();
    [
        c.a1,
        c.a2,
        c.a3,
        NominalModel::new(p, Load::none()).b_at_rest(),
    ]
}

fn multisine(duration: f64, amplitude: f64) -> Spec {
    Spec {
        signal: Signal::Multisine,
        loop_kind: Loop::Open,
        amplitude,
        f0: 0.5,
        f1: 40.0,
        duration,
        rate: 1000.0,
        period: 2048,
        phases: Phases::Crest,
        order: 10,
        clock: 5,
        hold: 0.5,
        seed: 1,
        kp: None,
    }
}

/// Designs, runs and logs an experiment: its trace.csv.
fn experiment(dir: &Path, name: &str, spec: &Spec, set: &[String]) -> PathBuf {
    let ex = dir.join(format!("{name}-excite"));
    excite_to_dir(spec, None, set, &ex).unwrap();
    let s = ehservo::scenario::Loop::load(&ex.join("scenario.toml"), &[]).unwrap();
    let run = dir.join(format!("{name}-run"));
    ehservo::output::run_to_dir(&run, &s, false).unwrap();
    run.join("trace.csv")
}

/// The sensor: a 16-bit encoder and white noise of `sd` rad, seeded.
fn sensor(sd: f64, seed: u64) -> Vec<String> {
    vec![
        format!("sensor.resolution=[{ENCODER_16:e},0,0]"),
        format!("sensor.noise=[{sd:e},0,0]"),
        format!("sensor.seed={seed}"),
    ]
}

fn options(files: Vec<PathBuf>, set: Vec<String>) -> Options {
    Options {
        files,
        set,
        lags: 25,
        map: ehservo::identify::data::ColumnMap {
            pressure: Some("none".into()),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The linear model's (a2, a3, b) against the truth: inside the 95 %
/// interval (when `ci`) and within `rel`.
fn check_linear(o: &Outcome, truth: [f64; 4], rel: f64, ci: bool) {
    for (key, t) in [("a2", truth[1]), ("a3", truth[2]), ("b", truth[3])] {
        let e = o.linear.fit.get(key).unwrap();
        assert_eq!(e.status, Status::Free, "{key}");
        assert!(
            (e.value / t - 1.0).abs() < rel,
            "{key}: {} vs {t} (within {rel})",
            e.value
        );
        if ci {
            let [lo, hi] = e.ci95.unwrap();
            assert!(lo <= t && t <= hi, "{key}: {t} outside [{lo}, {hi}]");
        }
    }
}

/// Open loop, 16-bit encoder: a2, a3, b within 2 % and their intervals;
/// a1 (0.4 s⁻³: the spring G = 1.13·10⁻³ N·m/rad) is fitted, its 95 %
/// interval holding the truth; the validation chirp is
/// simulated within 5 % NRMSE.
#[test]
fn open_loop_linear_model_within_two_percent() {
    let dir = tempfile::tempdir().unwrap();
    let mut set = linear_valve();
    set.extend(sensor(0.0, 1));
    let est = experiment(dir.path(), "est", &multisine(8.0, 0.05), &set);
    let chirp = Spec {
        signal: Signal::Chirp,
        f0: 1.0,
        f1: 30.0,
        duration: 4.0,
        ..multisine(4.0, 0.04)
    };
    let val = experiment(dir.path(), "val", &chirp, &set);
    let mut opts = options(vec![est], linear_valve());
    opts.validate = vec![val];
    opts.no_greybox = true;
    let o = identify(&opts).unwrap();
    check_linear(&o, linear_truth(), 0.02, true);
    // a1 is free from a start on its own scale (a2·2π/T): what the data
    // say of it is its interval, which must hold the truth 0.4 s⁻³.
    let a1 = o.linear.fit.get("a1").unwrap();
    let ci = a1.ci95.expect("a1 free, with its interval");
    assert_eq!(a1.status, Status::Free);
    let t1 = linear_truth()[0];
    assert!(ci[0] <= t1 && t1 <= ci[1], "a1 = {} {ci:?}", a1.value);
    assert!(
        o.linear.estimation[0].nrmse_pct < 5.0,
        "{}",
        o.linear.estimation[0].nrmse_pct
    );
    assert!(
        o.linear.validation[0].nrmse_pct < 5.0,
        "{}",
        o.linear.validation[0].nrmse_pct
    );
    // The hydraulic pair: ω_n² ≈ a2 for the tiny a1.
    let wn = o.linear.derived("omega_n_rad_s").unwrap().value;
    assert!((wn / linear_truth()[1].sqrt() - 1.0).abs() < 0.02, "{wn}");
}

/// The factors of a prior wrong by ±30 %: βe, Kce, Bm, Kv (chosen so
/// that no two cancel in a2, a3 or b).
const WRONG: [(&str, f64); 4] = [("beta_e", 1.3), ("Kce", 0.7), ("Bm", 0.7), ("Kv", 1.3)];

/// `p` with [`WRONG`]'s factors applied (`mirror`: each 1 ± 0.3 turned
/// to 1 ∓ 0.3), and the same as `--set` keys.
fn wrong_prior(p: &ServoParams, mirror: bool) -> (ServoParams, Vec<String>) {
    let f = |i: usize| if mirror { 2.0 - WRONG[i].1 } else { WRONG[i].1 };
    let mut w = *p;
    w.beta_e *= f(0);
    w.kce *= f(1);
    w.bm *= f(2);
    w.kv *= f(3);
    let set = [w.beta_e, w.kce, w.bm, w.kv]
        .iter()
        .zip(WRONG)
        .map(|(v, (k, _))| format!("plant.params.{k}={v:e}"))
        .collect();
    (w, set)
}

/// The linear fit started from a prior whose coefficients are off by
/// 15–50 % (the prior's βe, Kce, Bm and Kv off by ±30 %): a2, a3, b still
/// land within 2 % of the truth and inside their 95 % intervals.
#[test]
fn linear_fit_from_a_wrong_prior() {
    let dir = tempfile::tempdir().unwrap();
    let mut set = linear_valve();
    set.extend(sensor(0.0, 11));
    let est = experiment(dir.path(), "est", &multisine(4.0, 0.05), &set);
    let mut truth_p = ServoParams::paper();
    truth_p.ag *= (truth_p.ps / 1e13).sqrt();
    truth_p.ps = 1e13;
    for mirror in [false, true] {
        let (wrong, wrong_set) = wrong_prior(&truth_p, mirror);
        let mut prior_set = linear_valve();
        prior_set.extend(wrong_set);
        // The prior really is off: its (a2, a3, b) against the truth's.
        let c = wrong.coefficients();
        let prior_coeffs = [
            c.a2,
            c.a3,
            NominalModel::new(wrong, Load::none()).b_at_rest(),
        ];
        let t = linear_truth();
        for (q, tv) in prior_coeffs.iter().zip([t[1], t[2], t[3]]) {
            assert!(
                (q / tv - 1.0).abs() > 0.1,
                "the prior is not wrong: {q} vs {tv}"
            );
        }
        let mut opts = options(vec![est.clone()], prior_set);
        opts.no_greybox = true;
        let o = identify(&opts).unwrap();
        check_linear(&o, t, 0.02, true);
    }
}

/// The grey-box fit started from a prior with βe, Kce, Bm and Kv off by
/// ±30 % ([`WRONG`]; Jt, the known inertia, and the load true): the paper's servo
/// with its load 2·sin 4θ, the physical plant, a 16-bit encoder and
/// 10⁻⁵ rad of noise. The four land within 3 % of the truth and inside
/// their 95 % intervals.
#[test]
fn greybox_fit_from_a_wrong_prior() {
    let dir = tempfile::tempdir().unwrap();
    let mut set = sensor(1e-5, 12);
    set.push("plant.model=physical".into());
    let est = experiment(dir.path(), "gb", &multisine(8.0, 0.05), &set);
    let truth = ServoParams::paper();
    for mirror in [false, true] {
        let mut prior_set = vec!["plant.model=physical".to_string()];
        prior_set.extend(wrong_prior(&truth, mirror).1);
        let mut opts = options(vec![est.clone()], prior_set);
        opts.free = Some(
            ["beta_e", "Kce", "Bm", "Kv"]
                .iter()
                .map(|s| s.to_string())
                .collect(),
        );
        let o = identify(&opts).unwrap();
        let g = o.greybox.as_ref().unwrap();
        for (key, t) in [
            ("beta_e", truth.beta_e),
            ("Kce", truth.kce),
            ("Bm", truth.bm),
            ("Kv", truth.kv),
        ] {
            let e = g.fit.get(key).unwrap();
            assert_eq!(e.status, Status::Free, "{key}");
            assert!(
                (e.value / t - 1.0).abs() < 0.03,
                "{key}: {} vs {t}",
                e.value
            );
            let [lo, hi] = e.ci95.unwrap();
            assert!(lo <= t && t <= hi, "{key}: {t} outside [{lo}, {hi}]");
        }
    }
}

/// Closed loop under u = kp·(r − θ): the reference excites, the indirect
/// estimate is made, and the direct output-error fit on the logged command
/// finds the plant within 2 % and its intervals.
#[test]
fn closed_loop_experiment() {
    let dir = tempfile::tempdir().unwrap();
    let mut set = linear_valve();
    set.extend(sensor(2e-5, 4));
    let spec = Spec {
        loop_kind: Loop::Closed,
        amplitude: 0.01,
        ..multisine(8.0, 0.01)
    };
    let est = experiment(dir.path(), "cl", &spec, &set);
    let mut opts = options(vec![est], linear_valve());
    opts.no_greybox = true;
    let o = identify(&opts).unwrap();
    assert!(
        o.frf[0].1.is_some(),
        "the indirect estimate from the reference"
    );
    check_linear(&o, linear_truth(), 0.02, true);
}

/// βe and Vt enter the model only as βe/Vt: with both free, one of them
/// is named unidentifiable and held at its prior, and the fit of the
/// other still reproduces the truth's ratio.
#[test]
fn an_unidentifiable_parameter_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let mut set = linear_valve();
    set.extend(sensor(0.0, 2));
    let est = experiment(dir.path(), "u", &multisine(4.0, 0.05), &set);
    let mut opts = options(vec![est], linear_valve());
    opts.free = Some(vec!["beta_e".into(), "Vt".into(), "Bm".into(), "Kv".into()]);
    opts.fix = vec![("Jt".into(), ServoParams::paper().jt)];
    let o = identify(&opts).unwrap();
    let g = o.greybox.as_ref().unwrap();
    let (be, vt) = (g.fit.get("beta_e").unwrap(), g.fit.get("Vt").unwrap());
    let flagged = [be.status, vt.status]
        .iter()
        .filter(|s| **s == Status::Unidentifiable)
        .count();
    assert_eq!(flagged, 1, "{:?} {:?}", be.status, vt.status);
    let p = ServoParams::paper();
    let ratio = be.value / vt.value;
    assert!(
        (ratio / (p.beta_e / p.vt) - 1.0).abs() < 0.02,
        "βe/Vt = {ratio}"
    );
}

/// Without a load and with a linear valve, (θ, u) fix only the transfer
/// function's a2, a3 and b, not the four groups c1 = Bm/Jt, c4 = ω_h²,
/// c5 = 4βe·Kce/Vt and b behind them, nor the scale Jt (module doc of
/// `identify::greybox`): some of βe, Kce, Jt, Bm are named unidentifiable.
/// A load-pressure channel (P_l in Pa, with 10⁴ Pa of noise) fixes them
/// all: none unidentifiable, Jt inside its interval.
#[test]
fn a_pressure_channel_makes_jt_identifiable() {
    let dir = tempfile::tempdir().unwrap();
    let mut set = linear_valve();
    set.extend(sensor(0.0, 3));
    set.push("plant.model=physical".into());
    let est = experiment(dir.path(), "p", &multisine(4.0, 0.05), &set);
    let free: Vec<String> = ["beta_e", "Kce", "Jt", "Bm", "Kv"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut opts = options(vec![est.clone()], linear_valve());
    opts.free = Some(free.clone());
    let o = identify(&opts).unwrap();
    let g = o.greybox.as_ref().unwrap();
    let unid: Vec<&str> = g
        .fit
        .estimates
        .iter()
        .filter(|e| e.status == Status::Unidentifiable)
        .map(|e| e.key.as_str())
        .collect();
    assert!(!unid.is_empty(), "{unid:?}");
    assert!(
        unid.iter()
            .all(|k| ["beta_e", "Kce", "Jt", "Bm"].contains(k)),
        "{unid:?}"
    );
    // The pressure, logged with seeded noise.
    let text = std::fs::read_to_string(&est).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let pc = head.iter().position(|h| *h == "p_load_Pa").unwrap();
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(9);
    let mut out = head.join(",") + "\n";
    for l in lines {
        let mut f: Vec<String> = l.split(',').map(String::from).collect();
        let p: f64 = f[pc].parse().unwrap();
        f[pc] = format!("{}", p + 1e4 * ehservo::identify::normal(&mut rng));
        out.push_str(&f.join(","));
        out.push('\n');
    }
    let with_p = dir.path().join("with-pressure.csv");
    std::fs::write(&with_p, out).unwrap();
    let mut opts = options(vec![with_p], linear_valve());
    opts.map.pressure = None;
    opts.free = Some(free);
    let o = identify(&opts).unwrap();
    let g = o.greybox.as_ref().unwrap();
    for e in g.fit.estimates.iter().filter(|e| !e.nuisance) {
        assert_ne!(e.status, Status::Unidentifiable, "{}", e.key);
    }
    let jt = g.fit.get("Jt").unwrap();
    let [lo, hi] = jt.ci95.unwrap();
    let t = ServoParams::paper().jt;
    assert!(
        lo <= t && t <= hi,
        "Jt {t} outside [{lo}, {hi}] ({})",
        jt.value
    );
}

/// One seed of the coverage experiment: whether each of a2, a3, b is
/// inside its 95 % interval.
fn covered(dir: &Path, seed: u64) -> [bool; 3] {
    let mut set = linear_valve();
    set.extend(sensor(3e-5, seed));
    let est = experiment(dir, &format!("s{seed}"), &multisine(4.0, 0.05), &set);
    let mut opts = options(vec![est], linear_valve());
    opts.no_greybox = true;
    let o = identify(&opts).unwrap();
    let t = linear_truth();
    let inside = |key: &str, v: f64| {
        let [lo, hi] = o.linear.fit.get(key).unwrap().ci95.unwrap();
        lo <= v && v <= hi
    };
    [inside("a2", t[1]), inside("a3", t[2]), inside("b", t[3])]
}

fn coverage(seeds: u64) -> [usize; 3] {
    let dir = tempfile::tempdir().unwrap();
    let mut n = [0usize; 3];
    for seed in 0..seeds {
        let c = covered(dir.path(), 100 + seed);
        for i in 0..3 {
            n[i] += c[i] as usize;
        }
    }
    n
}

/// The claim, tested in CI: over 40 seeds each coefficient's 95 %
/// interval covers the truth in at least 36 (90 %).
#[test]
fn coverage_of_the_intervals() {
    let n = coverage(40);
    assert!(n.iter().all(|&c| c >= 36), "covered {n:?} of 40");
}

/// Two experiments at different amplitudes: each fitted alone, the spread
/// of their coefficients gives bound_a and bound_b, written into the
/// identified scenario, which runs.
#[test]
fn two_experiments_give_the_bounds_and_a_scenario_that_runs() {
    let dir = tempfile::tempdir().unwrap();
    let mut set = sensor(1e-5, 5);
    set.push("load.amplitude=0".into());
    let a = experiment(dir.path(), "a", &multisine(3.0, 0.03), &set);
    let b = experiment(dir.path(), "b", &multisine(3.0, 0.08), &set);
    let mut opts = options(vec![a, b], vec!["load.amplitude=0".into()]);
    opts.free = Some(vec!["beta_e".into(), "Bm".into(), "Kv".into()]);
    let o = identify(&opts).unwrap();
    let bounds = o.bounds.as_ref().expect("bounds from two experiments");
    assert_eq!(bounds.samples.len(), 2);
    assert!(
        bounds.bound_b > 0.0 && bounds.bound_b < 0.5,
        "{}",
        bounds.bound_b
    );
    assert!(
        bounds.bound_a > 0.0 && bounds.bound_a < 0.5,
        "{}",
        bounds.bound_a
    );
    let out = dir.path().join("id");
    report::write(&o, &opts, &out, false).unwrap();
    let s = ehservo::scenario::Loop::load(&out.join("identified.toml"), &[]).unwrap();
    let c = s.controller().to_table();
    let ba = c.get("bound_a").and_then(|v| v.as_float()).unwrap();
    assert!(
        (ba - bounds.bound_a).abs() <= 1e-5 * bounds.bound_a.max(1e-9) + 1e-12,
        "{ba}"
    );
    let r = ehservo::run::run(&s, ehservo::run::Keep::Every(1000));
    assert!(r.outcome.diverged.is_none());
    for f in ["identify.json", "frf.csv", "fit.csv"] {
        let text = std::fs::read_to_string(out.join(f)).unwrap();
        assert!(!text.contains("NaN") && !text.contains("inf"), "{f}");
    }
}

/// Bad data: exit 2, one line naming the file, the row and the column,
/// and nothing written.
#[test]
fn bad_data_is_refused_whole() {
    let dir = tempfile::tempdir().unwrap();
    let good = |k: usize| {
        format!(
            "{},{},{}\n",
            k as f64 * 0.001,
            (k % 7) as f64 * 0.01,
            1e-4 * k as f64
        )
    };
    let rows = |f: &dyn Fn(usize) -> String| -> String {
        std::iter::once("t_s,u_V,theta_rad\n".to_string())
            .chain((0..200).map(f))
            .collect()
    };
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "time.csv",
            rows(&|k| {
                if k == 50 {
                    "0.001,0,0\n".into()
                } else {
                    good(k)
                }
            }),
            "row 51), column `t_s`: time does not increase",
        ),
        (
            "nan.csv",
            rows(&|k| {
                if k == 10 {
                    "0.01,NaN,0\n".into()
                } else {
                    good(k)
                }
            }),
            "row 11), column `u_V`: NaN",
        ),
        (
            "grid.csv",
            rows(&|k| {
                if k == 30 {
                    format!("{},0,0\n", 0.0304)
                } else {
                    good(k)
                }
            }),
            "row 31), column `t_s`: non-uniform",
        ),
        (
            "few.csv",
            "t_s,u_V,theta_rad\n0,0,0\n0.001,1,0\n".into(),
            "2 data rows",
        ),
        (
            "still.csv",
            rows(&|k| format!("{},0.5,0\n", k as f64 * 0.001)),
            "never moves",
        ),
    ];
    for (name, text, expect) in cases {
        let f = dir.path().join(name);
        std::fs::write(&f, text).unwrap();
        let out = dir.path().join(format!("out-{name}"));
        let o = ehservo()
            .arg("identify")
            .arg(&f)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        crate::common::rejected_naming(name, &o, expect);
        assert!(!out.exists(), "{name}: nothing written");
    }
    // A window (--from, --to) that keeps too few rows, and one that is empty
    // by its bounds.
    let f = dir.path().join("window.csv");
    std::fs::write(&f, rows(&good)).unwrap();
    for (args, expect) in [
        (["--from", "0.15", "--to", "0.17"], "keeps 21 rows of 200"),
        (["--from", "0.2", "--to", "0.1"], "from < to"),
    ] {
        let out = dir.path().join("out-window");
        let o = ehservo()
            .arg("identify")
            .arg(&f)
            .args(args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        crate::common::rejected("window", &o, expect);
        assert!(!out.exists(), "window: nothing written");
    }
    // An excitation band above Nyquist.
    let out = dir.path().join("ex");
    let o = ehservo()
        .args(["excite", "--rate", "100", "--f1", "60", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    crate::common::rejected("excite", &o, "Nyquist");
    assert!(!out.exists());
}

/// The CLI end to end: excite, run, identify; the outputs are there.
#[test]
fn excite_run_identify_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let ex = dir.path().join("ex");
    let o = ehservo()
        .args([
            "excite",
            "--signal",
            "prbs",
            "--loop",
            "closed",
            "--amplitude",
            "0.02",
            "--duration",
            "4",
            "--set",
            "load.amplitude=0",
            "--out",
        ])
        .arg(&ex)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run = dir.path().join("run");
    let o = ehservo()
        .arg("run")
        .arg(ex.join("scenario.toml"))
        .arg("--out")
        .arg(&run)
        .arg("--no-plot")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let id = dir.path().join("id");
    let o = ehservo()
        .arg("identify")
        .arg(run.join("trace.csv"))
        .args(["--set", "load.amplitude=0", "--no-greybox", "--out"])
        .arg(&id)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "identify.json",
        "frf.csv",
        "fit.csv",
        "frf.png",
        "fit.svg",
        "residuals.png",
    ] {
        assert!(id.join(f).is_file(), "{f}");
    }
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(id.join("identify.json")).unwrap()).unwrap();
    let b = j["linear"]["fit"]["estimates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["key"] == "b")
        .unwrap();
    let truth = NominalModel::new(ServoParams::paper(), Load::none()).b_at_rest();
    assert!(
        (b["value"].as_f64().unwrap() / truth - 1.0).abs() < 0.05,
        "{b}"
    );
}

/// ω_h(x) = √(βe·(A_A²/V_A + A_B²/V_B)/M) of the cylinder in `scenario`
/// (its [plant.cylinder], [plant.fluid] and [plant.load] tables read
/// directly), V_A = V0_A + A_A·x, V_B = V0_B + A_B·(stroke − x):
/// docs/hopsan/position-servo.md, "Hydraulic natural frequency".
fn omega_h_of(scenario: &Path) -> impl Fn(f64) -> f64 {
    let t: toml::Table = std::fs::read_to_string(scenario).unwrap().parse().unwrap();
    let plant = &t["plant"];
    let f = |table: &str, key: &str| plant[table][key].as_float().unwrap();
    let (aa, ab, s) = (
        f("cylinder", "area_a"),
        f("cylinder", "area_b"),
        f("cylinder", "stroke"),
    );
    let (va, vb) = (
        f("cylinder", "dead_volume_a"),
        f("cylinder", "dead_volume_b"),
    );
    let (beta, m) = (f("fluid", "bulk_modulus"), f("load", "mass"));
    move |x| (beta * (aa * aa / (va + aa * x) + ab * ab / (vb + ab * (s - x))) / m).sqrt()
}

/// Hopsan's Position Servo from its validation trace, by the command of
/// docs/identification.md ("Hopsan's Position Servo"): the spool position
/// as input, the piston position as output, y⃛ + a3·ÿ + a2·ẏ = b·u (a1 = 0)
/// on the window from 1.2 s (after the step's pump-limited slew) to the
/// end. The identified ω_n is compared with ω_h computed from the model's
/// parameters (scenarios/hopsan/position-servo.toml): within 10 % of ω_h
/// at the window's mean position, and inside the range of ω_h over the
/// positions the trace visits. How fragile this is (the window's start
/// matters): the doc says.
#[test]
fn hopsan_position_servo_natural_frequency() {
    let repo = crate::common::repo();
    let data = repo.join("tests/data/hopsan/position-servo.csv");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("id");
    let from = 1.2;
    let o = ehservo()
        .current_dir(&repo)
        .arg("identify")
        .arg(&data)
        .args([
            "--time",
            "t_s",
            "--input",
            "spool_xv_m",
            "--output",
            "position_m",
            "--reference",
            "none",
            "--from",
            &from.to_string(),
            "--period-tolerance",
            "0.1",
            "--fix",
            "a1=0",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("identify.json")).unwrap()).unwrap();
    let wn = j["linear"]["derived"]
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["key"] == "omega_n_rad_s")
        .and_then(|d| d["value"].as_f64())
        .unwrap();
    // The positions: the whole trace's and the window's.
    let text = std::fs::read_to_string(&data).unwrap();
    let rows: Vec<(f64, f64)> = text
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            (f[0], f[1])
        })
        .collect();
    let window: Vec<f64> = rows.iter().filter(|r| r.0 >= from).map(|r| r.1).collect();
    let mean = window.iter().sum::<f64>() / window.len() as f64;
    let wh = omega_h_of(&repo.join("scenarios/hopsan/position-servo.toml"));
    let (lo, hi) = rows
        .iter()
        .map(|r| r.1)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    let range = (0..=100)
        .map(|i| wh(lo + (hi - lo) * i as f64 / 100.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), w| {
            (a.min(w), b.max(w))
        });
    assert!(
        (wn / wh(mean) - 1.0).abs() < 0.10,
        "ω_n {wn} rad/s against ω_h({mean} m) = {} rad/s",
        wh(mean)
    );
    assert!(
        range.0 <= wn && wn <= range.1,
        "ω_n {wn} rad/s outside ω_h over [{lo}, {hi}] m: {range:?}"
    );
}
