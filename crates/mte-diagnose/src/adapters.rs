//! Observation models of machine datasets (R-test, laser tracker): how each kinematic error slot
//! reaches the observations, from the machine's first-order kinematics.

use std::path::Path;

use crate::dataset::{Manifest, Prepared, Table};
use crate::{DiagnoseError, Result};

/// Prepares an R-test or tracker dataset.
pub(crate) fn prepare_machine_dataset(
    kind: &str,
    _manifest: &Manifest,
    _table: &Table,
    _dir: &Path,
    manifest_path: &Path,
) -> Result<Prepared> {
    Err(DiagnoseError::Dataset {
        path: manifest_path.display().to_string(),
        detail: format!("field `kind`: `{kind}`, expected one of axis, rtest, tracker"),
    })
}
