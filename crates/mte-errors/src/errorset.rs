//! Error sets: named error parameters with values or models, and distributions for sampling.
//! JSON form `"format": "mte-errors/1"` (see `docs/formats.md`).

use crate::csv::{CsvTable, UnitColumns};
use crate::distribution::Distribution;
use crate::error::{Error, Result};
use crate::models::{
    Constant, ErrorModel, Fourier, Legendre, Reversal, Sum, Tabulated, ThermalExponential,
    ThermalLinear, ToleranceForm, ToleranceModel,
};
use crate::units::{Kind, Unit, split_suffix};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde_json::{Map, Value};
use std::path::Path;
use std::sync::Arc;

/// The format tag every error-set file carries.
pub const FORMAT: &str = "mte-errors/1";

/// How one parameter's error is computed, before it is bound to a machine axis. All numbers in
/// internal units (mm, rad, s).
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum ModelSpec {
    /// A constant value.
    Constant(f64),
    /// Legendre series; `range` = (low, high) in axis units, `None` = the axis stroke.
    Legendre {
        /// Coefficients of P_0, P_1, ….
        coefficients: Vec<f64>,
        /// Range (mm or rad) and its kind, or the stroke of the axis.
        range: Option<(f64, f64, Kind)>,
    },
    /// Fourier series of period `period` (axis units).
    Fourier {
        /// Constant term.
        offset: f64,
        /// Cosine coefficients of harmonics 1..K.
        cos: Vec<f64>,
        /// Sine coefficients of harmonics 1..K.
        sin: Vec<f64>,
        /// Period (mm or rad).
        period: f64,
        /// Phase origin (mm or rad).
        phase_origin: f64,
        /// Kind of period/phase (length for linear axes, angle for rotary).
        position_kind: Kind,
    },
    /// Seed-000 tolerance model; `stroke`/`origin` default to the axis stroke (mm).
    Tolerance {
        /// Which of eqs 6–11.
        form: ToleranceForm,
        /// Stroke length L (mm), or the axis' stroke.
        stroke: Option<f64>,
        /// Axis coordinate of the start of the stroke (mm), or the axis' stroke start.
        origin: Option<f64>,
    },
    /// A measured table (positions in axis units).
    Table {
        /// Knots (mm or rad), strictly increasing.
        positions: Vec<f64>,
        /// Values (mm or rad).
        values: Vec<f64>,
        /// Kind of the positions.
        position_kind: Kind,
    },
    /// Linear thermal drift.
    ThermalLinear(ThermalLinear),
    /// First-order exponential thermal drift.
    ThermalExponential {
        /// Amplitude (mm or rad).
        amplitude: f64,
        /// Time constant (s).
        tau_s: f64,
        /// Start (s).
        t0_s: f64,
    },
    /// Reversal (backlash) of full span (mm or rad).
    Reversal(f64),
    /// Sum of models.
    Sum(Vec<ModelSpec>),
    /// A model built in code (any [`ErrorModel`]).
    Custom(Arc<dyn ErrorModel>),
}

/// The axis a model is bound to: kind and stroke (mm or rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisInfo {
    /// Length for linear axes, angle for rotary axes.
    pub kind: Kind,
    /// Stroke (min, max).
    pub stroke: (f64, f64),
}

impl ModelSpec {
    /// Build the model for an axis (`None` for parameters that belong to no axis).
    ///
    /// # Errors
    /// [`Error::Unit`] when positions are in the wrong kind of unit for the axis,
    /// [`Error::Invalid`] for bad settings or when a stroke is needed but there is no axis.
    pub fn build(&self, axis: Option<AxisInfo>, field: &str) -> Result<Arc<dyn ErrorModel>> {
        let need_axis = || {
            axis.ok_or_else(|| Error::Invalid {
                what: field.to_string(),
                message: "this model needs an axis range, but the parameter belongs to no axis; give the range explicitly".into(),
            })
        };
        let check_pos = |k: Kind| -> Result<()> {
            if let Some(a) = axis
                && a.kind != k
            {
                return Err(Error::Unit {
                    field: field.to_string(),
                    unit: k.internal_unit().to_string(),
                    message: format!(
                        "positions are given as {k:?} but the axis is {} (use {})",
                        if a.kind == Kind::Length {
                            "linear"
                        } else {
                            "rotary"
                        },
                        if a.kind == Kind::Length {
                            "_mm"
                        } else {
                            "_deg or _rad"
                        }
                    ),
                });
            }
            Ok(())
        };
        let m: Arc<dyn ErrorModel> = match self {
            ModelSpec::Constant(v) => Arc::new(Constant { value: *v }),
            ModelSpec::Legendre {
                coefficients,
                range,
            } => {
                let (lo, hi) = match range {
                    Some((lo, hi, k)) => {
                        check_pos(*k)?;
                        (*lo, *hi)
                    }
                    None => need_axis()?.stroke,
                };
                Arc::new(Legendre::new(coefficients.clone(), lo, hi).map_err(|e| rename(e, field))?)
            }
            ModelSpec::Fourier {
                offset,
                cos,
                sin,
                period,
                phase_origin,
                position_kind,
            } => {
                check_pos(*position_kind)?;
                Arc::new(
                    Fourier::new(*offset, cos.clone(), sin.clone(), *period, *phase_origin)
                        .map_err(|e| rename(e, field))?,
                )
            }
            ModelSpec::Tolerance {
                form,
                stroke,
                origin,
            } => {
                check_pos(Kind::Length)?;
                let (l, o) = match (stroke, origin) {
                    (Some(l), Some(o)) => (*l, *o),
                    _ => {
                        let s = need_axis()?.stroke;
                        (stroke.unwrap_or(s.1 - s.0), origin.unwrap_or(s.0))
                    }
                };
                Arc::new(ToleranceModel::new(*form, l, o).map_err(|e| rename(e, field))?)
            }
            ModelSpec::Table {
                positions,
                values,
                position_kind,
            } => {
                check_pos(*position_kind)?;
                Arc::new(
                    Tabulated::new(positions.clone(), values.clone())
                        .map_err(|e| rename(e, field))?,
                )
            }
            ModelSpec::ThermalLinear(t) => Arc::new(*t),
            ModelSpec::ThermalExponential {
                amplitude,
                tau_s,
                t0_s,
            } => Arc::new(
                ThermalExponential::new(*amplitude, *tau_s, *t0_s).map_err(|e| rename(e, field))?,
            ),
            ModelSpec::Reversal(s) => Arc::new(Reversal { span: *s }),
            ModelSpec::Sum(parts) => {
                let mut built: Vec<Box<dyn ErrorModel>> = Vec::with_capacity(parts.len());
                for (i, p) in parts.iter().enumerate() {
                    built.push(Box::new(ArcModel(
                        p.build(axis, &format!("{field}.terms[{i}]"))?,
                    )));
                }
                Arc::new(Sum::new(built))
            }
            ModelSpec::Custom(m) => m.clone(),
        };
        Ok(m)
    }
}

