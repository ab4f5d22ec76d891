//! # ehservo-web
//!
//! The engine of the browser playground (`web/`): ehservo's scenarios,
//! controller registry, simulator and metrics, compiled to WebAssembly and
//! exported through wasm-bindgen. Every export takes and returns JSON text
//! (the page parses it); the logic is plain Rust in [`playground`], tested
//! natively.
//!
//! | export | what |
//! |---|---|
//! | [`catalog`] | the embedded scenarios, every controller kind with its declared tunables and signals, the uncertainty keys |
//! | [`simulate`] | runs a set-up: metrics and the trace, or the complaints keyed by field |
//! | [`scenario_toml`] | the set-up as a scenario file for `ehservo run` |
//! | [`check`] | the complaints only |
//!
//! A set-up is a base scenario id and a JSON list of `[key, text]`
//! overrides, exactly the CLI's `--set key=text`.

pub mod playground;

use playground::FieldError;
use serde::Serialize;
use wasm_bindgen::prelude::wasm_bindgen;

fn json<T: Serialize>(v: &T) -> String {
    serde_json::to_string(v).unwrap_or_else(|e| {
        format!(r#"{{"ok":false,"errors":[{{"key":"","reason":"serialising: {e}"}}]}}"#)
    })
}

fn overrides(text: &str) -> Result<Vec<(String, String)>, Vec<FieldError>> {
    serde_json::from_str(text).map_err(|e| {
        vec![FieldError {
            key: String::new(),
            reason: format!("overrides must be a JSON list of [key, value] pairs: {e}"),
        }]
    })
}

#[derive(Serialize)]
#[serde(untagged)]
enum Reply<T> {
    Ok { ok: bool, value: T },
    Err { ok: bool, errors: Vec<FieldError> },
}

fn reply<T: Serialize>(r: Result<T, Vec<FieldError>>) -> String {
    json(&match r {
        Ok(value) => Reply::Ok { ok: true, value },
        Err(errors) => Reply::Err { ok: false, errors },
    })
}

/// The catalogue: `{scenarios, kinds, uncertainty}` ([`playground::Catalog`]).
#[wasm_bindgen]
pub fn catalog() -> String {
    json(&playground::catalog())
}

thread_local! {
    static TRACE: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// A run as the page receives it: everything but the trace's numbers,
/// which [`last_trace`] hands over as one `Float64Array` (formatting
/// thousands of floats as JSON text would cost more than the run).
#[derive(Serialize)]
struct RunReply {
    #[serde(flatten)]
    run: playground::RunOut,
    /// Samples per series in [`last_trace`].
    points: usize,
    /// The series of [`last_trace`], in order: `t`, `theta_d`, `theta`,
    /// `e`, `u`, then the signals' keys.
    series: Vec<&'static str>,
}

/// Runs scenario `id` with `overrides_json` (`[["controller.gamma1","200"],…]`):
/// `{ok: true, value: {name, kind, steps, metrics, divergence, trace: {signals}, points, series}}`
/// or `{ok: false, errors: [{key, reason}]}`. The trace's numbers are then
/// in [`last_trace`].
#[wasm_bindgen]
pub fn simulate(id: &str, overrides_json: &str) -> String {
    reply(
        overrides(overrides_json)
            .and_then(|o| playground::simulate(id, &o))
            .map(|mut run| {
                let t = std::mem::take(&mut run.trace);
                let points = t.t.len();
                let mut series = vec!["t", "theta_d", "theta", "e", "u"];
                let mut flat = Vec::with_capacity(points * (5 + t.signals.len()));
                for v in [t.t, t.theta_d, t.theta, t.e, t.u] {
                    flat.extend(v);
                }
                run.trace.signals = t
                    .signals
                    .into_iter()
                    .map(|mut s| {
                        series.push(s.info.key);
                        flat.extend(std::mem::take(&mut s.values));
                        s
                    })
                    .collect();
                TRACE.with(|c| *c.borrow_mut() = flat);
                RunReply {
                    run,
                    points,
                    series,
                }
            }),
    )
}

/// The trace of the last successful [`simulate`]: its series one after the
/// other, `points` values each.
#[wasm_bindgen]
pub fn last_trace() -> Vec<f64> {
    TRACE.with(|c| c.borrow().clone())
}

/// The set-up as a scenario file: `{ok: true, value: "…toml…"}` or the
/// complaints.
#[wasm_bindgen]
pub fn scenario_toml(id: &str, overrides_json: &str) -> String {
    reply(overrides(overrides_json).and_then(|o| playground::scenario_toml(id, &o)))
}

/// The complaints of a set-up (`{ok: true, value: null}` when none).
#[wasm_bindgen]
pub fn check(id: &str, overrides_json: &str) -> String {
    reply(overrides(overrides_json).and_then(|o| playground::resolve(id, &o).map(|_| ())))
}

/// The values scenario `id` gives every parameter of controller kind
/// `kind` and the uncertainty: `{ok: true, value: {key: number | null}}`.
#[wasm_bindgen]
pub fn base_values(id: &str, kind: &str) -> String {
    reply(playground::base_values(id, kind))
}
