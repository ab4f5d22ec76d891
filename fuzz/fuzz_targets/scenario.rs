//! Scenario text → parse, validate, analyse and (when small enough) run:
//! never a panic, never a hang, never a NaN in the metrics or the summary.
#![no_main]

use ehservo::run::{run, Keep};
use ehservo::scenario::Loop;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(s) = Loop::parse_with(&text, "fuzz.toml", &[]) {
        // The analysis is in every summary.json: it must end, whatever the values.
        let _ = ehservo::analysis::analyze(&s);
        if s.sim().steps * s.sim().substeps as u64 <= 2000 {
            let r = run(&s, Keep::Every(1));
            let m = r.metrics;
            for v in [m.e_max, m.e_final, m.e_rms, m.u_max, m.u_rms, m.chattering, m.w_norm_max] {
                assert!(v.is_none_or(f64::is_finite), "non-finite metric");
            }
            for smp in &r.trace {
                assert!(smp.u.is_finite() && smp.x.iter().all(|v| v.is_finite()));
                assert!(smp.values.iter().all(|v| v.is_finite()));
            }
            let json = serde_json::to_string(&ehservo::output::summary(&s, &r)).unwrap();
            assert!(!json.contains("NaN"));
        }
    }
});