/// Adapter so an `Arc<dyn ErrorModel>` can sit in a `Box<dyn ErrorModel>`.
#[derive(Debug)]
struct ArcModel(Arc<dyn ErrorModel>);

impl ErrorModel for ArcModel {
    fn value(&self, ctx: &crate::models::Context) -> f64 {
        self.0.value(ctx)
    }
    fn derivative(&self, ctx: &crate::models::Context) -> f64 {
        self.0.derivative(ctx)
    }
    fn n_basis(&self) -> usize {
        self.0.n_basis()
    }
    fn basis(&self, ctx: &crate::models::Context, out: &mut [f64]) {
        self.0.basis(ctx, out)
    }
    fn coefficients(&self) -> Vec<f64> {
        self.0.coefficients()
    }
    fn coefficient_names(&self) -> Vec<String> {
        self.0.coefficient_names()
    }
    fn domain(&self) -> Option<(f64, f64)> {
        self.0.domain()
    }
}

fn rename(e: Error, field: &str) -> Error {
    match e {
        Error::Invalid { what, message } => Error::Invalid {
            what: format!("{field} ({what})"),
            message,
        },
        e => e,
    }
}

/// One named parameter of an error set.
#[derive(Debug, Clone)]
pub struct Entry {
    /// The parameter name as written (ISO name or alias).
    pub name: String,
    /// Where it was defined (`parameters[3]`), for error messages.
    pub field: String,
    /// Kind of the values (length or angle).
    pub kind: Kind,
    /// The key that fixed the unit (`value_um`, `unit`), for unit-mismatch messages.
    pub unit_field: String,
    /// The model (a constant for plain values).
    pub spec: ModelSpec,
    /// Distribution for sampling (its nominal value is the constant when no value is given).
    pub distribution: Option<Distribution>,
}

/// A named set of error parameters.
#[derive(Debug, Clone)]
pub struct ErrorSet {
    /// Name of the set.
    pub name: String,
    /// Free text.
    pub description: String,
    /// Machine the set was written for (informative).
    pub machine: Option<String>,
    /// The parameters, in file order.
    pub entries: Vec<Entry>,
}

struct P<'a> {
    src: &'a str,
    dir: Option<&'a Path>,
}

impl P<'_> {
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Json {
            source_name: self.src.to_string(),
            field: field.into(),
            message: message.into(),
        }
    }
    fn obj<'v>(&self, v: &'v Value, path: &str) -> Result<&'v Map<String, Value>> {
        v.as_object()
            .ok_or_else(|| self.err(path, format!("expected an object, found {}", type_name(v))))
    }
    fn check_keys(&self, m: &Map<String, Value>, path: &str, allowed: &[&str]) -> Result<()> {
        for k in m.keys() {
            let base = k.split_once("_per_").map(|(b, _)| b).unwrap_or(k);
            let base = split_suffix(base).map(|(b, _)| b).unwrap_or(base);
            let base = base
                .strip_suffix("_s")
                .or(base.strip_suffix("_min"))
                .or(base.strip_suffix("_h"))
                .unwrap_or(base);
            if !allowed.contains(&k.as_str()) && !allowed.contains(&base) {
                return Err(self.err(
                    format!("{path}.{k}"),
                    format!("unknown field; expected one of: {}", allowed.join(", ")),
                ));
            }
        }
        Ok(())
    }
    fn number(&self, v: &Value, path: &str) -> Result<f64> {
        match v.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(self.err(
                path,
                format!("expected a finite number, found {}", type_name(v)),
            )),
        }
    }
    fn numbers(&self, v: &Value, path: &str) -> Result<Vec<f64>> {
        let a = v.as_array().ok_or_else(|| {
            self.err(
                path,
                format!("expected an array of numbers, found {}", type_name(v)),
            )
        })?;
        a.iter()
            .enumerate()
            .map(|(i, x)| self.number(x, &format!("{path}[{i}]")))
            .collect()
    }
    fn str<'v>(&self, m: &'v Map<String, Value>, path: &str, key: &str) -> Result<Option<&'v str>> {
        match m.get(key) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(self.err(
                format!("{path}.{key}"),
                format!("expected a string, found {}", type_name(v)),
            )),
        }
    }
    /// Find `base_<unit>` or `base` (+ `unit`): returns (value, unit, key).
    fn quantity<'v>(
        &self,
        m: &'v Map<String, Value>,
        path: &str,
        base: &str,
        default_unit: Option<(Unit, &str)>,
    ) -> Result<Option<(&'v Value, Unit, String)>> {
        let mut found: Option<(&Value, Unit, String)> = None;
        for (k, v) in m {
            let hit = if k == base {
                match default_unit {
                    Some((u, _)) => Some(u),
                    None => {
                        return Err(self.err(
                            format!("{path}.{k}"),
                            format!("no unit: write `{base}_um`, `{base}_urad`, … or give a `unit` field"),
                        ));
                    }
                }
            } else {
                match split_suffix(k) {
                    Some((b, u)) if b == base => Some(u),
                    _ => None,
                }
            };
            if let Some(u) = hit {
                if let Some((_, _, prev)) = &found {
                    return Err(self.err(
                        format!("{path}.{k}"),
                        format!("given twice (also `{prev}`)"),
                    ));
                }
                found = Some((v, u, format!("{path}.{k}")));
            }
        }
        Ok(found)
    }
    fn time(&self, m: &Map<String, Value>, path: &str, base: &str) -> Result<Option<f64>> {
        let mut out = None;
        for (suf, f) in [("s", 1.0), ("min", 60.0), ("h", 3600.0)] {
            let k = format!("{base}_{suf}");
            if let Some(v) = m.get(&k) {
                if out.is_some() {
                    return Err(self.err(format!("{path}.{k}"), format!("`{base}` given twice")));
                }
                out = Some(self.number(v, &format!("{path}.{k}"))? * f);
            }
        }
        Ok(out)
    }
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// Tracks the one value kind of a parameter across its fields.
struct KindTracker {
    kind: Option<(Kind, String)>,
}

