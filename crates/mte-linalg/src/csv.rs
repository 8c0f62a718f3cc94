//! The one CSV reader of the workspace: a header line, comma-separated fields, 1-based line
//! numbers kept for every row so that each crate's errors can name the file, line and column.
//!
//! Rules: the first non-comment line is the header; blank lines and lines starting with `#` are
//! skipped; fields are trimmed; no quoting (our formats have no commas inside fields). Numbers
//! must be finite: `NaN` and `inf` are rejected with the line and column. A header that is one
//! field with `;` or tabs in it is rejected as a file with another separator.
//!
//! ```
//! use mte_linalg::csv::CsvTable;
//! let t = CsvTable::parse("# probe run\nx_mm, e_um\n0, 1.5\n\n10, NaN\n", "run.csv").unwrap();
//! assert_eq!(t.number(0, 1).unwrap(), 1.5);
//! let err = t.number(1, 1).unwrap_err();
//! assert_eq!(err.to_string(), "run.csv: line 5: column `e_um`: `NaN` is not a finite number");
//! ```

/// A malformed table: the file, the 1-based line (0 when the table has no line at all) and what
/// was expected. Crates wrap it in their own error type.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{source_name}: line {line}: {message}")]
pub struct CsvError {
    /// File name (or `<string>`).
    pub source_name: String,
    /// 1-based line number in the file (0 when the table is empty).
    pub line: usize,
    /// What was wrong and what was expected.
    pub message: String,
}

/// A parsed table.
#[derive(Debug, Clone)]
pub struct CsvTable {
    /// File name used in error messages.
    pub source_name: String,
    /// Column names as written (trimmed).
    pub headers: Vec<String>,
    /// Line number of the header.
    pub header_line: usize,
    /// (line number, fields) per data row.
    pub rows: Vec<(usize, Vec<String>)>,
}

