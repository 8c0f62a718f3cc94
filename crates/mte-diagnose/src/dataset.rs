//! Datasets on disk: reading a manifest (JSON) and its observation tables (CSV) with messages
//! that name the file, the line and the field. The instruments ([`crate::instruments`]) build
//! on these; this module knows none of them.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

use crate::{DiagnoseError, Result};

pub(crate) use mte_linalg::csv::CsvTable as Table;

impl From<mte_linalg::csv::CsvError> for DiagnoseError {
    fn from(e: mte_linalg::csv::CsvError) -> Self {
        DiagnoseError::Dataset {
            path: e.source_name,
            detail: format!("line {}: {}", e.line, e.message),
        }
    }
}

/// Declares the manifest struct of an `mte-dataset/1` instrument: the fields every kind has
/// (`format`, `kind`, `description`, `data`, `noise_um`, `base_model`) and the instrument's
/// own, read by serde with unknown fields rejected.
macro_rules! dataset_manifest {
    ($(#[$meta:meta])* $name:ident { $($(#[$fmeta:meta])* $field:ident: $ty:ty,)* }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $name {
            #[allow(dead_code)]
            format: String,
            #[allow(dead_code)]
            kind: String,
            #[serde(default)]
            description: Option<String>,
            /// The observation table, relative to the manifest.
            data: String,
            #[serde(default)]
            noise_um: Option<f64>,
            #[serde(default)]
            base_model: Option<serde_json::Value>,
            $($(#[$fmeta])* #[serde(default)] $field: $ty,)*
        }
    };
}
pub(crate) use dataset_manifest;

/// A manifest read from disk: its JSON value, its path (for messages) and its folder (where
/// the tables it names are).
pub(crate) struct ManifestFile {
    /// The file, as named in messages.
    pub path: String,
    /// The folder the manifest's relative file names start from.
    pub dir: PathBuf,
    /// The parsed JSON.
    pub value: serde_json::Value,
    /// The text as read (a format with its own reader parses it again from this, not the disk).
    pub text: String,
}

impl ManifestFile {
    /// Reads and parses the manifest at `path` (a UTF-8 byte-order mark is accepted).
    pub fn read(path: &Path) -> Result<ManifestFile> {
        let name = path.display().to_string();
        let text = mte_linalg::text::read_text(path).map_err(|e| DiagnoseError::Dataset {
            path: name.clone(),
            detail: e.to_string(),
        })?;
        let value = serde_json::from_str(&text).map_err(|e| DiagnoseError::Dataset {
            path: name.clone(),
            detail: e.to_string(),
        })?;
        Ok(ManifestFile {
            path: name,
            dir: path
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_else(|| PathBuf::from(".")),
            value,
            text,
        })
    }

    /// The string field `field`, if present.
    pub fn str_field(&self, field: &str) -> Option<&str> {
        self.value.get(field).and_then(|v| v.as_str())
    }

    /// The manifest as an instrument's typed manifest (serde derive, unknown fields rejected).
    pub fn parse<T: DeserializeOwned>(&self) -> Result<T> {
        serde_json::from_str(&self.text).map_err(|e| self.error(e.to_string()))
    }

    /// An error about this manifest.
    pub fn error(&self, detail: impl Into<String>) -> DiagnoseError {
        DiagnoseError::Dataset {
            path: self.path.clone(),
            detail: detail.into(),
        }
    }

    /// "field `field`: missing (what)".
    pub fn missing(&self, field: &str, what: &str) -> DiagnoseError {
        self.error(format!("field `{field}`: missing ({what})"))
    }

    /// Reads the table `name` relative to the manifest.
    pub fn table(&self, name: &str) -> Result<Table> {
        read_table(&self.dir.join(name))
    }

    /// Checks that a stated uncertainty is a positive finite number.
    pub fn check_noise(&self, field: &str, value: Option<f64>) -> Result<()> {
        match value.filter(|n| !(n.is_finite() && *n > 0.0 && *n < 1e6)) {
            Some(n) => Err(self.error(format!(
                "field `{field}`: {n} is not a standard uncertainty (a positive number below 1e6)"
            ))),
            None => Ok(()),
        }
    }
}

/// Reads the CSV table at `path` (the workspace's one reader, [`mte_linalg::csv`]).
pub(crate) fn read_table(path: &Path) -> Result<Table> {
    let text = mte_linalg::text::read_text(path).map_err(|e| DiagnoseError::Dataset {
        path: path.display().to_string(),
        detail: e.to_string(),
    })?;
    Ok(Table::parse(&text, &path.display().to_string())?)
}