fn kind_units(k: Kind) -> &'static str {
    match k {
        Kind::Length => "mm, um, nm",
        Kind::Angle => "rad, mrad, urad, arcsec, deg",
    }
}

impl KindTracker {
    fn see(&mut self, u: Unit, key: &str) -> Result<f64> {
        if let Some((k, prev)) = &self.kind
            && *k != u.kind()
        {
            return Err(Error::Unit {
                field: key.to_string(),
                unit: u.suffix().to_string(),
                message: format!(
                    "unit mismatch: `{prev}` makes this parameter a {k:?} ({}), but `{}` is a unit of {:?}",
                    kind_units(*k),
                    u.suffix(),
                    u.kind()
                ),
            });
        }
        if self.kind.is_none() {
            self.kind = Some((u.kind(), key.to_string()));
        }
        Ok(u.to_internal())
    }
}

impl ErrorSet {
    /// An empty set.
    pub fn new(name: &str) -> ErrorSet {
        ErrorSet {
            name: name.to_string(),
            description: String::new(),
            machine: None,
            entries: Vec::new(),
        }
    }

    /// Add a constant parameter (value in mm or rad).
    pub fn with_constant(mut self, name: &str, value: f64, kind: Kind) -> ErrorSet {
        let field = format!("parameters[{}]", self.entries.len());
        self.entries.push(Entry {
            name: name.to_string(),
            field,
            kind,
            unit_field: kind.internal_unit().to_string(),
            spec: ModelSpec::Constant(value),
            distribution: None,
        });
        self
    }

    /// Add a parameter with a model (values in mm or rad).
    pub fn with_model(mut self, name: &str, spec: ModelSpec, kind: Kind) -> ErrorSet {
        let field = format!("parameters[{}]", self.entries.len());
        self.entries.push(Entry {
            name: name.to_string(),
            field,
            kind,
            unit_field: kind.internal_unit().to_string(),
            spec,
            distribution: None,
        });
        self
    }

    /// Add a parameter drawn from a distribution (internal units); its nominal value is the
    /// distribution's nominal.
    pub fn with_distribution(mut self, name: &str, d: Distribution, kind: Kind) -> ErrorSet {
        let field = format!("parameters[{}]", self.entries.len());
        self.entries.push(Entry {
            name: name.to_string(),
            field,
            kind,
            unit_field: kind.internal_unit().to_string(),
            spec: ModelSpec::Constant(d.nominal()),
            distribution: Some(d),
        });
        self
    }

    /// Parse the JSON form. Table files named in the set are read relative to `base_dir`.
    ///
    /// # Errors
    /// [`Error::Json`] naming the field (wrong type, unknown field, missing value, bad format
    /// tag), [`Error::Unit`] for unknown units or a parameter mixing lengths and angles,
    /// [`Error::Csv`] for bad table files, [`Error::Invalid`] for invalid model settings.
    pub fn from_json_str(
        text: &str,
        source_name: &str,
        base_dir: Option<&Path>,
    ) -> Result<ErrorSet> {
        let p = P {
            src: source_name,
            dir: base_dir,
        };
        let root: Value = serde_json::from_str(text).map_err(|e| {
            p.err(
                format!("(line {}, column {})", e.line(), e.column()),
                e.to_string(),
            )
        })?;
        let m = p.obj(&root, "(root)")?;
        p.check_keys(
            m,
            "(root)",
            &[
                "format",
                "name",
                "description",
                "machine",
                "parameters",
                "note",
            ],
        )
        .map_err(strip_root)?;
        match m.get("format") {
            Some(Value::String(f)) if f == FORMAT => {}
            Some(v) => return Err(p.err("format", format!("expected \"{FORMAT}\", found {v}"))),
            None => return Err(p.err("format", format!("missing (expected \"{FORMAT}\")"))),
        }
        let name = p
            .str(m, "", "name")
            .map_err(strip_root)?
            .unwrap_or(source_name)
            .to_string();
        let description = p
            .str(m, "", "description")
            .map_err(strip_root)?
            .unwrap_or("")
            .to_string();
        let machine = p
            .str(m, "", "machine")
            .map_err(strip_root)?
            .map(str::to_string);
        let params = match m.get("parameters") {
            Some(Value::Array(a)) => a,
            Some(v) => {
                return Err(p.err(
                    "parameters",
                    format!("expected an array, found {}", type_name(v)),
                ));
            }
            None => return Err(p.err("parameters", "missing (expected an array of parameters)")),
        };
        let mut entries = Vec::with_capacity(params.len());
        for (i, v) in params.iter().enumerate() {
            let e = parse_entry(&p, v, &format!("parameters[{i}]"))?;
            if let Some(prev) = entries.iter().find(|x: &&Entry| x.name == e.name) {
                return Err(p.err(
                    format!("parameters[{i}].name"),
                    format!(
                        "parameter `{}` is given twice (also {})",
                        e.name, prev.field
                    ),
                ));
            }
            entries.push(e);
        }
        Ok(ErrorSet {
            name,
            description,
            machine,
            entries,
        })
    }

