//! The instruments the diagnosis reads from disk, each an [`ObservationModel`] in its own
//! module, and the one table that picks an instrument from a manifest's `format` and `kind`.
//! To add an instrument: implement [`ObservationModel`] for its data, give it a reader, and add
//! one row to the `INSTRUMENTS` table in this module.

mod axis;
mod machine;
mod points;
mod rtest;
mod tracker;

use std::path::Path;

use crate::dataset::ManifestFile;
use crate::model::{ObservationModel, Prepared, prepare};
use crate::{DiagnoseError, Result};

pub use axis::AxisRuns;
pub(crate) use machine::{other_form, relative_form};
pub use points::Points;
pub use rtest::RTest;
pub use tracker::Tracker;

/// An instrument's data read from disk, and the base model its manifest states.
type Read = (Box<dyn ObservationModel>, Option<serde_json::Value>);

/// Reads an instrument's data from its manifest; the `f64` is a stated noise (µm) for data
/// whose manifest states none.
type Reader = fn(&ManifestFile, Option<f64>) -> Result<Read>;

/// One instrument: the manifest `format` and `kind` that select it, and its reader.
struct Instrument {
    format: &'static str,
    kind: Option<&'static str>,
    read: Reader,
}

fn boxed<M: ObservationModel + 'static>(
    read: Result<(M, Option<serde_json::Value>)>,
) -> Result<Read> {
    read.map(|(m, base)| (Box::new(m) as Box<dyn ObservationModel>, base))
}

/// Every instrument the diagnosis reads.
const INSTRUMENTS: &[Instrument] = &[
    Instrument {
        format: "mte-dataset/1",
        kind: Some("axis"),
        read: |f, noise| boxed(AxisRuns::read(f, noise)),
    },
    Instrument {
        format: "mte-dataset/1",
        kind: Some("tracker"),
        read: |f, noise| boxed(Tracker::read(f, noise)),
    },
    Instrument {
        format: "mte-dataset/1",
        kind: Some("points"),
        read: |f, noise| boxed(Points::read(f, noise)),
    },
    Instrument {
        format: "mte-rtest/1",
        kind: None,
        read: |f, noise| boxed(RTest::read(f, noise)),
    },
];

/// Reads a manifest and its tables and prepares the diagnosis: an `mte-dataset/1` manifest
/// (`kind` axis, tracker or points) or an `mte-rtest/1` manifest (R-test data). `noise_um` is the
/// stated standard uncertainty of one observation where the manifest states none (the R-test
/// format has no such field).
///
/// # Errors
/// [`DiagnoseError::Dataset`] naming the file, line and field for unreadable or malformed
/// input; [`DiagnoseError::InvalidData`] for a `noise_um` that is not a positive number.
pub fn load_with_noise(manifest_path: &Path, noise_um: Option<f64>) -> Result<Prepared> {
    if let Some(u) = noise_um.filter(|u| !(u.is_finite() && *u > 0.0)) {
        return Err(DiagnoseError::InvalidData {
            field: "the noise given (noise_um, `mte diagnose --noise-um`)".into(),
            detail: format!("{u} µm, expected the positive standard uncertainty of one reading"),
        });
    }
    let file = ManifestFile::read(manifest_path)?;
    let format = file
        .str_field("format")
        .ok_or_else(|| file.missing("format", "`mte-dataset/1` or `mte-rtest/1`"))?;
    let kind = file.str_field("kind");
    let instrument = INSTRUMENTS
        .iter()
        .find(|i| i.format == format && (i.kind.is_none() || i.kind == kind))
        .ok_or_else(|| {
            let formats: Vec<&str> = INSTRUMENTS.iter().map(|i| i.format).collect();
            if formats.contains(&format) {
                let kinds: Vec<&str> = INSTRUMENTS
                    .iter()
                    .filter(|i| i.format == format)
                    .filter_map(|i| i.kind)
                    .collect();
                file.error(format!(
                    "field `kind`: {}, expected one of {} (R-test data use the mte-rtest/1 manifest)",
                    kind.map_or("missing".to_string(), |k| format!("`{k}`")),
                    kinds.join(", ")
                ))
            } else {
                file.error(format!(
                    "field `format`: `{format}`, expected `mte-dataset/1` or `mte-rtest/1`"
                ))
            }
        })?;
    let (model, base_model) = (instrument.read)(&file, noise_um)?;
    prepare(model.as_ref(), base_model.as_ref(), &file.path)
}

/// [`load_with_noise`] with the noise the dataset states.
///
/// # Errors
/// As [`load_with_noise`].
pub fn load(manifest_path: &Path) -> Result<Prepared> {
    load_with_noise(manifest_path, None)
}
