//! ISO 230-2:2014 evaluation of the positioning accuracy and repeatability of a linear axis
//! from bidirectional runs (clause 2 definitions, clause 5 evaluation).
//!
//! For target i and run j, xᵢⱼ = Pᵢⱼ − Pᵢ is the positional deviation (measured − target).
//! ↑ / ↓ denote the approach direction.
//!
//! | quantity | definition |
//! |---|---|
//! | x̄ᵢ↑, x̄ᵢ↓ | mean unidirectional positional deviation (mean over runs) |
//! | x̄ᵢ | mean bidirectional positional deviation (x̄ᵢ↑ + x̄ᵢ↓)/2 |
//! | Bᵢ | reversal value x̄ᵢ↑ − x̄ᵢ↓; B = max\|Bᵢ\|; B̄ = mean Bᵢ |
//! | sᵢ↑, sᵢ↓ | estimator of the unidirectional standard uncertainty (n − 1) |
//! | Rᵢ↑ = 4sᵢ↑ | unidirectional repeatability; R↑ = max Rᵢ↑ (↓ alike) |
//! | Rᵢ | max(2sᵢ↑ + 2sᵢ↓ + \|Bᵢ\|, Rᵢ↑, Rᵢ↓); R = max Rᵢ |
//! | E↑ | max x̄ᵢ↑ − min x̄ᵢ↑ (↓ alike); E = max(x̄ᵢ↑, x̄ᵢ↓) − min(x̄ᵢ↑, x̄ᵢ↓) |
//! | M | max x̄ᵢ − min x̄ᵢ |
//! | A↑ | max(x̄ᵢ↑ + 2sᵢ↑) − min(x̄ᵢ↑ − 2sᵢ↑) (↓ alike); A from both directions |

use crate::error::{MetrologyError, Result, invalid};
use mte_linalg::csv::CsvTable;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Approach direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Direction {
    /// Positive direction (↑).
    Up,
    /// Negative direction (↓).
    Down,
}

/// One measured deviation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reading {
    /// Target position Pᵢ (mm).
    pub target_mm: f64,
    /// Run number j (1-based).
    pub run: usize,
    /// Approach direction.
    pub direction: Direction,
    /// Positional deviation xᵢⱼ (µm).
    pub deviation_um: f64,
}

/// Per-target results (µm).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetResult {
    /// Target position (mm).
    pub target_mm: f64,
    /// x̄ᵢ↑.
    pub mean_up_um: f64,
    /// x̄ᵢ↓.
    pub mean_down_um: f64,
    /// x̄ᵢ.
    pub mean_um: f64,
    /// Bᵢ.
    pub reversal_um: f64,
    /// sᵢ↑.
    pub s_up_um: f64,
    /// sᵢ↓.
    pub s_down_um: f64,
    /// Rᵢ↑.
    pub r_up_um: f64,
    /// Rᵢ↓.
    pub r_down_um: f64,
    /// Rᵢ.
    pub r_um: f64,
}

/// Axis results (µm), ISO 230-2 clause 2.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisResult {
    /// Per target, ascending position.
    pub targets: Vec<TargetResult>,
    /// Runs per direction.
    pub runs: usize,
    /// Reversal B = max |Bᵢ|.
    pub reversal_b_um: f64,
    /// Mean reversal B̄.
    pub mean_reversal_um: f64,
    /// R↑.
    pub repeatability_up_um: f64,
    /// R↓.
    pub repeatability_down_um: f64,
    /// R.
    pub repeatability_um: f64,
    /// E↑.
    pub systematic_up_um: f64,
    /// E↓.
    pub systematic_down_um: f64,
    /// E.
    pub systematic_um: f64,
    /// M.
    pub mean_range_um: f64,
    /// A↑.
    pub accuracy_up_um: f64,
    /// A↓.
    pub accuracy_down_um: f64,
    /// A.
    pub accuracy_um: f64,
}

fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let s = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    (m, s)
}

fn range<I: Iterator<Item = f64> + Clone>(it: I) -> f64 {
    it.clone().fold(f64::MIN, f64::max) - it.fold(f64::MAX, f64::min)
}

