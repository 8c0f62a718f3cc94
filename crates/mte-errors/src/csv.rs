//! Unit-suffixed columns (`x_mm`, `a_deg`) on the workspace's one CSV reader,
//! [`mte_linalg::csv`] (rules there: header line, `#` comments, trimmed fields, finite numbers).

use crate::error::{Error, Result};
use crate::units::{Unit, split_suffix};
pub use mte_linalg::csv::{CsvError, CsvTable};

impl From<CsvError> for Error {
    fn from(e: CsvError) -> Error {
        Error::Csv {
            source_name: e.source_name,
            line: e.line,
            message: e.message,
        }
    }
}

/// Column lookup by unit suffix, and errors of this crate's type, on a [`CsvTable`].
pub trait UnitColumns {
    /// Finds a column `base_<unit>` (e.g. `x_mm`, `a_deg`); returns its index and unit.
    ///
    /// # Errors
    /// [`Error::Csv`] on the header line when two columns match (`x_mm` and `x_um`).
    fn column_with_unit(&self, base: &str) -> Result<Option<(usize, Unit)>>;

    /// Like [`UnitColumns::column_with_unit`] but the column must exist.
    ///
    /// # Errors
    /// [`Error::Csv`] on the header line naming the missing column and the columns found.
    fn require_with_unit(&self, base: &str, example: &str) -> Result<(usize, Unit)>;

    /// An error of this crate at `line` of the table's file.
    fn err(&self, line: usize, message: String) -> Error;
}

impl UnitColumns for CsvTable {
    fn column_with_unit(&self, base: &str) -> Result<Option<(usize, Unit)>> {
        let mut found = None;
        for (j, h) in self.headers.iter().enumerate() {
            if let Some((b, u)) = split_suffix(h)
                && b.eq_ignore_ascii_case(base)
            {
                if found.is_some() {
                    return Err(self.err(
                        self.header_line,
                        format!("two columns give `{base}` (`{h}` and another)"),
                    ));
                }
                found = Some((j, u));
            }
        }
        Ok(found)
    }

    fn require_with_unit(&self, base: &str, example: &str) -> Result<(usize, Unit)> {
        self.column_with_unit(base)?.ok_or_else(|| {
            self.err(
                self.header_line,
                format!(
                    "missing column `{base}_<unit>` (e.g. `{example}`); found: {}",
                    self.headers.join(", ")
                ),
            )
        })
    }

    fn err(&self, line: usize, message: String) -> Error {
        self.error(line, message).into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_reports_lines() {
        let t = CsvTable::parse(
            "# comment\nposition_mm, error_um\n0, 1\n\n10, NaN\n",
            "t.csv",
        )
        .unwrap();
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.line(1), 5);
        assert_eq!(
            t.require_with_unit("position", "position_mm").unwrap(),
            (0, Unit::Mm)
        );
        let e = t.number(1, 1).unwrap_err().to_string();
        assert!(e.contains("line 5") && e.contains("error_um"), "{e}");
        let e = t.require_with_unit("time", "t_s").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("missing column"), "{e}");
        let e = t.require_with_unit("time", "t_s").unwrap_err();
        assert!(matches!(e, Error::Csv { line: 2, .. }), "{e}");
        let both = CsvTable::parse("x_mm,x_um\n1,2\n", "x.csv").unwrap();
        assert!(both.column_with_unit("x").is_err());
    }
}
