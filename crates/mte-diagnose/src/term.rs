//! Model terms: named blocks of design columns with the physics that gives them their name.

use mte_linalg::{DMat, DVec};
use serde::Serialize;

/// The physical family of an effect, as engineers group them.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub enum Family {
    /// Part of the base model the user believes in.
    Base,
    /// Position or orientation of a rotary axis line (ISO 230-1 location error, e.g. EX0C).
    Location,
    /// Squareness between two axes (EC0Y, EB0Y …).
    Squareness,
    /// A component error of an axis as a polynomial in its coordinate (straightness,
    /// positioning, angular error).
    Component {
        /// Polynomial degree.
        degree: usize,
    },
    /// Scale (linear positioning) error of an axis.
    Scale,
    /// Periodic error along an axis, e.g. ball-screw pitch error.
    Periodic {
        /// Period found in the data, mm (or rad for a rotary axis).
        period: f64,
    },
    /// Reversal (backlash) error: depends on the direction of approach.
    Reversal,
    /// Thermal drift of a parameter in time.
    Drift {
        /// `None` for a linear drift, `Some(τ)` for a first-order exponential with time constant τ (s).
        time_constant_s: Option<f64>,
    },
    /// Setup error: ball position, sensor nest offset, tool length.
    Setup,
    /// Error of the instrument itself, e.g. the scale of a laser tracker's lengths.
    Instrument,
    /// Supplied by a user's [`crate::Candidate`].
    Custom,
}

/// How a coefficient is read by people: the unit of the report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[non_exhaustive]
pub enum Quantity {
    /// A length in mm, reported in µm.
    Length,
    /// An angle in rad, reported in µrad and arcsec.
    Angle,
    /// A length rate in mm/s, reported in µm/min.
    LengthRate,
    /// An angle rate in rad/s, reported in µrad/min.
    AngleRate,
    /// A dimensionless ratio, reported in ppm (µm/m).
    Ratio,
    /// A ratio changing in time, 1/s, reported in ppm/min.
    RatioRate,
    /// A distance along an axis in mm, reported in mm (a period).
    Distance,
    /// A duration in s, reported in s (a time constant).
    Duration,
    /// A turn of a rotary axis in rad, reported in degrees (a period along a rotary axis).
    AxisAngle,
}

impl Quantity {
    /// Factor from the internal unit to the reported one and the reported unit's symbol.
    pub fn report_unit(self) -> (f64, &'static str) {
        match self {
            Quantity::Length => (1e3, "µm"),
            Quantity::Angle => (1e6, "µrad"),
            Quantity::LengthRate => (1e3 * 60.0, "µm/min"),
            Quantity::AngleRate => (1e6 * 60.0, "µrad/min"),
            Quantity::Ratio => (1e6, "ppm"),
            Quantity::RatioRate => (1e6 * 60.0, "ppm/min"),
            Quantity::Distance => (1.0, "mm"),
            Quantity::Duration => (1.0, "s"),
            Quantity::AxisAngle => (180.0 / std::f64::consts::PI, "°"),
        }
    }

    /// A value without uncertainty in the reported unit, to three significant digits.
    pub fn format_value(self, value: f64) -> String {
        self.format_to(value, value.abs() / 10.0)
    }

    /// The value in the reported unit, to the decimals that show `resolution` (same unit as
    /// the value) with two significant digits.
    fn format_to(self, value: f64, resolution: f64) -> String {
        let (f, unit) = self.report_unit();
        let digits = significant_decimals(resolution * f);
        format!("{:.*} {unit}", digits, value * f)
    }

    /// The value in the reported unit, with arcsec alongside for angles.
    pub fn format(self, value: f64, u: f64) -> String {
        let (f, unit) = self.report_unit();
        let digits = significant_decimals(u * f);
        let main = format!("{:.*} ± {:.*} {unit}", digits, value * f, digits, u * f);
        if self == Quantity::Angle {
            let arcsec = value.to_degrees() * 3600.0;
            let u_arcsec = u.to_degrees() * 3600.0;
            let d = significant_decimals(u_arcsec);
            format!("{main} ({:.*} ± {:.*}″)", d, arcsec, d, u_arcsec)
        } else {
            main
        }
    }
}

/// Decimals that show an uncertainty with two significant digits.
pub(crate) fn significant_decimals(u: f64) -> usize {
    if !(u.is_finite() && u > 0.0) {
        return 2;
    }
    (1.0 - u.log10().floor()).clamp(0.0, 6.0) as usize
}

