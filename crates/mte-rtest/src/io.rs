//! Import and export of R-test data: a small JSON manifest (`"format": "mte-rtest/1"`) naming the
//! machine, the setups (ball positions, centring) and the CSV file with one row per reading.
//! The format is documented in `docs/formats.md` ("R-test data").

use crate::error::{Result, RtestError};
use crate::model::{Dataset, Reading, Setup};
use mte_linalg::Vec3;
use mte_linalg::csv::CsvTable;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Format tag of the manifest.
pub const FORMAT: &str = "mte-rtest/1";

/// Largest |coordinate| (ball, nest, linear axis) the reader accepts, mm (exclusive): 1 km.
pub const MAX_COORDINATE_MM: f64 = 1e6;
/// Largest |rotary axis angle| the reader accepts, degrees (exclusive).
pub const MAX_ANGLE_DEG: f64 = 1e5;
/// Largest |time| the reader accepts, s (exclusive): about 30 years.
pub const MAX_TIME_S: f64 = 1e9;
/// Largest |sensor reading| the reader accepts, µm (exclusive): 100 mm, far beyond any
/// R-test sensor's range.
pub const MAX_READING_UM: f64 = 1e5;
const READING_MEANING: &str =
    "a ball-to-nest displacement of 100 mm or more is not an R-test reading (µm)";

/// One setup as written in the manifest (angles in degrees).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ManifestSetup {
    /// Setup id, as used in the CSV `setup` column.
    pub id: String,
    /// Ball centre, table coordinates, mm.
    pub ball_mm: [f64; 3],
    /// Nest centre, tool coordinates, mm (default 0).
    #[serde(default)]
    pub nest_mm: [f64; 3],
    /// Commanded axes at the centring: linear axes in mm, rotary axes in degrees, by axis name.
    pub centring: BTreeMap<String, f64>,
    /// Time of the centring, s.
    #[serde(default)]
    pub centring_t_s: f64,
}

/// The manifest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Must be [`FORMAT`].
    pub format: String,
    /// Machine: a library name or a path to a machine JSON (relative to the manifest).
    pub machine: String,
    /// Instrument description.
    #[serde(default)]
    pub instrument: String,
    /// Where the data come from (measured, simulated with …).
    #[serde(default)]
    pub note: String,
    /// The CSV file, relative to the manifest.
    pub csv: String,
    /// Axis order of the machine, as the CSV columns use it.
    pub axes: Vec<String>,
    /// Setups.
    pub setups: Vec<ManifestSetup>,
    /// Optional: the programs run (free form, for the record).
    #[serde(default)]
    pub programs: Vec<serde_json::Value>,
    /// Optional: the base model of a diagnosis of these data (`mte diagnose`; format in
    /// `docs/formats-diagnose.md`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_model: Option<serde_json::Value>,
}

fn axis_unit(name: &str, rotary: bool) -> String {
    format!(
        "{}_{}",
        name.to_lowercase(),
        if rotary { "deg" } else { "mm" }
    )
}