impl CsvTable {
    /// Parses `text`; `source_name` names the file in errors.
    ///
    /// # Errors
    /// [`CsvError`] for an empty table, duplicate or empty column names, a header of one field
    /// with `;` or tabs in it, or a row with another number of fields than the header.
    pub fn parse(text: &str, source_name: &str) -> Result<CsvTable, CsvError> {
        let err = |line, message: String| CsvError {
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
                    // A spreadsheet set to a decimal comma writes `;` between fields, and some
                    // exports write tabs: one field with either in it is such a file.
                    if let [h] = &fields[..] {
                        if let Some(sep) = [';', '\t'].into_iter().find(|&c| h.contains(c)) {
                            return Err(err(
                                line,
                                format!(
                                    "the header is one field with {} in it: fields must be \
                                     separated by commas, numbers written with a decimal point \
                                     (export as comma-separated values with `.` as the decimal \
                                     mark)",
                                    if sep == ';' { "`;`" } else { "tabs" }
                                ),
                            ));
                        }
                    }
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

    /// Number of data rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether the table has no data rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Index of the column named exactly `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.headers.iter().position(|h| h == name)
    }

    /// Index of the column named exactly `name`, which must exist.
    ///
    /// # Errors
    /// [`CsvError`] on the header line naming the missing column and the columns found.
    pub fn require(&self, name: &str) -> Result<usize, CsvError> {
        self.column(name).ok_or_else(|| {
            self.error(
                self.header_line,
                format!(
                    "missing column `{name}`; found: {}",
                    self.headers.join(", ")
                ),
            )
        })
    }

    /// The text in row `r`, column `c`.
    pub fn text(&self, r: usize, c: usize) -> &str {
        &self.rows[r].1[c]
    }

    /// The number in row `r`, column `c`.
    ///
    /// # Errors
    /// [`CsvError`] naming the line and column when the field is not a finite number.
    pub fn number(&self, r: usize, c: usize) -> Result<f64, CsvError> {
        let (line, f) = &self.rows[r];
        let s = &f[c];
        let what = match s.parse::<f64>() {
            Ok(v) if v.is_finite() => return Ok(v),
            Ok(_) => "is not a finite number",
            Err(_) => "is not a number",
        };
        Err(self.error(*line, format!("column `{}`: `{s}` {what}", self.headers[c])))
    }

    /// Every number of column `c`, each checked as [`CsvTable::number_within`].
    ///
    /// # Errors
    /// The first field that is not a number or is out of range, with its line.
    pub fn numbers_within(
        &self,
        c: usize,
        max_abs: f64,
        meaning: &str,
    ) -> Result<Vec<f64>, CsvError> {
        (0..self.len())
            .map(|r| self.number_within(r, c, max_abs, meaning))
            .collect()
    }

    /// The number in row `r`, column `c`, which must be physically possible: |value| below
    /// `max_abs`, which `meaning` explains (e.g. `"a deviation of 1 m (10^6 µm) or more is not a
    /// measured positioning error"`).
    ///
    /// ```
    /// use mte_linalg::csv::CsvTable;
    /// let t = CsvTable::parse("deviation_um\n1e150\n", "runs.csv").unwrap();
    /// let err = t.number_within(0, 0, 1e6, "1 m or more is not a positioning error").unwrap_err();
    /// assert_eq!(err.to_string(), "runs.csv: line 2: column `deviation_um`: `1e150` is out of range (|value| < 1e6): 1 m or more is not a positioning error");
    /// ```
    ///
    /// # Errors
    /// As [`CsvTable::number`], and [`CsvError`] naming the line and column for a value out
    /// of range.
    pub fn number_within(
        &self,
        r: usize,
        c: usize,
        max_abs: f64,
        meaning: &str,
    ) -> Result<f64, CsvError> {
        let v = self.number(r, c)?;
        if v.abs() < max_abs {
            return Ok(v);
        }
        let (line, f) = &self.rows[r];
        Err(self.error(
            *line,
            format!(
                "column `{}`: `{}` is out of range (|value| < {max_abs:e}): {meaning}",
                self.headers[c], f[c]
            ),
        ))
    }

    /// The distinct texts of column `c` in order of first appearance, and each row's index
    /// among them (run ids, set-up ids).
    ///
    /// ```
    /// use mte_linalg::csv::CsvTable;
    /// let t = CsvTable::parse("run\nb\na\nb\n", "runs.csv").unwrap();
    /// assert_eq!(t.groups(0), (vec!["b".to_string(), "a".to_string()], vec![0, 1, 0]));
    /// ```
    pub fn groups(&self, c: usize) -> (Vec<String>, Vec<usize>) {
        let mut names: Vec<String> = Vec::new();
        let index = (0..self.len())
            .map(|r| {
                let id = self.text(r, c);
                names.iter().position(|s| s == id).unwrap_or_else(|| {
                    names.push(id.to_string());
                    names.len() - 1
                })
            })
            .collect();
        (names, index)
    }

    /// The numbers of column `c`, every row.
    ///
    /// # Errors
    /// As [`CsvTable::number`], for the first bad field.
    pub fn numbers(&self, c: usize) -> Result<Vec<f64>, CsvError> {
        (0..self.len()).map(|r| self.number(r, c)).collect()
    }

    /// The line number of data row `r`.
    pub fn line(&self, r: usize) -> usize {
        self.rows[r].0
    }

    /// An error at `line` of this file.
    pub fn error(&self, line: usize, message: String) -> CsvError {
        CsvError {
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
            "\u{feff}# comment\nposition_mm, error_um\n0, 1\n\n10, inf\n11, x\n",
            "t.csv",
        )
        .unwrap();
        assert_eq!((t.len(), t.header_line, t.line(1)), (3, 2, 5));
        assert_eq!(t.require("error_um").unwrap(), 1);
        assert_eq!(t.text(2, 1), "x");
        let e = t.number(1, 1).unwrap_err().to_string();
        assert_eq!(
            e,
            "t.csv: line 5: column `error_um`: `inf` is not a finite number"
        );
        let e = t.numbers(1).unwrap_err();
        assert_eq!(e.line, 5);
        let e = t.number(2, 1).unwrap_err().to_string();
        assert!(e.contains("line 6") && e.contains("is not a number"), "{e}");
        let e = t.require("time_s").unwrap_err().to_string();
        assert!(
            e.contains("line 2") && e.contains("missing column `time_s`"),
            "{e}"
        );
    }

    #[test]
    fn malformed_tables_are_rejected_with_their_line() {
        let line_of = |text: &str| CsvTable::parse(text, "x.csv").unwrap_err().line;
        assert_eq!(line_of("a,b\n1\n"), 2);
        assert_eq!(line_of("# only\n\n"), 0);
        assert_eq!(line_of("\na,a\n"), 2);
        assert_eq!(line_of("a,,b\n"), 1);
        // Another separator is named on the header line, not met as a count of fields later.
        let e = CsvTable::parse("# run 1\nx_mm;e_um\n0;1,5\n", "x.csv").unwrap_err();
        assert_eq!(e.line, 2);
        assert!(
            e.message.contains("`;`") && e.message.contains("decimal point"),
            "{e}"
        );
        let e = CsvTable::parse("x_mm\te_um\n0\t1.5\n", "x.csv").unwrap_err();
        assert!(e.message.contains("tabs"), "{e}");
        // A one-column table is still one.
        assert_eq!(CsvTable::parse("x_mm\n0\n", "x.csv").unwrap().len(), 1);
    }
}