/// Evaluate bidirectional runs.
///
/// # Errors
/// Non-finite values, a deviation of [`MAX_DEVIATION_UM`] or more or a target of
/// [`MAX_TARGET_MM`] or more, fewer than 2 targets, fewer than 2 runs in a direction, or different
/// run counts between targets/directions, naming the target.
///
/// ```
/// use mte_metrology::iso230_2::{evaluate, Direction::*, Reading};
/// let mut r = Vec::new();
/// for (t, up, dn) in [(0.0, [1.0, 2.0, 3.0], [0.0, 1.0, 2.0]), (100.0, [4.0, 4.0, 4.0], [2.0, 2.0, 2.0])] {
///     for k in 0..3 {
///         r.push(Reading { target_mm: t, run: k + 1, direction: Up, deviation_um: up[k] });
///         r.push(Reading { target_mm: t, run: k + 1, direction: Down, deviation_um: dn[k] });
///     }
/// }
/// let a = evaluate(&r).unwrap();
/// assert_eq!(a.reversal_b_um, 2.0);
/// assert_eq!(a.systematic_um, 4.0 - 1.0);
/// ```
pub fn evaluate(readings: &[Reading]) -> Result<AxisResult> {
    let mut by: BTreeMap<(i64, Direction), (f64, Vec<f64>)> = BTreeMap::new();
    for (k, r) in readings.iter().enumerate() {
        if !r.target_mm.is_finite() || !r.deviation_um.is_finite() {
            return Err(invalid(format!(
                "reading #{k} (target {} mm, run {}): value not finite",
                r.target_mm, r.run
            )));
        }
        if r.target_mm.abs() >= MAX_TARGET_MM || r.deviation_um.abs() >= MAX_DEVIATION_UM {
            return Err(invalid(format!(
                "reading #{k} (target {} mm, run {}): deviation {} µm or target out of range (|deviation| < 1 m, |target| < 100 m)",
                r.target_mm, r.run, r.deviation_um
            )));
        }
        // key targets on 1 nm
        let key = (r.target_mm * 1e6).round() as i64;
        by.entry((key, r.direction))
            .or_insert((r.target_mm, Vec::new()))
            .1
            .push(r.deviation_um);
    }
    let keys: Vec<i64> = {
        let mut k: Vec<i64> = by.keys().map(|k| k.0).collect();
        k.dedup();
        k
    };
    if keys.len() < 2 {
        return Err(MetrologyError::TooFewData {
            what: format!(
                "{} target position(s); ISO 230-2 needs several (≥ 5 per metre)",
                keys.len()
            ),
        });
    }
    let mut runs = None;
    let mut targets = Vec::new();
    for k in &keys {
        let (t, up) = by
            .get(&(*k, Direction::Up))
            .cloned()
            .unwrap_or((*k as f64 * 1e-6, vec![]));
        let dn = by
            .get(&(*k, Direction::Down))
            .map(|x| x.1.clone())
            .unwrap_or_default();
        for (name, v) in [("↑", &up), ("↓", &dn)] {
            if v.len() < 2 {
                return Err(MetrologyError::TooFewData {
                    what: format!(
                        "target {t} mm, direction {name}: {} run(s); at least 2 needed (5 standard)",
                        v.len()
                    ),
                });
            }
            match runs {
                None => runs = Some(v.len()),
                Some(n) if n != v.len() => {
                    return Err(invalid(format!(
                        "target {t} mm, direction {name}: {} runs, other targets have {n}",
                        v.len()
                    )));
                }
                _ => {}
            }
        }
        let (mu, su) = mean_sd(&up);
        let (md, sd) = mean_sd(&dn);
        let b = mu - md;
        let (ru, rd) = (4.0 * su, 4.0 * sd);
        targets.push(TargetResult {
            target_mm: t,
            mean_up_um: mu,
            mean_down_um: md,
            mean_um: 0.5 * (mu + md),
            reversal_um: b,
            s_up_um: su,
            s_down_um: sd,
            r_up_um: ru,
            r_down_um: rd,
            r_um: (2.0 * su + 2.0 * sd + b.abs()).max(ru).max(rd),
        });
    }
    let t = &targets;
    let maxf = |f: &dyn Fn(&TargetResult) -> f64| t.iter().map(f).fold(f64::MIN, f64::max);
    let minf = |f: &dyn Fn(&TargetResult) -> f64| t.iter().map(f).fold(f64::MAX, f64::min);
    let res = AxisResult {
        runs: runs.unwrap_or(0),
        reversal_b_um: maxf(&|x| x.reversal_um.abs()),
        mean_reversal_um: t.iter().map(|x| x.reversal_um).sum::<f64>() / t.len() as f64,
        repeatability_up_um: maxf(&|x| x.r_up_um),
        repeatability_down_um: maxf(&|x| x.r_down_um),
        repeatability_um: maxf(&|x| x.r_um),
        systematic_up_um: range(t.iter().map(|x| x.mean_up_um)),
        systematic_down_um: range(t.iter().map(|x| x.mean_down_um)),
        systematic_um: maxf(&|x| x.mean_up_um.max(x.mean_down_um))
            - minf(&|x| x.mean_up_um.min(x.mean_down_um)),
        mean_range_um: range(t.iter().map(|x| x.mean_um)),
        accuracy_up_um: maxf(&|x| x.mean_up_um + 2.0 * x.s_up_um)
            - minf(&|x| x.mean_up_um - 2.0 * x.s_up_um),
        accuracy_down_um: maxf(&|x| x.mean_down_um + 2.0 * x.s_down_um)
            - minf(&|x| x.mean_down_um - 2.0 * x.s_down_um),
        accuracy_um: maxf(&|x| {
            (x.mean_up_um + 2.0 * x.s_up_um).max(x.mean_down_um + 2.0 * x.s_down_um)
        }) - minf(&|x| {
            (x.mean_up_um - 2.0 * x.s_up_um).min(x.mean_down_um - 2.0 * x.s_down_um)
        }),
        targets,
    };
    Ok(res)
}