/// The amplitude √(a² + b²) of a·sin + b·cos and its variance by the delta method
/// (∂amplitude/∂(a, b) = (a, b)/amplitude) from the covariance (or a cofactor) `cov` of a and b
/// (its first two rows and columns).
pub(crate) fn amplitude_and_variance(a: f64, b: f64, cov: &DMat) -> (f64, f64) {
    let amp = a.hypot(b);
    let g = if amp > 0.0 {
        [a / amp, b / amp]
    } else {
        [std::f64::consts::FRAC_1_SQRT_2; 2]
    };
    let var =
        g[0] * g[0] * cov[(0, 0)] + 2.0 * g[0] * g[1] * cov[(0, 1)] + g[1] * g[1] * cov[(1, 1)];
    (amp, var)
}

/// How the coefficients of a term are summarised for the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub enum Summary {
    /// Each coefficient is a physical quantity of its own.
    EachCoefficient,
    /// Two coefficients (a·sin + b·cos) summarised as an amplitude √(a² + b²).
    Amplitude,
    /// Two coefficients, a scale change s and a zero change z of one axis, each reported, and
    /// after them (derived, named here) the point that stays, x = −z/s, where the axis'
    /// expansion is anchored.
    FixedPoint(String),
}

/// A named block of design columns: the first-order effect of one physical cause on every
/// observation, one column per coefficient.
#[derive(Debug, Clone)]
pub struct Term {
    /// Short name, the ISO 230-1 name where there is one (`EB0Y`, `EXX periodic`).
    pub name: String,
    /// What an engineer calls it ("squareness of B axis to Y").
    pub label: String,
    /// One sentence of physical meaning.
    pub meaning: String,
    /// The family of effect.
    pub family: Family,
    /// Design columns, `n × k`: the change of each observation per unit coefficient.
    pub columns: DMat,
    /// Name and quantity of each coefficient.
    pub coefficients: Vec<(String, Quantity)>,
    /// How the report summarises the coefficients.
    pub summary: Summary,
    /// The covariate whose residual plot shows this effect best (`t`, `X`, `direction`).
    pub exposed_by: Option<String>,
    /// The measurement that would separate this effect from others it may be confounded with.
    pub separated_by: Option<String>,
}

impl Term {
    /// A term with one coefficient.
    pub fn single(
        name: impl Into<String>,
        label: impl Into<String>,
        meaning: impl Into<String>,
        family: Family,
        column: DVec,
        quantity: Quantity,
    ) -> Self {
        let name = name.into();
        Term {
            coefficients: vec![(name.clone(), quantity)],
            name,
            label: label.into(),
            meaning: meaning.into(),
            family,
            columns: DMat::from_column_slice(column.len(), 1, column.as_slice()),
            summary: Summary::EachCoefficient,
            exposed_by: None,
            separated_by: None,
        }
    }

    /// Number of coefficients.
    pub fn width(&self) -> usize {
        self.columns.ncols()
    }

    /// Sets the covariate that exposes the effect.
    pub fn exposed_by(mut self, variable: impl Into<String>) -> Self {
        self.exposed_by = Some(variable.into());
        self
    }

    /// Sets the measurement that would separate the effect from what it is confounded with.
    pub fn separated_by(mut self, hint: impl Into<String>) -> Self {
        self.separated_by = Some(hint.into());
        self
    }

    /// Sets or clears the separating measurement.
    pub fn separated_by_opt(mut self, hint: Option<String>) -> Self {
        self.separated_by = hint;
        self
    }

    /// `true` when every column is zero to rounding: the effect does not reach these data.
    pub fn is_invisible(&self) -> bool {
        self.columns.iter().all(|v| v.abs() < 1e-15)
    }
}

/// An estimated quantity as reported.
#[derive(Debug, Clone, Serialize)]
pub struct Estimate {
    /// Name of the quantity (coefficient name or "amplitude").
    pub name: String,
    /// Value in internal units (mm, rad, mm/s, rad/s or ratio).
    pub value: f64,
    /// Standard uncertainty, same unit.
    pub uncertainty: f64,
    /// What kind of quantity it is.
    pub quantity: Quantity,
    /// Value ± uncertainty in the units engineers read (with the interval, where there is one).
    pub text: String,
    /// Where the estimate depends on a nonlinear parameter the data determine poorly (a
    /// first-order drift's final value, beyond the record, through its time constant): the
    /// 95 % profile-likelihood interval, which the ± u of the linearisation does not describe.
    pub interval: Option<Interval>,
}

