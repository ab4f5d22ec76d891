//! The league's tables, figures and pages.

use super::{League, LeagueResult};
use crate::output::escape::{self, md_cell};
use crate::plot::{Bars, Dash, Figure, Panel, Series};
use serde::Serialize;
use std::fmt::Write as _;

/// One controller on one scenario, over its draws.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Controller label.
    pub controller: String,
    /// Controller kind.
    pub kind: &'static str,
    /// "tuned", "tuned (defaults kept)" or "given".
    pub parameters: String,
    /// Scenario label.
    pub scenario: String,
    /// Runs (draws).
    pub draws: usize,
    /// Runs that diverged.
    pub unbounded: usize,
    /// Runs whose scenario refused the parameters.
    pub refused: usize,
    /// Runs that hit an end stop (bounded or not).
    pub hit_end_stop: usize,
    /// Runs whose error oscillates after the transient without decaying.
    pub oscillating: usize,
    /// Runs whose command sat at its limit in more than
    /// [`crate::behaviour::SATURATION_SHARE_LIMIT`] of the samples.
    pub saturated: usize,
    /// Worst e_max (°), when every run is bounded.
    pub e_max_worst_deg: Option<f64>,
    /// Mean e_max over the bounded runs (°).
    pub e_max_mean_deg: Option<f64>,
    /// Mean e_rms over the bounded runs (°).
    pub e_rms_mean_deg: Option<f64>,
    /// Mean chattering index over the bounded runs.
    pub chattering_mean: Option<f64>,
    /// Mean control energy over the bounded runs (V²·s).
    pub energy_mean_v2s: Option<f64>,
    /// Worst u_max over the bounded runs (V).
    pub u_max_worst_v: Option<f64>,
    /// The controller's margin, as text.
    pub margin: String,
    /// The controller's margin, as a number (the largest bounded x).
    pub margin_value: Option<f64>,
}

/// The errors' unit as the tables print it: ° or mm.
fn sym(l: &League) -> &'static str {
    l.axis.symbol_unit()
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn max(v: &[f64]) -> Option<f64> {
    v.iter().copied().reduce(f64::max)
}

/// The rows, controller-major.
pub fn rows(l: &League, r: &LeagueResult) -> Vec<Row> {
    let mut out = Vec::new();
    for (ci, s) in r.standings.iter().enumerate() {
        for (si, case) in l.cases.iter().enumerate() {
            let cells: Vec<_> = r
                .cells
                .iter()
                .filter(|c| c.controller == ci && c.scenario == si)
                .collect();
            let ok: Vec<_> = cells.iter().filter(|c| c.bounded()).collect();
            let metric = |f: &dyn Fn(&crate::metrics::Metrics) -> Option<f64>| -> Vec<f64> {
                ok.iter()
                    .filter_map(|c| c.metrics.as_ref().and_then(f))
                    .filter(|v| v.is_finite())
                    .collect()
            };
            let e_max = metric(&|m| m.e_max);
            let refused = cells.iter().filter(|c| c.refused.is_some()).count();
            let unbounded = cells.len() - ok.len() - refused;
            let findings: Vec<Vec<crate::behaviour::Finding>> = cells
                .iter()
                .filter_map(|c| c.metrics.map(|m| m.behaviour.findings(m.diverged)))
                .collect();
            let [_, hit_end_stop, oscillating, saturated] =
                crate::behaviour::tally(findings.iter().map(Vec::as_slice));
            let low = l.margin.as_ref().map(|m| m.cfg.low).unwrap_or(0.0);
            out.push(Row {
                controller: s.name.clone(),
                kind: s.kind,
                parameters: s.parameters.clone(),
                scenario: case.name.clone(),
                draws: cells.len(),
                unbounded,
                refused,
                hit_end_stop,
                oscillating,
                saturated,
                e_max_worst_deg: if ok.len() == cells.len() {
                    max(&e_max)
                } else {
                    None
                },
                e_max_mean_deg: mean(&e_max),
                e_rms_mean_deg: mean(&metric(&|m| m.e_rms)),
                chattering_mean: mean(&metric(&|m| m.chattering)),
                energy_mean_v2s: mean(&ok.iter().filter_map(|c| c.energy).collect::<Vec<_>>()),
                u_max_worst_v: max(&metric(&|m| m.u_max)),
                margin: s.margin.map(|m| m.text(low)).unwrap_or_default(),
                margin_value: s.margin.and_then(|m| m.value),
            });
        }
    }
    out
}

