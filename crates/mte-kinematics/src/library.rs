//! The bundled machines (`fixtures/machines/*.json`, embedded at compile time).

use crate::error::{KinError, Result};
use crate::machine::Machine;

const LIBRARY: &[(&str, &str)] = &[
    (
        "seed000-ca-gantry",
        include_str!("../../../fixtures/machines/seed000-ca-gantry.json"),
    ),
    (
        "seed001-4axis",
        include_str!("../../../fixtures/machines/seed001-4axis.json"),
    ),
    (
        "seed002-bc-trunnion",
        include_str!("../../../fixtures/machines/seed002-bc-trunnion.json"),
    ),
    (
        "seed003-ac-table",
        include_str!("../../../fixtures/machines/seed003-ac-table.json"),
    ),
    (
        "seed004-3axis",
        include_str!("../../../fixtures/machines/seed004-3axis.json"),
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
        Machine::parse(text, &format!("fixtures/machines/{name}.json"))
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
