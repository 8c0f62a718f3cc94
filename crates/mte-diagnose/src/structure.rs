//! Structure tests of residuals: does what the model leaves over still depend on an axis
//! position, on time, on the direction of motion, periodically on position, or on the setup?

use std::borrow::Cow;

use mte_linalg::{DMat, DVec, stats};
use serde::Serialize;

use crate::basis::{Spread, legendre_columns, periods_to_scan, sin_cos_columns};
use crate::data::{Observations, Variable, VariableKind};
use crate::fit::{Projector, select, select_rows};
use crate::term::Term;
use rayon::prelude::*;

/// One test of the residuals.
#[derive(Debug, Clone, Serialize)]
pub struct StructureTest {
    /// What the residuals were tested against: `X`, `t`, `direction`, `setup`.
    pub variable: String,
    /// Which channel (`dx`, `length` …).
    pub channel: String,
    /// The kind of dependence tested: "trend (cubic)", "periodic", "direction", "setup".
    pub test: String,
    /// F statistic of the dependence beyond the current model.
    pub f_statistic: f64,
    /// p-value, Bonferroni-adjusted for every test run on this dataset (and for the period scan).
    pub p_value: f64,
    /// Share of the residual sum of squares the dependence explains.
    pub share_of_residual: f64,
    /// For a periodic dependence, the best period (mm or rad).
    pub period: Option<f64>,
    /// The period as people read it (`20.1 mm`, `120.0°`).
    pub period_text: Option<String>,
}

impl StructureTest {
    /// Significant at the workspace's discovery level.
    pub fn is_significant(&self, alpha: f64) -> bool {
        self.p_value < alpha
    }
}

/// The design columns of the structure test `t` on all observations (zero outside its
/// channel), as [`structure_tests`] built them: how a plot draws the dependence it found.
pub(crate) fn test_columns(obs: &Observations, t: &StructureTest, probes: &[Term]) -> Option<DMat> {
    let n = obs.len();
    let cols = if let Some(p) = probes.iter().find(|p| p.label == t.test) {
        p.columns.clone()
    } else if t.variable == "setup" {
        setup_columns(obs)
    } else {
        let v = obs.variable(&t.variable)?;
        match (t.test.as_str(), t.period) {
            (TREND, _) => legendre_columns(&v.values, 1..=3),
            (PERIODIC, Some(p)) => sin_cos_columns(&v.values, p),
            (DIRECTION, _) => DMat::from_column_slice(n, 1, &v.values),
            _ => return None,
        }
    };
    let channel = obs.channel_names.iter().position(|c| *c == t.channel);
    Some(DMat::from_fn(n, cols.ncols(), |i, j| {
        if channel.is_none_or(|ch| obs.channel[i] == ch) {
            cols[(i, j)]
        } else {
            0.0
        }
    }))
}

const TREND: &str = "trend (cubic)";
const PERIODIC: &str = "periodic";
const DIRECTION: &str = "direction";

/// One indicator column per set-up but the first.
fn setup_columns(obs: &Observations) -> DMat {
    let k = obs.setup_names.len();
    DMat::from_fn(obs.len(), k.saturating_sub(1), |i, j| {
        if obs.setup[i] == j + 1 { 1.0 } else { 0.0 }
    })
}

