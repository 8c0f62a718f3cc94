//! Report helpers shared by the subcommands: a Markdown table builder, number formatting as
//! engineers read it (µm, µrad, arcsec, deg from the internal mm and rad), and JSON/text writing
//! whose errors name the file.
//!
//! Non-finite numbers are never printed as `NaN`/`inf`: every formatter writes `n/a` instead.
//!
//! ```
//! use mte::report::{fmt_um, MarkdownTable, Align};
//! let mut t = MarkdownTable::new(["parameter", "value"]).align(1, Align::Right);
//! t.row(["EX0C", &fmt_um(0.01234)])?;
//! assert_eq!(t.render(), "| parameter | value |\n|---|---:|\n| EX0C | 12.3 µm |\n");
//! # Ok::<(), mte::CliError>(())
//! ```

use crate::CliError;
use std::path::Path;

/// Column alignment in a Markdown table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Align {
    /// `|---|`
    #[default]
    Default,
    /// `|:---|`
    Left,
    /// `|---:|` (numbers)
    Right,
    /// `|:---:|`
    Center,
}

/// A GitHub-flavoured Markdown table, built row by row.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkdownTable {
    headers: Vec<String>,
    align: Vec<Align>,
    rows: Vec<Vec<String>>,
}

impl MarkdownTable {
    /// A table with these column headers.
    pub fn new<I, S>(headers: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        let headers: Vec<String> = headers.into_iter().map(Into::into).collect();
        let align = vec![Align::Default; headers.len()];
        Self {
            headers,
            align,
            rows: Vec::new(),
        }
    }

    /// Sets the alignment of column `col` (ignored when out of range).
    pub fn align(mut self, col: usize, align: Align) -> Self {
        if let Some(a) = self.align.get_mut(col) {
            *a = align;
        }
        self
    }

    /// Appends a row.
    ///
    /// # Errors
    /// [`CliError::Usage`] when the number of cells differs from the number of headers.
    pub fn row<I, S>(&mut self, cells: I) -> Result<(), CliError>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<str>,
    {
        let cells: Vec<String> = cells.into_iter().map(|c| escape(c.as_ref())).collect();
        if cells.len() != self.headers.len() {
            return Err(CliError::Usage(format!(
                "table row has {} cells, the table has {} columns ({})",
                cells.len(),
                self.headers.len(),
                self.headers.join(", ")
            )));
        }
        self.rows.push(cells);
        Ok(())
    }

    /// Number of rows so far.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// `true` when no row was added.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The table as Markdown, one line per row, ending with a newline.
    pub fn render(&self) -> String {
        let mut out = String::new();
        let line = |cells: &[String]| format!("| {} |\n", cells.join(" | "));
        let headers: Vec<String> = self.headers.iter().map(|h| escape(h)).collect();
        out.push_str(&line(&headers));
        let seps: Vec<&str> = self
            .align
            .iter()
            .map(|a| match a {
                Align::Default => "---",
                Align::Left => ":---",
                Align::Right => "---:",
                Align::Center => ":---:",
            })
            .collect();
        out.push_str(&format!("|{}|\n", seps.join("|")));
        for r in &self.rows {
            out.push_str(&line(r));
        }
        out
    }
}

fn escape(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// Text written for a non-finite number.
pub const NOT_AVAILABLE: &str = "n/a";

/// `v` with `digits` significant digits in fixed notation for 1e-4 ≤ |v| < 1e6, scientific
/// otherwise; `0` for zero, `n/a` for non-finite values.
///
/// ```
/// use mte::report::fmt_sig;
/// assert_eq!(fmt_sig(0.0123456, 3), "0.0123");
/// assert_eq!(fmt_sig(-1234.6, 3), "-1235");
/// assert_eq!(fmt_sig(12.0, 3), "12.0");
/// assert_eq!(fmt_sig(3.2e-7, 2), "3.2e-7");
/// assert_eq!(fmt_sig(f64::NAN, 3), "n/a");
/// ```
pub fn fmt_sig(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return NOT_AVAILABLE.to_string();
    }
    if v == 0.0 {
        return "0".to_string();
    }
    let digits = digits.max(1);
    let a = v.abs();
    if !(1e-4..1e6).contains(&a) {
        return format!("{:.*e}", digits - 1, v);
    }
    let exponent = a.log10().floor() as i32;
    let decimals = (digits as i32 - 1 - exponent).max(0) as usize;
    let s = format!("{v:.decimals$}");
    // rounding can carry into a new digit (9.99 → 10.0): recompute once
    let rounded: f64 = s.parse().unwrap_or(v);
    let e2 = rounded.abs().log10().floor() as i32;
    if e2 > exponent && decimals > 0 {
        let d2 = (digits as i32 - 1 - e2).max(0) as usize;
        return format!("{v:.d2$}");
    }
    s
}

