//! Volumetric error simulation over a grid, a list of poses or a program.

use crate::csv::{CsvTable, UnitColumns};
use crate::error::{Error, Result};
use crate::evaluator::{AxisState, Evaluator};
use crate::models::Direction;
use crate::units::Kind;
use mte_kinematics::{AxisKind, Machine};
use mte_linalg::{DMat, Vec3};
use rayon::prelude::*;

/// One point to simulate.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Axis commands (mm, rad) in [`Machine::axes`] order.
    pub q: Vec<f64>,
    /// Time (s).
    pub time_s: f64,
    /// Direction of motion per axis (empty = unknown).
    pub directions: Vec<Direction>,
}

/// Exact or first-order pose error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Full transforms.
    #[default]
    Exact,
    /// `J(q)·e`.
    FirstOrder,
}

/// Summary of a volumetric run (mm and rad).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Number of points.
    pub n_points: usize,
    /// Largest |position error| (mm).
    pub max_position_mm: f64,
    /// Index of that point.
    pub worst_point: usize,
    /// RMS of |position error| (mm).
    pub rms_position_mm: f64,
    /// Per direction (x, y, z): min, max and range (max − min) of the position error (mm).
    pub min_mm: [f64; 3],
    /// See `min_mm`.
    pub max_mm: [f64; 3],
    /// See `min_mm`.
    pub range_mm: [f64; 3],
    /// Largest |orientation error| (rad).
    pub max_orientation_rad: f64,
    /// RMS of |orientation error| (rad).
    pub rms_orientation_rad: f64,
    /// Per direction range of the orientation error (rad).
    pub range_rad: [f64; 3],
}

/// Pose errors at every point plus their summary.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumetricResult {
    /// Position error per point (mm, workpiece frame).
    pub position_mm: Vec<[f64; 3]>,
    /// Orientation error per point (rad, rotation vector, workpiece frame).
    pub orientation_rad: Vec<[f64; 3]>,
    /// Summary.
    pub summary: Summary,
}

/// (position, orientation) error of one point.
type PointError = ([f64; 3], [f64; 3]);

/// Points per parallel chunk (fixed, so the work split does not depend on the thread count).
const CHUNK: usize = 2048;

/// Simulate the pose error at every point, in parallel (rayon) over fixed chunks.
///
/// # Errors
/// The first error of any point (wrong lengths, a model outside its range), naming the point.
pub fn simulate(ev: &Evaluator, points: &[Point], method: Method) -> Result<VolumetricResult> {
    let n_slots = ev.n_slots();
    let chunks: Vec<Result<Vec<PointError>>> = points
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut e = vec![0.0; n_slots];
            let mut jac = if method == Method::FirstOrder {
                DMat::zeros(6, n_slots)
            } else {
                DMat::zeros(0, 0)
            };
            let mut out = Vec::with_capacity(chunk.len());
            for (k, p) in chunk.iter().enumerate() {
                let st = AxisState {
                    q: &p.q,
                    time_s: p.time_s,
                    directions: &p.directions,
                };
                let pe = match method {
                    Method::Exact => ev.pose_error(&st, &mut e),
                    Method::FirstOrder => ev.pose_error_first_order(&st, &mut e, &mut jac),
                }
                .map_err(|err| at_point(err, ci * CHUNK + k))?;
                out.push((pe.position.into(), pe.orientation.into()));
            }
            Ok(out)
        })
        .collect();
    let mut position_mm = Vec::with_capacity(points.len());
    let mut orientation_rad = Vec::with_capacity(points.len());
    for c in chunks {
        for (p, o) in c? {
            position_mm.push(p);
            orientation_rad.push(o);
        }
    }
    let summary = summarize(&position_mm, &orientation_rad);
    Ok(VolumetricResult {
        position_mm,
        orientation_rad,
        summary,
    })
}

