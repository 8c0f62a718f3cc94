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
/// [`RtestError::Invalid`] naming the manifest field or the CSV line and column.
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
    for r in 0..table.len() {
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
                let v = table.number(r, c)?;
                Ok(if rotary(a) { v.to_radians() } else { v })
            })
            .collect::<Result<Vec<f64>>>()?;
        readings.push(Reading {
            setup,
            test: table.text(r, c_test).to_string(),
            t_s: table.number(r, c_t)?,
            q,
            d_mm: Vec3::new(
                table.number(r, c_d[0])? * 1e-3,
                table.number(r, c_d[1])? * 1e-3,
                table.number(r, c_d[2])? * 1e-3,
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
    let read = |p: &Path| {
        std::fs::read_to_string(p).map_err(|e| RtestError::Io {
            path: p.display().to_string(),
            message: e.to_string(),
        })
    };
    let man = read(manifest_path)?;
    let parsed: serde_json::Value =
        serde_json::from_str(&man).map_err(|e| RtestError::Invalid {
            field: format!(
                "{} line {} column {}",
                manifest_path.display(),
                e.line(),
                e.column()
            ),
            message: e.to_string(),
        })?;
    let csv_rel =
        parsed
            .get("csv")
            .and_then(|v| v.as_str())
            .ok_or_else(|| RtestError::Invalid {
                field: format!("{}: csv", manifest_path.display()),
                message: "missing string field `csv`".into(),
            })?;
    let csv_path = manifest_path
        .parent()
        .unwrap_or(Path::new("."))
        .join(csv_rel);
    let csv = read(&csv_path)?;
    dataset_from_str(
        &manifest_path.display().to_string(),
        &man,
        &csv_path.display().to_string(),
        &csv,
        rotary,
    )
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