/// Builds a dataset from manifest and CSV text. `rotary(name)` says which axes are rotary (their
/// columns are `<axis>_deg`, the others `<axis>_mm`).
///
/// # Errors
/// [`RtestError::Invalid`] naming the manifest field or the CSV line and column: numbers out
/// of range ([`MAX_COORDINATE_MM`], [`MAX_ANGLE_DEG`], [`MAX_TIME_S`], [`MAX_READING_UM`]),
/// duplicate axes or setup ids (naming both), a reading repeated (naming both lines).
pub fn dataset_from_str(
    manifest_name: &str,
    manifest: &str,
    csv_name: &str,
    csv: &str,
    rotary: &dyn Fn(&str) -> bool,
) -> Result<Dataset> {
    let man: Manifest = serde_json::from_str(manifest).map_err(|e| RtestError::Invalid {
        field: format!("{manifest_name} line {} column {}", e.line(), e.column()),
        message: e.to_string(),
    })?;
    if man.format != FORMAT {
        return Err(RtestError::Invalid {
            field: format!("{manifest_name}: format"),
            message: format!("`{}`, expected `{FORMAT}`", man.format),
        });
    }
    let to_q = |m: &BTreeMap<String, f64>, field: &str| -> Result<Vec<f64>> {
        for k in m.keys() {
            if !man.axes.contains(k) {
                return Err(RtestError::Invalid {
                    field: field.into(),
                    message: format!("unknown axis `{k}` (axes: {})", man.axes.join(", ")),
                });
            }
        }
        man.axes
            .iter()
            .map(|a| {
                let v = *m.get(a).ok_or_else(|| RtestError::Invalid {
                    field: field.into(),
                    message: format!("missing axis `{a}`"),
                })?;
                Ok(if rotary(a) { v.to_radians() } else { v })
            })
            .collect()
    };
    let bad = |field: String, message: String| RtestError::Invalid { field, message };
    for (i, a) in man.axes.iter().enumerate() {
        if let Some(j) = man.axes[..i].iter().position(|b| b == a) {
            return Err(bad(
                format!("{manifest_name}: axes[{i}]"),
                format!("axis `{a}` appears twice (axes[{j}] and axes[{i}])"),
            ));
        }
    }
    for (i, s) in man.setups.iter().enumerate() {
        if let Some(j) = man.setups[..i].iter().position(|o| o.id == s.id) {
            return Err(bad(
                format!("{manifest_name}: setups[{i}].id"),
                format!(
                    "setup id `{}` appears twice (setups[{j}] and setups[{i}])",
                    s.id
                ),
            ));
        }
        for (name, v) in [("ball_mm", s.ball_mm), ("nest_mm", s.nest_mm)] {
            if let Some(x) = v.iter().find(|x| x.abs() >= MAX_COORDINATE_MM) {
                return Err(bad(
                    format!("{manifest_name}: setups[{i}].{name}"),
                    format!(
                        "{x:e} mm is out of range (|value| < 1e6 mm): a ball or nest 1 km away is not an R-test setup"
                    ),
                ));
            }
        }
        for (a, v) in &s.centring {
            let limit = if rotary(a) {
                MAX_ANGLE_DEG
            } else {
                MAX_COORDINATE_MM
            };
            if v.abs() >= limit {
                return Err(bad(
                    format!("{manifest_name}: setups[{i}].centring.{a}"),
                    format!(
                        "{v:e} is out of range (|value| < {limit:e} {})",
                        if rotary(a) { "deg" } else { "mm" }
                    ),
                ));
            }
        }
        if s.centring_t_s.abs() >= MAX_TIME_S {
            return Err(bad(
                format!("{manifest_name}: setups[{i}].centring_t_s"),
                format!(
                    "{:e} s is out of range (|value| < 1e9 s, 30 years)",
                    s.centring_t_s
                ),
            ));
        }
    }
    let mut setups = Vec::new();
    for (i, s) in man.setups.iter().enumerate() {
        setups.push(Setup {
            id: s.id.clone(),
            ball_mm: Vec3::from(s.ball_mm),
            nest_mm: Vec3::from(s.nest_mm),
            centring_q: to_q(
                &s.centring,
                &format!("{manifest_name}: setups[{i}].centring"),
            )?,
            centring_t_s: s.centring_t_s,
        });
    }
    let table = CsvTable::parse(csv, csv_name)?;
    let c_setup = table.require("setup")?;
    let c_test = table.require("test")?;
    let c_t = table.require("t_s")?;
    let c_axes: Vec<usize> = man
        .axes
        .iter()
        .map(|a| table.require(&axis_unit(a, rotary(a))))
        .collect::<std::result::Result<_, _>>()?;
    let c_d = [
        table.require("dx_um")?,
        table.require("dy_um")?,
        table.require("dz_um")?,
    ];
    let mut readings = Vec::new();
    let mut seen: std::collections::HashMap<Vec<&str>, usize> = std::collections::HashMap::new();
    for r in 0..table.len() {
        let mut key: Vec<&str> = vec![
            table.text(r, c_setup),
            table.text(r, c_test),
            table.text(r, c_t),
        ];
        key.extend(c_axes.iter().map(|&c| table.text(r, c)));
        if let Some(first) = seen.insert(key, table.line(r)) {
            return Err(bad(
                format!("{csv_name} line {}", table.line(r)),
                format!("the same reading (setup, test, time and axes) as line {first}"),
            ));
        }
        let sid = table.text(r, c_setup);
        let setup = setups
            .iter()
            .position(|s| s.id == sid)
            .ok_or_else(|| RtestError::Invalid {
                field: format!("{csv_name} line {}, column setup", table.line(r)),
                message: format!("setup `{sid}` is not in the manifest"),
            })?;
        let q = man
            .axes
            .iter()
            .zip(&c_axes)
            .map(|(a, &c)| {
                Ok(if rotary(a) {
                    table
                        .number_within(
                            r,
                            c,
                            MAX_ANGLE_DEG,
                            "an axis angle of 10^5 degrees or more is not a command",
                        )?
                        .to_radians()
                } else {
                    table.number_within(
                        r,
                        c,
                        MAX_COORDINATE_MM,
                        "an axis 1 km or more from its origin is not a command (mm)",
                    )?
                })
            })
            .collect::<Result<Vec<f64>>>()?;
        readings.push(Reading {
            setup,
            test: table.text(r, c_test).to_string(),
            t_s: table.number_within(
                r,
                c_t,
                MAX_TIME_S,
                "a time of 10^9 s (30 years) or more is not a reading time",
            )?,
            q,
            d_mm: Vec3::new(
                table.number_within(r, c_d[0], MAX_READING_UM, READING_MEANING)? * 1e-3,
                table.number_within(r, c_d[1], MAX_READING_UM, READING_MEANING)? * 1e-3,
                table.number_within(r, c_d[2], MAX_READING_UM, READING_MEANING)? * 1e-3,
            ),
        });
    }
    Ok(Dataset {
        machine: man.machine,
        axis_names: man.axes,
        setups,
        readings,
        note: man.note,
    })
}

