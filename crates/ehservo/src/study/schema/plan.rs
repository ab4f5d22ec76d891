//! The checks that turn a study file into a [`Plan`]: its size in checked
//! arithmetic against the run limit, its result columns, its axes against
//! the base scenario, and its Monte Carlo draws.

use super::*;

impl Plan {
    /// Reads and checks a study file (and its base scenario).
    pub fn load(path: &Path) -> Result<Plan, InputError> {
        let file = path.display().to_string();
        let study: Study = load_toml(path, "study")?;
        let base_path = path.parent().unwrap_or(Path::new(".")).join(&study.base);
        let base = crate::formats::load(&base_path, &study.set)
            .map_err(|e: ScenarioError| InputError::file(&file, format!("base: {e}")))?;
        Self::build(study, base, &file)
    }

    pub(in crate::study) fn build(
        study: Study,
        base: Loop,
        file: &str,
    ) -> Result<Plan, InputError> {
        let (replicates, runs) = size(&study, file)?;
        check_columns(&study, file)?;
        let axes = axes(&study, &base, file)?;
        check_draws(&study, &base, file)?;
        let base_table = base.table().ok();
        // The typed seed-only path must give what the round trip gives.
        let seed_only_typed = base_table.as_ref().is_some_and(|t| {
            base.scenario()
                .with_values_on(t.clone(), &[])
                .is_ok_and(|s| s == *base.scenario())
        });
        Ok(Plan {
            file: file.to_string(),
            study,
            base_table,
            seed_only_typed,
            base,
            axes,
            replicates,
            runs,
        })
    }
}

/// The error at `key` of study file `file`.
fn bad(file: &str, key: String, reason: impl Into<Reason>) -> InputError {
    InputError::key(file, key, reason)
}

/// The study's size, from the ranges alone: every axis's count and their
/// product with the replicates, in checked arithmetic, against the run
/// limit — before anything is expanded or allocated. The replicates and
/// the runs.
fn size(study: &Study, file: &str) -> Result<(u64, u64), InputError> {
    let bad = |key: String, reason: String| self::bad(file, key, reason);
    let mut counts = Vec::new();
    for (i, a) in study.axis.iter().enumerate() {
        if a.keys().is_empty() {
            return Err(bad(format!("axis[{i}]"), "needs `key` or `keys`".into()));
        }
        counts.push(
            a.count()
                .map_err(|r| bad(format!("axis[{i}].values"), r.to_string()))?,
        );
    }
    let replicates = match &study.monte_carlo {
        Some(mc) if mc.runs == 0 => {
            return Err(bad("monte_carlo.runs".into(), "must be ≥ 1".into()))
        }
        Some(mc) => u64::from(mc.runs),
        None => 1,
    };
    let within = |acc: u64, n: &u64| acc.checked_mul(*n).filter(|r| *r <= MAX_RUNS);
    let grid = counts.iter().try_fold(1u64, within);
    let Some(runs) = grid.and_then(|g| within(g, &replicates)) else {
        let mut shape: Vec<String> = Vec::new();
        if !counts.is_empty() {
            let c: Vec<String> = counts.iter().map(u64::to_string).collect();
            shape.push(format!("{} values", c.join(" × ")));
        }
        if study.monte_carlo.is_some() {
            shape.push(format!("{replicates} replicates"));
        }
        return Err(bad(
            if grid.is_some() {
                "monte_carlo.runs"
            } else {
                "axis"
            }
            .into(),
            format!(
                "{} is more than the limit of {MAX_RUNS} runs",
                shape.join(" × ")
            ),
        ));
    };
    Ok((replicates, runs))
}

/// Columns must be distinct and not those results.csv writes itself; a
/// key may be set by one axis or draw only (else one would silently
/// override the other).
fn check_columns(study: &Study, file: &str) -> Result<(), InputError> {
    let bad = |key: String, reason: String| self::bad(file, key, reason);
    let mut columns: Vec<String> = ["run", "seed", "error"]
        .iter()
        .chain(super::super::METRIC_COLUMNS.iter())
        .chain(crate::metrics::Metrics::CSV_LINEAR.iter())
        .chain(crate::behaviour::columns(crate::axis::Axis::Rotary).iter())
        .chain(crate::behaviour::columns(crate::axis::Axis::Linear).iter())
        .map(|c| c.to_string())
        .collect();
    let reserved = columns.len();
    let mut owners: Vec<(String, String)> = Vec::new();
    if study.monte_carlo.is_some() {
        owners.push((
            "uncertainty.seed".into(),
            "the run seed of a Monte Carlo study".into(),
        ));
    }
    let mut claim = |who: String, column: String, keys: Vec<String>| {
        if let Some(at) = columns.iter().position(|c| *c == column) {
            return Err(bad(
                who,
                if at < reserved {
                    format!("column `{column}` is one results.csv writes itself: give it another `name`")
                } else {
                    format!("column `{column}` appears twice")
                },
            ));
        }
        columns.push(column);
        for k in keys {
            let norm = k.split('.').map(str::trim).collect::<Vec<_>>().join(".");
            if let Some((_, owner)) = owners.iter().find(|(o, _)| *o == norm) {
                return Err(bad(who, format!("`{k}` is also set by {owner}")));
            }
            owners.push((norm, who.clone()));
        }
        Ok(())
    };
    for (i, a) in study.axis.iter().enumerate() {
        claim(format!("axis[{i}]"), a.column(), a.keys())?;
    }
    for (j, d) in study
        .monte_carlo
        .iter()
        .flat_map(|mc| mc.draw.iter())
        .enumerate()
    {
        claim(
            format!("monte_carlo.draw[{j}]"),
            d.key.clone(),
            vec![d.key.clone()],
        )?;
    }
    Ok(())
}

/// Each axis with its values: finite, and each giving a valid scenario
/// (first and last suffice for ranges; lists are checked whole).
fn axes(
    study: &Study,
    base: &Loop,
    file: &str,
) -> Result<Vec<(Axis, Vec<toml::Value>)>, InputError> {
    let mut axes = Vec::new();
    for (i, a) in study.axis.iter().enumerate() {
        let vals = a
            .expand()
            .map_err(|r| bad(file, format!("axis[{i}].values"), r))?;
        let probe: Vec<&toml::Value> = match a.values {
            AxisValues::List(_) => vals.iter().collect(),
            _ => vec![&vals[0], &vals[vals.len() - 1]],
        };
        for v in probe {
            let set: Vec<(String, toml::Value)> =
                a.keys().into_iter().map(|k| (k, v.clone())).collect();
            base.with_values(&set).map_err(|e| {
                bad(
                    file,
                    format!("axis[{i}]"),
                    format!("value {}: {e}", show(v)),
                )
            })?;
        }
        axes.push((a.clone(), vals));
    }
    Ok(axes)
}

/// The draws, like the axes: parameters that cannot overflow, and a key
/// the scenario knows (a typo would otherwise make every run invalid).
fn check_draws(study: &Study, base: &Loop, file: &str) -> Result<(), InputError> {
    for (j, d) in study
        .monte_carlo
        .iter()
        .flat_map(|mc| mc.draw.iter())
        .enumerate()
    {
        d.check()
            .map_err(|r| bad(file, format!("monte_carlo.draw[{j}]"), r))?;
        for v in d.probes() {
            base.with_values(&[(d.key.clone(), v.clone())])
                .map_err(|e| {
                    bad(
                        file,
                        format!("monte_carlo.draw[{j}]"),
                        format!("value {}: {e}", show(&v)),
                    )
                })?;
        }
    }
    Ok(())
}
