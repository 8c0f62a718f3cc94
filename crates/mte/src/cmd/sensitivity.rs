//! `mte sensitivity <morris|sobol|pce|local> --problem problem.json --out DIR`: sensitivity of a
//! built-in test model (ishigami, gfunction, linear) over the inputs of a problem file, or of a
//! machine's pose error at test points over the random entries of an error set (`"model":
//! {"name": "machine", …}`; format in docs/formats.md, "Sensitivity problem"). Writes
//! result.json, indices.csv and indices.svg (bar chart with intervals); for a machine, the
//! indices per output (`p07.PX` …) in long format, and aggregate.csv / aggregate-PX.svg … with
//! the variance-weighted index of each direction over the points.

use clap::{Args as ClapArgs, ValueEnum};
use mte::CliError;
use mte::output::OutDir;
use mte::plot::{Axis, Interval, error_bar_chart};
use mte::report::read_text;
use mte_errors::pose_model::{
    COMPONENTS, Linearisation, PoseErrorModel, PoseModelError, diagonal_points, generalised_index,
    point_from_mm_deg, points_from_csv,
};
use mte_errors::units::{Kind, Unit};
use mte_errors::{Catalogue, ErrorSet};
use mte_kinematics::AxisKind;
use mte_sensitivity::testfn::{GFunction, Ishigami, Linear};
use mte_sensitivity::{Model, Problem};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One row of the index table: input name, index values per output, and their intervals.
type IndexRow = (String, Vec<f64>, Vec<[f64; 2]>);

/// Which analysis.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Method {
    /// Morris elementary effects.
    Morris,
    /// Sobol' first/total indices (Saltelli 2010 / Jansen).
    Sobol,
    /// Sparse polynomial chaos (OMP, K-fold CV).
    Pce,
    /// Gradient × spread at the means.
    Local,
}

/// Arguments of `mte sensitivity`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Method.
    method: Method,
    /// Problem JSON (inputs, model, method settings).
    #[arg(long)]
    problem: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "sensitivity-out")]
    out: PathBuf,
    /// Accept machine test points (`model.points`) outside an axis's stroke (an error
    /// otherwise).
    #[arg(long)]
    allow_outside_stroke: bool,
}

fn lib(e: mte_sensitivity::Error, path: &std::path::Path) -> CliError {
    CliError::Library(format!("{}: {e}", path.display()))
}

fn build_model(v: &Value, k: usize, path: &std::path::Path) -> Result<Box<dyn Model>, CliError> {
    let bad = |m: String| CliError::Library(format!("{}: field `model`: {m}", path.display()));
    let name = v
        .get("name")
        .and_then(Value::as_str)
        .ok_or_else(|| bad("missing `name` (ishigami, gfunction, linear)".into()))?;
    let floats = |f: &str| -> Result<Vec<f64>, CliError> {
        v.get(f)
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .map(|x| {
                        x.as_f64()
                            .ok_or_else(|| bad(format!("`{f}` must hold numbers")))
                    })
                    .collect()
            })
            .unwrap_or_else(|| {
                Err(bad(format!(
                    "`{f}` (array of {k} numbers) is required for `{name}`"
                )))
            })
    };
    match name {
        "ishigami" if k == 3 => Ok(Box::new(Ishigami::default())),
        "ishigami" => Err(bad(format!("ishigami needs 3 inputs, the problem has {k}"))),
        "gfunction" => {
            let a = if v.get("a").is_some() {
                floats("a")?
            } else {
                (0..k).map(|i| i as f64 / 2.0).collect()
            };
            if a.len() != k {
                return Err(bad(format!("`a` has {} values, expected {k}", a.len())));
            }
            Ok(Box::new(GFunction::new(a)))
        }
        "linear" => {
            let c = floats("coef")?;
            if c.len() != k {
                return Err(bad(format!("`coef` has {} values, expected {k}", c.len())));
            }
            Ok(Box::new(Linear::new(c)))
        }
        o => Err(bad(format!(
            "unknown model `{o}`; expected ishigami, gfunction or linear"
        ))),
    }
}

struct Boxed<'a>(&'a dyn Model);
impl Model for Boxed<'_> {
    fn evaluate(&self, x: &[f64], y: &mut [f64]) {
        self.0.evaluate(x, y)
    }
    fn n_outputs(&self) -> usize {
        self.0.n_outputs()
    }
    fn evaluate_batch(&self, n: usize, x: &[f64], y: &mut [f64]) {
        self.0.evaluate_batch(n, x, y)
    }
}

