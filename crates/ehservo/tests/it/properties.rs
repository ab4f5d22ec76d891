//! Property tests over scenario input and the simulator (bounded run time:
//! they run in CI; `fuzz/` holds the cargo-fuzz targets for longer runs).

use ehservo::output::summary;
use ehservo::run::{run, Keep};
use ehservo::scenario::Loop;
use proptest::prelude::*;

const KEYS: [&str; 24] = [
    "simulation.horizon",
    "simulation.step",
    "simulation.substeps",
    "simulation.mode",
    "simulation.settle",
    "simulation.theta_limit",
    "plant.model",
    "plant.params.Jt",
    "plant.params.Ps",
    "plant.params.Kce",
    "load.amplitude",
    "load.friction.coulomb",
    "uncertainty.a_bias",
    "uncertainty.b_random",
    "uncertainty.seed",
    "reference.amplitude_deg",
    "surface.poles",
    "controller.kind",
    "controller.gamma1",
    "controller.eta",
    "controller.alpha_bar",
    "controller.rbf.width",
    "controller.nope",
    "nope",
];

fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        (-1e7f64..1e7).prop_map(|v| format!("{v}")),
        (-3i64..1_000_000).prop_map(|v| v.to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just("0".to_string()),
        Just("true".to_string()),
        Just("\"text\"".to_string()),
        Just("[-20, -30, -40]".to_string()),
        Just("[1, 2]".to_string()),
        Just("continuous".to_string()),
        Just("physical".to_string()),
        Just("vsc-sat".to_string()),
        Just("{ a = 1 }".to_string()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    /// Any combination of overrides either loads a valid scenario or is
    /// rejected with a key and a reason — never a panic; a valid one runs to
    /// a finite result (or a reported divergence).
    #[test]
    fn overrides_never_panic_and_valid_scenarios_run(
        sets in proptest::collection::vec((0..KEYS.len(), value()), 0..5),
    ) {
        let mut overrides: Vec<String> = sets.iter().map(|(k, v)| format!("{}={v}", KEYS[*k])).collect();
        // Keep runs short.
        overrides.insert(0, "simulation.horizon=0.5".into());
        overrides.insert(1, "simulation.settle=0.1".into());
        match Loop::parse_with("", "prop.toml", &overrides) {
            Err(e) => prop_assert!(!e.reason.to_string().is_empty()),
            Ok(s) => {
                let steps = s.sim().steps.saturating_mul(s.sim().substeps as u64);
                if steps <= 20_000 {
                    let r = run(&s, Keep::Every(1));
                    for smp in &r.trace {
                        prop_assert!(smp.u.is_finite() && smp.x.iter().all(|v| v.is_finite()));
                        prop_assert!(smp.values.iter().all(|v| v.is_finite()));
                    }
                    let json = serde_json::to_string(&summary(&s, &r)).unwrap();
                    prop_assert!(!json.contains("NaN"));
                }
            }
        }
    }
}

/// The same scenario and seed give the same summary, bit for bit, run
/// after run (the thread-count and shard cases are in tests/it/study.rs; the
/// release-vs-debug case is in .ci/run).
#[test]
fn summaries_are_deterministic() {
    let s = Loop::parse(
        "[uncertainty]\na_bias = 0.5\na_random = 0.5\nb_bias = 0.25\nb_random = 0.25\nseed = 9\n",
    )
    .unwrap();
    let a = serde_json::to_string(&summary(&s, &run(&s, Keep::Nothing))).unwrap();
    let b = serde_json::to_string(&summary(&s, &run(&s, Keep::Nothing))).unwrap();
    assert_eq!(a, b);
    // And a different seed gives a different result (the seed is used).
    let s2 = Loop::parse_with(
        &s.scenario().to_toml(),
        "x",
        &["uncertainty.seed=10".into()],
    )
    .unwrap();
    let c = serde_json::to_string(&summary(&s2, &run(&s2, Keep::Nothing))).unwrap();
    assert_ne!(a, c);
}

/// Parameters from 1e-300 to 1e300: the analysis overflows its matrices
/// there. Whatever the validator accepts must be analysed and run to an
/// end — not hang — within a bound proportional to its size: the
/// simulation's work is bounded at validation (steps × sub-steps, random
/// draws), and the analysis's iterations are bounded. Each case runs in a
/// thread with a generous 60 s deadline (a hang, not a slow machine, is
/// what this catches: a case takes milliseconds).
fn extreme() -> impl Strategy<Value = String> {
    (-300i32..300, prop::bool::ANY).prop_map(|(e, neg)| {
        let v = 10f64.powi(e);
        format!("{}", if neg { -v } else { v })
    })
}

const EXTREME_KEYS: [&str; 14] = [
    "plant.params.Jt",
    "plant.params.Dm",
    "plant.params.Vt",
    "plant.params.beta_e",
    "plant.params.Kv",
    "plant.params.Bm",
    "plant.params.G",
    "load.amplitude",
    "load.wavenumber",
    "controller.gamma1",
    "controller.alpha",
    "uncertainty.a_bias",
    "uncertainty.b_reference",
    "reference.frequency_hz",
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    #[test]
    fn accepted_scenarios_end_whatever_the_magnitudes(
        sets in proptest::collection::vec((0..EXTREME_KEYS.len(), extreme()), 1..4),
        poles in prop::option::of((-6i32..6).prop_map(|e| 10f64.powi(e))),
    ) {
        let mut overrides: Vec<String> =
            sets.iter().map(|(k, v)| format!("{}={v}", EXTREME_KEYS[*k])).collect();
        if let Some(a) = poles {
            overrides.push(format!("surface.poles=[{}, {}, {}]", -a, -2.0 * a, -3.0 * a));
        }
        overrides.push("simulation.horizon=0.2".into());
        overrides.push("simulation.settle=0.1".into());
        let Ok(s) = Loop::parse_with("", "prop.toml", &overrides) else {
            return Ok(());
        };
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let a = ehservo::analysis::analyze(&s);
            let r = run(&s, Keep::Every(1));
            let json = serde_json::to_string(&summary(&s, &r)).unwrap();
            tx.send((a.open_loop_poles, json)).ok();
        });
        let got = rx.recv_timeout(std::time::Duration::from_secs(60));
        prop_assert!(got.is_ok(), "no end within 60 s: {overrides:?}");
        let (_, json) = got.unwrap();
        prop_assert!(!json.contains("NaN"), "{json}");
        // Distinct poles are never called repeated, however slow or fast.
        if poles.is_some() {
            prop_assert!(!json.contains("repeated dominant pole"), "{json}");
        }
    }
}
