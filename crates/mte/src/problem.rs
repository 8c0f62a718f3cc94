//! The sensitivity problem file (`"format": "mte-sensitivity/1"`, docs/formats.md): read,
//! checked field by field, every error naming the file.
//!
//! ```
//! let dir = std::env::temp_dir().join(format!("mte-problem-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let p = dir.join("p.json");
//! std::fs::write(&p, r#"{"inputs": [{"name": "a", "dist": "normal", "sd": 1}], "model": {"name": "linear", "coef": [1]}}"#).unwrap();
//! let err = mte::problem::read_problem(&p).unwrap_err().to_string();
//! assert!(err.contains("p.json") && err.contains("`format`"), "{err}");
//! # std::fs::remove_dir_all(&dir).unwrap();
//! ```

use crate::CliError;
use crate::report::read_text;
use serde_json::Value;
use std::path::Path;

fn field_err(path: &Path, field: &str, m: impl std::fmt::Display) -> CliError {
    CliError::Library(format!("{}: field `{field}`: {m}", path.display()))
}

/// Reads a problem file: JSON syntax, [`check_fields`], and for a test-function model the
/// inputs (`mte_sensitivity::Problem::from_json`); the method sections (`sobol`, `pce`,
/// `morris`) parse into their parameter types. A machine model's files are read by the
/// command (they are machine and error-set files with readers of their own).
///
/// # Errors
/// [`CliError`] naming the file and the field (or line and column for JSON syntax).
pub fn read_problem(path: &Path) -> Result<Value, CliError> {
    let text = read_text(path)?;
    let v: Value = serde_json::from_str(&text).map_err(|e| {
        CliError::Library(format!(
            "{}: line {} column {}: {e}",
            path.display(),
            e.line(),
            e.column()
        ))
    })?;
    check_fields(&v, path)?;
    let machine = v
        .get("model")
        .and_then(|m| m.get("name"))
        .and_then(Value::as_str)
        == Some("machine");
    if !machine {
        mte_sensitivity::Problem::from_json(&v)
            .map_err(|e| CliError::Library(format!("{}: {e}", path.display())))?;
    }
    fn section<T: serde::de::DeserializeOwned>(
        v: &Value,
        key: &str,
        path: &Path,
    ) -> Result<(), CliError> {
        if let Some(s) = v.get(key) {
            serde_json::from_value::<T>(s.clone()).map_err(|e| field_err(path, key, e))?;
        }
        Ok(())
    }
    section::<mte_sensitivity::sobol::SobolParams>(&v, "sobol", path)?;
    section::<mte_sensitivity::pce::PceParams>(&v, "pce", path)?;
    section::<mte_sensitivity::morris::MorrisParams>(&v, "morris", path)?;
    Ok(v)
}

/// Format tag of a problem file.
pub const FORMAT: &str = "mte-sensitivity/1";

/// The problem file's own fields: `format` present and right, no unknown or misspelt field at
/// the top level or in `model` (the method sections and inputs are checked by the library).
///
/// # Errors
/// [`CliError::Library`] naming the file and the field.
pub fn check_fields(v: &Value, path: &Path) -> Result<(), CliError> {
    let Some(o) = v.as_object() else {
        return Err(CliError::Library(format!(
            "{}: expected a JSON object {{\"format\": \"{FORMAT}\", …}}",
            path.display()
        )));
    };
    match o.get("format") {
        Some(Value::String(f)) if f == FORMAT => {}
        Some(f) => {
            return Err(field_err(
                path,
                "format",
                format!("{f}, expected \"{FORMAT}\""),
            ));
        }
        None => {
            return Err(field_err(
                path,
                "format",
                format!("missing; expected \"format\": \"{FORMAT}\""),
            ));
        }
    }
    let unknown = |keys: &serde_json::Map<String, Value>, known: &[&str], at: &str| match keys
        .keys()
        .find(|k| !known.contains(&k.as_str()))
    {
        Some(k) => {
            let near = mte_linalg::text::closest(k, known, 1);
            Err(field_err(
                path,
                &format!("{at}{k}"),
                format!(
                    "unknown field{}; expected one of {}",
                    near.first()
                        .map(|n| format!(" (did you mean `{n}`?)"))
                        .unwrap_or_default(),
                    known.join(", ")
                ),
            ))
        }
        None => Ok(()),
    };
    unknown(
        o,
        &[
            "format",
            "description",
            "inputs",
            "correlation",
            "model",
            "sobol",
            "pce",
            "morris",
        ],
        "",
    )?;
    if let Some(Value::Object(m)) = o.get("model") {
        let known: &[&str] = match m.get("name").and_then(Value::as_str) {
            Some("machine") => &["name", "machine", "errors", "points", "linearisation"],
            _ => &["name", "a", "coef"],
        };
        unknown(m, known, "model.")?;
        if let Some(Value::Object(p)) = m.get("points") {
            unknown(p, &["csv", "diagonals"], "model.points.")?;
        }
    }
    Ok(())
}