fn at_point(e: Error, i: usize) -> Error {
    match e {
        Error::OutOfRange {
            parameter,
            position,
            low,
            high,
        } => Error::OutOfRange {
            parameter: format!("{parameter}` at point {i} (`{parameter}"),
            position,
            low,
            high,
        },
        Error::Invalid { what, message } => Error::Invalid {
            what: format!("point {i}: {what}"),
            message,
        },
        Error::Dimension {
            what,
            expected,
            got,
        } => Error::Dimension {
            what: format!("point {i}: {what}"),
            expected,
            got,
        },
        e => e,
    }
}

/// Summary statistics of position and orientation errors.
pub fn summarize(pos: &[[f64; 3]], ori: &[[f64; 3]]) -> Summary {
    let n = pos.len();
    let norm = |v: &[f64; 3]| Vec3::new(v[0], v[1], v[2]).norm();
    let mut s = Summary {
        n_points: n,
        max_position_mm: 0.0,
        worst_point: 0,
        rms_position_mm: 0.0,
        min_mm: [0.0; 3],
        max_mm: [0.0; 3],
        range_mm: [0.0; 3],
        max_orientation_rad: 0.0,
        rms_orientation_rad: 0.0,
        range_rad: [0.0; 3],
    };
    if n == 0 {
        return s;
    }
    s.min_mm = [f64::INFINITY; 3];
    s.max_mm = [f64::NEG_INFINITY; 3];
    let mut omin = [f64::INFINITY; 3];
    let mut omax = [f64::NEG_INFINITY; 3];
    let (mut sp, mut so) = (0.0, 0.0);
    for (i, (p, o)) in pos.iter().zip(ori).enumerate() {
        let d = norm(p);
        if d > s.max_position_mm {
            s.max_position_mm = d;
            s.worst_point = i;
        }
        sp += d * d;
        let a = norm(o);
        s.max_orientation_rad = s.max_orientation_rad.max(a);
        so += a * a;
        for k in 0..3 {
            s.min_mm[k] = s.min_mm[k].min(p[k]);
            s.max_mm[k] = s.max_mm[k].max(p[k]);
            omin[k] = omin[k].min(o[k]);
            omax[k] = omax[k].max(o[k]);
        }
    }
    s.rms_position_mm = (sp / n as f64).sqrt();
    s.rms_orientation_rad = (so / n as f64).sqrt();
    for k in 0..3 {
        s.range_mm[k] = s.max_mm[k] - s.min_mm[k];
        s.range_rad[k] = omax[k] - omin[k];
    }
    s
}

/// A regular grid: `n` equally spaced values per listed axis (end points included), the other
/// axes held at `fixed` values (default 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// (axis name, low, high, count) with low/high in mm or rad.
    pub axes: Vec<(String, f64, f64, usize)>,
    /// (axis name, value) for axes not on the grid.
    pub fixed: Vec<(String, f64)>,
}

impl Grid {
    /// The default grid over the linear axes' strokes with `n` values each (rotary axes at 0,
    /// clamped into their strokes).
    pub fn over_strokes(machine: &Machine, n: usize) -> Grid {
        let axes = machine
            .axes()
            .iter()
            .filter(|a| a.kind == AxisKind::Linear)
            .map(|a| (a.name.clone(), a.stroke.0, a.stroke.1, n))
            .collect();
        let fixed = machine
            .axes()
            .iter()
            .filter(|a| a.kind == AxisKind::Rotary)
            .map(|a| (a.name.clone(), 0f64.clamp(a.stroke.0, a.stroke.1)))
            .collect();
        Grid { axes, fixed }
    }

