//! Study text (over the paper's Fig. 2 scenario as its base) → plan and,
//! when small, execute: never a panic, never a non-finite cell.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::io::Write;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("ehservo-fuzz-study-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/paper/fig2.toml");
    let path = dir.join("study.toml");
    let mut f = std::fs::File::create(&path).unwrap();
    writeln!(f, "base = {base:?}").unwrap();
    f.write_all(data).unwrap();
    drop(f);
    if let Ok(plan) = ehservo::study::Plan::load(&path) {
        let steps = plan.base.sim_config().steps * plan.base.simulation.substeps as u64;
        if plan.runs * steps <= 4000 {
            let bar = indicatif::ProgressBar::hidden();
            let rows = ehservo::study::execute(&plan, 0..plan.runs, Some(1), &bar).unwrap();
            let csv = ehservo::study::results_csv(&plan, &rows).unwrap();
            let text = String::from_utf8(csv).unwrap();
            assert!(!text.to_lowercase().contains("nan") && !text.contains("inf"), "{text}");
        }
    }
});
