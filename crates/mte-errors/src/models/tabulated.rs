//! Tabulated measurements (e.g. a laser-interferometer run), linearly interpolated.

use super::{Context, ErrorModel};
use crate::csv::{CsvTable, UnitColumns};
use crate::error::{Result, invalid};
use crate::units::Kind;

/// A measured error table `(x_i, e_i)`, strictly increasing `x_i`, linearly interpolated.
/// Outside `[x_0, x_n]` evaluators report [`crate::Error::OutOfRange`] (see [`ErrorModel::domain`]).
/// The model is linear in the table values: basis function `i` is the hat function of knot `i`.
#[derive(Debug, Clone, PartialEq)]
pub struct Tabulated {
    positions: Vec<f64>,
    values: Vec<f64>,
}

impl Tabulated {
    /// A table from positions (mm or rad) and values (mm or rad).
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] when fewer than 2 points, lengths differ, a number is not finite,
    /// or positions do not strictly increase (naming the first offending index, 0-based).
    pub fn new(positions: Vec<f64>, values: Vec<f64>) -> Result<Tabulated> {
        if positions.len() != values.len() {
            return Err(invalid(
                "table",
                format!("{} positions but {} values", positions.len(), values.len()),
            ));
        }
        if positions.len() < 2 {
            return Err(invalid("table", "needs at least 2 points"));
        }
        if let Some(i) = positions.iter().chain(&values).position(|v| !v.is_finite()) {
            return Err(invalid(
                "table",
                format!("entry {} is not finite", i % positions.len()),
            ));
        }
        if let Some(i) = first_non_increasing(&positions) {
            return Err(invalid(
                "table",
                format!(
                    "positions must strictly increase: entry {i} ({}) ≤ entry {} ({})",
                    positions[i],
                    i - 1,
                    positions[i - 1]
                ),
            ));
        }
        Ok(Tabulated { positions, values })
    }

    /// Read a table from CSV text with a position column `position_<unit>` and a value column
    /// `error_<unit>` (the base names can be changed). Positions convert to mm/rad, values to mm/rad.
    /// `value_kind` is the kind the parameter expects (unit mismatch is an error).
    ///
    /// # Errors
    /// [`crate::Error::Csv`] naming the line: missing column, not-a-number, non-monotonic position.
    /// [`crate::Error::Unit`] when the value column's unit is of the wrong kind.
    pub fn from_csv(
        text: &str,
        source_name: &str,
        position_base: &str,
        value_base: &str,
        value_kind: Kind,
        position_kind: Option<Kind>,
    ) -> Result<Tabulated> {
        let t = CsvTable::parse(text, source_name)?;
        let (pc, pu) = t.require_with_unit(position_base, &format!("{position_base}_mm"))?;
        let (vc, vu) = t.require_with_unit(value_base, &format!("{value_base}_um"))?;
        vu.expect_kind(
            value_kind,
            &format!("{source_name}: column `{}`", t.headers[vc]),
        )?;
        if let Some(k) = position_kind {
            pu.expect_kind(k, &format!("{source_name}: column `{}`", t.headers[pc]))?;
        }
        let mut xs = Vec::with_capacity(t.rows.len());
        let mut vs = Vec::with_capacity(t.rows.len());
        for r in 0..t.rows.len() {
            let x = t.number(r, pc)? * pu.to_internal();
            if let Some(&prev) = xs.last()
                && x <= prev
            {
                return Err(t.err(
                    t.line(r),
                    format!(
                        "positions must strictly increase: `{}` = {} after {}",
                        t.headers[pc],
                        t.rows[r].1[pc],
                        t.rows[r - 1].1[pc]
                    ),
                ));
            }
            xs.push(x);
            vs.push(t.number(r, vc)? * vu.to_internal());
        }
        if xs.len() < 2 {
            return Err(t.err(t.header_line, "a table needs at least 2 data rows".into()));
        }
        Tabulated::new(xs, vs)
    }

    /// The knots (mm or rad).
    pub fn positions(&self) -> &[f64] {
        &self.positions
    }
    /// The values at the knots (mm or rad).
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// Segment index i with x in [x_i, x_{i+1}] (clamped to the end segments).
    fn segment(&self, x: f64) -> usize {
        let n = self.positions.len();
        let i = self.positions.partition_point(|&p| p <= x);
        i.saturating_sub(1).min(n - 2)
    }
}

fn first_non_increasing(p: &[f64]) -> Option<usize> {
    (1..p.len()).find(|&i| p[i] <= p[i - 1])
}