fn params<T: serde::de::DeserializeOwned + Default>(
    v: &Value,
    key: &str,
    path: &std::path::Path,
) -> Result<T, CliError> {
    match v.get(key) {
        None => Ok(T::default()),
        Some(s) => serde_json::from_value(s.clone())
            .map_err(|e| CliError::Library(format!("{}: field `{key}`: {e}", path.display()))),
    }
}

/// Factor from the internal unit (mm, rad) to the one this report uses (µm, arcsec).
fn display_scale(kind: Kind) -> f64 {
    match kind {
        Kind::Length => 1.0 / Unit::Um.to_internal(),
        Kind::Angle => 1.0 / Unit::Arcsec.to_internal(),
    }
}

/// An output is left out when its first-order standard deviation is below this fraction of the
/// largest one (µm and arcsec alike): it has no variance, and every estimator rejects it.
const NO_VARIANCE: f64 = 1e-9;

/// The pose-error model restricted to the outputs with variance, in µm and arcsec.
struct DisplayUnits {
    model: PoseErrorModel,
    /// Output index in the full model and its scale (µm per mm or arcsec per rad).
    keep: Vec<(usize, f64)>,
}

impl Model for DisplayUnits {
    fn evaluate(&self, x: &[f64], y: &mut [f64]) {
        self.evaluate_batch(1, x, y)
    }
    fn n_outputs(&self) -> usize {
        self.keep.len()
    }
    fn evaluate_batch(&self, n: usize, xs: &[f64], ys: &mut [f64]) {
        let m = self.model.n_outputs();
        let mut full = vec![0.0; n * m];
        self.model.evaluate_batch(n, xs, &mut full);
        for (row, out) in full
            .chunks_exact(m)
            .zip(ys.chunks_exact_mut(self.keep.len()))
        {
            for (y, &(o, scale)) in out.iter_mut().zip(&self.keep) {
                *y = row[o] * scale;
            }
        }
    }
}

/// What a machine study adds to the report: the names and directions of the outputs analysed.
struct MachineOutputs {
    /// Name (`p07.PX`), point index and component index of each analysed output.
    outputs: Vec<(String, usize, usize)>,
    /// Outputs left out for having no variance.
    dropped: Vec<String>,
    /// Number of test points.
    n_points: usize,
    /// Description for result.json (machine, error set, points, inputs with their spread).
    info: Value,
}

/// A problem and its model: a test function, or a machine's pose error.
struct Study {
    problem: Problem,
    model: Box<dyn Model>,
    machine: Option<MachineOutputs>,
}

fn field_err(path: &Path, field: &str, m: impl std::fmt::Display) -> CliError {
    CliError::Library(format!("{}: field `{field}`: {m}", path.display()))
}

/// Test points of `model.points`, in mm and rad.
fn parse_points(
    v: Option<&Value>,
    m: &mte_kinematics::Machine,
    dir: &Path,
    path: &Path,
) -> Result<Vec<Vec<f64>>, CliError> {
    let f = "model.points";
    let expected =
        "an array of points (mm, deg in axis order), {\"csv\": FILE} or {\"diagonals\": N}";
    match v {
        Some(Value::Array(a)) => a
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let nums: Option<Vec<f64>> = p
                    .as_array()
                    .and_then(|a| a.iter().map(Value::as_f64).collect());
                nums.map(|n| point_from_mm_deg(m, &n)).ok_or_else(|| {
                    field_err(path, &format!("{f}[{i}]"), "expected an array of numbers")
                })
            })
            .collect(),
        Some(Value::Object(o)) => {
            if let Some(c) = o.get("csv") {
                let file =
                    dir.join(c.as_str().ok_or_else(|| {
                        field_err(path, &format!("{f}.csv"), "expected a file name")
                    })?);
                let text = read_text(&file)?;
                points_from_csv(m, &text, &file.display().to_string())
                    .map_err(|e| field_err(path, &format!("{f}.csv"), e))
            } else if let Some(n) = o.get("diagonals") {
                let n = n.as_u64().ok_or_else(|| {
                    field_err(
                        path,
                        &format!("{f}.diagonals"),
                        "expected a whole number of points per diagonal",
                    )
                })?;
                diagonal_points(m, n as usize)
                    .map_err(|e| field_err(path, &format!("{f}.diagonals"), e))
            } else {
                Err(field_err(path, f, format!("expected {expected}")))
            }
        }
        _ => Err(field_err(
            path,
            f,
            format!("missing or malformed; expected {expected}"),
        )),
    }
}