    /// Read and parse a file (tables relative to its directory).
    ///
    /// # Errors
    /// [`Error::Io`] when the file cannot be read, else as [`ErrorSet::from_json_str`].
    pub fn from_file(path: &Path) -> Result<ErrorSet> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        ErrorSet::from_json_str(&text, &path.display().to_string(), path.parent())
    }

    /// Entries that have a distribution, in order (the columns of a sample matrix).
    pub fn random_entries(&self) -> Vec<usize> {
        (0..self.entries.len())
            .filter(|&i| self.entries[i].distribution.is_some())
            .collect()
    }

    /// Draw sample number `index` of the random parameters (internal units, in the order of
    /// [`ErrorSet::random_entries`]). The stream of sample `index` is ChaCha8 seeded with `seed`
    /// on stream `index`, so a sample does not depend on which thread draws it.
    pub fn sample_values(&self, seed: u64, index: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(index);
        self.entries
            .iter()
            .filter_map(|e| e.distribution.as_ref())
            .map(|d| d.sample(&mut rng))
            .collect()
    }

    /// `n` samples (rows) of the random parameters, drawn in parallel; identical for any number
    /// of threads.
    pub fn sample_matrix(&self, seed: u64, n: usize) -> Vec<Vec<f64>> {
        (0..n as u64)
            .into_par_iter()
            .map(|i| self.sample_values(seed, i))
            .collect()
    }

    /// This set with each random parameter replaced by the constant of sample `index`.
    pub fn sample(&self, seed: u64, index: u64) -> ErrorSet {
        self.with_values(&self.sample_values(seed, index))
    }

    /// This set with the random parameters (in [`ErrorSet::random_entries`] order) set to
    /// `values` (internal units).
    ///
    /// # Panics
    /// When `values.len()` differs from the number of random parameters (caller contract).
    pub fn with_values(&self, values: &[f64]) -> ErrorSet {
        let idx = self.random_entries();
        assert_eq!(values.len(), idx.len(), "one value per random parameter");
        let mut s = self.clone();
        for (k, &i) in idx.iter().enumerate() {
            s.entries[i].spec = ModelSpec::Constant(values[k]);
        }
        s
    }
}

fn strip_root(e: Error) -> Error {
    match e {
        Error::Json {
            source_name,
            field,
            message,
        } => Error::Json {
            source_name,
            field: field
                .trim_start_matches("(root)")
                .trim_start_matches('.')
                .to_string(),
            message,
        },
        e => e,
    }
}

fn parse_entry(p: &P, v: &Value, path: &str) -> Result<Entry> {
    let m = p.obj(v, path)?;
    p.check_keys(
        m,
        path,
        &["name", "unit", "value", "model", "distribution", "note"],
    )?;
    let name = p
        .str(m, path, "name")?
        .ok_or_else(|| p.err(format!("{path}.name"), "missing parameter name"))?
        .to_string();
    let path = format!("{path} ({name})");
    let default_unit = match p.str(m, &path, "unit")? {
        Some(u) => Some((Unit::parse(u, &format!("{path}.unit"))?, "unit")),
        None => None,
    };
    let mut kt = KindTracker {
        kind: default_unit.map(|(u, _)| (u.kind(), format!("{path}.unit = \"{}\"", u.suffix()))),
    };
    let value = p.quantity(m, &path, "value", default_unit)?;
    let model = m.get("model");
    let distribution = match m.get("distribution") {
        Some(d) => Some(parse_distribution(
            p,
            d,
            &format!("{path}.distribution"),
            default_unit,
            &mut kt,
        )?),
        None => None,
    };
    let spec = match (value, model) {
        (Some(_), Some(_)) => {
            return Err(p.err(
                format!("{path}.model"),
                "give either a value or a model, not both",
            ));
        }
        (Some((v, u, key)), None) => {
            let f = kt.see(u, &key)?;
            ModelSpec::Constant(p.number(v, &key)? * f)
        }
        (None, Some(mv)) => {
            if distribution.is_some() {
                return Err(p.err(
                    format!("{path}.distribution"),
                    "a distribution applies to a constant value; a parameter with a model cannot have one",
                ));
            }
            parse_model(p, mv, &format!("{path}.model"), default_unit, &mut kt)?
        }
        (None, None) => match &distribution {
            Some(d) => ModelSpec::Constant(d.nominal()),
            None => {
                return Err(p.err(
                    path.clone(),
                    "needs `value_<unit>`, `model` or `distribution`",
                ));
            }
        },
    };
    let (kind, unit_field) = kt
        .kind
        .ok_or_else(|| p.err(path.clone(), "no unit anywhere in this parameter"))?;
    Ok(Entry {
        name,
        field: path,
        kind,
        unit_field,
        spec,
        distribution,
    })
}

