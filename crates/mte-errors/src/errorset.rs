//! Error sets: named error parameters with values or models, and distributions for sampling.
//! JSON form `"format": "mte-errors/1"` (see `docs/formats.md`).
//!
//! The JSON form is read by serde (`mte_linalg::json`: unknown fields rejected, the path of the
//! offending field in every message) after unit suffixes are moved out of the keys
//! (`"value_um": 5` is read as the quantity `value` in µm), then converted to internal units with
//! the kind (length or angle) and magnitude of every value checked.
//!
//! # Adding a JSON model
//! 1. the model itself: an [`ErrorModel`] in `models/`;
//! 2. here, one struct with its JSON fields (`#[derive(Deserialize)]`,
//!    `#[serde(deny_unknown_fields)]`; a quantity with a unit suffix is a `Q<f64>` or
//!    `Q<Vec<f64>>` field named without the suffix) and its `JsonModel` impl, which converts
//!    the fields with `Cx` (`value`/`values` for error values, `position(s)` for axis
//!    positions, `time`) and returns a [`ModelSpec`] — `ModelSpec::Custom(Arc::new(model))`
//!    unless the model needs the axis' stroke;
//! 3. one line `Name(NameJson)` in `json_models!`: the `"type"` is `name` in snake case.
//!
//! The list of types in messages and the dispatch follow from that line.