/// The study of a problem file whose `model` is `{"name": "machine", …}`.
fn machine_study(
    v: &Value,
    mv: &Value,
    path: &Path,
    allow_outside_stroke: bool,
) -> Result<Study, CliError> {
    for key in ["inputs", "correlation"] {
        if v.get(key).is_some() {
            return Err(field_err(
                path,
                key,
                "not allowed with model `machine`: the inputs are the entries of the error set (`model.errors`) that carry a distribution",
            ));
        }
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let text_of = |key: &str| -> Result<&str, CliError> {
        mv.get(key)
            .and_then(Value::as_str)
            .ok_or_else(|| field_err(path, &format!("model.{key}"), "missing; expected a string"))
    };
    let name = text_of("machine")?;
    let machine_arg = if mte_kinematics::Machine::library_names().contains(&name) {
        name.to_string()
    } else {
        dir.join(name).display().to_string()
    };
    let machine =
        super::machine::load(&machine_arg).map_err(|e| field_err(path, "model.machine", e))?;
    let errors_path = dir.join(text_of("errors")?);
    mte::report::check_regular_file(&errors_path)?;
    let set = ErrorSet::from_file(&errors_path).map_err(|e| field_err(path, "model.errors", e))?;
    let mode = match mv.get("linearisation").map(|l| l.as_str()) {
        None | Some(Some("first_order")) => Linearisation::FirstOrder,
        Some(Some("exact")) => Linearisation::Exact,
        _ => {
            return Err(field_err(
                path,
                "model.linearisation",
                "expected \"first_order\" or \"exact\"",
            ));
        }
    };
    let points = parse_points(mv.get("points"), &machine, dir, path)?;
    if !allow_outside_stroke {
        for (i, q) in points.iter().enumerate() {
            for (a, v) in machine.axes().iter().zip(q) {
                let (lo, hi) = a.stroke;
                let tol = 1e-9 * (1.0 + lo.abs().max(hi.abs()));
                if *v < lo - tol || *v > hi + tol {
                    let (f, unit) = match a.kind {
                        AxisKind::Linear => (1.0, "mm"),
                        AxisKind::Rotary => (180.0 / std::f64::consts::PI, "deg"),
                    };
                    return Err(field_err(
                        path,
                        "model.points",
                        format!(
                            "point {} has {} = {} {unit}, outside the stroke [{}, {}] {unit}; pass --allow-outside-stroke to analyse it anyway",
                            i + 1,
                            a.name,
                            v * f,
                            lo * f,
                            hi * f
                        ),
                    ));
                }
            }
        }
    }
    let catalogue = Catalogue::for_machine(&machine);
    let (problem, model) = PoseErrorModel::from_error_set(&machine, &catalogue, &set, points, mode)
        .map_err(|e| match e {
            PoseModelError::PointLength { .. }
            | PoseModelError::NotFinite { .. }
            | PoseModelError::NoPoints => field_err(path, "model.points", e),
            e => field_err(
                path,
                "model.errors",
                format!("{}: {e}", errors_path.display()),
            ),
        })?;
    // Scale of each output and its first-order standard deviation, in µm or arcsec.
    let names = model.output_names();
    let scale = |o: usize| display_scale(if o % 6 < 3 { Kind::Length } else { Kind::Angle });
    let sd: Vec<f64> = (0..model.n_outputs())
        .map(|o| {
            let e = model.effect().row(o);
            let var: f64 = problem
                .inputs()
                .iter()
                .zip(e.iter())
                .map(|(i, a)| (a * i.dist.sd()).powi(2))
                .sum();
            var.sqrt() * scale(o)
        })
        .collect();
    let largest = sd.iter().fold(0.0f64, |a, &b| a.max(b));
    let (kept, dropped): (Vec<usize>, Vec<usize>) =
        (0..sd.len()).partition(|&o| sd[o] > NO_VARIANCE * largest);
    let random = set.random_entries();
    let inputs: Vec<Value> = random
        .iter()
        .zip(problem.inputs())
        .map(|(&i, inp)| {
            let kind = set.entries[i].kind;
            let key = match kind {
                Kind::Length => "sd_um",
                Kind::Angle => "sd_arcsec",
            };
            let f = display_scale(kind);
            serde_json::json!({"name": inp.name, "field": set.entries[i].field, key: inp.dist.sd() * f})
        })
        .collect();
    let axis_keys: Vec<(String, f64)> = machine
        .axes()
        .iter()
        .map(|a| match a.kind {
            AxisKind::Linear => (format!("{}_mm", a.name), 1.0),
            AxisKind::Rotary => (format!("{}_deg", a.name), 180.0 / std::f64::consts::PI),
        })
        .collect();
    let pts: Vec<Value> = model
        .points()
        .iter()
        .enumerate()
        .map(|(p, q)| {
            let mut o = serde_json::Map::new();
            o.insert(
                "point".into(),
                names[6 * p].split('.').next().unwrap_or("").into(),
            );
            for ((k, f), x) in axis_keys.iter().zip(q) {
                o.insert(k.clone(), (x * f).into());
            }
            Value::Object(o)
        })
        .collect();
    let info = serde_json::json!({
        "machine": machine.name(),
        "errors": errors_path.display().to_string(),
        "linearisation": match mode { Linearisation::Exact => "exact", _ => "first_order" },
        "units": "outputs: position in um, orientation in arcsec; indices are dimensionless",
        "inputs": inputs,
        "points": pts,
        "outputs": kept.iter().map(|&o| names[o].clone()).collect::<Vec<_>>(),
        "outputs_without_variance": dropped.iter().map(|&o| names[o].clone()).collect::<Vec<_>>(),
    });
    let n_points = model.points().len();
    let outputs = kept
        .iter()
        .map(|&o| (names[o].clone(), o / 6, o % 6))
        .collect();
    let dropped = dropped.iter().map(|&o| names[o].clone()).collect();
    let model = DisplayUnits {
        keep: kept.iter().map(|&o| (o, scale(o))).collect(),
        model,
    };
    Ok(Study {
        problem,
        model: Box::new(model),
        machine: Some(MachineOutputs {
            outputs,
            dropped,
            n_points,
            info,
        }),
    })
}

fn study(v: &Value, path: &Path, allow_outside_stroke: bool) -> Result<Study, CliError> {
    let mv = v.get("model").unwrap_or(&Value::Null);
    if mv.get("name").and_then(Value::as_str) == Some("machine") {
        return machine_study(v, mv, path, allow_outside_stroke);
    }
    let problem = Problem::from_json(v).map_err(|e| lib(e, path))?;
    let model = build_model(mv, problem.dim(), path)?;
    Ok(Study {
        problem,
        model,
        machine: None,
    })
}

/// One index over outputs: its name, and per output the value and interval of each input.
type OverOutputs = (String, Vec<Vec<f64>>, Vec<Vec<[f64; 2]>>);

/// The rows (S1, ST) of one output of Sobol' or PCE, and its variance (the aggregate's weight).
fn s1_st(
    first: &[f64],
    first_ci: &[[f64; 2]],
    total: &[f64],
    total_ci: &[[f64; 2]],
    variance: f64,
) -> (Vec<IndexRow>, f64) {
    let rows = vec![
        ("S1".to_string(), first.to_vec(), first_ci.to_vec()),
        ("ST".to_string(), total.to_vec(), total_ci.to_vec()),
    ];
    (rows, variance)
}

/// What a PCE reports of its errors (for many outputs, those of the output with the largest
/// error on new inputs), each named for what it is.
fn pce_summary(r: &mte_sensitivity::pce::PceResult) -> String {
    use mte_sensitivity::pce::{LOO_CHECK_FOLDS, Selection};
    let on_new = |o: &mte_sensitivity::pce::PceOutput| {
        o.validation_error
            .unwrap_or(f64::NEG_INFINITY)
            .max(o.selection_aware_error)
    };
    let worst = r
        .outputs
        .iter()
        .max_by(|a, b| on_new(a).total_cmp(&on_new(b)))
        .expect("at least one output");
    let mut s = format!(
        "PCE ({} output{}): degree {}, {} terms of {} candidates, {} model runs",
        r.outputs.len(),
        if r.outputs.len() > 1 {
            "s, the one with the largest error on new inputs shown"
        } else {
            ""
        },
        worst.degree,
        worst.terms.len(),
        r.n_candidates,
        r.n_samples
    );
    let rel = "mean squared error / variance";
    match r.params.selection {
        Selection::KFold { folds } => s.push_str(&format!(
            "\n  selection-aware error {:.3e}: {folds}-fold CV {rel} (the term search repeated in each fold)",
            worst.selection_aware_error
        )),
        Selection::CorrectedLoo => s.push_str(&format!(
            "\n  corrected LOO error {:.3e}: the rule's own score; it does not see the term search\
             \n  selection-aware error {:.3e}: {rel} on held-out runs, the corrected-LOO search repeated in {LOO_CHECK_FOLDS} folds",
            worst.loo_error, worst.selection_aware_error
        )),
    }
    if let (Some(v), Some(e)) = (r.params.validation, worst.validation_error) {
        s.push_str(&format!(
            "\n  validation error {e:.3e}: {rel} on {} fresh model runs",
            v.n
        ));
    }
    s
}

/// Sobol' and PCE: the rows (S1, ST) of each output, weighted by its variance.
fn sobol_like(json: Value, per_output: Vec<(Vec<IndexRow>, f64)>) -> Indices {
    let shares = ["S1", "ST"]
        .iter()
        .enumerate()
        .map(|(j, l)| {
            (
                l.to_string(),
                per_output.iter().map(|(r, _)| r[j].1.clone()).collect(),
                per_output.iter().map(|(r, _)| r[j].2.clone()).collect(),
            )
        })
        .collect();
    let weights = per_output.iter().map(|p| p.1).collect();
    Indices {
        json,
        rows: per_output.into_iter().map(|p| p.0).collect(),
        shares,
        weights,
        warnings: vec![],
    }
}

/// Indices of one method for every output, and what the per-direction aggregate is built from.
struct Indices {
    json: Value,
    /// Per output: (index name, value per input, interval per input or empty).
    rows: Vec<Vec<IndexRow>>,
    /// Per aggregated index: its name, and per output the shares and intervals to weight.
    shares: Vec<OverOutputs>,
    /// Weight of each output: its variance (Sobol', PCE) or the sum of its squared effects.
    weights: Vec<f64>,
    /// What the user must know before reading the indices, one message per output and issue
    /// (printed, and in result.json `warnings`).
    warnings: Vec<String>,
}

impl Study {
    /// How reports name output `o`: `p07.PX` for a machine, `output 2` for a test model with
    /// several outputs, `output` for one.
    fn output_label(&self, o: usize) -> String {
        match &self.machine {
            Some(mo) => format!("output {}", mo.outputs[o].0),
            None if self.model.n_outputs() > 1 => format!("output {}", o + 1),
            None => "output".into(),
        }
    }
}

/// Warns on stderr: every message when there are few, else the first ones and how many more
/// result.json holds.
fn print_warnings(warnings: &[String]) {
    const SHOWN: usize = 4;
    let shown = if warnings.len() <= SHOWN + 1 {
        warnings.len()
    } else {
        SHOWN
    };
    for w in &warnings[..shown] {
        eprintln!("warning: {w}");
    }
    if shown < warnings.len() {
        eprintln!(
            "warning: … and {} more, listed in result.json `warnings`",
            warnings.len() - shown
        );
    }
}

/// The Sobol' warnings: per output and index, the inputs whose interval is wider than the index.
fn sobol_warnings(r: &mte_sensitivity::sobol::SobolResult, st: &Study) -> Vec<String> {
    use mte_sensitivity::sobol::IndexKind;
    let mut out = vec![];
    for (o, ix) in r.outputs.iter().enumerate() {
        let wide = ix.wide();
        for kind in [IndexKind::First, IndexKind::Total] {
            let list: Vec<String> = wide
                .iter()
                .filter(|w| w.index == kind)
                .map(|w| {
                    format!(
                        "{} {:.3} [{:.3}, {:.3}]",
                        r.names[w.input], w.value, w.interval[0], w.interval[1]
                    )
                })
                .collect();
            if !list.is_empty() {
                out.push(format!(
                    "{}: {} interval wider than the index, not resolved from 0 at {} model runs: \
                     {}",
                    st.output_label(o),
                    kind.label(),
                    r.n_model_runs,
                    list.join(", ")
                ));
            }
        }
    }
    out
}

/// Squared effects normalised per output (0 for an output without effect), and their sum: for a linear model with independent
/// inputs, (|aᵢ|σᵢ)² / Σⱼ(|aⱼ|σⱼ)² is the first-order Sobol' index and the sum the variance.
fn squared_shares(effects: &[&Vec<f64>]) -> (Vec<Vec<f64>>, Vec<f64>) {
    effects
        .iter()
        .map(|e| {
            let w: f64 = e.iter().map(|x| x * x).sum();
            let share = |x: &f64| if w > 0.0 { x * x / w } else { 0.0 };
            (e.iter().map(share).collect(), w)
        })
        .unzip()
}

fn analyse(args: &Args, v: &Value, st: &Study, path: &Path) -> Result<Indices, CliError> {
    let model = Boxed(st.model.as_ref());
    let problem = &st.problem;
    Ok(match args.method {
        Method::Sobol => {
            let p: mte_sensitivity::sobol::SobolParams = params(v, "sobol", path)?;
            mte::limits::check_memory(
                &format!(
                    "{}: Sobol' with n = {} over {} inputs and {} outputs",
                    path.display(),
                    p.n,
                    problem.dim(),
                    model.n_outputs()
                ),
                sobol_bytes(&p, problem.dim(), model.n_outputs()),
            )?;
            let total = (p.n * (problem.dim() + 2)) as u64;
            let bar = mte::progress::bar(total, "Sobol' model runs");
            let r = mte_sensitivity::sobol::sobol_with_progress(&model, problem, &p, &|n: u64| {
                bar.inc(n)
            })
            .map_err(|e| lib(e, path))?;
            bar.finish_and_clear();
            let intervals = if p.n_bootstrap > 0 {
                format!(
                    "{:.0} % bootstrap intervals ({} replicates)",
                    100.0 * r.confidence,
                    p.n_bootstrap
                )
            } else {
                "no intervals (n_bootstrap = 0)".into()
            };
            eprintln!(
                "Sobol' ({} output{}): N = {} base samples, {} model runs, {intervals}",
                r.outputs.len(),
                if r.outputs.len() > 1 { "s" } else { "" },
                r.n,
                r.n_model_runs
            );
            let json = serde_json::to_value(&r).expect("serialisable");
            let mut ix = sobol_like(
                json,
                r.outputs
                    .iter()
                    .map(|o| s1_st(&o.first, &o.first_ci, &o.total, &o.total_ci, o.variance))
                    .collect(),
            );
            ix.warnings = sobol_warnings(&r, st);
            ix
        }
        Method::Pce => {
            let p: mte_sensitivity::pce::PceParams = params(v, "pce", path)?;
            mte::limits::check_memory(
                &format!(
                    "{}: PCE of degree {} over {} inputs with {} runs",
                    path.display(),
                    p.degree,
                    problem.dim(),
                    p.n_samples
                ),
                pce_bytes(&p, problem.dim(), model.n_outputs()),
            )?;
            let r =
                mte_sensitivity::pce::build_pce(&model, problem, &p).map_err(|e| lib(e, path))?;
            eprintln!("{}", pce_summary(&r));
            let json = serde_json::to_value(&r).expect("serialisable");
            let mut ix = sobol_like(
                json,
                r.outputs
                    .iter()
                    .map(|o| s1_st(&o.first, &o.first_ci, &o.total, &o.total_ci, o.variance))
                    .collect(),
            );
            ix.warnings = r
                .outputs
                .iter()
                .enumerate()
                .flat_map(|(o, out)| {
                    out.warnings
                        .iter()
                        .map(move |w| format!("{}: {w}", st.output_label(o)))
                })
                .collect();
            ix
        }
        Method::Morris => {
            let p: mte_sensitivity::morris::MorrisParams = params(v, "morris", path)?;
            let (k, m) = (problem.dim() as f64, model.n_outputs() as f64);
            mte::limits::check_memory(
                &format!(
                    "{}: Morris with r = {} over {} inputs",
                    path.display(),
                    p.r,
                    problem.dim()
                ),
                // every trajectory's k + 1 points, their model outputs and elementary effects
                p.r as f64 * (k + 1.0) * (2.0 * k + m) * 8.0,
            )?;
            let r =
                mte_sensitivity::morris::morris(&model, problem, &p).map_err(|e| lib(e, path))?;
            let rows = r
                .outputs
                .iter()
                .map(|o| {
                    vec![
                        (
                            "mu_star".to_string(),
                            o.mu_star.clone(),
                            o.mu_star_ci.clone(),
                        ),
                        ("sigma".to_string(), o.sigma.clone(), vec![]),
                    ]
                })
                .collect();
            let (sh, weights) =
                squared_shares(&r.outputs.iter().map(|o| &o.mu_star).collect::<Vec<_>>());
            Indices {
                json: serde_json::to_value(&r).expect("serialisable"),
                rows,
                shares: vec![("mu_star_share".into(), sh, vec![])],
                weights,
                warnings: vec![],
            }
        }
        Method::Local => {
            let r = mte_sensitivity::local::gradient_spread(&model, problem, 1e-4)
                .map_err(|e| lib(e, path))?;
            let rows = r
                .iter()
                .map(|o| vec![("share".to_string(), o.share.clone(), vec![])])
                .collect();
            let (sh, weights) = squared_shares(&r.iter().map(|o| &o.effect).collect::<Vec<_>>());
            Indices {
                json: serde_json::to_value(&r).expect("serialisable"),
                rows,
                shares: vec![("variance_share".into(), sh, vec![])],
                weights,
                warnings: vec![],
            }
        }
    })
}

fn bars(names: &[String], vals: &[f64], ci: &[[f64; 2]]) -> Vec<Interval> {
    names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let (lo, hi) = ci
                .get(i)
                .map(|c| (c[0].min(vals[i]), c[1].max(vals[i])))
                .unwrap_or((vals[i], vals[i]));
            Interval {
                label: n.clone(),
                value: vals[i],
                low: lo,
                high: hi,
            }
        })
        .collect()
}