/// Micrometres from millimetres, a plain number for table cells: three significant digits, at
/// most three decimals (0.001 µm = 1 nm is the finest any of our instruments resolves).
///
/// ```
/// use mte::report::fmt_um_value;
/// assert_eq!(fmt_um_value(0.0123456), "12.3");
/// assert_eq!(fmt_um_value(0.1234), "123");
/// assert_eq!(fmt_um_value(-0.0004), "-0.400");
/// assert_eq!(fmt_um_value(2.5e-8), "0.000");
/// ```
pub fn fmt_um_value(mm: f64) -> String {
    let um = mm * 1e3;
    if !um.is_finite() {
        return NOT_AVAILABLE.to_string();
    }
    let a = um.abs();
    if a >= 1e6 {
        return format!("{um:.3e}");
    }
    let decimals = if a >= 100.0 {
        0
    } else if a >= 10.0 {
        1
    } else if a >= 1.0 {
        2
    } else {
        3
    };
    format!("{um:.decimals$}")
}

/// Micrometres with the unit, e.g. `"12.3 µm"`; see [`fmt_um_value`].
pub fn fmt_um(mm: f64) -> String {
    with_unit(fmt_um_value(mm), "µm")
}

/// Microradians from radians with the unit, three significant digits, e.g. `"48.5 µrad"`.
///
/// ```
/// assert_eq!(mte::report::fmt_urad(4.848e-5), "48.5 µrad");
/// ```
pub fn fmt_urad(rad: f64) -> String {
    with_unit(fmt_fixed_sig(rad * 1e6), "µrad")
}

/// Arcseconds from radians with the unit, e.g. `"10.0″"` for 48.48 µrad.
///
/// ```
/// assert_eq!(mte::report::fmt_arcsec(10.0_f64.to_radians() / 3600.0), "10.0″");
/// ```
pub fn fmt_arcsec(rad: f64) -> String {
    let v = fmt_fixed_sig(rad.to_degrees() * 3600.0);
    if v == NOT_AVAILABLE {
        v
    } else {
        format!("{v}″")
    }
}

/// Degrees from radians with the unit, three decimals (1 mdeg), e.g. `"45.000°"`.
///
/// ```
/// assert_eq!(mte::report::fmt_deg(std::f64::consts::FRAC_PI_4), "45.000°");
/// ```
pub fn fmt_deg(rad: f64) -> String {
    let d = rad.to_degrees();
    if d.is_finite() {
        format!("{d:.3}°")
    } else {
        NOT_AVAILABLE.to_string()
    }
}

/// Value ± expanded uncertainty in µm from mm, both with the decimals of the uncertainty's two
/// significant digits, e.g. `"12.34 ± 0.52 µm"`.
///
/// ```
/// assert_eq!(mte::report::fmt_um_pm(0.012341, 0.000523), "12.34 ± 0.52 µm");
/// ```
pub fn fmt_um_pm(value_mm: f64, uncertainty_mm: f64) -> String {
    let (v, u) = (value_mm * 1e3, uncertainty_mm * 1e3);
    if !v.is_finite() || !u.is_finite() {
        return NOT_AVAILABLE.to_string();
    }
    if u <= 0.0 {
        return format!("{} µm", fmt_um_value(value_mm));
    }
    let decimals = (1 - u.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.decimals$} ± {u:.decimals$} µm")
}

/// Three significant digits in fixed notation below 1e6, one decimal at least for 10..1000.
fn fmt_fixed_sig(v: f64) -> String {
    if !v.is_finite() {
        return NOT_AVAILABLE.to_string();
    }
    let a = v.abs();
    if a == 0.0 {
        return "0".to_string();
    }
    if !(1e-3..1e6).contains(&a) {
        return format!("{v:.2e}");
    }
    fmt_sig(v, 3)
}

fn with_unit(v: String, unit: &str) -> String {
    if v == NOT_AVAILABLE {
        v
    } else {
        format!("{v} {unit}")
    }
}