/// A 95 % interval (the values whose profile χ² lies within 4 of its least); an open end is a
/// bound the data do not set.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Interval {
    /// Lower end, `None` where the data set none.
    pub lower: Option<f64>,
    /// Upper end, `None` where the data set none.
    pub upper: Option<f64>,
}

impl Interval {
    /// Whether `v` lies inside.
    pub fn contains(&self, v: f64) -> bool {
        self.lower.is_none_or(|l| v >= l) && self.upper.is_none_or(|u| v <= u)
    }

    /// The interval in words, in the units engineers read `q` in: "between a and b",
    /// "a or above", "b or below", "any value".
    pub fn describe(&self, q: Quantity) -> String {
        match (self.lower, self.upper) {
            // To the decimals that show a quarter of its width (about a u) to two digits, at
            // least those of its values' own size: an interval narrow beside its values (a
            // period's) keeps the digits that tell its ends apart.
            (Some(a), Some(b)) => {
                let resolution = ((b - a) / 4.0).min(a.abs().max(b.abs()) / 10.0);
                format!(
                    "between {} and {}",
                    q.format_to(a, resolution),
                    q.format_to(b, resolution)
                )
            }
            (Some(a), None) => format!("{} or above", q.format_value(a)),
            (None, Some(b)) => format!("{} or below", q.format_value(b)),
            (None, None) => "any value".to_string(),
        }
    }
}

impl Estimate {
    /// An estimate with value ± u in the units engineers read.
    pub fn new(name: impl Into<String>, value: f64, uncertainty: f64, quantity: Quantity) -> Self {
        Estimate {
            name: name.into(),
            value,
            uncertainty,
            quantity,
            text: quantity.format(value, uncertainty),
            interval: None,
        }
    }

    /// The estimate with its 95 % interval, which the text states after value ± u.
    pub fn with_interval(mut self, interval: Interval) -> Self {
        self.text = format!("{} (95 %: {})", self.text, interval.describe(self.quantity));
        self.interval = Some(interval);
        self
    }
}

impl Term {
    /// The term on the observations `rows` only (their rows of the columns, in that order).
    pub fn select_rows(&self, rows: &[usize]) -> Term {
        Term {
            columns: crate::fit::select_rows(&self.columns, rows),
            ..self.clone_without_columns()
        }
    }

    fn clone_without_columns(&self) -> Term {
        Term {
            name: self.name.clone(),
            label: self.label.clone(),
            meaning: self.meaning.clone(),
            family: self.family.clone(),
            columns: DMat::zeros(0, 0),
            coefficients: self.coefficients.clone(),
            summary: self.summary.clone(),
            exposed_by: self.exposed_by.clone(),
            separated_by: self.separated_by.clone(),
        }
    }

    /// Reported estimates from the term's coefficients and their covariance block.
    pub fn estimates(&self, coef: &[f64], cov: &DMat) -> Vec<Estimate> {
        match &self.summary {
            Summary::FixedPoint(name) if coef.len() == 2 => {
                let (s, z) = (coef[0], coef[1]);
                let x = -z / s;
                // Delta method: ∂x/∂(s, z) = (z/s², −1/s).
                let g = [z / (s * s), -1.0 / s];
                let var = g[0] * g[0] * cov[(0, 0)]
                    + 2.0 * g[0] * g[1] * cov[(0, 1)]
                    + g[1] * g[1] * cov[(1, 1)];
                let mut out: Vec<Estimate> = (0..2)
                    .map(|i| {
                        let (n, q) = &self.coefficients[i];
                        Estimate::new(n, coef[i], cov[(i, i)].max(0.0).sqrt(), *q)
                    })
                    .collect();
                out.push(Estimate::new(
                    name,
                    x,
                    var.max(0.0).sqrt(),
                    Quantity::Distance,
                ));
                out
            }
            Summary::Amplitude if coef.len() == 2 => {
                let (amp, var) = amplitude_and_variance(coef[0], coef[1], cov);
                vec![Estimate::new(
                    "amplitude",
                    amp,
                    var.max(0.0).sqrt(),
                    self.coefficients[0].1,
                )]
            }
            _ => self
                .coefficients
                .iter()
                .enumerate()
                .map(|(i, (name, q))| Estimate::new(name, coef[i], cov[(i, i)].max(0.0).sqrt(), *q))
                .collect(),
        }
    }
}