use crate::csv::{CsvTable, UnitColumns};
use crate::distribution::Distribution;
use crate::error::{Error, Result};
use crate::models::{
    Constant, ErrorModel, Fourier, Legendre, Reversal, Sum, Tabulated, ThermalExponential,
    ThermalLinear, ToleranceForm, ToleranceModel,
};
use crate::units::{Kind, Unit, split_suffix};
use mte_linalg::json::{self, Tagged};
use mte_linalg::text::read_text;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use serde::de::IgnoredAny;
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
        let err = |field: String, message: String| Error::Json {
            source_name: source_name.to_string(),
            field,
            message,
        };
        let mut root = json::parse(text).map_err(|e| {
            err(
                format!("(line {}, column {})", e.line(), e.column()),
                e.to_string(),
            )
        })?;
        let original = root.clone();
        // `parameters[2]._um` → `parameters[2] (EXX)_um`… see split_units
        let field = |path: &str| {
            let path = path.replace("._", "_");
            let entry = path
                .strip_prefix("parameters[")
                .and_then(|r| r.split_once(']'));
            match entry.and_then(|(i, rest)| {
                let name = original["parameters"][i.parse::<usize>().ok()?]["name"].as_str()?;
                Some(format!("parameters[{i}] ({name}){rest}"))
            }) {
                Some(p) => p,
                None if path.is_empty() => "(root)".to_string(),
                None => path,
            }
        };
        json::check_format(&root, FORMAT).map_err(|e| err(field(&e.path), e.message))?;
        split_units(&mut root, "").map_err(|(path, m)| err(field(&path[1..]), m))?;
        let set: SetJson = json::from_value(&root).map_err(|e| err(field(&e.path), e.message))?;
        let mut entries: Vec<Entry> = Vec::with_capacity(set.parameters.len());
        for (i, p) in set.parameters.iter().enumerate() {
            if let Some(prev) = entries.iter().find(|x| x.name == p.name) {
                return Err(err(
                    format!("parameters[{i}].name"),
                    format!(
                        "parameter `{}` is given twice (also {})",
                        p.name, prev.field
                    ),
                ));
            }
            // Settings that are wrong as a whole (units, distributions) name the file too.
            entries.push(p.entry(source_name, base_dir, i).map_err(|e| match e {
                Error::Unit {
                    field,
                    unit,
                    message,
                } => err(field, format!("unit `{unit}` does not fit: {message}")),
                Error::Invalid { what, message } => err(what, message),
                other => other,
            })?);
        }
        Ok(ErrorSet {
            name: set.name.unwrap_or_else(|| source_name.to_string()),
            description: set.description.unwrap_or_default(),
            machine: set.machine,
            entries,
        })
    }

    /// Read and parse a file (a regular file; a UTF-8 byte-order mark is dropped; tables
    /// relative to its directory).
    ///
    /// # Errors
    /// [`Error::Io`] when the file cannot be read, else as [`ErrorSet::from_json_str`].
    pub fn from_file(path: &Path) -> Result<ErrorSet> {
        let text = read_text(path).map_err(|e| Error::Io {
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

// The JSON form, read by serde into the `…Json` types below, then converted (units, kinds,
// magnitudes) with the path of every field in its messages.

/// Largest error value: 1 m (mm) or 1 rad; anything beyond is a typo or a wrong unit.
fn max_error(k: Kind) -> (f64, &'static str) {
    match k {
        Kind::Length => (1e3, "1 m"),
        Kind::Angle => (1.0, "1 rad"),
    }
}

/// Largest axis position, period or distance: 10 km (mm) or 1e6 degrees.
fn max_position(k: Kind) -> (f64, &'static str) {
    match k {
        Kind::Length => (1e7, "10 km"),
        Kind::Angle => (1e6f64.to_radians(), "1e6 deg"),
    }
}

/// Largest time (about 30 years).
const MAX_TIME_S: f64 = 1e9;

/// Moves unit suffixes out of keys, so that serde sees fixed field names: `"value_um": 5`
/// becomes `"value": {"_um": 5}` (read as a [`Q`]); likewise `rate_um_per_h`, `tau_min`. A base
/// given twice (`value_um` and `value_mm`, or `value` and `value_um`) is an error.
fn split_units(v: &mut Value, path: &str) -> std::result::Result<(), (String, String)> {
    match v {
        Value::Array(a) => a
            .iter_mut()
            .enumerate()
            .try_for_each(|(i, x)| split_units(x, &format!("{path}[{i}]"))),
        Value::Object(m) => {
            let mut out = Map::new();
            let mut written: Vec<(String, String)> = Vec::new(); // (base, key as written)
            for (k, mut x) in std::mem::take(m) {
                split_units(&mut x, &format!("{path}.{k}"))?;
                let (b, per) = k
                    .split_once("_per_")
                    .map_or((k.as_str(), None), |(b, p)| (b, Some(p)));
                let base = match split_suffix(b) {
                    Some((base, _)) => base,
                    None if per.is_none() => ["_s", "_min", "_h"]
                        .iter()
                        .find_map(|t| k.strip_suffix(t))
                        .unwrap_or(&k),
                    None => &k,
                };
                if let Some((_, prev)) = written.iter().find(|(b, _)| b == base) {
                    return Err((
                        format!("{path}.{k}"),
                        format!("given twice (also `{prev}`)"),
                    ));
                }
                written.push((base.to_string(), k.clone()));
                if base.len() < k.len() && !base.is_empty() {
                    x = Value::Object(Map::from_iter([(k[base.len()..].to_string(), x)]));
                }
                out.insert(base.to_string(), x);
            }
            *m = out;
            Ok(())
        }
        _ => Ok(()),
    }
}

/// A quantity as written: a number or an array, with the unit suffix of its key (`"_um"`,
/// `"_um_per_h"`, `"_min"`; see [`split_units`]) or none (`"value": 5` and the parameter's
/// `unit`).
struct Q<T> {
    suffix: Option<String>,
    v: T,
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Q<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::{self, IntoDeserializer, value::SeqAccessDeserializer};
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> de::Visitor<'de> for V<T> {
            type Value = Q<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a finite number or an array of finite numbers")
            }
            fn visit_map<A: de::MapAccess<'de>>(
                self,
                mut m: A,
            ) -> std::result::Result<Q<T>, A::Error> {
                let suffix = m.next_key()?;
                let v = m.next_value()?;
                Ok(Q { suffix, v })
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, s: A) -> std::result::Result<Q<T>, A::Error> {
                let v = T::deserialize(SeqAccessDeserializer::new(s))?;
                Ok(Q { suffix: None, v })
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> std::result::Result<Q<T>, E> {
                let v = T::deserialize(x.into_deserializer())?;
                Ok(Q { suffix: None, v })
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> std::result::Result<Q<T>, E> {
                self.visit_f64(x as f64)
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> std::result::Result<Q<T>, E> {
                self.visit_f64(x as f64)
            }
        }
        d.deserialize_any(V(std::marker::PhantomData))
    }
}

impl Q<f64> {
    fn slice(&self) -> Q<&[f64]> {
        Q {
            suffix: self.suffix.clone(),
            v: std::slice::from_ref(&self.v),
        }
    }
}

impl Q<Vec<f64>> {
    fn slice(&self) -> Q<&[f64]> {
        Q {
            suffix: self.suffix.clone(),
            v: &self.v,
        }
    }
}

/// Converts the fields of one parameter: the unit of its `unit` field, the kind (length or
/// angle) the first unit fixed — every value of a parameter has one kind — and where tables are.
struct Cx<'a> {
    src: &'a str,
    dir: Option<&'a Path>,
    unit: Option<Unit>,
    kind: Option<(Kind, String)>,
}

impl Cx<'_> {
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Json {
            source_name: self.src.to_string(),
            field: field.into(),
            message: message.into(),
        }
    }

    /// The unit of `{path}.{base}…` and the key as written; `default`: the `unit` field applies.
    fn unit(
        &self,
        suffix: &Option<String>,
        path: &str,
        base: &str,
        default: bool,
    ) -> Result<(Unit, String)> {
        match (suffix, self.unit) {
            (Some(s), _) => {
                let key = format!("{path}.{base}{s}");
                Ok((Unit::parse(s.trim_start_matches('_'), &key)?, key))
            }
            (None, Some(u)) if default => Ok((u, format!("{path}.{base}"))),
            (None, _) => Err(self.err(
                format!("{path}.{base}"),
                format!("no unit: write `{base}_um`, `{base}_urad`, … or give a `unit` field"),
            )),
        }
    }

    /// Every number of `q` in internal units, each within `max(kind)`.
    fn convert(
        &self,
        q: &Q<&[f64]>,
        u: Unit,
        key: &str,
        max: fn(Kind) -> (f64, &'static str),
        what: &str,
    ) -> Result<Vec<f64>> {
        let (limit, text) = max(u.kind());
        let one = q.v.len() == 1;
        q.v.iter()
            .enumerate()
            .map(|(i, x)| {
                let y = x * u.to_internal();
                if y.abs() > limit {
                    let key = if one {
                        key.to_string()
                    } else {
                        format!("{key}[{i}]")
                    };
                    return Err(self.err(
                        key,
                        format!("{x} {} is beyond any {what} (at most {text})", u.suffix()),
                    ));
                }
                Ok(y)
            })
            .collect()
    }

    /// Error values: in the parameter's kind, at most 1 m or 1 rad.
    fn values(&mut self, q: Q<&[f64]>, path: &str, base: &str) -> Result<Vec<f64>> {
        let (u, key) = self.unit(&q.suffix, path, base, true)?;
        self.see(u, &key)?;
        self.convert(&q, u, &key, max_error, "machine error")
    }

    fn value(&mut self, q: &Q<f64>, path: &str, base: &str) -> Result<f64> {
        Ok(self.values(q.slice(), path, base)?[0])
    }

    /// Positions (mm or rad, by their own suffix) and their kind.
    fn positions(&self, q: Q<&[f64]>, path: &str, base: &str) -> Result<(Vec<f64>, Kind)> {
        let (u, key) = self.unit(&q.suffix, path, base, false)?;
        Ok((
            self.convert(&q, u, &key, max_position, "machine")?,
            u.kind(),
        ))
    }

    fn position(&self, q: &Q<f64>, path: &str, base: &str) -> Result<(f64, Kind)> {
        let (x, k) = self.positions(q.slice(), path, base)?;
        Ok((x[0], k))
    }

    /// A length (mm) of a tolerance model: `error` says whether it is an error value (at most
    /// 1 m) or a distance.
    fn length(
        &self,
        q: Option<&Q<f64>>,
        path: &str,
        base: &str,
        error: bool,
    ) -> Result<Option<f64>> {
        let Some(q) = q else { return Ok(None) };
        let (u, key) = self.unit(&q.suffix, path, base, false)?;
        u.expect_kind(Kind::Length, &key)?;
        let max = if error { max_error } else { max_position };
        Ok(Some(self.convert(&q.slice(), u, &key, max, "machine")?[0]))
    }

    /// A time (s) written `{base}_s`, `_min` or `_h`.
    fn time(&self, q: Option<&Q<f64>>, path: &str, base: &str) -> Result<Option<f64>> {
        let Some(q) = q else { return Ok(None) };
        let s = q.suffix.as_deref().unwrap_or("");
        let f = match s {
            "_s" => 1.0,
            "_min" => 60.0,
            "_h" => 3600.0,
            _ => {
                return Err(self.err(
                    format!("{path}.{base}{s}"),
                    format!("expected a time: `{base}_s`, `{base}_min` or `{base}_h`"),
                ));
            }
        };
        if q.v.abs() * f > MAX_TIME_S {
            return Err(self.err(
                format!("{path}.{base}{s}"),
                format!(
                    "{} {} is beyond any run (at most {MAX_TIME_S:e} s)",
                    q.v,
                    &s[1..]
                ),
            ));
        }
        Ok(Some(q.v * f))
    }

    /// Fixes the parameter's kind at the first unit seen; a later unit of the other kind is an
    /// error naming both fields.
    fn see(&mut self, u: Unit, key: &str) -> Result<()> {
        match &self.kind {
            Some((k, prev)) if *k != u.kind() => Err(Error::Unit {
                field: key.to_string(),
                unit: u.suffix().to_string(),
                message: format!(
                    "unit mismatch: `{prev}` makes this parameter a {k:?} ({}), but `{}` is a unit of {:?}",
                    match k {
                        Kind::Length => "mm, um, nm",
                        Kind::Angle => "rad, mrad, urad, arcsec, deg",
                    },
                    u.suffix(),
                    u.kind()
                ),
            }),
            Some(_) => Ok(()),
            None => {
                self.kind = Some((u.kind(), key.to_string()));
                Ok(())
            }
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SetJson {
    #[serde(rename = "format")]
    _format: String,
    name: Option<String>,
    description: Option<String>,
    machine: Option<String>,
    parameters: Vec<EntryJson>,
    #[serde(rename = "note")]
    _note: Option<IgnoredAny>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EntryJson {
    name: String,
    unit: Option<String>,
    value: Option<Q<f64>>,
    model: Option<Tagged<ModelJson>>,
    distribution: Option<Tagged<DistJson>>,
    #[serde(rename = "note")]
    _note: Option<IgnoredAny>,
}

impl EntryJson {
    fn entry(&self, src: &str, dir: Option<&Path>, index: usize) -> Result<Entry> {
        let path = format!("parameters[{index}] ({})", self.name);
        let unit = match &self.unit {
            Some(u) => Some(Unit::parse(u, &format!("{path}.unit"))?),
            None => None,
        };
        let mut cx = Cx {
            src,
            dir,
            unit,
            kind: unit.map(|u| (u.kind(), format!("{path}.unit = \"{}\"", u.suffix()))),
        };
        let distribution = match &self.distribution {
            Some(d) => Some(d.0.distribution(&mut cx, &format!("{path}.distribution"))?),
            None => None,
        };
        let spec = match (&self.value, &self.model, &distribution) {
            (Some(_), Some(_), _) => {
                return Err(cx.err(
                    format!("{path}.model"),
                    "give either a value or a model, not both",
                ));
            }
            (Some(v), None, _) => ModelSpec::Constant(cx.value(v, &path, "value")?),
            (None, Some(_), Some(_)) => {
                return Err(cx.err(
                    format!("{path}.distribution"),
                    "a distribution applies to a constant value; a parameter with a model cannot have one",
                ));
            }
            (None, Some(m), None) => m.0.spec(&mut cx, &format!("{path}.model"))?,
            (None, None, Some(d)) => ModelSpec::Constant(d.nominal()),
            (None, None, None) => {
                return Err(cx.err(path, "needs `value_<unit>`, `model` or `distribution`"));
            }
        };
        let (kind, unit_field) = cx
            .kind
            .clone()
            .ok_or_else(|| cx.err(path.clone(), "no unit anywhere in this parameter"))?;
        Ok(Entry {
            name: self.name.clone(),
            field: path,
            kind,
            unit_field,
            spec,
            distribution,
        })
    }
}

#[derive(Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
enum DistJson {
    Normal {
        mean: Option<Q<f64>>,
        sd: Q<f64>,
    },
    Uniform {
        low: Q<f64>,
        high: Q<f64>,
    },
    TruncatedNormal {
        mean: Option<Q<f64>>,
        sd: Q<f64>,
        low: Q<f64>,
        high: Q<f64>,
    },
    Tolerance {
        tolerance: Q<f64>,
        sigma_level: Option<f64>,
        truncate: Option<bool>,
    },
}

impl DistJson {
    fn distribution(&self, cx: &mut Cx, path: &str) -> Result<Distribution> {
        let mut q = |q: &Q<f64>, base: &str| cx.value(q, path, base);
        let (d, ty) = match self {
            DistJson::Normal { mean, sd } => (
                Distribution::Normal {
                    mean: mean.as_ref().map_or(Ok(0.0), |m| q(m, "mean"))?,
                    sd: q(sd, "sd")?,
                },
                "normal",
            ),
            DistJson::Uniform { low, high } => (
                Distribution::Uniform {
                    lo: q(low, "low")?,
                    hi: q(high, "high")?,
                },
                "uniform",
            ),
            DistJson::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            } => (
                Distribution::TruncatedNormal {
                    mean: mean.as_ref().map_or(Ok(0.0), |m| q(m, "mean"))?,
                    sd: q(sd, "sd")?,
                    lo: q(low, "low")?,
                    hi: q(high, "high")?,
                },
                "truncated_normal",
            ),
            DistJson::Tolerance {
                tolerance,
                sigma_level,
                truncate,
            } => {
                let t = q(tolerance, "tolerance")?;
                let d = crate::distribution::from_tolerance(
                    t,
                    sigma_level.unwrap_or(3.0),
                    truncate.unwrap_or(false),
                )
                .map_err(|e| rename(e, path))?;
                (d, "tolerance")
            }
        };
        crate::distribution::validate(&d, ty).map_err(|e| rename(e, path))?;
        Ok(d)
    }
}

/// One JSON model (`"type": "<name>"`): its fields are read by serde, [`JsonModel::spec`]
/// converts them (see the module docs for adding one).
trait JsonModel {
    /// The model's spec; `path` names the model object in messages (`parameters[3] (EXX).model`).
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec>;
}

/// Registers the JSON models: `Variant(Struct)` is `"type": "variant"` in snake case.
macro_rules! json_models {
    ($($variant:ident($ty:ident)),* $(,)?) => {
        #[derive(Deserialize)]
        #[serde(rename_all = "snake_case")]
        enum ModelJson {
            $($variant($ty)),*
        }
        impl JsonModel for ModelJson {
            fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
                match self {
                    $(ModelJson::$variant(m) => m.spec(cx, path)),*
                }
            }
        }
    };
}

json_models!(
    Constant(ConstantJson),
    Legendre(LegendreJson),
    Fourier(FourierJson),
    Tolerance(ToleranceJson),
    Table(TableJson),
    ThermalLinear(ThermalLinearJson),
    ThermalExponential(ThermalExponentialJson),
    Reversal(ReversalJson),
    Sum(SumJson),
);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ConstantJson {
    value: Q<f64>,
}

impl JsonModel for ConstantJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        Ok(ModelSpec::Constant(cx.value(&self.value, path, "value")?))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LegendreJson {
    coefficients: Q<Vec<f64>>,
    range: Option<Q<Vec<f64>>>,
}

impl JsonModel for LegendreJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        let coefficients = cx.values(self.coefficients.slice(), path, "coefficients")?;
        let range = match &self.range {
            Some(q) => match cx.positions(q.slice(), path, "range")? {
                (r, k) if r.len() == 2 => Some((r[0], r[1], k)),
                _ => {
                    let s = q.suffix.as_deref().unwrap_or("");
                    return Err(cx.err(format!("{path}.range{s}"), "expected [low, high]"));
                }
            },
            None => None,
        };
        Ok(ModelSpec::Legendre {
            coefficients,
            range,
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FourierJson {
    offset: Option<Q<f64>>,
    cos: Option<Q<Vec<f64>>>,
    sin: Option<Q<Vec<f64>>>,
    period: Q<f64>,
    phase_origin: Option<Q<f64>>,
}

impl JsonModel for FourierJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        let offset = match &self.offset {
            Some(o) => cx.value(o, path, "offset")?,
            None => 0.0,
        };
        let mut series = |q: &Option<Q<Vec<f64>>>, base| match q {
            Some(q) => cx.values(q.slice(), path, base),
            None => Ok(Vec::new()),
        };
        let (cos, sin) = (series(&self.cos, "cos")?, series(&self.sin, "sin")?);
        if cos.is_empty() && sin.is_empty() && cx.kind.is_none() {
            return Err(cx.err(
                format!("{path}.cos_<unit>"),
                "missing `cos` (e.g. `cos_um`)",
            ));
        }
        let (period, position_kind) = cx.position(&self.period, path, "period")?;
        let phase_origin = match &self.phase_origin {
            Some(p) => match cx.position(p, path, "phase_origin")? {
                (x, k) if k == position_kind => x,
                _ => {
                    return Err(cx.err(
                        format!("{path}.phase_origin"),
                        "phase origin and period must both be lengths or both angles",
                    ));
                }
            },
            None => 0.0,
        };
        Ok(ModelSpec::Fourier {
            offset,
            cos,
            sin,
            period,
            phase_origin,
            position_kind,
        })
    }
}

#[derive(Deserialize)]
#[serde(rename_all = "snake_case")]
enum FormJson {
    Straightness,
    Positioning,
    CarriageDifference,
    Twist,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ToleranceJson {
    form: FormJson,
    tolerance: Q<f64>,
    half_waves: Option<f64>,
    scale: Option<Q<f64>>,
    carriage_spacing: Option<Q<f64>>,
    rail_spacing: Option<Q<f64>>,
    sign: Option<f64>,
    stroke: Option<Q<f64>>,
    origin: Option<Q<f64>>,
}

impl JsonModel for ToleranceJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        let tolerance = cx
            .length(Some(&self.tolerance), path, "tolerance", true)?
            .unwrap_or(0.0);
        let half_waves = match self.half_waves {
            None => 1,
            Some(x) if x.fract() == 0.0 && (1.0..=8.0).contains(&x) => x as u32,
            Some(x) => {
                return Err(cx.err(
                    format!("{path}.half_waves"),
                    format!("expected an integer in 1..=8, found {x}"),
                ));
            }
        };
        let required = |q: &Option<Q<f64>>, base: &str| {
            let q = q.as_ref();
            cx.length(q, path, base, false)?.ok_or_else(|| {
                cx.err(
                    format!("{path}.{base}_<unit>"),
                    format!("missing `{base}` (e.g. `{base}_um` or `{base}_mm`)"),
                )
            })
        };
        let (form, kind) = match self.form {
            FormJson::Straightness => (
                ToleranceForm::Straightness {
                    tolerance,
                    half_waves,
                },
                Kind::Length,
            ),
            FormJson::Positioning => (
                ToleranceForm::Positioning {
                    tolerance,
                    half_waves,
                    scale: cx
                        .length(self.scale.as_ref(), path, "scale", true)?
                        .unwrap_or(0.0),
                },
                Kind::Length,
            ),
            FormJson::CarriageDifference => (
                ToleranceForm::CarriageDifference {
                    tolerance,
                    half_waves,
                    carriage_spacing: required(&self.carriage_spacing, "carriage_spacing")?,
                    sign: self.sign.unwrap_or(1.0),
                },
                Kind::Angle,
            ),
            FormJson::Twist => (
                ToleranceForm::Twist {
                    tolerance,
                    half_waves,
                    rail_spacing: required(&self.rail_spacing, "rail_spacing")?,
                },
                Kind::Angle,
            ),
        };
        let internal = if kind == Kind::Length {
            Unit::Mm
        } else {
            Unit::Rad
        };
        cx.see(internal, &format!("{path}.form"))?;
        Ok(ModelSpec::Tolerance {
            form,
            stroke: cx.length(self.stroke.as_ref(), path, "stroke", false)?,
            origin: cx.length(self.origin.as_ref(), path, "origin", false)?,
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TableJson {
    file: Option<String>,
    position_column: Option<String>,
    value_column: Option<String>,
    positions: Option<Q<Vec<f64>>>,
    values: Option<Q<Vec<f64>>>,
}

impl JsonModel for TableJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        let Some(file) = &self.file else {
            let values = match &self.values {
                Some(v) => cx.values(v.slice(), path, "values")?,
                None => {
                    return Err(cx.err(
                        format!("{path}.values_<unit>"),
                        "missing `values` (e.g. `values_um`)",
                    ));
                }
            };
            let Some(p) = &self.positions else {
                return Err(cx.err(
                    format!("{path}.positions_<unit>"),
                    "missing `positions` (e.g. `positions_mm`) or `file`",
                ));
            };
            let (positions, position_kind) = cx.positions(p.slice(), path, "positions")?;
            let key = format!("{path}.positions{}", p.suffix.as_deref().unwrap_or(""));
            if let Some(i) = (1..positions.len()).find(|&i| positions[i] <= positions[i - 1]) {
                return Err(cx.err(format!("{key}[{i}]"), "positions must strictly increase"));
            }
            if positions.len() != values.len() {
                return Err(cx.err(
                    key,
                    format!("{} positions but {} values", positions.len(), values.len()),
                ));
            }
            return Ok(ModelSpec::Table {
                positions,
                values,
                position_kind,
            });
        };
        let full = cx
            .dir
            .map_or_else(|| Path::new(file).to_path_buf(), |d| d.join(file));
        let name = full.display().to_string();
        let text = read_text(&full).map_err(|e| Error::Io {
            path: name.clone(),
            message: e.to_string(),
        })?;
        let pc = self.position_column.as_deref().unwrap_or("position");
        let vc = self.value_column.as_deref().unwrap_or("error");
        let t = CsvTable::parse(&text, &name)?;
        let (_, pu) = t.require_with_unit(pc, &format!("{pc}_mm"))?;
        let (vci, vu) = t.require_with_unit(vc, &format!("{vc}_um"))?;
        cx.see(vu, &format!("{name}: column `{}`", t.headers[vci]))?;
        let tab = Tabulated::from_csv(&text, &name, pc, vc, vu.kind(), None)?;
        for (xs, u, limit) in [
            (tab.positions(), pu, max_position(pu.kind())),
            (tab.values(), vu, max_error(vu.kind())),
        ] {
            if let Some(x) = xs.iter().find(|x| x.abs() > limit.0) {
                return Err(cx.err(
                    format!("{name}: column {}", if u == pu { pc } else { vc }),
                    format!(
                        "{} {} is beyond any machine (at most {})",
                        x / u.to_internal(),
                        u.suffix(),
                        limit.1
                    ),
                ));
            }
        }
        Ok(ModelSpec::Table {
            positions: tab.positions().to_vec(),
            values: tab.values().to_vec(),
            position_kind: pu.kind(),
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ThermalLinearJson {
    rate: Q<f64>,
    t0: Option<Q<f64>>,
}

impl JsonModel for ThermalLinearJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        let s = self.rate.suffix.as_deref().unwrap_or("");
        let (unit, per) = s.split_once("_per_").unwrap_or((s, ""));
        let key = format!("{path}.rate{s}");
        let per_s = match per {
            "s" => 1.0,
            "min" => 1.0 / 60.0,
            "h" => 1.0 / 3600.0,
            _ => {
                return Err(cx.err(
                    key,
                    "expected `rate_<unit>_per_<s|min|h>` (e.g. `rate_um_per_h`)",
                ));
            }
        };
        let u = Unit::parse(unit.trim_start_matches('_'), &key)?;
        cx.see(u, &key)?;
        let rate_per_s = self.rate.v * u.to_internal() * per_s;
        let (limit, text) = max_error(u.kind());
        if rate_per_s.abs() * 3600.0 > limit {
            return Err(cx.err(
                key,
                format!(
                    "{} {}/{per} is beyond any thermal drift (at most {text} per hour)",
                    self.rate.v,
                    u.suffix()
                ),
            ));
        }
        Ok(ModelSpec::ThermalLinear(ThermalLinear {
            rate_per_s,
            t0_s: cx.time(self.t0.as_ref(), path, "t0")?.unwrap_or(0.0),
        }))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ThermalExponentialJson {
    amplitude: Q<f64>,
    tau: Q<f64>,
    t0: Option<Q<f64>>,
}

impl JsonModel for ThermalExponentialJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        Ok(ModelSpec::ThermalExponential {
            amplitude: cx.value(&self.amplitude, path, "amplitude")?,
            tau_s: cx.time(Some(&self.tau), path, "tau")?.unwrap_or(0.0),
            t0_s: cx.time(self.t0.as_ref(), path, "t0")?.unwrap_or(0.0),
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReversalJson {
    span: Q<f64>,
}

impl JsonModel for ReversalJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        Ok(ModelSpec::Reversal(cx.value(&self.span, path, "span")?))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SumJson {
    terms: Vec<Tagged<ModelJson>>,
}

impl JsonModel for SumJson {
    fn spec(&self, cx: &mut Cx, path: &str) -> Result<ModelSpec> {
        let terms = self.terms.iter().enumerate();
        Ok(ModelSpec::Sum(
            terms
                .map(|(i, t)| t.0.spec(cx, &format!("{path}.terms[{i}]")))
                .collect::<Result<_>>()?,
        ))
    }
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

    /// The input contract (issue #20): a BOM, unknown fields, magnitudes, duplicates.
    #[test]
    fn bom_is_accepted() {
        let dir = std::env::temp_dir().join(format!("mte-errors-bom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("s.json");
        std::fs::write(&path, format!("\u{feff}{SET}")).unwrap();
        assert_eq!(ErrorSet::from_file(&path).unwrap().entries.len(), 9);
        std::fs::write(
            dir.join("t.csv"),
            "\u{feff}position_mm,error_um\n0,0\n50,1\n",
        )
        .unwrap();
        let json = r#"{"format": "mte-errors/1", "parameters": [{"name": "EXX", "model": {"type": "table", "file": "t.csv"}}]}"#;
        assert!(ErrorSet::from_json_str(json, "s.json", Some(&dir)).is_ok());
        let e = ErrorSet::from_file(&dir).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn unknown_fields_are_rejected_at_every_level() {
        let wrap = |p: &str| format!(r#"{{"format": "mte-errors/1", "parameters": [{p}]}}"#);
        let e = err_of(r#"{"format": "mte-errors/1", "parameter": []}"#);
        assert!(
            e.starts_with("bad.json: field `parameter`: unknown field")
                && e.contains("did you mean `parameters`?"),
            "{e}"
        );
        let e = err_of(&wrap(
            r#"{"name": "EXX", "model": {"type": "legendre", "coeficients_um": [1]}}"#,
        ));
        assert!(
            e.contains("`parameters[0] (EXX).model.coeficients`")
                && e.contains("did you mean `coefficients`?"),
            "{e}"
        );
        let e = err_of(&wrap(
            r#"{"name": "EXX", "distribution": {"type": "normal", "sd_um": 1, "mode_um": 0}}"#,
        ));
        assert!(
            e.contains("`parameters[0] (EXX).distribution.mode`") && e.contains("unknown field"),
            "{e}"
        );
        let e = err_of(&wrap(
            r#"{"name": "EXX", "model": {"type": "tolerance", "form": "straight", "tolerance_um": 3}}"#,
        ));
        assert!(
            e.contains("`parameters[0] (EXX).model.form`")
                && e.contains("did you mean `straightness`?"),
            "{e}"
        );
        let e = err_of(&wrap(
            r#"{"name": "EXX", "model": {"type": "sum", "terms": [{"type": "reversal", "spam_um": 1}]}}"#,
        ));
        assert!(
            e.contains("`parameters[0] (EXX).model.terms[0].spam`"),
            "{e}"
        );
    }

    #[test]
    fn impossible_magnitudes_are_rejected() {
        let wrap = |p: &str| format!(r#"{{"format": "mte-errors/1", "parameters": [{p}]}}"#);
        for (p, field, what) in [
            (
                r#"{"name": "EXX", "value_mm": 2000}"#,
                "parameters[0] (EXX).value_mm",
                "2000 mm is beyond any machine error (at most 1 m)",
            ),
            (
                r#"{"name": "EAX", "unit": "deg", "value": 90}"#,
                "parameters[0] (EAX).value",
                "90 deg is beyond any machine error (at most 1 rad)",
            ),
            (
                r#"{"name": "EXX", "model": {"type": "legendre", "coefficients_um": [1, 2e9]}}"#,
                "parameters[0] (EXX).model.coefficients_um[1]",
                "2000000000 um",
            ),
            (
                r#"{"name": "EXX", "model": {"type": "legendre", "coefficients_um": [1], "range_mm": [0, 1e12]}}"#,
                "parameters[0] (EXX).model.range_mm[1]",
                "(at most 10 km)",
            ),
            (
                r#"{"name": "EXX", "model": {"type": "thermal_linear", "rate_mm_per_s": 1}}"#,
                "parameters[0] (EXX).model.rate_mm_per_s",
                "at most 1 m per hour",
            ),
            (
                r#"{"name": "EXX", "model": {"type": "thermal_exponential", "amplitude_um": 1, "tau_h": 1e9}}"#,
                "parameters[0] (EXX).model.tau_h",
                "beyond any run",
            ),
            (
                r#"{"name": "EXX", "distribution": {"type": "normal", "sd_um": 1e7}}"#,
                "parameters[0] (EXX).distribution.sd_um",
                "beyond any machine error",
            ),
        ] {
            let e = err_of(&wrap(p));
            assert!(
                e.contains(&format!("bad.json: field `{field}`: ")) && e.contains(what),
                "{e}"
            );
        }
    }

    #[test]
    fn duplicates_name_both_occurrences() {
        let wrap = |p: &str| format!(r#"{{"format": "mte-errors/1", "parameters": [{p}]}}"#);
        let e = err_of(&wrap(r#"{"name": "EXX", "value_um": 1, "value_mm": 2}"#));
        assert!(
            e.contains("`parameters[0] (EXX).value_um`: given twice (also `value_mm`)"),
            "{e}"
        );
        let e = err_of(&wrap(
            r#"{"name": "EXX", "unit": "um", "value": 1, "value_um": 2}"#,
        ));
        assert!(e.contains("given twice (also `value`)"), "{e}");
        let e = err_of(&wrap(
            r#"{"name": "EXX", "value_um": 1}, {"name": "EYY", "value_um": 1}, {"name": "EXX", "value_um": 2}"#,
        ));
        assert!(
            e.contains(
                "`parameters[2].name`: parameter `EXX` is given twice (also parameters[0] (EXX))"
            ),
            "{e}"
        );
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