/// Writes `value` as pretty JSON (trailing newline) to `path`, creating parent directories.
///
/// # Errors
/// [`CliError::Io`] or [`CliError::Json`] naming `path`.
pub fn write_json<T: serde::Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), CliError> {
    let mut text = serde_json::to_string_pretty(value).map_err(|source| CliError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    text.push('\n');
    write_text(path, &text)
}

/// Reads JSON from `path`.
///
/// # Errors
/// [`CliError::Io`] if the file cannot be read, [`CliError::Json`] (with line and column) if it
/// does not parse into `T`.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, CliError> {
    let text = read_text(path)?;
    serde_json::from_str(&text).map_err(|source| CliError::Json {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads a user's text file with [`mte_linalg::text::read_text`]: regular files only (a FIFO
/// would block), a UTF-8 byte-order mark dropped.
///
/// # Errors
/// [`CliError::Io`] naming the file.
pub fn read_text(path: &Path) -> Result<String, CliError> {
    mte_linalg::text::read_text(path).map_err(|source| CliError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Refuses a path that exists but is not a regular file (a FIFO or device would block the
/// reader that opens it). A missing path passes: its reader reports it.
///
/// # Errors
/// [`CliError::Io`] naming the file.
pub fn check_regular_file(path: &Path) -> Result<(), CliError> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => Err(CliError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a regular file (a directory, FIFO or device cannot be read as data)",
            ),
        }),
        _ => Ok(()),
    }
}

/// Writes text (Markdown, SVG, CSV) to `path`, creating parent directories.
///
/// # Errors
/// [`CliError::Io`] naming the file (or the directory that could not be created).
pub fn write_text(path: &Path, text: &str) -> Result<(), CliError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| CliError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    std::fs::write(path, text).map_err(|source| CliError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_renders_alignment_and_escapes_pipes() {
        let mut t = MarkdownTable::new(["a", "b|c", "d"])
            .align(0, Align::Left)
            .align(1, Align::Center)
            .align(2, Align::Right);
        t.row(["x|y", "2", "3"]).unwrap();
        assert_eq!(
            t.render(),
            "| a | b\\|c | d |\n|:---|:---:|---:|\n| x\\|y | 2 | 3 |\n"
        );
        assert_eq!(t.len(), 1);
        let err = t.row(["only one"]).unwrap_err();
        assert!(err.to_string().contains("1 cells"), "{err}");
    }

    #[test]
    fn micrometre_formatting_chooses_digits_by_magnitude() {
        // mm → µm: 1 mm = 1000 µm
        let cases = [
            (1.0, "1000"),
            (0.2, "200"),
            (0.05, "50.0"),
            (0.0123, "12.3"),
            (0.001, "1.00"),
            (0.00012, "0.120"),
            (-0.0025, "-2.50"),
            (0.0, "0.000"),
        ];
        for (mm, s) in cases {
            assert_eq!(fmt_um_value(mm), s, "{mm} mm");
        }
        assert_eq!(fmt_um(f64::NAN), "n/a");
        assert_eq!(fmt_um(f64::INFINITY), "n/a");
    }

    #[test]
    fn angle_formatting_uses_the_definitions() {
        // 1″ = π / 648000 rad = 4.8481 µrad
        let arcsec = std::f64::consts::PI / 648_000.0;
        assert_eq!(fmt_arcsec(arcsec), "1.00″");
        assert_eq!(fmt_arcsec(-25.0 * arcsec), "-25.0″");
        assert_eq!(fmt_urad(arcsec), "4.85 µrad");
        assert_eq!(fmt_urad(1e-4), "100 µrad");
        assert_eq!(fmt_deg(std::f64::consts::PI), "180.000°");
        assert_eq!(fmt_deg(f64::NAN), "n/a");
        assert_eq!(fmt_arcsec(f64::NAN), "n/a");
    }

    #[test]
    fn significant_digits_and_plus_minus() {
        assert_eq!(fmt_sig(9.996, 3), "10.0");
        assert_eq!(fmt_sig(0.99996, 4), "1.000");
        assert_eq!(fmt_sig(123456.0, 3), "123456");
        assert_eq!(fmt_sig(2.5e7, 3), "2.50e7");
        assert_eq!(fmt_um_pm(0.0101, 0.0021), "10.1 ± 2.1 µm");
        assert_eq!(fmt_um_pm(0.0101, 0.0), "10.1 µm");
        assert_eq!(fmt_um_pm(f64::NAN, 0.001), "n/a");
    }

    #[test]
    fn json_round_trip_and_errors_name_the_path() {
        let dir = std::env::temp_dir().join(format!("mte-report-test-{}", std::process::id()));
        let path = dir.join("sub").join("out.json");
        let value = serde_json::json!({"dz_um": [1.5, -2.0], "name": "EX0C"});
        write_json(&path, &value).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.ends_with('\n'));
        let back: serde_json::Value = read_json(&path).unwrap();
        assert_eq!(back, value);
        std::fs::write(&path, "{ \"a\": ").unwrap();
        let err = read_json::<serde_json::Value>(&path).unwrap_err();
        assert!(matches!(err, CliError::Json { .. }));
        assert!(err.to_string().contains("out.json"), "{err}");
        let missing = dir.join("missing.json");
        let err = read_json::<serde_json::Value>(&missing).unwrap_err();
        assert!(err.to_string().contains("missing.json"), "{err}");
        // a path below a regular file cannot be created
        let err = write_text(&path.join("x.md"), "x").unwrap_err();
        assert!(err.to_string().contains("out.json"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