fn parse_distribution(
    p: &P,
    v: &Value,
    path: &str,
    du: Option<(Unit, &str)>,
    kt: &mut KindTracker,
) -> Result<Distribution> {
    let m = p.obj(v, path)?;
    let ty = p.str(m, path, "type")?.ok_or_else(|| {
        p.err(
            format!("{path}.type"),
            "missing (normal, uniform, truncated_normal or tolerance)",
        )
    })?;
    let mut q = |base: &str, required: bool| -> Result<Option<f64>> {
        match p.quantity(m, path, base, du)? {
            Some((v, u, key)) => {
                let f = kt.see(u, &key)?;
                Ok(Some(p.number(v, &key)? * f))
            }
            None if required => Err(p.err(
                format!("{path}.{base}_<unit>"),
                format!("missing `{base}` (e.g. `{base}_um`)"),
            )),
            None => Ok(None),
        }
    };
    let d = match ty {
        "normal" => {
            p.check_keys(m, path, &["type", "mean", "sd"])?;
            Distribution::Normal {
                mean: q("mean", false)?.unwrap_or(0.0),
                sd: q("sd", true)?.unwrap_or(0.0),
            }
        }
        "uniform" => {
            p.check_keys(m, path, &["type", "low", "high"])?;
            Distribution::Uniform {
                lo: q("low", true)?.unwrap_or(0.0),
                hi: q("high", true)?.unwrap_or(0.0),
            }
        }
        "truncated_normal" => {
            p.check_keys(m, path, &["type", "mean", "sd", "low", "high"])?;
            Distribution::TruncatedNormal {
                mean: q("mean", false)?.unwrap_or(0.0),
                sd: q("sd", true)?.unwrap_or(0.0),
                lo: q("low", true)?.unwrap_or(0.0),
                hi: q("high", true)?.unwrap_or(0.0),
            }
        }
        "tolerance" => {
            p.check_keys(m, path, &["type", "tolerance", "sigma_level", "truncate"])?;
            let t = q("tolerance", true)?.unwrap_or(0.0);
            let k = match m.get("sigma_level") {
                Some(v) => p.number(v, &format!("{path}.sigma_level"))?,
                None => 3.0,
            };
            let tr = match m.get("truncate") {
                None => false,
                Some(Value::Bool(b)) => *b,
                Some(v) => {
                    return Err(p.err(
                        format!("{path}.truncate"),
                        format!("expected true or false, found {}", type_name(v)),
                    ));
                }
            };
            crate::distribution::from_tolerance(t, k, tr).map_err(|e| rename(e, path))?
        }
        other => {
            return Err(p.err(
                format!("{path}.type"),
                format!(
                    "unknown distribution `{other}` (normal, uniform, truncated_normal, tolerance)"
                ),
            ));
        }
    };
    crate::distribution::validate(&d, ty).map_err(|e| rename(e, path))?;
    Ok(d)
}

/// Position-like quantity (mm / deg / rad): returns internal value(s) and kind.
fn position_q<'v>(
    p: &P,
    m: &'v Map<String, Value>,
    path: &str,
    base: &str,
) -> Result<Option<(&'v Value, Unit, String)>> {
    p.quantity(m, path, base, None)
}