fn cell(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

fn csv_text(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// league.csv: a row per controller × scenario. Empty cells are
/// undefined (e_max_worst_deg is empty when a run diverged or was refused).
pub fn league_csv(l: &League, rows: &[Row]) -> String {
    let u = l.axis.unit();
    let mut s = format!(
        "controller,kind,parameters,scenario,draws,unbounded,refused,e_max_worst_{u},e_max_mean_{u},e_rms_mean_{u},chattering_mean,energy_mean_V2s,u_max_worst_V,margin,hit_end_stop,oscillating,saturated\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            csv_text(&r.controller),
            r.kind,
            csv_text(&r.parameters),
            csv_text(&r.scenario),
            r.draws,
            r.unbounded,
            r.refused,
            cell(r.e_max_worst_deg),
            cell(r.e_max_mean_deg),
            cell(r.e_rms_mean_deg),
            cell(r.chattering_mean),
            cell(r.energy_mean_v2s),
            cell(r.u_max_worst_v),
            csv_text(&r.margin),
            r.hit_end_stop,
            r.oscillating,
            r.saturated
        );
    }
    s
}

/// runs.csv: a row per run, with every metric and the scenario file that
/// reproduces it.
pub fn runs_csv(l: &League, r: &LeagueResult) -> String {
    let mut s = String::from("controller,scenario,draw,seed,set,file,refused,energy_V2s");
    for n in crate::metrics::Metrics::csv_names(l.axis) {
        s.push(',');
        s.push_str(n);
    }
    for n in crate::behaviour::columns(l.axis) {
        s.push(',');
        s.push_str(n);
    }
    s.push('\n');
    for c in &r.cells {
        let name = &r.standings[c.controller].name;
        let case = &l.cases[c.scenario].name;
        let _ = write!(
            s,
            "{},{},{},{},{},scenarios/{}/{}.toml,{},{}",
            csv_text(name),
            csv_text(case),
            c.draw,
            c.seed,
            csv_text(&super::param_box::point_text(
                l.cases[c.scenario].run(c.draw).1
            )),
            name,
            case,
            csv_text(c.refused.as_deref().unwrap_or("")),
            cell(c.energy)
        );
        for n in crate::metrics::Metrics::csv_names(l.axis) {
            s.push(',');
            if let Some(m) = &c.metrics {
                s.push_str(&m.cell(n));
            }
        }
        let cells = c.metrics.map(|m| m.behaviour.cells(m.diverged));
        for k in 0..crate::behaviour::columns(l.axis).len() {
            s.push(',');
            if let Some(cs) = &cells {
                s.push_str(&cs[k]);
            }
        }
        s.push('\n');
    }
    s
}

/// Each controller's rank on each scenario by worst e_max (1 = best;
/// unbounded or refused last), and the mean over scenarios, in standings
/// order.
pub fn ranks(l: &League, rows: &[Row]) -> Vec<(Vec<usize>, f64)> {
    let nc = rows.len() / l.cases.len().max(1);
    let ns = l.cases.len();
    let key = |ci: usize, si: usize| rows[ci * ns + si].e_max_worst_deg.unwrap_or(f64::INFINITY);
    let per: Vec<Vec<usize>> = (0..nc)
        .map(|ci| {
            (0..ns)
                .map(|si| 1 + (0..nc).filter(|&o| key(o, si) < key(ci, si)).count())
                .collect()
        })
        .collect();
    per.into_iter()
        .map(|r| {
            let m = r.iter().sum::<usize>() as f64 / ns.max(1) as f64;
            (r, m)
        })
        .collect()
}

/// Controller indices, best mean rank first (ties: the suite's order).
fn order(l: &League, rows: &[Row]) -> Vec<usize> {
    let rk = ranks(l, rows);
    let mut idx: Vec<usize> = (0..rk.len()).collect();
    idx.sort_by(|&a, &b| rk[a].1.total_cmp(&rk[b].1).then(a.cmp(&b)));
    idx
}

fn num(v: Option<f64>) -> String {
    match v {
        None => "—".into(),
        Some(0.0) => "0".into(),
        Some(x) if x.abs() >= 1e4 || x.abs() < 1e-3 => format!("{x:.3e}"),
        Some(x) => format!("{x:.4}"),
    }
}

fn worst(r: &Row) -> String {
    match r.e_max_worst_deg {
        Some(v) => num(Some(v)),
        None if r.refused > 0 => format!("refused ({}/{})", r.refused, r.draws),
        None => format!("unbounded ({}/{})", r.unbounded, r.draws),
    }
}

/// The tuned or given values of a controller, as text.
fn params_text(l: &League, r: &LeagueResult, ci: usize) -> String {
    let s = &r.standings[ci];
    match &s.tune {
        Some(t) if !t.kept_defaults => t
            .params
            .iter()
            .map(|(k, v)| format!("{k} = {}", num(Some(*v))))
            .collect::<Vec<_>>()
            .join(", "),
        Some(_) => "the kind's defaults (the tune found nothing better)".into(),
        None => {
            let given = &l.file.controller[ci].params;
            if given.is_empty() {
                "the kind's defaults".into()
            } else {
                given
                    .iter()
                    .map(|(k, v)| format!("{k} = {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        }
    }
}

/// What the report says of the set-up, as (heading, lines) pairs shared by
/// the Markdown and the HTML.
fn setup_lines(l: &League) -> Vec<String> {
    let sym = sym(l);
    let mut v = Vec::new();
    if let Some(t) = &l.file.tuning {
        v.push(format!(
            "Tuning budget (every tuned controller): {} evaluations of argmin's particle swarm ({} particles, seed {}), objective the {} score over {} × {} draw(s), score = e_max after the transient ({}){}{}, each kind's declared tunable parameters and ranges.",
            t.budget,
            t.particles,
            t.seed,
            match t.objective {
                crate::tune::Objective::Mean => "mean",
                crate::tune::Objective::Worst => "worst",
            },
            t.scenarios
                .iter()
                .map(|p| format!("`{}`", p.display()))
                .collect::<Vec<_>>()
                .join(", "),
            t.draws,
            sym,
            t.penalty
                .u_limit
                .map(|u| format!(" + {}{sym}/V of u_max beyond ±{u} V", t.penalty.u_excess))
                .unwrap_or_default(),
            if t.penalty.chattering > 0.0 {
                format!(" + {}·chattering", t.penalty.chattering)
            } else {
                String::new()
            }
        ));
    }
    for c in &l.cases {
        let draws = match (c.seeds.len(), c.seeds[0]) {
            (1, None) => format!("its own seed ({})", c.scenario.scenario().uncertainty.seed),
            (1, Some(s)) => format!("seed {s}"),
            (n, Some(s)) => format!("{n} draws, seeds {s}–{}", s + n as u64 - 1),
            (n, None) => format!("{n} draws"),
        };
        let points = c.points.len();
        let draws = if points > 1 || !c.points[0].is_empty() {
            let keys: Vec<&str> = c.points[0].iter().map(|(k, _)| k.as_str()).collect();
            format!(
                "{draws}, each at {points} points of the box of {} (its corners and draws inside; the worst counts)",
                keys.join(", ")
            )
        } else {
            draws
        };
        v.push(format!(
            "Scenario `{}`: {} — {}.",
            c.name,
            if c.scenario.scenario().description.is_empty() {
                c.scenario.name().to_string()
            } else {
                c.scenario.scenario().description.clone()
            },
            draws
        ));
    }
    if let Some(m) = &l.margin {
        v.push(format!(
            "Robustness margin: the largest x in [{}, {}] with {} = {}x on `{}` that stays bounded{} (bisection to {}; one boundary assumed).",
            m.cfg.low,
            m.cfg.high,
            m.cfg.keys.join(" = "),
            match m.cfg.scale {
                1.0 => String::new(),
                -1.0 => "−".to_string(),
                k => format!("{k}·"),
            },
            m.cfg.scenario.display(),
            m.cfg
                .e_limit()
                .map(|e| format!(" with e_max ≤ {e}{}", l.axis.suffix()))
                .unwrap_or_default(),
            m.cfg.tolerance
        ));
    }
    v
}

/// A table of the report, rendered to Markdown or HTML alike.
struct Table {
    head: Vec<String>,
    /// Cells: text and an HTML attribute (e.g. ` class="best"`; Markdown
    /// has none).
    rows: Vec<Vec<(String, &'static str)>>,
}

impl Table {
    fn markdown(&self) -> String {
        let mut s = String::from("|");
        for h in &self.head {
            let _ = write!(s, " {} |", md_cell(h));
        }
        s.push_str("\n|");
        s.push_str(&"---|".repeat(self.head.len()));
        s.push('\n');
        for row in &self.rows {
            s.push('|');
            for (c, _) in row {
                let _ = write!(s, " {} |", md_cell(c));
            }
            s.push('\n');
        }
        s
    }

    fn html(&self) -> String {
        let mut s = String::from("<table><tr>");
        for h in &self.head {
            let _ = write!(s, "<th>{}</th>", escape::html(h));
        }
        s.push_str("</tr>\n");
        for row in &self.rows {
            s.push_str("<tr>");
            for (c, attr) in row {
                let _ = write!(s, "<td{attr}>{}</td>", escape::html(c));
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</table>\n");
        s
    }
}

/// Worst e_max per scenario, the mean rank and the margin, best first; the
/// best of each scenario and the unbounded marked (for HTML).
fn standings_table(l: &League, r: &LeagueResult, rows: &[Row]) -> Table {
    let ns = l.cases.len();
    let rk = ranks(l, rows);
    let mut head: Vec<String> = ["controller", "kind", "parameters"]
        .map(String::from)
        .to_vec();
    head.extend(l.cases.iter().map(|c| c.name.clone()));
    head.push("mean rank".into());
    if l.margin.is_some() {
        head.push("margin".into());
    }
    let rows = order(l, rows)
        .into_iter()
        .map(|ci| {
            let st = &r.standings[ci];
            let mut cells = vec![
                (st.name.clone(), ""),
                (st.kind.to_string(), ""),
                (st.parameters.clone(), ""),
            ];
            for si in 0..ns {
                let row = &rows[ci * ns + si];
                let attr = if row.e_max_worst_deg.is_none() {
                    " class=\"bad\""
                } else if rk[ci].0[si] == 1 {
                    " class=\"best\""
                } else {
                    ""
                };
                cells.push((worst(row), attr));
            }
            cells.push((format!("{:.2}", rk[ci].1), ""));
            if l.margin.is_some() {
                cells.push((rows[ci * ns].margin.clone(), ""));
            }
            cells
        })
        .collect();
    Table { head, rows }
}

/// Each controller's parameters, best first.
fn params_table(l: &League, r: &LeagueResult, rows: &[Row]) -> Table {
    Table {
        head: vec!["controller".into(), "parameters".into()],
        rows: order(l, rows)
            .into_iter()
            .map(|ci| {
                vec![
                    (r.standings[ci].name.clone(), ""),
                    (params_text(l, r, ci), " style=\"text-align:left\""),
                ]
            })
            .collect(),
    }
}

/// Every metric of every controller on scenario `si`, best first.
fn scenario_table(l: &League, r: &LeagueResult, rows: &[Row], si: usize) -> Table {
    let ns = l.cases.len();
    let rk = ranks(l, rows);
    let mut idx: Vec<usize> = (0..r.standings.len()).collect();
    idx.sort_by_key(|&ci| rk[ci].0[si]);
    Table {
        head: [
            "controller",
            &format!("e_max worst ({})", sym(l)),
            &format!("e_max mean ({})", sym(l)),
            &format!("e_rms mean ({})", sym(l)),
            "chattering",
            "energy (V²·s)",
            "u_max worst (V)",
            "unbounded",
            "end stop / oscillating / saturated",
        ]
        .map(String::from)
        .to_vec(),
        rows: idx
            .into_iter()
            .map(|ci| {
                let row = &rows[ci * ns + si];
                [
                    row.controller.clone(),
                    worst(row),
                    num(row.e_max_mean_deg),
                    num(row.e_rms_mean_deg),
                    num(row.chattering_mean),
                    num(row.energy_mean_v2s),
                    num(row.u_max_worst_v),
                    format!("{}/{}", row.unbounded + row.refused, row.draws),
                    format!(
                        "{} / {} / {}",
                        row.hit_end_stop, row.oscillating, row.saturated
                    ),
                ]
                .map(|c| (c, ""))
                .to_vec()
            })
            .collect(),
    }
}

/// league.md.
pub fn markdown(l: &League, r: &LeagueResult, rows: &[Row], figures: bool) -> String {
    let mut s = format!("# League `{}`\n\n", l.file.name);
    if !l.file.description.is_empty() {
        let _ = writeln!(s, "{}\n", l.file.description);
    }
    let _ = writeln!(
        s,
        "Written by `ehservo league` ({} {}). Every number is re-made by that command; every run by `ehservo run scenarios/<controller>/<scenario>.toml` (other draws: `--set uncertainty.seed=S`, S in runs.csv).\n",
        crate::output::SOFTWARE.name,
        crate::output::SOFTWARE.version
    );
    s.push_str("## Set-up\n\n");
    for line in setup_lines(l) {
        let _ = writeln!(s, "- {line}");
    }
    s.push_str(&format!("\n## Standings\n\nWorst e_max after the transient ({}) on each scenario, over its draws; controllers ordered by their mean rank over the scenarios (1 = best; unbounded ranks last).\n\n", sym(l)));
    s.push_str(&standings_table(l, r, rows).markdown());
    s.push_str("\n## Parameters\n\n");
    s.push_str(&params_table(l, r, rows).markdown());
    for (si, c) in l.cases.iter().enumerate() {
        let _ = write!(s, "\n## Scenario `{}`\n\n", c.name);
        s.push_str(&scenario_table(l, r, rows, si).markdown());
    }
    if figures {
        s.push_str("\n## Figures\n\n![accuracy against chattering](pareto.svg)\n\n![worst e_max per scenario](bars.svg)\n");
    }
    s
}

/// league.html: the same tables, and the figures inline (one file to send).
pub fn html(l: &League, r: &LeagueResult, rows: &[Row], svgs: Option<(String, String)>) -> String {
    let mut s = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>League {}</title>\n<style>body{{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}}table{{border-collapse:collapse;margin:1em 0}}th,td{{border:1px solid #ccc;padding:4px 8px;text-align:right}}th{{background:#f0f0f0}}td:first-child,th:first-child{{text-align:left}}td.best{{font-weight:bold;background:#e8f4e8}}td.bad{{color:#b00}}svg{{max-width:100%;height:auto}}</style></head><body>\n<h1>League <code>{}</code></h1>\n",
        escape::html(&l.file.name),
        escape::html(&l.file.name)
    );
    if !l.file.description.is_empty() {
        let _ = writeln!(s, "<p>{}</p>", escape::html(&l.file.description));
    }
    let _ = writeln!(
        s,
        "<p>Written by <code>ehservo league</code> ({} {}). Every run is re-made by <code>ehservo run scenarios/&lt;controller&gt;/&lt;scenario&gt;.toml</code> (other draws: <code>--set uncertainty.seed=S</code>, S in runs.csv).</p>\n<h2>Set-up</h2><ul>",
        crate::output::SOFTWARE.name,
        crate::output::SOFTWARE.version
    );
    for line in setup_lines(l) {
        let _ = writeln!(s, "<li>{}</li>", escape::html(&line));
    }
    s.push_str(&format!("</ul>\n<h2>Standings</h2><p>Worst e_max after the transient ({}) on each scenario, over its draws; ordered by mean rank (1 = best; unbounded last). The best of each column is marked.</p>\n", sym(l)));
    s.push_str(&standings_table(l, r, rows).html());
    s.push_str("<h2>Parameters</h2>");
    s.push_str(&params_table(l, r, rows).html());
    if let Some((pareto, bars)) = &svgs {
        let _ = writeln!(
            s,
            "<h2>Figures</h2>\n<figure>{}</figure>\n<figure>{}</figure>",
            strip_xml(pareto),
            strip_xml(bars)
        );
    }
    for (si, c) in l.cases.iter().enumerate() {
        let _ = write!(
            s,
            "<h2>Scenario <code>{}</code></h2>",
            escape::html(&c.name)
        );
        s.push_str(&scenario_table(l, r, rows, si).html());
    }
    s.push_str("</body></html>\n");
    s
}

/// An SVG file's text without its XML declaration, to inline in HTML.
fn strip_xml(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

/// Accuracy against chattering: a panel per scenario, a point per bounded
/// controller (worst e_max, mean chattering).
pub fn pareto(l: &League, rows: &[Row]) -> Figure {
    let ns = l.cases.len();
    let nc = rows.len() / ns.max(1);
    let cols = ns.clamp(1, 3);
    let panels = l
        .cases
        .iter()
        .enumerate()
        .map(|(si, c)| {
            let mut missing = Vec::new();
            let series: Vec<Series> = (0..nc)
                .filter_map(|ci| {
                    let r = &rows[ci * ns + si];
                    // The legend once, in the first panel: the colours
                    // are the same in every panel.
                    let label = if si == 0 {
                        r.controller.clone()
                    } else {
                        String::new()
                    };
                    match (r.e_max_worst_deg, r.chattering_mean) {
                        (Some(e), Some(ch)) if e > 0.0 && ch.is_finite() => {
                            Some(Series::new(label, vec![ch], vec![e], ci % 10).dash(Dash::Points))
                        }
                        _ => {
                            missing.push(r.controller.clone());
                            None
                        }
                    }
                })
                .collect();
            // Padded ranges, so that no point sits on an axis.
            let xs: Vec<f64> = series_xy(&series, |s| s.x[0]);
            let ys: Vec<f64> = series_xy(&series, |s| s.y[0]);
            let x_range = bounds(&xs).map(|(a, b)| {
                let pad = 0.08 * (b - a).max(0.05 * b.abs()).max(1e-12);
                (a - pad, b + pad)
            });
            let y_range = bounds(&ys).map(|(a, b)| (a / 2.0, b * 2.0));
            Panel {
                x_range,
                y_range,
                title: if missing.is_empty() {
                    c.name.clone()
                } else {
                    format!("{} (not shown, unbounded: {})", c.name, missing.join(", "))
                },
                x_label: "chattering index (mean)".into(),
                y_label: format!("e_max worst ({})", sym(l)),
                series,
                log_y: true,
                ..Default::default()
            }
        })
        .collect();
    let rows_n = ns.div_ceil(cols);
    Figure {
        title: format!(
            "league {} — accuracy against chattering (lower left is better)",
            l.file.name
        ),
        rows: rows_n,
        cols,
        panels,
        size: (500 * cols as u32, 420 * rows_n as u32 + 60),
        footer: String::new(),
    }
}

fn series_xy(series: &[Series], f: impl Fn(&Series) -> f64) -> Vec<f64> {
    series.iter().map(f).collect()
}

fn bounds(v: &[f64]) -> Option<(f64, f64)> {
    let lo = v.iter().copied().reduce(f64::min)?;
    let hi = v.iter().copied().reduce(f64::max)?;
    Some((lo, hi))
}

/// Worst e_max per scenario, a bar per controller.
pub fn bars(l: &League, rows: &[Row]) -> Bars {
    let ns = l.cases.len();
    let nc = rows.len() / ns.max(1);
    Bars {
        title: format!(
            "league {} — worst e_max after the transient, per scenario (× = unbounded)",
            l.file.name
        ),
        y_label: format!("e_max worst ({})", sym(l)),
        groups: l.cases.iter().map(|c| c.name.clone()).collect(),
        series: (0..nc)
            .map(|ci| {
                (
                    rows[ci * ns].controller.clone(),
                    (0..ns)
                        .map(|si| rows[ci * ns + si].e_max_worst_deg)
                        .collect(),
                )
            })
            .collect(),
        size: (1200, 560),
    }
}