/// Largest |deviation| the reader accepts, µm (exclusive): 1 m.
pub const MAX_DEVIATION_UM: f64 = 1e6;
/// Largest |target position| the reader accepts, mm (exclusive): 100 m.
pub const MAX_TARGET_MM: f64 = 1e5;

/// Read ISO 230-2 runs from CSV with header `target_mm,run,direction,deviation_um`
/// (`direction` = `up`/`+` or `down`/`-`).
///
/// # Errors
/// Parse errors naming the source, line and field: a value that is not a finite number, a
/// deviation of [`MAX_DEVIATION_UM`] or more, a target of [`MAX_TARGET_MM`] or more, a second
/// reading of the same target, run and direction (naming both lines).
pub fn readings_from_csv(source_name: &str, text: &str) -> Result<Vec<Reading>> {
    let c = CsvTable::parse(text, source_name)?;
    let (ct, cr, cd, cx) = (
        c.require("target_mm")?,
        c.require("run")?,
        c.require("direction")?,
        c.require("deviation_um")?,
    );
    let mut out = Vec::new();
    let mut seen: BTreeMap<(i64, usize, Direction), usize> = BTreeMap::new();
    for (i, r) in c.rows.iter().enumerate() {
        let dir = match r.1[cd].to_ascii_lowercase().as_str() {
            "up" | "+" | "pos" | "positive" => Direction::Up,
            "down" | "-" | "neg" | "negative" => Direction::Down,
            other => {
                return Err(MetrologyError::Parse {
                    source_name: source_name.into(),
                    line: r.0,
                    what: format!("field `direction`: expected `up` or `down`, got `{other}`"),
                });
            }
        };
        let run = r.1[cr]
            .parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| MetrologyError::Parse {
                source_name: source_name.into(),
                line: r.0,
                what: format!(
                    "field `run`: expected a positive integer, got `{}`",
                    r.1[cr]
                ),
            })?;
        let target_mm = c.number_within(
            i,
            ct,
            MAX_TARGET_MM,
            "a target 100 m or more from the origin is not a machine-tool axis position (mm)",
        )?;
        let deviation_um = c.number_within(
            i,
            cx,
            MAX_DEVIATION_UM,
            "a deviation of 1 m (10^6 µm) or more is not a measured positioning error; is the column in µm?",
        )?;
        let key = ((target_mm * 1e6).round() as i64, run, dir);
        if let Some(first) = seen.insert(key, r.0) {
            return Err(MetrologyError::Parse {
                source_name: source_name.into(),
                line: r.0,
                what: format!(
                    "duplicate reading: target {target_mm} mm, run {run}, direction {} already on line {first}",
                    if dir == Direction::Up { "up" } else { "down" }
                ),
            });
        }
        out.push(Reading {
            target_mm,
            run,
            direction: dir,
            deviation_um,
        });
    }
    Ok(out)
}