    /// All grid points (the first listed axis varies slowest).
    ///
    /// # Errors
    /// [`Error::Invalid`] for an unknown axis name, a count of 0, or more than 10⁸ points.
    pub fn points(&self, machine: &Machine) -> Result<Vec<Point>> {
        let n_ax = machine.axes().len();
        let mut base = vec![0.0; n_ax];
        for a in machine.axes().iter().enumerate() {
            base[a.0] = 0f64.clamp(a.1.stroke.0, a.1.stroke.1);
        }
        let idx = |name: &str| {
            machine.axis_index(name).ok_or_else(|| {
                crate::error::invalid(
                    "grid",
                    format!(
                        "unknown axis `{name}` (machine axes: {})",
                        machine
                            .axes()
                            .iter()
                            .map(|a| a.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
        };
        for (name, v) in &self.fixed {
            base[idx(name)?] = *v;
        }
        let mut dims = Vec::new();
        let mut total: usize = 1;
        for (name, lo, hi, n) in &self.axes {
            if *n == 0 || !lo.is_finite() || !hi.is_finite() {
                return Err(crate::error::invalid(
                    "grid",
                    format!("axis `{name}`: need a count ≥ 1 and finite bounds"),
                ));
            }
            total = total.saturating_mul(*n);
            dims.push((idx(name)?, *lo, *hi, *n));
        }
        if total > 100_000_000 {
            return Err(crate::error::invalid(
                "grid",
                format!("{total} points is too many (limit 1e8)"),
            ));
        }
        let mut pts = Vec::with_capacity(total);
        for i in 0..total {
            let mut q = base.clone();
            let mut r = i;
            for &(a, lo, hi, n) in dims.iter().rev() {
                let k = r % n;
                r /= n;
                q[a] = if n == 1 {
                    lo
                } else {
                    lo + (hi - lo) * k as f64 / (n - 1) as f64
                };
            }
            pts.push(Point {
                q,
                time_s: 0.0,
                directions: Vec::new(),
            });
        }
        Ok(pts)
    }
}

/// Read a program: a CSV with one column per machine axis (`x_mm`, `y_mm`, `z_mm`, `a_deg`,
/// `c_rad` …, names case-insensitive, units required), an optional time column `t_s` (or
/// `t_min`, `t_h`) and optional direction columns `dir_<axis>` (+1, −1, 0). Without a direction
/// column an axis' direction is inferred from the sign of its change since the previous row
/// (kept when it does not move; unknown at the start).
///
/// # Errors
/// [`Error::Csv`] naming the line: missing axis column, wrong unit kind, not-a-number, time
/// going backwards, direction not in {−1, 0, 1}.
pub fn program_from_csv(text: &str, source_name: &str, machine: &Machine) -> Result<Vec<Point>> {
    let t = CsvTable::parse(text, source_name)?;
    let mut cols = Vec::new();
    for a in machine.axes() {
        let example = if a.kind == AxisKind::Linear {
            format!("{}_mm", a.name.to_lowercase())
        } else {
            format!("{}_deg", a.name.to_lowercase())
        };
        let (c, u) = t.require_with_unit(&a.name.to_lowercase(), &example)?;
        let want = if a.kind == AxisKind::Linear {
            Kind::Length
        } else {
            Kind::Angle
        };
        if u.kind() != want {
            return Err(t.err(
                t.header_line,
                format!(
                    "column `{}`: axis {} needs a unit of {want:?} (e.g. `{example}`)",
                    t.headers[c], a.name
                ),
            ));
        }
        let dir = t
            .headers
            .iter()
            .position(|h| h.eq_ignore_ascii_case(&format!("dir_{}", a.name)));
        cols.push((c, u.to_internal(), dir));
    }
    let mut tcol = None;
    for (suf, f) in [("s", 1.0), ("min", 60.0), ("h", 3600.0)] {
        if let Some(c) = t.column(&format!("t_{suf}")) {
            if tcol.is_some() {
                return Err(t.err(t.header_line, "two time columns".into()));
            }
            tcol = Some((c, f));
        }
    }
    let n_ax = cols.len();
    let mut pts: Vec<Point> = Vec::with_capacity(t.rows.len());
    for r in 0..t.rows.len() {
        let mut q = Vec::with_capacity(n_ax);
        for &(c, f, _) in &cols {
            q.push(t.number(r, c)? * f);
        }
        let time_s = match tcol {
            Some((c, f)) => t.number(r, c)? * f,
            None => 0.0,
        };
        if let Some(prev) = pts.last()
            && tcol.is_some()
            && time_s < prev.time_s
        {
            return Err(t.err(
                t.line(r),
                format!("time goes backwards ({time_s} s after {} s)", prev.time_s),
            ));
        }
        let mut dirs = Vec::with_capacity(n_ax);
        for (k, &(_, _, dc)) in cols.iter().enumerate() {
            let d = match dc {
                Some(c) => {
                    let v = t.number(r, c)?;
                    if v != 1.0 && v != -1.0 && v != 0.0 {
                        return Err(t.err(
                            t.line(r),
                            format!(
                                "column `{}`: direction must be 1, -1 or 0, found {v}",
                                t.headers[c]
                            ),
                        ));
                    }
                    Direction::from_sign(v)
                }
                None => match pts.last() {
                    Some(p) => {
                        let dq = q[k] - p.q[k];
                        if dq == 0.0 {
                            p.directions[k]
                        } else {
                            Direction::from_sign(dq)
                        }
                    }
                    None => Direction::Unknown,
                },
            };
            dirs.push(d);
        }
        pts.push(Point {
            q,
            time_s,
            directions: dirs,
        });
    }
    Ok(pts)
}

/// Read tool poses (`x_mm, y_mm, z_mm` of the tool tip in the workpiece frame, optional tool axis
/// `i, j, k`, default +z) and convert each by inverse kinematics, taking the branch closest to
/// the previous point's axis commands (the first branch for the first point).
///
/// # Errors
/// [`Error::Csv`] naming the line for missing columns, bad numbers or unreachable poses.
pub fn poses_from_csv(text: &str, source_name: &str, machine: &Machine) -> Result<Vec<Point>> {
    let t = CsvTable::parse(text, source_name)?;
    let mut c = [0usize; 3];
    let mut f = [1.0; 3];
    for (k, n) in ["x", "y", "z"].iter().enumerate() {
        let (ci, u) = t.require_with_unit(n, &format!("{n}_mm"))?;
        if u.kind() != Kind::Length {
            return Err(t.err(
                t.header_line,
                format!("column `{}` must be a length", t.headers[ci]),
            ));
        }
        c[k] = ci;
        f[k] = u.to_internal();
    }
    let ijk: Option<[usize; 3]> = match (t.column("i"), t.column("j"), t.column("k")) {
        (Some(a), Some(b), Some(cc)) => Some([a, b, cc]),
        (None, None, None) => None,
        _ => {
            return Err(t.err(
                t.header_line,
                "give all three tool-axis columns i, j, k or none".into(),
            ));
        }
    };
    let mut pts: Vec<Point> = Vec::with_capacity(t.rows.len());
    for r in 0..t.rows.len() {
        let tip = Vec3::new(
            t.number(r, c[0])? * f[0],
            t.number(r, c[1])? * f[1],
            t.number(r, c[2])? * f[2],
        );
        let axis = match ijk {
            Some(ix) => Vec3::new(
                t.number(r, ix[0])?,
                t.number(r, ix[1])?,
                t.number(r, ix[2])?,
            ),
            None => Vec3::z(),
        };
        if axis.norm() < 1e-12 {
            return Err(t.err(t.line(r), "tool axis (i, j, k) is zero".into()));
        }
        let sols = machine
            .inverse(&tip, &(axis / axis.norm()))
            .map_err(|e| t.err(t.line(r), format!("inverse kinematics: {e}")))?;
        let best = match pts.last() {
            Some(p) => sols.into_iter().min_by(|a, b| {
                let da: f64 = a.iter().zip(&p.q).map(|(x, y)| (x - y).powi(2)).sum();
                let db: f64 = b.iter().zip(&p.q).map(|(x, y)| (x - y).powi(2)).sum();
                da.total_cmp(&db)
            }),
            None => sols.into_iter().next(),
        };
        let q =
            best.ok_or_else(|| t.err(t.line(r), "pose not reachable within the strokes".into()))?;
        pts.push(Point {
            q,
            time_s: 0.0,
            directions: Vec::new(),
        });
    }
    Ok(pts)
}