/// Runs every structure test on the residuals `r` of the model whose design is `x` and fit
/// `projector` ([`Projector::fit`]), the library's structure probes `probes`
/// ([`crate::Role::Probe`]) among them, each on the channels its columns touch. On a long
/// record the period scans choose their period on the observations `scan_rows` (evenly thinned)
/// and test it on all; the Bonferroni factor counts the whole scan either way.
#[allow(clippy::too_many_arguments)]
pub(crate) fn structure_tests(
    obs: &Observations,
    projector: &Projector,
    x: &DMat,
    r: &DVec,
    w: &DVec,
    rss_w: f64,
    dof: usize,
    scan_rows: Option<&[usize]>,
    probes: &[Term],
) -> Vec<StructureTest> {
    // Where the period scans run: all observations, or the thinned ones.
    let thin = scan_rows.map(|rows| {
        (
            obs.select(rows),
            Projector::new(&select_rows(x, rows), &select(w, rows), &select(r, rows)),
        )
    });
    let (scan_obs, scan_projector) = match &thin {
        Some((o, p)) => (o, p),
        None => (obs, projector),
    };
    let n = obs.len();
    let channels: Vec<usize> = (0..obs.channel_names.len()).collect();
    // A test is of one channel: its columns are zero elsewhere, so it runs on that channel's rows.
    let rows_of = |o: &Observations, ch: usize| -> Vec<usize> {
        (0..o.len()).filter(|&i| o.channel[i] == ch).collect()
    };
    let rows: Vec<Vec<usize>> = channels.iter().map(|&ch| rows_of(obs, ch)).collect();
    let projectors: Vec<Cow<Projector>> = rows.iter().map(|r| projector.on_rows(r)).collect();
    let scan_channels: Option<Vec<(Vec<usize>, Cow<Projector>)>> = thin.as_ref().map(|_| {
        channels
            .iter()
            .map(|&ch| {
                let r = rows_of(scan_obs, ch);
                let p = scan_projector.on_rows(&r);
                (r, p)
            })
            .collect()
    });
    // A test on one channel, or (`None`) on all observations.
    let run = |variable: &str,
               channel: Option<usize>,
               test: &str,
               cols: DMat,
               period: Option<(f64, &str)>,
               inner: f64|
     -> Option<(StructureTest, f64)> {
        let inc = match channel {
            Some(ch) => projectors[ch].increment(&select_rows(&cols, &rows[ch])),
            None => projector.increment(&cols),
        };
        if inc.new_rank == 0 || dof <= inc.new_rank {
            return None;
        }
        let rss_new = (rss_w - inc.delta_rss).max(1e-300);
        let d2 = (dof - inc.new_rank) as f64;
        let f = (inc.delta_rss / inc.new_rank as f64) / (rss_new / d2);
        let p = stats::f_sf(f, inc.new_rank as f64, d2);
        Some((
            StructureTest {
                variable: variable.to_string(),
                channel: channel.map_or_else(
                    || "all channels".to_string(),
                    |ch| obs.channel_names[ch].clone(),
                ),
                test: test.to_string(),
                f_statistic: f,
                p_value: p,
                share_of_residual: inc.delta_rss / rss_w.max(1e-300),
                period: period.map(|p| p.0),
                period_text: period.map(|(p, unit)| match unit {
                    "°" => format!("{:.1}°", p.to_degrees()),
                    unit => format!("{p:.2} {unit}"),
                }),
            },
            inner,
        ))
    };
    // The tests of one variable on one channel (`None`: of the set-up), independent of each
    // other: run in parallel, collected in order (the same report for any thread count).
    let tests_of = |ch: usize, variable: Option<&Variable>| -> Vec<(StructureTest, f64)> {
        let Some(v) = variable else {
            return run("setup", Some(ch), "setup", setup_columns(obs), None, 1.0)
                .into_iter()
                .collect();
        };
        let mut out = Vec::new();
        match v.kind {
            VariableKind::LinearAxis | VariableKind::RotaryAxis | VariableKind::Time => {
                out.extend(run(
                    &v.name,
                    Some(ch),
                    TREND,
                    legendre_columns(&v.values, 1..=3),
                    None,
                    1.0,
                ));
                if v.kind != VariableKind::Time {
                    let rotary = v.kind == VariableKind::RotaryAxis;
                    let scan_values = &scan_obs
                        .variable(&v.name)
                        .expect("the thinned observations have the same variables")
                        .values;
                    let periods = periods_to_scan(scan_values, rotary);
                    let (scan_rows, scan_projector) = match &scan_channels {
                        Some(s) => (&s[ch].0, &s[ch].1),
                        None => (&rows[ch], &projectors[ch]),
                    };
                    let on_channel: Vec<f64> = scan_rows.iter().map(|&i| scan_values[i]).collect();
                    let ones = vec![1.0; on_channel.len()];
                    let increments = scan_projector.increments_on(
                        &Spread::new(&[(&on_channel, &ones)]),
                        periods.len(),
                        |k, values| sin_cos_columns(values, periods[k]),
                    );
                    let mut best: Option<(f64, f64)> = None;
                    for (&p, inc) in periods.iter().zip(increments) {
                        if best.is_none_or(|(_, d)| inc.delta_rss > d) {
                            best = Some((p, inc.delta_rss));
                        }
                    }
                    if let Some((p, _)) = best {
                        out.extend(run(
                            &v.name,
                            Some(ch),
                            PERIODIC,
                            sin_cos_columns(&v.values, p),
                            Some((p, if rotary { "°" } else { "mm" })),
                            periods.len() as f64,
                        ));
                    }
                }
            }
            VariableKind::Direction => {
                out.extend(run(
                    &v.name,
                    Some(ch),
                    DIRECTION,
                    DMat::from_column_slice(n, 1, &v.values),
                    None,
                    1.0,
                ));
            }
        }
        out
    };
    let jobs: Vec<(usize, Option<&Variable>)> = channels
        .iter()
        .flat_map(|&ch| {
            obs.variables
                .iter()
                .map(move |v| (ch, Some(v)))
                .chain((obs.setup_names.len() > 1).then_some((ch, None)))
        })
        .collect();
    let mut raw: Vec<(StructureTest, f64)> = jobs
        .par_iter()
        .map(|&(ch, v)| tests_of(ch, v))
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect();
    // The probes: on the one channel their columns touch, else on all observations.
    raw.extend(
        probes
            .par_iter()
            .filter_map(|p| {
                let touched: Vec<usize> = channels
                    .iter()
                    .copied()
                    .filter(|&ch| {
                        rows[ch]
                            .iter()
                            .any(|&i| p.columns.row(i).iter().any(|&v| v != 0.0))
                    })
                    .collect();
                let channel = match touched[..] {
                    [ch] => Some(ch),
                    _ => None,
                };
                let variable = p.exposed_by.clone().unwrap_or_default();
                run(&variable, channel, &p.label, p.columns.clone(), None, 1.0)
            })
            .collect::<Vec<_>>(),
    );
    let total: f64 = raw.iter().map(|(_, inner)| inner).sum();
    raw.into_iter()
        .map(|(mut t, inner)| {
            // Bonferroni over every hypothesis examined, the period scan counted in full.
            t.p_value = (t.p_value * total.max(inner)).min(1.0);
            t
        })
        .collect()
}