/// CSV header cells of the index columns.
fn header(labels: impl Iterator<Item = (String, bool)>) -> String {
    labels
        .map(|(l, ci)| {
            if ci {
                format!(",{l},{l}_low,{l}_high")
            } else {
                format!(",{l}")
            }
        })
        .collect()
}

/// Bytes a Sobol' analysis holds: the Latin-hypercube permutations (n × 2k × 4 bytes, the
/// largest), each thread's block of model runs (inputs and outputs), and the per-block sums.
fn sobol_bytes(p: &mte_sensitivity::sobol::SobolParams, k: usize, m: usize) -> f64 {
    let (n, k, m) = (p.n as f64, k as f64, m as f64);
    let runs_per_row = if p.second_order {
        2.0 * k + 2.0
    } else {
        k + 2.0
    };
    let block = (n / 1024.0).ceil().max(64.0);
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()) as f64;
    let s_len = 4.0
        + 2.0 * k
        + if p.second_order {
            k * (k - 1.0) / 2.0
        } else {
            0.0
        };
    n * 2.0 * k * 4.0 + threads * block * runs_per_row * (k + m) * 8.0 + 1024.0 * m * s_len * 8.0
}

/// Bytes a PCE holds: the candidate basis (total degree: C(k + p, p) terms, an upper bound for
/// q < 1) evaluated at every run, twice (design and Gram work), and the runs themselves.
fn pce_bytes(p: &mte_sensitivity::pce::PceParams, k: usize, m: usize) -> f64 {
    let mut candidates = 1.0f64;
    for i in 1..=p.degree {
        candidates *= (k + i) as f64 / i as f64;
    }
    let n = p.n_samples as f64;
    let validation = p.validation.map_or(0.0, |v| v.n as f64);
    2.0 * 8.0 * n * candidates
        + 8.0 * candidates * k as f64
        + 8.0 * (n + validation) * (k + m) as f64
}

