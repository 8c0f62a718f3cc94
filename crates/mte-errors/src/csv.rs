//! A small CSV reader with line numbers and unit-suffixed headers.
//!
//! Rules: comma-separated, first non-comment line is the header, blank lines and lines starting
//! with `#` are skipped, fields are trimmed, no quoting. Numbers must be finite (`NaN`, `inf` are
//! rejected with the line and column).

use crate::error::{Error, Result};
use crate::units::{Unit, split_suffix};

/// A parsed table.
#[derive(Debug, Clone)]
pub struct CsvTable {
    /// File name used in error messages.
    pub source_name: String,
    /// Column names as written.
    pub headers: Vec<String>,
    /// Line number of the header.
    pub header_line: usize,
    /// (line number, fields) per data row.
    pub rows: Vec<(usize, Vec<String>)>,
}

impl CsvTable {
    /// Parse `text`; `source_name` names the file in errors.
    ///
    /// # Errors
    /// [`Error::Csv`] for an empty table, duplicate or empty column names, or a row with the wrong
    /// number of fields.
    pub fn parse(text: &str, source_name: &str) -> Result<CsvTable> {
        let err = |line, message: String| Error::Csv {
            source_name: source_name.to_string(),
            line,
            message,
        };
        let mut headers: Option<(usize, Vec<String>)> = None;
        let mut rows = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let t = raw.trim().trim_start_matches('\u{feff}');
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            let fields: Vec<String> = t.split(',').map(|f| f.trim().to_string()).collect();
            match &headers {
                None => {
                    for (j, h) in fields.iter().enumerate() {
                        if h.is_empty() {
                            return Err(err(line, format!("column {} has an empty name", j + 1)));
                        }
                        if fields[..j].contains(h) {
                            return Err(err(line, format!("column `{h}` appears twice")));
                        }
                    }
                    headers = Some((line, fields));
                }
                Some((_, h)) => {
                    if fields.len() != h.len() {
                        return Err(err(
                            line,
                            format!(
                                "expected {} fields (as the header), found {}",
                                h.len(),
                                fields.len()
                            ),
                        ));
                    }
                    rows.push((line, fields));
                }
            }
        }
        let Some((header_line, headers)) = headers else {
            return Err(err(0, "the table is empty (no header line)".into()));
        };
        Ok(CsvTable {
            source_name: source_name.to_string(),
            headers,
            header_line,
            rows,
        })
    }

    /// Index of the column named exactly `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.headers.iter().position(|h| h == name)
    }

    /// Find a column `base_<unit>` (e.g. `x_mm`, `a_deg`); returns its index and unit.
    ///
    /// # Errors
    /// [`Error::Csv`] on the header line when two columns match (`x_mm` and `x_um`).
    pub fn column_with_unit(&self, base: &str) -> Result<Option<(usize, Unit)>> {
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

    /// Like [`CsvTable::column_with_unit`] but the column must exist.
    ///
    /// # Errors
    /// [`Error::Csv`] on the header line naming the missing column and the columns found.
    pub fn require_with_unit(&self, base: &str, example: &str) -> Result<(usize, Unit)> {
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

    /// The number in row `r`, column `c`.
    ///
    /// # Errors
    /// [`Error::Csv`] naming the line and column when the field is not a finite number.
    pub fn number(&self, r: usize, c: usize) -> Result<f64> {
        let (line, f) = &self.rows[r];
        let s = &f[c];
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.err(
                *line,
                format!("column `{}`: `{s}` is not a finite number", self.headers[c]),
            )),
            Err(_) => Err(self.err(
                *line,
                format!("column `{}`: `{s}` is not a number", self.headers[c]),
            )),
        }
    }

    /// The line number of data row `r`.
    pub fn line(&self, r: usize) -> usize {
        self.rows[r].0
    }

    /// An error at `line` of this file.
    pub fn err(&self, line: usize, message: String) -> Error {
        Error::Csv {
            source_name: self.source_name.clone(),
            line,
            message,
        }
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
        let e = CsvTable::parse("a,b\n1\n", "x.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2"), "{e}");
        assert!(CsvTable::parse("# only\n", "x.csv").is_err());
        assert!(CsvTable::parse("a,a\n", "x.csv").is_err());
    }
}