fn parse_model(
    p: &P,
    v: &Value,
    path: &str,
    du: Option<(Unit, &str)>,
    kt: &mut KindTracker,
) -> Result<ModelSpec> {
    let m = p.obj(v, path)?;
    let ty = p.str(m, path, "type")?.ok_or_else(|| {
        p.err(
            format!("{path}.type"),
            "missing (constant, legendre, fourier, tolerance, table, thermal_linear, thermal_exponential, reversal, sum)",
        )
    })?;
    let val = |base: &str, kt: &mut KindTracker| -> Result<Option<(Vec<f64>, bool)>> {
        match p.quantity(m, path, base, du)? {
            Some((v, u, key)) => {
                let f = kt.see(u, &key)?;
                if v.is_array() {
                    Ok(Some((
                        p.numbers(v, &key)?.into_iter().map(|x| x * f).collect(),
                        true,
                    )))
                } else {
                    Ok(Some((vec![p.number(v, &key)? * f], false)))
                }
            }
            None => Ok(None),
        }
    };
    let missing = |base: &str| {
        p.err(
            format!("{path}.{base}_<unit>"),
            format!("missing `{base}` (e.g. `{base}_um`)"),
        )
    };
    let scalar = |x: Option<(Vec<f64>, bool)>, base: &str| -> Result<Option<f64>> {
        match x {
            None => Ok(None),
            Some((v, false)) => Ok(Some(v[0])),
            Some(_) => Err(p.err(
                format!("{path}.{base}"),
                "expected a number, found an array",
            )),
        }
    };
    let array = |x: Option<(Vec<f64>, bool)>, base: &str| -> Result<Option<Vec<f64>>> {
        match x {
            None => Ok(None),
            Some((v, true)) => Ok(Some(v)),
            Some(_) => Err(p.err(format!("{path}.{base}"), "expected an array of numbers")),
        }
    };
    let pos_scalar = |base: &str| -> Result<Option<(f64, Kind)>> {
        match position_q(p, m, path, base)? {
            Some((v, u, key)) => Ok(Some((p.number(v, &key)? * u.to_internal(), u.kind()))),
            None => Ok(None),
        }
    };
    let spec = match ty {
        "constant" => {
            p.check_keys(m, path, &["type", "value"])?;
            ModelSpec::Constant(
                scalar(val("value", kt)?, "value")?.ok_or_else(|| missing("value"))?,
            )
        }
        "legendre" => {
            p.check_keys(m, path, &["type", "coefficients", "range"])?;
            let c = array(val("coefficients", kt)?, "coefficients")?
                .ok_or_else(|| missing("coefficients"))?;
            let range = match position_q(p, m, path, "range")? {
                Some((v, u, key)) => {
                    let r = p.numbers(v, &key)?;
                    if r.len() != 2 {
                        return Err(p.err(key, "expected [low, high]"));
                    }
                    Some((r[0] * u.to_internal(), r[1] * u.to_internal(), u.kind()))
                }
                None => None,
            };
            ModelSpec::Legendre {
                coefficients: c,
                range,
            }
        }
        "fourier" => {
            p.check_keys(
                m,
                path,
                &["type", "offset", "cos", "sin", "period", "phase_origin"],
            )?;
            let offset = scalar(val("offset", kt)?, "offset")?.unwrap_or(0.0);
            let cos = array(val("cos", kt)?, "cos")?.unwrap_or_default();
            let sin = array(val("sin", kt)?, "sin")?.unwrap_or_default();
            if cos.is_empty() && sin.is_empty() && kt.kind.is_none() {
                return Err(missing("cos"));
            }
            let (period, pk) = pos_scalar("period")?.ok_or_else(|| {
                p.err(
                    format!("{path}.period_<unit>"),
                    "missing `period` (e.g. `period_mm`)",
                )
            })?;
            let phase = match pos_scalar("phase_origin")? {
                Some((x, k)) if k == pk => x,
                Some(_) => {
                    return Err(p.err(
                        format!("{path}.phase_origin"),
                        "phase origin and period must both be lengths or both angles",
                    ));
                }
                None => 0.0,
            };
            ModelSpec::Fourier {
                offset,
                cos,
                sin,
                period,
                phase_origin: phase,
                position_kind: pk,
            }
        }
        "tolerance" => parse_tolerance(p, m, path, kt)?,
        "table" => {
            p.check_keys(
                m,
                path,
                &[
                    "type",
                    "file",
                    "position_column",
                    "value_column",
                    "positions",
                    "values",
                ],
            )?;
            if let Some(file) = p.str(m, path, "file")? {
                let full = match p.dir {
                    Some(d) => d.join(file),
                    None => Path::new(file).to_path_buf(),
                };
                let text = std::fs::read_to_string(&full).map_err(|e| Error::Io {
                    path: full.display().to_string(),
                    message: e.to_string(),
                })?;
                let pc = p.str(m, path, "position_column")?.unwrap_or("position");
                let vc = p.str(m, path, "value_column")?.unwrap_or("error");
                let t = CsvTable::parse(&text, &full.display().to_string())?;
                let (pci, pu) = t.require_with_unit(pc, &format!("{pc}_mm"))?;
                let (vci, vu) = t.require_with_unit(vc, &format!("{vc}_um"))?;
                kt.see(
                    vu,
                    &format!("{}: column `{}`", full.display(), t.headers[vci]),
                )?;
                let _ = pci;
                let tab = Tabulated::from_csv(
                    &text,
                    &full.display().to_string(),
                    pc,
                    vc,
                    vu.kind(),
                    None,
                )?;
                ModelSpec::Table {
                    positions: tab.positions().to_vec(),
                    values: tab.values().to_vec(),
                    position_kind: pu.kind(),
                }
            } else {
                let values =
                    array(val("values", kt)?, "values")?.ok_or_else(|| missing("values"))?;
                let (pv, pu, key) = position_q(p, m, path, "positions")?.ok_or_else(|| {
                    p.err(
                        format!("{path}.positions_<unit>"),
                        "missing `positions` (e.g. `positions_mm`) or `file`",
                    )
                })?;
                let positions: Vec<f64> = p
                    .numbers(pv, &key)?
                    .into_iter()
                    .map(|x| x * pu.to_internal())
                    .collect();
                if let Some(i) = (1..positions.len()).find(|&i| positions[i] <= positions[i - 1]) {
                    return Err(p.err(format!("{key}[{i}]"), "positions must strictly increase"));
                }
                if positions.len() != values.len() {
                    return Err(p.err(
                        key,
                        format!("{} positions but {} values", positions.len(), values.len()),
                    ));
                }
                ModelSpec::Table {
                    positions,
                    values,
                    position_kind: pu.kind(),
                }
            }
        }
        "thermal_linear" => {
            p.check_keys(m, path, &["type", "rate", "t0"])?;
            let mut rate = None;
            for (k, v) in m {
                if let Some((b, per)) = k.split_once("_per_")
                    && let Some((base, u)) = split_suffix(b)
                    && base == "rate"
                {
                    let f = match per {
                        "s" => 1.0,
                        "min" => 1.0 / 60.0,
                        "h" => 1.0 / 3600.0,
                        _ => {
                            return Err(p.err(
                                format!("{path}.{k}"),
                                "rate must be per s, per min or per h",
                            ));
                        }
                    };
                    let key = format!("{path}.{k}");
                    let uf = kt.see(u, &key)?;
                    rate = Some(p.number(v, &key)? * uf * f);
                }
            }
            let rate = rate.ok_or_else(|| {
                p.err(
                    format!("{path}.rate"),
                    "missing `rate_<unit>_per_<s|min|h>` (e.g. `rate_um_per_h`)",
                )
            })?;
            ModelSpec::ThermalLinear(ThermalLinear {
                rate_per_s: rate,
                t0_s: p.time(m, path, "t0")?.unwrap_or(0.0),
            })
        }
        "thermal_exponential" => {
            p.check_keys(m, path, &["type", "amplitude", "tau", "t0"])?;
            let a =
                scalar(val("amplitude", kt)?, "amplitude")?.ok_or_else(|| missing("amplitude"))?;
            let tau = p.time(m, path, "tau")?.ok_or_else(|| {
                p.err(
                    format!("{path}.tau_s"),
                    "missing `tau_s` (or tau_min, tau_h)",
                )
            })?;
            ModelSpec::ThermalExponential {
                amplitude: a,
                tau_s: tau,
                t0_s: p.time(m, path, "t0")?.unwrap_or(0.0),
            }
        }
        "reversal" => {
            p.check_keys(m, path, &["type", "span"])?;
            ModelSpec::Reversal(scalar(val("span", kt)?, "span")?.ok_or_else(|| missing("span"))?)
        }
        "sum" => {
            p.check_keys(m, path, &["type", "terms"])?;
            let terms = m
                .get("terms")
                .and_then(Value::as_array)
                .ok_or_else(|| p.err(format!("{path}.terms"), "expected an array of models"))?;
            let mut parts = Vec::with_capacity(terms.len());
            for (i, t) in terms.iter().enumerate() {
                parts.push(parse_model(p, t, &format!("{path}.terms[{i}]"), du, kt)?);
            }
            ModelSpec::Sum(parts)
        }
        other => {
            return Err(p.err(
                format!("{path}.type"),
                format!(
                    "unknown model `{other}` (constant, legendre, fourier, tolerance, table, thermal_linear, thermal_exponential, reversal, sum)"
                ),
            ));
        }
    };
    Ok(spec)
}

