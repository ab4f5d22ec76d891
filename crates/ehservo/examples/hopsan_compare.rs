//! ehservo's run of Hopsan's "Position Servo" beside Hopsan's own traces:
//! the figure and the tables of docs/cylinder.md.
//!
//! ```sh
//! cargo run --release -p ehservo --example hopsan_compare -- docs/cylinder
//! ```
//!
//! writes `hopsan-position-servo.png` and `.svg` into the folder and prints
//! the Markdown tables (step metrics, RMS differences) on standard output.

use anyhow::{Context, Result};
use ehservo::analysis::step::{difference, read_columns, step_metrics, StepMetrics};
use ehservo::plot::{Dash, Figure, Panel, Series};
use ehservo::run::{run, Keep};
use ehservo::scenario::Loop;
use std::path::{Path, PathBuf};

/// A trace: time (s), position (m), reference (m), spool (m), supply (Pa).
struct Trace {
    name: &'static str,
    t: Vec<f64>,
    y: Vec<f64>,
    r: Vec<f64>,
    spool: Vec<f64>,
    supply: Vec<f64>,
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn hopsan(name: &'static str, file: &str, pressure: bool) -> Result<Trace> {
    let p = repo().join("tests/data/hopsan").join(file);
    let mut cols = vec!["t_s", "position_m", "reference_m", "spool_xv_m"];
    if pressure {
        cols.push("p_s_Pa");
    }
    let c = read_columns(&p, &cols)?;
    Ok(Trace {
        name,
        t: c[0].clone(),
        y: c[1].clone(),
        r: c[2].clone(),
        spool: c[3].clone(),
        supply: c.get(4).cloned().unwrap_or_default(),
    })
}

fn ours(name: &'static str, set: &[&str]) -> Result<Trace> {
    let path = repo().join("scenarios/hopsan/position-servo.toml");
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let s = Loop::load(&path, &set)?;
    // The valve's gain: the spool in metres is Kv times the spool in volts.
    let kv = 0.01 / 10.0;
    let every = ((1e-4 / s.sim().step).round() as u32).max(1);
    let r = run(&s, Keep::Every(every));
    let sup = s
        .plant()
        .states()
        .iter()
        .position(|g| g.key == "p_supply")
        .context("the cylinder logs its supply pressure")?;
    Ok(Trace {
        name,
        t: r.trace.iter().map(|x| x.t).collect(),
        y: r.trace.iter().map(|x| x.x[0]).collect(),
        r: r.trace.iter().map(|x| x.z[0]).collect(),
        spool: r.trace.iter().map(|x| kv * x.spool).collect(),
        supply: r.trace.iter().map(|x| x.states[sup]).collect(),
    })
}

fn ms(v: Option<f64>) -> String {
    v.map_or("—".into(), |x| format!("{:.2}", 1e3 * x))
}

fn row(tr: &Trace, m: &StepMetrics) -> String {
    let (p, a) = m.oscillation.map_or(("—".into(), "—".into()), |(p, a)| {
        (format!("{:.2}", 1e3 * p), format!("{:.2}", 1e3 * a))
    });
    format!(
        "| {} | {} / {} / {} | {:.2} mm at {:.1} ms | {:.2} % | {} | {} ms, {} mm | {:+.2} mm |",
        tr.name,
        ms(m.rise[0]),
        ms(m.rise[1]),
        ms(m.rise[2]),
        1e3 * m.peak,
        1e3 * m.peak_time,
        m.overshoot_pct,
        m.settling
            .map_or("never".into(), |s| format!("{:.1} ms", 1e3 * s)),
        p,
        a,
        1e3 * m.offset
    )
}

fn main() -> Result<()> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "docs/cylinder".into()),
    );
    std::fs::create_dir_all(&out)?;
    let traces = [
        hopsan(
            "Hopsan, its validation trace (1e-4 s)",
            "position-servo.csv",
            false,
        )?,
        hopsan("Hopsan at 1e-6 s", "position-servo-dt1e-6.csv", true)?,
        ours(
            "ehservo, the shipped scenario (PI at 1e-4 s, RK4 at 10 µs)",
            &[],
        )?,
        ours(
            "ehservo, PI and RK4 at 1e-5 s",
            &["simulation.step=1e-5", "simulation.substeps=1"],
        )?,
    ];
    let metrics: Vec<Vec<StepMetrics>> = traces
        .iter()
        .map(|tr| step_metrics(&tr.t, &tr.y, &tr.r, &[1.0], true))
        .collect();
    for (s, title) in ["the start, 0 → 0.2 m", "the step 0.2 → 0.7 m at 1 s"]
        .iter()
        .enumerate()
    {
        println!("\nStep: {title}\n");
        println!("| trace | t10 / t50 / t90 (ms) | peak | overshoot | 2 % settling | sustained oscillation | mean offset |");
        println!("|---|---|---|---|---|---|---|");
        for (tr, m) in traces.iter().zip(&metrics) {
            println!("{}", row(tr, &m[s]));
        }
    }
    println!("\nPosition difference over 0–3 s (at the second trace's samples):\n");
    println!("| traces | RMS (mm) | max (mm) |");
    println!("|---|---:|---:|");
    // The continuous mode (no controller sampling at all) is in the table
    // only: on the figure it is the 1e-5 s run's line.
    let continuous = ours(
        "ehservo, continuous (the PI in every RK4 stage, 1e-5 s)",
        &["simulation.mode=continuous", "simulation.step=1e-5"],
    )?;
    let pairs = [(2, 0), (2, 1), (3, 1), (4, 1), (1, 0)];
    for (a, b) in pairs {
        let ta = if a == 4 { &continuous } else { &traces[a] };
        let (rms, max) = difference(&ta.t, &ta.y, &traces[b].t, &traces[b].y);
        println!(
            "| {} − {} | {:.3} | {:.3} |",
            ta.name,
            traces[b].name,
            1e3 * rms,
            1e3 * max
        );
    }
    let styles = [Dash::Dotted, Dash::Dashed, Dash::Solid, Dash::DashDot];
    type Pick<'a> = &'a dyn Fn(&Trace) -> (Vec<f64>, Vec<f64>);
    let lines = |f: Pick, scale: f64| -> Vec<Series> {
        traces
            .iter()
            .enumerate()
            .filter_map(|(i, tr)| {
                let (x, y) = f(tr);
                (!y.is_empty()).then(|| {
                    Series::new(tr.name, x, y.iter().map(|v| v * scale).collect(), i)
                        .dash(styles[i])
                })
            })
            .collect()
    };
    let pos = |tr: &Trace| (tr.t.clone(), tr.y.clone());
    let panel = |title: &str, y: &str, series: Vec<Series>, x: Option<(f64, f64)>| Panel {
        title: title.into(),
        x_label: "t (s)".into(),
        y_label: y.into(),
        series,
        x_range: x,
        ..Default::default()
    };
    let fig = Figure {
        title: "Hopsan's Position Servo: Hopsan's traces and ehservo's runs of the same model".into(),
        rows: 3,
        cols: 2,
        size: (1400, 1500),
        panels: vec![
            panel("(a) position y", "y (mm)", lines(&pos, 1e3), None),
            panel("(b) the step at 1 s", "y (mm)", lines(&pos, 1e3), Some((0.95, 1.35))),
            panel("(c) the start", "y (mm)", lines(&pos, 1e3), Some((0.0, 0.3))),
            panel("(d) the limit cycle at the end", "y (mm)", lines(&pos, 1e3), Some((2.8, 3.0))),
            panel(
                "(e) spool position",
                "x_v (mm)",
                lines(&|tr: &Trace| (tr.t.clone(), tr.spool.clone()), 1e3),
                Some((0.95, 1.35)),
            ),
            panel(
                "(f) supply pressure",
                "p_s (MPa)",
                lines(&|tr: &Trace| (tr.t.clone(), tr.supply.clone()), 1e-6),
                Some((0.95, 1.35)),
            ),
        ],
        footer: "Hopsan/hopsan@0c3995e, Models/Example Models/Position Servo.hmf; scenarios/hopsan/position-servo.toml".into(),
    };
    fig.png(&out.join("hopsan-position-servo.png"))?;
    fig.svg(&out.join("hopsan-position-servo.svg"))?;
    eprintln!("wrote {}/hopsan-position-servo.{{png,svg}}", out.display());
    Ok(())
}
