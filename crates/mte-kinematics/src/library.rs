//! The bundled machines (`crates/mte-kinematics/machines/*.json`, embedded at compile time), and
//! the one lookup of a machine by library name or file.

use crate::error::{KinError, Result};
use crate::machine::Machine;
use std::path::Path;

const LIBRARY: &[(&str, &str)] = &[
    (
        "seed000-ca-gantry",
        include_str!("../machines/seed000-ca-gantry.json"),
    ),
    (
        "seed001-4axis",
        include_str!("../machines/seed001-4axis.json"),
    ),
    (
        "seed002-bc-trunnion",
        include_str!("../machines/seed002-bc-trunnion.json"),
    ),
    (
        "seed003-ac-table",
        include_str!("../machines/seed003-ac-table.json"),
    ),
    (
        "seed004-3axis",
        include_str!("../machines/seed004-3axis.json"),
    ),
];

const NAMES: &[&str] = &[
    "seed000-ca-gantry",
    "seed001-4axis",
    "seed002-bc-trunnion",
    "seed003-ac-table",
    "seed004-3axis",
];

impl Machine {
    /// A bundled machine by name (see [`Machine::library_names`]).
    ///
    /// # Errors
    /// [`KinError::UnknownMachine`] listing the known names.
    ///
    /// ```
    /// let m = mte_kinematics::Machine::library("seed003-ac-table").unwrap();
    /// assert_eq!(m.axes().len(), 5);
    /// ```
    pub fn library(name: &str) -> Result<Machine> {
        let (_, text) =
            LIBRARY
                .iter()
                .find(|(n, _)| *n == name)
                .ok_or_else(|| KinError::UnknownMachine {
                    name: name.to_string(),
                    known: NAMES.join(", "),
                })?;
        Machine::parse(text, &format!("mte-kinematics/machines/{name}.json"))
    }

    /// A machine named by a bundled machine's name or by a machine JSON file, as manifests and
    /// the command line name them: a library name wins; otherwise `dir.join(name)` is read
    /// (`dir` is the folder of the file that names the machine, `Path::new("")` for the
    /// current directory).
    ///
    /// # Errors
    /// [`KinError::NoSuchMachine`] when `name` is not a library name and no such file exists;
    /// the errors of [`Machine::from_file`] for a file that does not parse.
    ///
    /// ```
    /// use mte_kinematics::Machine;
    /// use std::path::Path;
    /// let m = Machine::library_or_file("seed004-3axis", Path::new("any/dir")).unwrap();
    /// assert_eq!(m.name(), "seed004-3axis");
    /// let err = Machine::library_or_file("nope.json", Path::new("")).unwrap_err();
    /// assert!(err.to_string().contains("neither a library machine"), "{err}");
    /// ```
    pub fn library_or_file(name: &str, dir: &Path) -> Result<Machine> {
        if NAMES.contains(&name) {
            return Machine::library(name);
        }
        let path = dir.join(name);
        if path.is_file() {
            Machine::from_file(&path)
        } else {
            Err(KinError::NoSuchMachine {
                name: name.to_string(),
                path: path.display().to_string(),
                known: NAMES.join(", "),
            })
        }
    }

    /// Names of the bundled machines.
    pub fn library_names() -> &'static [&'static str] {
        NAMES
    }

    /// The JSON text of a bundled machine.
    pub fn library_json(name: &str) -> Option<&'static str> {
        LIBRARY.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_match_table_and_files() {
        assert_eq!(NAMES.len(), LIBRARY.len());
        for (n, (m, _)) in NAMES.iter().zip(LIBRARY) {
            assert_eq!(n, m);
            assert_eq!(Machine::library(n).unwrap().name(), *n);
        }
        let err = Machine::library("nope").unwrap_err().to_string();
        assert!(err.contains("seed003-ac-table"), "{err}");
    }
}
