//! `identify` on a linear axis: the grey-box of the prior's cylinder
//! (identify/greybox_axis.rs) finds the axis that made the data, and
//! writes an identified scenario of it.
//!
//! The "machine" is the newcomer's slide (scenarios/cylinders/slide.toml)
//! with three values unlike its datasheet prior: βe = 1.1e9 Pa (prior
//! 8e8), the seals' viscous friction B = 3000 N·s/m (prior 2000) and the
//! valve's rated flow 1.5e-3 m³/s (prior 100 L/min = 1.667e-3). Its
//! experiment is `excite`'s closed-loop multisine, logged through the
//! slide's 1 µm position sensor (`y_meas_mm`).

use crate::common::{ehservo, rejected, repo, succeeded};
use std::path::Path;

const TRUTH: [(&str, &str, f64); 3] = [
    ("bulk_modulus", "plant.fluid.bulk_modulus", 1.1e9),
    ("viscous", "plant.cylinder.viscous", 3000.0),
    ("rated_flow", "plant.valve.rated_flow", 1.5e-3),
];

/// The slide's closed-loop experiment run on the "machine": its trace.
fn logged(dir: &Path) -> std::path::PathBuf {
    let slide = repo().join("scenarios/cylinders/slide.toml");
    let ex = dir.join("ex");
    let o = ehservo()
        .args(["excite", "--loop", "closed", "--duration", "4"])
        .args(["--period", "1000", "--amplitude", "0.01", "--prior"])
        .arg(&slide)
        .arg("--out")
        .arg(&ex)
        .output()
        .unwrap();
    succeeded("excite", &o);
    let mut run = ehservo();
    run.arg("run").arg(ex.join("scenario.toml"));
    for (_, path, v) in TRUTH {
        run.args(["--set", &format!("{path}={v:e}")]);
    }
    let o = run
        .args(["--no-plot", "-q", "--out"])
        .arg(dir.join("data"))
        .output()
        .unwrap();
    succeeded("run on the machine", &o);
    dir.join("data/trace.csv")
}

fn number(t: &toml::Value, path: &str) -> f64 {
    path.split('.')
        .fold(t, |v, k| &v[k])
        .as_float()
        .unwrap_or_else(|| panic!("{path} is not a float"))
}

#[test]
fn a_cylinders_grey_box_finds_the_axis_that_made_the_data() {
    let dir = tempfile::tempdir().unwrap();
    let trace = logged(dir.path());
    let out = dir.path().join("id");
    let slide = repo().join("scenarios/cylinders/slide.toml");
    let o = ehservo()
        .arg("identify")
        .arg(&trace)
        .args(["--output", "y_meas_mm", "--no-plot", "--prior"])
        .arg(&slide)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    succeeded("identify", &o);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("identify.json")).unwrap()).unwrap();
    let gb = &json["greybox"];
    assert_eq!(gb["fit"]["converged"], true, "{gb}");
    let est = |k: &str| {
        gb["fit"]["estimates"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["key"] == k)
            .unwrap_or_else(|| panic!("no estimate {k}"))
            .clone()
    };
    // Each estimate within 0.1 % of the machine's value, and the value
    // inside its 95 % interval: a sensor's 1 µm quantisation is the only
    // error in these data.
    for (k, _, truth) in TRUTH {
        let e = est(k);
        let v = e["value"].as_f64().unwrap();
        assert!((v / truth - 1.0).abs() < 1e-3, "{k}: {v} vs {truth}");
        let ci: Vec<f64> = serde_json::from_value(e["ci95"].clone()).unwrap();
        assert!(
            ci[0] <= truth && truth <= ci[1],
            "{k}: {truth} outside {ci:?}"
        );
        assert_eq!(e["status"], "free", "{k}");
    }
    // ω_h = √(βe·(A_A²/V_A + A_B²/V_B)/M) at the data's mean position, by
    // hand from the slide's drawing: A_A = π/4·0.063², A_B = A_A − π/4·0.045²,
    // V_A = 1.571e-4 + A_A·y, V_B = 1.571e-4 + A_B·(0.4 − y), M = 1200 kg.
    let text = std::fs::read_to_string(&trace).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = head.iter().position(|h| *h == "y_meas_mm").unwrap();
    let ys: Vec<f64> = lines
        .map(|l| l.split(',').nth(col).unwrap().parse::<f64>().unwrap() * 1e-3)
        .collect();
    let y = ys.iter().sum::<f64>() / ys.len() as f64;
    let aa = std::f64::consts::FRAC_PI_4 * 0.063f64.powi(2);
    let ab = aa - std::f64::consts::FRAC_PI_4 * 0.045f64.powi(2);
    let (va, vb) = (1.571e-4 + aa * y, 1.571e-4 + ab * (0.4 - y));
    let wh = (1.1e9 * (aa * aa / va + ab * ab / vb) / 1200.0).sqrt();
    let derived = gb["derived"]
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["key"] == "omega_h_rad_s")
        .unwrap()["value"]
        .as_f64()
        .unwrap();
    assert!((derived / wh - 1.0).abs() < 1e-3, "ω_h {derived} vs {wh}");
    // The identified scenario: the slide with the machine's values, valid
    // as `run` reads it, each fitted key's variation its interval's.
    let id: toml::Value =
        toml::from_str(&std::fs::read_to_string(out.join("identified.toml")).unwrap()).unwrap();
    for (_, path, truth) in TRUTH {
        let v = number(&id, path);
        assert!((v / truth - 1.0).abs() < 1e-3, "{path}: {v}");
    }
    let e = est("bulk_modulus");
    let hi = e["ci95"][1].as_f64().unwrap() / e["value"].as_f64().unwrap() - 1.0;
    let random = number(&id, "uncertainty.physical.bulk_modulus.random");
    assert!(
        random > 0.0 && (random - hi).abs() <= 1e-12,
        "{random} vs {hi}"
    );
    let mass = number(&id, "plant.load.mass");
    assert!((mass - 1200.0).abs() < 1e-9, "the mass is given: {mass}");
    let o = ehservo()
        .arg("check")
        .arg(out.join("identified.toml"))
        .output()
        .unwrap();
    succeeded("check identified.toml", &o);
}

#[test]
fn a_cylinders_grey_box_refuses_what_the_prior_cannot_start() {
    let dir = tempfile::tempdir().unwrap();
    let trace = logged(dir.path());
    let slide = repo().join("scenarios/cylinders/slide.toml");
    for (free, expect) in [
        (
            "bulk_modulus,leakage",
            "--free leakage: the prior sets no positive plant.cylinder.leakage",
        ),
        (
            "beta_e",
            "--free beta_e: no such grey-box parameter of a linear axis",
        ),
    ] {
        let out = dir.path().join(free);
        let o = ehservo()
            .arg("identify")
            .arg(&trace)
            .args(["--free", free, "--no-plot", "--prior"])
            .arg(&slide)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        rejected(free, &o, expect);
        assert!(!out.exists(), "{free}: nothing written");
    }
    // Linear data without a prior: the linear model alone, and a note.
    let out = dir.path().join("no-prior");
    let o = ehservo()
        .arg("identify")
        .arg(&trace)
        .args(["--no-plot", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    succeeded("identify without a prior", &o);
    assert!(!out.join("identified.toml").exists());
    let json = std::fs::read_to_string(out.join("identify.json")).unwrap();
    assert!(json.contains("without --prior: no grey-box"), "{json}");
}