/// Reads a manifest and the CSV it names.
///
/// # Errors
/// [`RtestError::Io`] for unreadable files, else as [`dataset_from_str`].
pub fn read_dataset(manifest_path: &Path, rotary: &dyn Fn(&str) -> bool) -> Result<Dataset> {
    let man = read_file(manifest_path)?;
    dataset_from_manifest(
        &manifest_path.display().to_string(),
        &man,
        manifest_path.parent().unwrap_or(Path::new(".")),
        rotary,
    )
}

/// A dataset from its manifest's text (already read, named `manifest_name` in messages) and
/// the CSV the manifest names, relative to `dir`.
///
/// # Errors
/// As [`read_dataset`].
pub fn dataset_from_manifest(
    manifest_name: &str,
    manifest_text: &str,
    dir: &Path,
    rotary: &dyn Fn(&str) -> bool,
) -> Result<Dataset> {
    let parsed: serde_json::Value =
        serde_json::from_str(manifest_text).map_err(|e| RtestError::Invalid {
            field: format!("{manifest_name} line {} column {}", e.line(), e.column()),
            message: e.to_string(),
        })?;
    let csv_rel =
        parsed
            .get("csv")
            .and_then(|v| v.as_str())
            .ok_or_else(|| RtestError::Invalid {
                field: format!("{manifest_name}: csv"),
                message: "missing string field `csv`".into(),
            })?;
    let csv_path = dir.join(csv_rel);
    let csv = read_file(&csv_path)?;
    dataset_from_str(
        manifest_name,
        manifest_text,
        &csv_path.display().to_string(),
        &csv,
        rotary,
    )
}

/// A user's text file ([`mte_linalg::text::read_text`]), its error naming the file.
fn read_file(p: &Path) -> Result<String> {
    mte_linalg::text::read_text(p).map_err(|e| RtestError::Io {
        path: p.display().to_string(),
        message: e.to_string(),
    })
}

/// Manifest and CSV text of a dataset.
pub fn dataset_to_strings(
    ds: &Dataset,
    csv_name: &str,
    instrument: &str,
    rotary: &dyn Fn(&str) -> bool,
) -> (String, String) {
    let conv = |a: &str, v: f64| if rotary(a) { v.to_degrees() } else { v };
    let man = Manifest {
        format: FORMAT.into(),
        machine: ds.machine.clone(),
        instrument: instrument.into(),
        note: ds.note.clone(),
        csv: csv_name.into(),
        axes: ds.axis_names.clone(),
        setups: ds
            .setups
            .iter()
            .map(|s| ManifestSetup {
                id: s.id.clone(),
                ball_mm: s.ball_mm.into(),
                nest_mm: s.nest_mm.into(),
                centring: ds
                    .axis_names
                    .iter()
                    .zip(&s.centring_q)
                    .map(|(a, v)| (a.clone(), conv(a, *v)))
                    .collect(),
                centring_t_s: s.centring_t_s,
            })
            .collect(),
        programs: vec![],
        base_model: None,
    };
    let mut csv = String::from("setup,test,t_s");
    for a in &ds.axis_names {
        csv.push(',');
        csv.push_str(&axis_unit(a, rotary(a)));
    }
    csv.push_str(",dx_um,dy_um,dz_um\n");
    for r in &ds.readings {
        csv.push_str(&format!(
            "{},{},{:.4}",
            ds.setups[r.setup].id, r.test, r.t_s
        ));
        for (a, v) in ds.axis_names.iter().zip(&r.q) {
            csv.push_str(&format!(",{:.6}", conv(a, *v)));
        }
        csv.push_str(&format!(
            ",{:.4},{:.4},{:.4}\n",
            r.d_mm.x * 1e3,
            r.d_mm.y * 1e3,
            r.d_mm.z * 1e3
        ));
    }
    let man = serde_json::to_string_pretty(&man).unwrap_or_default();
    (man, csv)
}