impl ErrorModel for Tabulated {
    fn value(&self, ctx: &Context) -> f64 {
        let i = self.segment(ctx.position);
        let (x0, x1) = (self.positions[i], self.positions[i + 1]);
        let t = (ctx.position - x0) / (x1 - x0);
        self.values[i] + t * (self.values[i + 1] - self.values[i])
    }
    /// Slope of the segment containing the position (right segment at interior knots).
    fn derivative(&self, ctx: &Context) -> f64 {
        let i = self.segment(ctx.position);
        (self.values[i + 1] - self.values[i]) / (self.positions[i + 1] - self.positions[i])
    }
    fn n_basis(&self) -> usize {
        self.positions.len()
    }
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        out.fill(0.0);
        let i = self.segment(ctx.position);
        let t = (ctx.position - self.positions[i]) / (self.positions[i + 1] - self.positions[i]);
        out[i] = 1.0 - t;
        out[i + 1] = t;
    }
    fn coefficients(&self) -> Vec<f64> {
        self.values.clone()
    }
    fn coefficient_names(&self) -> Vec<String> {
        self.positions.iter().map(|p| format!("at {p}")).collect()
    }
    fn domain(&self) -> Option<(f64, f64)> {
        Some((
            self.positions[0],
            *self.positions.last().unwrap_or(&self.positions[0]),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{checked_value, testutil::*};
    use super::*;
    use approx::assert_relative_eq;

    const CSV: &str = "# EXX of a 700 mm axis, laser interferometer, 100 mm steps\n\
position_mm,error_um\n0,0.0\n100,1.5\n200,2.7\n300,3.1\n400,2.2\n500,0.9\n600,-0.4\n700,-1.8\n";

    #[test]
    fn reproduces_its_table_and_interpolates() {
        let t = Tabulated::from_csv(
            CSV,
            "exx.csv",
            "position",
            "error",
            Kind::Length,
            Some(Kind::Length),
        )
        .unwrap();
        let want = [0.0, 1.5, 2.7, 3.1, 2.2, 0.9, -0.4, -1.8];
        for (i, w) in want.iter().enumerate() {
            // Knots are reproduced to rounding (µm → mm conversion only).
            assert_relative_eq!(
                t.value(&Context::at(100.0 * i as f64)),
                w * 1e-3,
                epsilon = 1e-15
            );
        }
        // Midway between 200 (2.7 µm) and 300 (3.1 µm): 2.9 µm.
        assert_relative_eq!(t.value(&Context::at(250.0)), 2.9e-3, epsilon = 1e-15);
        // Slope on [300, 400]: (2.2 − 3.1) µm / 100 mm.
        assert_relative_eq!(
            t.derivative(&Context::at(350.0)),
            -0.9e-3 / 100.0,
            epsilon = 1e-18
        );
        for i in 0..70 {
            let c = Context::at(3.0 + 10.0 * i as f64);
            check_basis(&t, &c);
            // Inside a segment the FD slope equals the segment slope (piecewise linear).
            assert_relative_eq!(t.derivative(&c), fd(&t, &c, 0.5), epsilon = 1e-15);
        }
        // Outside the measured range: a clear error naming the parameter and range.
        let e = checked_value(&t, &Context::at(701.0), "EXX")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("EXX") && e.contains("701") && e.contains("700"),
            "{e}"
        );
        assert!(checked_value(&t, &Context::at(700.0), "EXX").is_ok());
    }

    #[test]
    fn bad_tables_name_the_line() {
        let bad = "position_mm,error_um\n0,0\n100,1\n100,2\n";
        let e = Tabulated::from_csv(bad, "b.csv", "position", "error", Kind::Length, None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("b.csv") && e.contains("line 4") && e.contains("increase"),
            "{e}"
        );
        let bad = "position_mm,error_um\n0,0\n100,nan\n";
        let e = Tabulated::from_csv(bad, "b.csv", "position", "error", Kind::Length, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3"), "{e}");
        let bad = "position_mm,value_um\n0,0\n100,1\n";
        let e = Tabulated::from_csv(bad, "b.csv", "position", "error", Kind::Length, None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("missing column `error_<unit>`") && e.contains("line 1"),
            "{e}"
        );
        let bad = "position_mm,error_urad\n0,0\n100,1\n";
        let e = Tabulated::from_csv(bad, "b.csv", "position", "error", Kind::Length, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("error_urad"), "{e}");
        assert!(Tabulated::new(vec![0.0, 1.0], vec![1.0]).is_err());
        assert!(Tabulated::new(vec![1.0, 0.0], vec![1.0, 2.0]).is_err());
    }
}