/// Runs the subcommand.
///
/// # Errors
/// Unreadable or invalid problem files (the message names the field), analysis errors, I/O errors.
pub fn run(args: &Args) -> Result<(), CliError> {
    let mut out = OutDir::prepare(&args.out)?;
    let path = &args.problem;
    let v = mte::problem::read_problem(path)?;
    let st = study(&v, path, args.allow_outside_stroke)?;
    let names = st.problem.names();
    let mut ix = analyse(args, &v, &st, path)?;
    print_warnings(&ix.warnings);
    let mut write = |name: &str, s: String| -> Result<(), CliError> {
        out.add(name, s);
        Ok(())
    };
    let Some(mo) = &st.machine else {
        if let Value::Object(o) = &mut ix.json {
            o.insert("warnings".into(), ix.warnings.clone().into());
        }
        write(
            "result.json",
            serde_json::to_string_pretty(&ix.json).expect("json"),
        )?;
        let rows = &ix.rows[0];
        let mut csv = format!(
            "input{}\n",
            header(rows.iter().map(|(l, _, ci)| (l.clone(), !ci.is_empty())))
        );
        for (i, n) in names.iter().enumerate() {
            csv.push_str(n);
            for (_, vals, ci) in rows {
                csv.push_str(&format!(",{}", vals[i]));
                if !ci.is_empty() {
                    csv.push_str(&format!(",{},{}", ci[i][0], ci[i][1]));
                }
            }
            csv.push('\n');
        }
        write("indices.csv", csv)?;
        let (label, vals, ci) = &rows[rows.len().min(2) - 1];
        write(
            "indices.svg",
            error_bar_chart(
                &format!("{:?}: {label}", args.method),
                &Axis::new(label.as_str(), ""),
                &bars(&names, vals, ci),
            )?,
        )?;
        out.commit()?;
        println!(
            "wrote {}/result.json, indices.csv, indices.svg",
            args.out.display()
        );
        return Ok(());
    };
    // Long format: one row per output and input.
    let rows0 = &ix.rows[0];
    let mut csv = format!(
        "output,point,component,unit,input{}\n",
        header(rows0.iter().map(|(l, _, ci)| (l.clone(), !ci.is_empty())))
    );
    for ((oname, p, c), rows) in mo.outputs.iter().zip(&ix.rows) {
        let unit = if *c < 3 { "um" } else { "arcsec" };
        for (i, n) in names.iter().enumerate() {
            csv.push_str(&format!("{oname},{},{},{unit},{n}", p + 1, COMPONENTS[*c]));
            for (_, vals, ci) in rows {
                csv.push_str(&format!(",{}", vals[i]));
                if let Some(c) = ci.get(i) {
                    csv.push_str(&format!(",{},{}", c[0], c[1]));
                }
            }
            csv.push('\n');
        }
    }
    write("indices.csv", csv)?;
    // Per direction: the variance-weighted index over the points.
    let mut agg_json = Vec::new();
    let mut agg_csv = format!(
        "direction,input{}\n",
        header(
            ix.shares
                .iter()
                .map(|(l, _, ci)| (l.clone(), !ci.is_empty()))
        )
    );
    let mut charts = Vec::new();
    for (c, dir) in COMPONENTS.iter().enumerate() {
        let members: Vec<usize> = (0..mo.outputs.len())
            .filter(|&o| mo.outputs[o].2 == c)
            .collect();
        if members.is_empty() {
            continue;
        }
        let per: Vec<(String, Vec<f64>, Vec<[f64; 2]>)> = ix
            .shares
            .iter()
            .filter_map(|(l, vals, ci)| {
                generalised_index(vals, ci, &ix.weights, &members).map(|(a, b)| (l.clone(), a, b))
            })
            .collect();
        if per.len() != ix.shares.len() {
            continue;
        }
        for (i, n) in names.iter().enumerate() {
            agg_csv.push_str(&format!("{dir},{n}"));
            for (_, vals, ci) in &per {
                agg_csv.push_str(&format!(",{}", vals[i]));
                if let Some(c) = ci.get(i) {
                    agg_csv.push_str(&format!(",{},{}", c[0], c[1]));
                }
            }
            agg_csv.push('\n');
        }
        for (l, vals, ci) in &per {
            agg_json.push(serde_json::json!({
                "direction": dir, "index": l, "values": vals, "intervals": ci,
                "n_outputs": members.len(),
            }));
        }
        let (label, vals, ci) = per.last().expect("one index at least");
        let file = format!("aggregate-{dir}.svg");
        write(
            &file,
            error_bar_chart(
                &format!(
                    "{:?}: {label} of {dir}, variance-weighted over {} points",
                    args.method,
                    members.len()
                ),
                &Axis::new(label.as_str(), ""),
                &bars(&names, vals, ci),
            )?,
        )?;
        charts.push(file);
    }
    let json = serde_json::json!({
        "study": mo.info,
        "n_points": mo.n_points,
        "aggregate": {
            "definition": "per direction and input: sum_p V_p S_p / sum_p V_p over the points' outputs of that direction (generalised Sobol index, Gamboa et al. 2014); V_p = output variance (sobol, pce) or sum of squared effects (morris: mu_star, local: |df/dx|·sd, with S_p the normalised squared effect)",
            "interval": "the same weighting of the per-output interval ends (conservative: outputs' errors taken as fully correlated, weights as exact)",
            "indices": agg_json,
        },
        "result": ix.json,
        "warnings": ix.warnings,
    });
    write(
        "result.json",
        serde_json::to_string_pretty(&json).expect("json"),
    )?;
    write("aggregate.csv", agg_csv)?;
    out.commit()?;
    if !mo.dropped.is_empty() {
        eprintln!(
            "left out {} outputs without variance: {}",
            mo.dropped.len(),
            mo.dropped.join(", ")
        );
    }
    println!(
        "wrote {}/result.json, indices.csv ({} outputs × {} inputs), aggregate.csv, {}",
        args.out.display(),
        mo.outputs.len(),
        names.len(),
        charts.join(", ")
    );
    Ok(())
}
