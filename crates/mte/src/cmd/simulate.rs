//! `mte simulate`: volumetric error of a machine with an error set, over a grid, a list of tool
//! poses or a program; writes `result.json`, `points.csv` and `map.svg`.

use std::fmt::Write;
use std::path::{Path, PathBuf};

use mte::CliError;
use mte::output::OutDir;
use mte::plot::{Axis, FieldMap, Series, XyChart, heat_arrow_map};
use mte::report::read_text;
use mte_errors::volumetric::{
    Grid, Method, Point, VolumetricResult, poses_from_csv, program_from_csv, simulate,
};
use mte_errors::{ErrorSet, Evaluator};
use mte_kinematics::{AxisKind, Machine};

/// Arguments of `mte simulate`.
#[derive(clap::Args)]
pub struct Args {
    /// A library machine name (`mte machine list`) or an mte-machine/1 JSON file.
    #[arg(long)]
    machine: String,
    /// An mte-errors/1 error-set JSON file.
    #[arg(long)]
    errors: PathBuf,
    /// Grid: comma-separated `AXIS=low:high:count` (mm for linear, deg for rotary axes), e.g.
    /// `X=0:700:8,Y=-500:0:6,Z=-700:0:3`. Default: every linear axis over its stroke.
    #[arg(long, conflicts_with_all = ["poses", "program"])]
    grid: Option<String>,
    /// Points per linear axis of the default grid.
    #[arg(long, default_value_t = 8)]
    n: usize,
    /// Axes held fixed on the grid: `AXIS=value,…` (mm or deg). Default 0 (clamped to the stroke).
    #[arg(long)]
    at: Option<String>,
    /// CSV of tool poses in the workpiece frame (`x_mm,y_mm,z_mm[,i,j,k]`), converted by inverse kinematics.
    #[arg(long, conflicts_with = "program")]
    poses: Option<PathBuf>,
    /// CSV program of axis commands (`x_mm,…,a_deg,…[,t_s][,dir_x,…]`).
    #[arg(long)]
    program: Option<PathBuf>,
    /// Use the first-order model J(q)·e instead of the exact transforms.
    #[arg(long)]
    first_order: bool,
    /// Accept grid bounds, `--at` values and program or pose points outside an axis's stroke
    /// (an error otherwise).
    #[arg(long)]
    allow_outside_stroke: bool,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

fn lib<E: std::fmt::Display>(e: E) -> CliError {
    CliError::Library(e.to_string())
}

/// A library machine name or an mte-machine/1 file.
fn to_internal(m: &Machine, axis: usize, v: f64) -> f64 {
    if m.axes()[axis].kind == AxisKind::Rotary {
        v.to_radians()
    } else {
        v
    }
}

fn axis_of(m: &Machine, name: &str, what: &str) -> Result<usize, CliError> {
    m.axis_index(name).ok_or_else(|| {
        CliError::Usage(format!(
            "{what}: unknown axis `{name}` (machine axes: {})",
            m.axes()
                .iter()
                .map(|a| a.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })
}

/// The stroke of axis `k` in the units users write (mm, deg).
fn stroke_user(m: &Machine, k: usize) -> (f64, f64, &'static str) {
    let a = &m.axes()[k];
    if a.kind == AxisKind::Rotary {
        (a.stroke.0.to_degrees(), a.stroke.1.to_degrees(), "deg")
    } else {
        (a.stroke.0, a.stroke.1, "mm")
    }
}

/// `v` (internal units) lies in the stroke of axis `k`, up to rounding.
fn in_stroke(m: &Machine, k: usize, v: f64) -> bool {
    let (lo, hi) = m.axes()[k].stroke;
    let tol = 1e-9 * (1.0 + lo.abs().max(hi.abs()));
    v >= lo - tol && v <= hi + tol
}

fn outside_stroke(m: &Machine, k: usize, what: &str, v_user: f64) -> CliError {
    let (lo, hi, unit) = stroke_user(m, k);
    CliError::Usage(format!(
        "{what}: {} = {v_user} {unit} is outside the stroke [{lo}, {hi}] {unit} of axis {}; pass --allow-outside-stroke to simulate it anyway",
        m.axes()[k].name,
        m.axes()[k].name
    ))
}

/// Bytes `simulate` holds per point: the point, its errors, and its CSV row.
fn bytes_per_point(m: &Machine) -> f64 {
    300.0 + 16.0 * m.axes().len() as f64
}

fn parse_grid(m: &Machine, args: &Args) -> Result<Grid, CliError> {
    let allow = args.allow_outside_stroke;
    let mut g = Grid::over_strokes(m, args.n);
    if args.n == 0 && args.grid.is_none() {
        return Err(CliError::Usage(
            "--n: needs at least 1 point per axis".into(),
        ));
    }
    if let Some(spec) = args.grid.as_deref() {
        g.axes.clear();
        let mut seen: Vec<(usize, String)> = Vec::new();
        for part in spec.split(',').filter(|s| !s.trim().is_empty()) {
            let bad = || CliError::Usage(format!("--grid: `{part}` is not AXIS=low:high:count"));
            let (name, rest) = part.trim().split_once('=').ok_or_else(bad)?;
            let f: Vec<&str> = rest.split(':').collect();
            if f.len() != 3 {
                return Err(bad());
            }
            let k = axis_of(m, name.trim(), "--grid")?;
            if let Some((_, first)) = seen.iter().find(|(j, _)| *j == k) {
                return Err(CliError::Usage(format!(
                    "--grid: axis {} appears twice (`{first}` and `{}`); give each axis once",
                    m.axes()[k].name,
                    part.trim()
                )));
            }
            seen.push((k, part.trim().to_string()));
            let num = |t: &str| -> Result<f64, CliError> {
                match t.trim().parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(CliError::Usage(format!(
                        "--grid: `{part}`: `{}` is not a finite number",
                        t.trim()
                    ))),
                }
            };
            let lo = num(f[0])?;
            let hi = num(f[1])?;
            let cnt: usize = f[2].trim().parse().map_err(|_| bad())?;
            if cnt == 0 {
                return Err(CliError::Usage(format!(
                    "--grid: `{part}`: the count must be at least 1"
                )));
            }
            if cnt > 1 && lo == hi {
                return Err(CliError::Usage(format!(
                    "--grid: `{part}`: {cnt} points between equal bounds are the same point; use a count of 1"
                )));
            }
            let (lo_i, hi_i) = (to_internal(m, k, lo), to_internal(m, k, hi));
            if !allow {
                for (v, vi) in [(lo, lo_i), (hi, hi_i)] {
                    if !in_stroke(m, k, vi) {
                        return Err(outside_stroke(m, k, "--grid", v));
                    }
                }
            }
            g.axes.push((m.axes()[k].name.clone(), lo_i, hi_i, cnt));
        }
        if g.axes.is_empty() {
            return Err(CliError::Usage(format!(
                "--grid: `{spec}` names no axis; expected AXIS=low:high:count,…"
            )));
        }
        let on_grid: Vec<String> = g.axes.iter().map(|a| a.0.clone()).collect();
        g.fixed.retain(|(a, _)| !on_grid.contains(a));
    }
    if let Some(at) = args.at.as_deref() {
        let mut seen: Vec<usize> = Vec::new();
        for part in at.split(',').filter(|s| !s.trim().is_empty()) {
            let (name, v) = part
                .trim()
                .split_once('=')
                .ok_or_else(|| CliError::Usage(format!("--at: `{part}` is not AXIS=value")))?;
            let k = axis_of(m, name.trim(), "--at")?;
            if seen.contains(&k) {
                return Err(CliError::Usage(format!(
                    "--at: axis {} appears twice",
                    m.axes()[k].name
                )));
            }
            seen.push(k);
            if g.axes.iter().any(|a| a.0 == m.axes()[k].name) {
                return Err(CliError::Usage(format!(
                    "--at: axis {} is on the grid; an axis is either on the grid or held at a value",
                    m.axes()[k].name
                )));
            }
            let v: f64 = match v.trim().parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                _ => {
                    return Err(CliError::Usage(format!(
                        "--at: `{part}`: not a finite number"
                    )));
                }
            };
            if !allow && !in_stroke(m, k, to_internal(m, k, v)) {
                return Err(outside_stroke(m, k, "--at", v));
            }
            g.fixed.retain(|(a, _)| a != &m.axes()[k].name);
            g.fixed
                .push((m.axes()[k].name.clone(), to_internal(m, k, v)));
        }
    }
    let total: f64 = g.axes.iter().map(|a| a.3 as f64).product();
    mte::limits::check_memory(
        &format!("a grid of {total:.0} points"),
        total * bytes_per_point(m),
    )?;
    Ok(g)
}

/// Points of a program or pose file outside the strokes are an error unless allowed.
fn check_strokes(m: &Machine, points: &[Point], file: &Path) -> Result<(), CliError> {
    for (i, p) in points.iter().enumerate() {
        for (k, v) in p.q.iter().enumerate() {
            if !in_stroke(m, k, *v) {
                let (_, _, unit) = stroke_user(m, k);
                let user = if unit == "deg" { v.to_degrees() } else { *v };
                return Err(outside_stroke(
                    m,
                    k,
                    &format!("{}: point {} (data row {})", file.display(), i, i + 1),
                    user,
                ));
            }
        }
    }
    Ok(())
}

/// Run `mte simulate`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let mut out = OutDir::prepare(&args.out)?;
    let m = super::machine::load(&args.machine)?;
    mte::report::check_regular_file(&args.errors)?;
    let set = ErrorSet::from_file(&args.errors).map_err(lib)?;
    let ev = Evaluator::new(&m, &set).map_err(lib)?;
    let (source, points, grid) = if let Some(p) = &args.program {
        let pts = program_from_csv(&read_text(p)?, &p.display().to_string(), &m).map_err(lib)?;
        if !args.allow_outside_stroke {
            check_strokes(&m, &pts, p)?;
        }
        ("program", pts, None)
    } else if let Some(p) = &args.poses {
        let pts = poses_from_csv(&read_text(p)?, &p.display().to_string(), &m).map_err(lib)?;
        if !args.allow_outside_stroke {
            check_strokes(&m, &pts, p)?;
        }
        ("poses", pts, None)
    } else {
        let g = parse_grid(&m, args)?;
        ("grid", g.points(&m).map_err(lib)?, Some(g))
    };
    if points.is_empty() {
        return Err(CliError::Usage("no points to simulate".into()));
    }
    let method = if args.first_order {
        Method::FirstOrder
    } else {
        Method::Exact
    };
    let r = simulate(&ev, &points, method).map_err(lib)?;
    // The plot first: if it fails, nothing is written.
    let svg = match &grid {
        Some(g) if g.axes.iter().filter(|a| a.3 >= 2).count() >= 2 => grid_map(&m, g, &points, &r)?,
        _ => path_chart(&r)?,
    };
    out.add("points.csv", points_csv(&m, &points, &r));
    out.add_json(
        "result.json",
        &result_json(&m, &set, source, method, &points, &r),
    )?;
    out.add("map.svg", svg);
    out.commit()?;
    let s = &r.summary;
    println!(
        "{}: {} points ({source}), max |position error| {:.2} µm at point {}, RMS {:.2} µm, ranges x/y/z {:.2}/{:.2}/{:.2} µm, max |orientation error| {:.2} µrad",
        m.name(),
        s.n_points,
        s.max_position_mm * 1e3,
        s.worst_point,
        s.rms_position_mm * 1e3,
        s.range_mm[0] * 1e3,
        s.range_mm[1] * 1e3,
        s.range_mm[2] * 1e3,
        s.max_orientation_rad * 1e6
    );
    println!(
        "wrote {}/result.json, points.csv, map.svg",
        args.out.display()
    );
    Ok(())
}

fn axis_header(m: &Machine) -> Vec<String> {
    m.axes()
        .iter()
        .map(|a| {
            format!(
                "{}_{}",
                a.name.to_lowercase(),
                if a.kind == AxisKind::Linear {
                    "mm"
                } else {
                    "deg"
                }
            )
        })
        .collect()
}

fn axis_values(m: &Machine, q: &[f64]) -> Vec<f64> {
    q.iter()
        .zip(m.axes())
        .map(|(v, a)| {
            if a.kind == AxisKind::Linear {
                *v
            } else {
                v.to_degrees()
            }
        })
        .collect()
}

fn points_csv(m: &Machine, pts: &[Point], r: &VolumetricResult) -> String {
    let mut s = String::new();
    let mut h = axis_header(m);
    h.extend(
        [
            "t_s", "dx_um", "dy_um", "dz_um", "d_um", "ex_urad", "ey_urad", "ez_urad",
        ]
        .map(String::from),
    );
    let _ = writeln!(s, "{}", h.join(","));
    for (k, p) in pts.iter().enumerate() {
        let mut row: Vec<String> = axis_values(m, &p.q)
            .iter()
            .map(|v| format!("{v}"))
            .collect();
        row.push(format!("{}", p.time_s));
        let d = r.position_mm[k];
        let o = r.orientation_rad[k];
        for v in d {
            row.push(format!("{:.6}", v * 1e3));
        }
        row.push(format!(
            "{:.6}",
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * 1e3
        ));
        for v in o {
            row.push(format!("{:.6}", v * 1e6));
        }
        let _ = writeln!(s, "{}", row.join(","));
    }
    s
}

fn result_json(
    m: &Machine,
    set: &ErrorSet,
    source: &str,
    method: Method,
    pts: &[Point],
    r: &VolumetricResult,
) -> serde_json::Value {
    let s = &r.summary;
    let um = |v: [f64; 3]| v.map(|x| x * 1e3);
    let worst = &pts[s.worst_point];
    let mut worst_axes = serde_json::Map::new();
    for (h, v) in axis_header(m).iter().zip(axis_values(m, &worst.q)) {
        worst_axes.insert(h.clone(), v.into());
    }
    serde_json::json!({
        "format": "mte-simulate-result/1",
        "machine": m.name(),
        "error_set": set.name,
        "source": source,
        "method": if method == Method::Exact { "exact" } else { "first_order" },
        "frame": "workpiece; position = tool tip actual - ideal; orientation = rotation vector of R_actual R_ideal^T",
        "n_points": s.n_points,
        "summary": {
            "max_position_um": s.max_position_mm * 1e3,
            "rms_position_um": s.rms_position_mm * 1e3,
            "worst_point": s.worst_point,
            "worst_point_axes": worst_axes,
            "min_position_um_xyz": um(s.min_mm),
            "max_position_um_xyz": um(s.max_mm),
            "range_position_um_xyz": um(s.range_mm),
            "max_orientation_urad": s.max_orientation_rad * 1e6,
            "rms_orientation_urad": s.rms_orientation_rad * 1e6,
            "range_orientation_urad_xyz": s.range_rad.map(|x| x * 1e6),
        },
        "points_csv": "points.csv",
    })
}

/// Heat/arrow map over the first two grid axes, in the layer of the other grid axes that
/// holds the worst point.
fn grid_map(
    m: &Machine,
    g: &Grid,
    pts: &[Point],
    r: &VolumetricResult,
) -> Result<String, CliError> {
    let dims: Vec<(usize, f64, f64, usize)> = g
        .axes
        .iter()
        .map(|(n, lo, hi, c)| (m.axis_index(n).unwrap_or(0), *lo, *hi, *c))
        .collect();
    let plotted: Vec<usize> = (0..dims.len())
        .filter(|&d| dims[d].3 >= 2)
        .take(2)
        .collect();
    let (pa, pb) = (plotted[0], plotted[1]);
    // Index of the worst point per grid dimension (first listed axis slowest).
    let mut strides = vec![1usize; dims.len()];
    for d in (0..dims.len().saturating_sub(1)).rev() {
        strides[d] = strides[d + 1] * dims[d + 1].3;
    }
    let w = r.summary.worst_point;
    let base: usize = (0..dims.len())
        .filter(|d| *d != pa && *d != pb)
        .map(|d| ((w / strides[d]) % dims[d].3) * strides[d])
        .sum();
    let coord = |d: usize, k: usize| {
        let (ax, lo, hi, n) = dims[d];
        let v = lo + (hi - lo) * k as f64 / (n - 1) as f64;
        if m.axes()[ax].kind == AxisKind::Rotary {
            v.to_degrees()
        } else {
            v
        }
    };
    let xs: Vec<f64> = (0..dims[pa].3).map(|k| coord(pa, k)).collect();
    let ys: Vec<f64> = (0..dims[pb].3).map(|k| coord(pb, k)).collect();
    let (ia, ib) = (dims[pa].0, dims[pb].0);
    let mut values = vec![vec![0.0; xs.len()]; ys.len()];
    let mut arrows = vec![vec![(0.0, 0.0); xs.len()]; ys.len()];
    for (j, row) in values.iter_mut().enumerate() {
        for (i, v) in row.iter_mut().enumerate() {
            let k = base + i * strides[pa] + j * strides[pb];
            let d = r.position_mm[k];
            *v = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * 1e3;
            // In-plane components along the plotted axes' directions (linear axes: x, y, z).
            let comp = |ax: usize| {
                let dir = m.axes()[ax].direction;
                (d[0] * dir.x + d[1] * dir.y + d[2] * dir.z) * 1e3
            };
            arrows[j][i] = (comp(ia), comp(ib));
        }
    }
    let unit = |ax: usize| {
        if m.axes()[ax].kind == AxisKind::Linear {
            "mm"
        } else {
            "deg"
        }
    };
    let layer: Vec<String> = (0..dims.len())
        .filter(|d| *d != pa && *d != pb)
        .map(|d| {
            format!(
                "{} = {:.4}",
                m.axes()[dims[d].0].name,
                axis_values(m, &pts[base].q)[dims[d].0]
            )
        })
        .chain(g.fixed.iter().map(|(n, v)| {
            let k = m.axis_index(n).unwrap_or(0);
            format!(
                "{n} = {:.4}",
                if m.axes()[k].kind == AxisKind::Rotary {
                    v.to_degrees()
                } else {
                    *v
                }
            )
        }))
        .collect();
    let title = format!(
        "{}: |position error| (µm), {}",
        m.name(),
        if layer.is_empty() {
            "all points".into()
        } else {
            layer.join(", ")
        }
    );
    let map = FieldMap {
        xs,
        ys,
        values,
        arrows: Some(arrows),
        unit: "µm".into(),
    };
    heat_arrow_map(
        &title,
        &Axis::new(&m.axes()[ia].name, unit(ia)),
        &Axis::new(&m.axes()[ib].name, unit(ib)),
        &map,
    )
}

/// Position error components along the point sequence (programs, pose lists, 1-D grids).
fn path_chart(r: &VolumetricResult) -> Result<String, CliError> {
    let series = |c: usize| {
        r.position_mm
            .iter()
            .enumerate()
            .map(|(k, d)| (k as f64, d[c] * 1e3))
            .collect::<Vec<_>>()
    };
    XyChart::new("Position error along the points")
        .x_axis(Axis::new("point", ""))
        .y_axis(Axis::new("position error", "µm"))
        .series(Series::line_markers("δx", series(0)))
        .series(Series::line_markers("δy", series(1)))
        .series(Series::line_markers("δz", series(2)))
        .render()
}