fn parse_tolerance(
    p: &P,
    m: &Map<String, Value>,
    path: &str,
    kt: &mut KindTracker,
) -> Result<ModelSpec> {
    p.check_keys(
        m,
        path,
        &[
            "type",
            "form",
            "tolerance",
            "half_waves",
            "scale",
            "carriage_spacing",
            "rail_spacing",
            "sign",
            "stroke",
            "origin",
        ],
    )?;
    let form = p.str(m, path, "form")?.ok_or_else(|| {
        p.err(
            format!("{path}.form"),
            "missing (straightness, positioning, carriage_difference, twist)",
        )
    })?;
    let len = |base: &str, required: bool| -> Result<Option<f64>> {
        match p.quantity(m, path, base, None)? {
            Some((v, u, key)) => {
                u.expect_kind(Kind::Length, &key)?;
                Ok(Some(p.number(v, &key)? * u.to_internal()))
            }
            None if required => Err(p.err(
                format!("{path}.{base}_<unit>"),
                format!("missing `{base}` (e.g. `{base}_um` or `{base}_mm`)"),
            )),
            None => Ok(None),
        }
    };
    let k = len("tolerance", true)?.unwrap_or(0.0);
    let n = match m.get("half_waves") {
        None => 1,
        Some(v) => {
            let x = p.number(v, &format!("{path}.half_waves"))?;
            if x.fract() != 0.0 || !(1.0..=8.0).contains(&x) {
                return Err(p.err(
                    format!("{path}.half_waves"),
                    format!("expected an integer in 1..=8, found {x}"),
                ));
            }
            x as u32
        }
    };
    let out_kind = |kind: Kind, kt: &mut KindTracker| -> Result<()> {
        kt.see(
            if kind == Kind::Length {
                Unit::Mm
            } else {
                Unit::Rad
            },
            &format!("{path}.form ({form})"),
        )
        .map(|_| ())
    };
    let f = match form {
        "straightness" => {
            out_kind(Kind::Length, kt)?;
            ToleranceForm::Straightness {
                tolerance: k,
                half_waves: n,
            }
        }
        "positioning" => {
            out_kind(Kind::Length, kt)?;
            ToleranceForm::Positioning {
                tolerance: k,
                half_waves: n,
                scale: len("scale", false)?.unwrap_or(0.0),
            }
        }
        "carriage_difference" => {
            out_kind(Kind::Angle, kt)?;
            let sign = match m.get("sign") {
                None => 1.0,
                Some(v) => p.number(v, &format!("{path}.sign"))?,
            };
            ToleranceForm::CarriageDifference {
                tolerance: k,
                half_waves: n,
                carriage_spacing: len("carriage_spacing", true)?.unwrap_or(0.0),
                sign,
            }
        }
        "twist" => {
            out_kind(Kind::Angle, kt)?;
            ToleranceForm::Twist {
                tolerance: k,
                half_waves: n,
                rail_spacing: len("rail_spacing", true)?.unwrap_or(0.0),
            }
        }
        other => {
            return Err(p.err(
                format!("{path}.form"),
                format!(
                    "unknown form `{other}` (straightness, positioning, carriage_difference, twist)"
                ),
            ));
        }
    };
    Ok(ModelSpec::Tolerance {
        form: f,
        stroke: len("stroke", false)?,
        origin: len("origin", false)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::Context;
    use approx::assert_relative_eq;

    const SET: &str = r#"{
      "format": "mte-errors/1",
      "name": "demo",
      "parameters": [
        {"name": "EXX", "value_um": 5},
        {"name": "EC0Y", "unit": "arcsec", "value": 2},
        {"name": "EBX", "unit": "urad", "model": {"type": "legendre", "coefficients": [0, 3, 1]}},
        {"name": "EYY", "model": {"type": "fourier", "period_mm": 10, "cos_um": [1.0], "sin_um": [0.5]}},
        {"name": "EZY", "model": {"type": "tolerance", "form": "straightness", "tolerance_um": 20, "half_waves": 2}},
        {"name": "EXZ", "model": {"type": "sum", "terms": [
            {"type": "reversal", "span_um": 3},
            {"type": "thermal_linear", "rate_um_per_h": 3.6},
            {"type": "thermal_exponential", "amplitude_um": 10, "tau_min": 10}]}},
        {"name": "EYX", "model": {"type": "table", "positions_mm": [0, 100, 200], "values_um": [0, 1, 3]}},
        {"name": "EAX", "distribution": {"type": "tolerance", "tolerance_arcsec": 10, "sigma_level": 3}},
        {"name": "EZX", "value_um": 1, "distribution": {"type": "uniform", "low_um": -15, "high_um": 15}}
      ]
    }"#;

    fn build(e: &Entry) -> Arc<dyn ErrorModel> {
        e.spec
            .build(
                Some(AxisInfo {
                    kind: Kind::Length,
                    stroke: (0.0, 400.0),
                }),
                &e.field,
            )
            .unwrap()
    }

    #[test]
    fn parses_units_and_models() {
        let s = ErrorSet::from_json_str(SET, "demo.json", None).unwrap();
        assert_eq!(s.entries.len(), 9);
        let c = Context::at(100.0);
        assert_relative_eq!(build(&s.entries[0]).value(&c), 5e-3, epsilon = 1e-18);
        assert_eq!(s.entries[1].kind, Kind::Angle);
        assert_relative_eq!(
            build(&s.entries[1]).value(&c),
            2.0 * std::f64::consts::PI / 648000.0,
            epsilon = 1e-18
        );
        // Legendre over the stroke [0, 400]: u(100) = −0.5: 3·(−0.5) + (3·0.25 − 1)/2 = −1.625 µrad.
        assert_relative_eq!(build(&s.entries[2]).value(&c), -1.625e-6, epsilon = 1e-18);
        // Tolerance default stroke = 400 mm: (0.020/2)·sin(2π·100/400) = 0.010 mm.
        assert_relative_eq!(build(&s.entries[4]).value(&c), 0.010, epsilon = 1e-15);
        // Sum at t = 600 s moving +: 1.5 µm + 3.6 µm/h·600 s = 0.6 µm + 10(1 − e^{−1}) µm.
        let ctx = Context {
            position: 0.0,
            time_s: 600.0,
            direction: crate::models::Direction::Positive,
        };
        let want = 1.5e-3 + 0.6e-3 + 10e-3 * (1.0 - (-1.0f64).exp());
        assert_relative_eq!(build(&s.entries[5]).value(&ctx), want, epsilon = 1e-15);
        assert_relative_eq!(
            build(&s.entries[6]).value(&Context::at(150.0)),
            2e-3,
            epsilon = 1e-15
        );
        // ±10″ at 3σ → sd = 10/3 arcsec; nominal 0.
        let d = s.entries[7].distribution.unwrap();
        assert_relative_eq!(
            d.sd(),
            10.0 / 3.0 * std::f64::consts::PI / 648000.0,
            epsilon = 1e-18
        );
        assert_eq!(s.random_entries(), vec![7, 8]);
        // A value and a distribution: the value is the nominal.
        assert_relative_eq!(build(&s.entries[8]).value(&c), 1e-3, epsilon = 1e-18);
    }

    #[test]
    fn sampling_is_seeded_and_thread_independent() {
        let s = ErrorSet::from_json_str(SET, "demo.json", None).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| s.sample_matrix(42, 200));
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
            .install(|| s.sample_matrix(42, 200));
        assert_eq!(one, two);
        assert_eq!(one[17], s.sample_values(42, 17));
        assert_ne!(one[0], one[1]);
        assert_ne!(s.sample_matrix(43, 1)[0], one[0]);
        let drawn = s.sample(42, 3);
        match drawn.entries[8].spec {
            ModelSpec::Constant(v) => assert_eq!(v, one[3][1]),
            _ => panic!("expected a constant"),
        }
        assert!(one.iter().all(|r| r[1].abs() <= 15e-3));
    }

    fn err_of(json: &str) -> String {
        ErrorSet::from_json_str(json, "bad.json", None)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn bad_json_names_the_field() {
        let wrap = |p: &str| format!(r#"{{"format": "mte-errors/1", "parameters": [{p}]}}"#);
        let e = err_of(&wrap(r#"{"name": "EXX", "value_um": 5, "unit": "urad"}"#));
        assert!(
            e.contains("EXX") && e.contains("unit mismatch") && e.contains("urad"),
            "{e}"
        );
        let e = err_of(&wrap(r#"{"name": "EXX", "value": 5}"#));
        assert!(
            e.contains("parameters[0] (EXX).value") && e.contains("no unit"),
            "{e}"
        );
        let e = err_of(&wrap(r#"{"name": "EXX", "value_inch": 5}"#));
        assert!(
            e.contains("value_inch") && e.contains("unknown field"),
            "{e}"
        );
        let e = err_of(&wrap(r#"{"name": "EXX", "value_um": "five"}"#));
        assert!(e.contains("value_um") && e.contains("finite number"), "{e}");
        let e = err_of(&wrap(r#"{"name": "EXX", "model": {"type": "spline"}}"#));
        assert!(e.contains("model.type") && e.contains("spline"), "{e}");
        let e = err_of(&wrap(
            r#"{"name": "EXX", "model": {"type": "table", "positions_mm": [0, 5, 5], "values_um": [0, 1, 2]}}"#,
        ));
        assert!(
            e.contains("positions_mm[2]") && e.contains("increase"),
            "{e}"
        );
        // A range in degrees parses (it is checked against the axis kind when bound).
        assert!(ErrorSet::from_json_str(&wrap(r#"{"name": "EXX", "model": {"type": "legendre", "coefficients_um": [1], "range_deg": [0, 1]}}"#), "x", None).is_ok());
        let e = err_of(&wrap(
            r#"{"name": "EXX", "value_um": 1}, {"name": "EXX", "value_um": 2}"#,
        ));
        assert!(e.contains("twice"), "{e}");
        let e = err_of(r#"{"format": "mte-errors/2", "parameters": []}"#);
        assert!(e.contains("format"), "{e}");
        let e = err_of(r#"{"format": "mte-errors/1", "parameters": [}"#);
        assert!(e.contains("line 1"), "{e}");
        let e = err_of(&wrap(
            r#"{"name": "EXX", "distribution": {"type": "normal", "sd_um": -1}}"#,
        ));
        assert!(e.contains("distribution") && e.contains("sd"), "{e}");
        let e = err_of(&wrap(
            r#"{"name": "EXX", "model": {"type": "sum", "terms": [{"type": "reversal", "span_um": 1}, {"type": "reversal", "span_urad": 1}]}}"#,
        ));
        assert!(e.contains("terms[1]") && e.contains("span_urad"), "{e}");
        let e = err_of(&wrap(
            r#"{"name": "EXX", "model": {"type": "table", "file": "/nonexistent/t.csv"}}"#,
        ));
        assert!(e.contains("/nonexistent/t.csv"), "{e}");
    }

    #[test]
    fn table_file_errors_name_the_line() {
        let dir = std::env::temp_dir().join(format!("mte-errors-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("t.csv"), "position_mm,error_um\n0,0\n50,1\n40,2\n").unwrap();
        let json = r#"{"format": "mte-errors/1", "parameters": [{"name": "EXX", "model": {"type": "table", "file": "t.csv"}}]}"#;
        let e = ErrorSet::from_json_str(json, "s.json", Some(&dir))
            .unwrap_err()
            .to_string();
        assert!(e.contains("t.csv") && e.contains("line 4"), "{e}");
        std::fs::write(dir.join("t.csv"), "position_mm,error_urad\n0,0\n50,1\n").unwrap();
        let json = r#"{"format": "mte-errors/1", "parameters": [{"name": "EXX", "unit": "um", "model": {"type": "table", "file": "t.csv"}}]}"#;
        let e = ErrorSet::from_json_str(json, "s.json", Some(&dir))
            .unwrap_err()
            .to_string();
        assert!(e.contains("error_urad"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn position_unit_must_fit_the_axis() {
        let json = r#"{"format": "mte-errors/1", "parameters": [{"name": "EXX", "model": {"type": "fourier", "period_deg": 10, "cos_um": [1]}}]}"#;
        let s = ErrorSet::from_json_str(json, "s.json", None).unwrap();
        let e = s.entries[0]
            .spec
            .build(
                Some(AxisInfo {
                    kind: Kind::Length,
                    stroke: (0.0, 1.0),
                }),
                "EXX",
            )
            .unwrap_err()
            .to_string();
        assert!(e.contains("EXX") && e.contains("linear"), "{e}");
    }
}
