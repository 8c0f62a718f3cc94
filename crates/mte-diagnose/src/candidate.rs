//! Candidate extensions: the extension point ([`Candidate`]) and the library of physical effects
//! built from how each kinematic error slot reaches the observations.

use mte_linalg::{DMat, DVec};

pub use crate::basis::Spread;
use crate::basis::{legendre_columns, periods_to_scan, sin_cos_columns, time_constants_to_scan};
use crate::data::{Observations, Variable, VariableKind};
use crate::term::{Family, Quantity, Summary, Term};

/// A candidate extension of the model: one physical cause, possibly with a hyper-parameter
/// (a period, a time constant) that the data must choose.
///
/// Implement it to add an effect of your own; the diagnosis tries it beside the library.
///
/// ```
/// use mte_diagnose::{Candidate, Family, Observations, Quantity, Term};
/// use mte_linalg::DVec;
/// /// A constant offset of every reading of the first channel (e.g. a sensor zero error).
/// struct SensorZero;
/// impl Candidate for SensorZero {
///     fn variants(&self, obs: &Observations) -> Vec<Term> {
///         let column = DVec::from_fn(obs.len(), |i, _| if obs.channel[i] == 0 { 1.0 } else { 0.0 });
///         vec![Term::single("zero", "sensor zero error", "a constant offset of the sensor", Family::Custom, column, Quantity::Length)]
///     }
/// }
/// ```
pub trait Candidate: Send + Sync {
    /// The candidate's design on these observations. Several terms are alternatives of the same
    /// cause (e.g. one per period of a scan): the diagnosis tries the one that explains most,
    /// and counts all of them when it judges significance.
    fn variants(&self, obs: &Observations) -> Vec<Term>;

    /// Improves the best of the variants once it is known (e.g. refines a scanned period),
    /// given `score`, the weighted residual sum of squares that a term leaves. `None` keeps
    /// the variant as it is.
    fn refine(&self, _best: usize, _score: &Score) -> Option<Term> {
        None
    }

    /// The variant `variant` with its hyper-parameter (period, time constant) set to `value`;
    /// `None` for a cause without one. The diagnosis uses it for the uncertainty that the
    /// hyper-parameter adds to the effect's size.
    fn at(&self, _variant: usize, _value: f64) -> Option<Term> {
        None
    }

    /// The name of a model term this cause builds on: a thermal drift of `EX0B` is a candidate
    /// only once `EX0B` itself is in the model (in the base, or found first).
    fn requires(&self) -> Option<&str> {
        None
    }

    /// How many design columns all variants together have on these observations (the memory
    /// the diagnosis reserves for them is this × observations × 8 bytes). The default builds
    /// the variants; override it where that is costly.
    fn columns(&self, obs: &Observations) -> usize {
        self.variants(obs).iter().map(|t| t.columns.ncols()).sum()
    }

    /// The variants as functions of one variable spread over the observations
    /// ([`SpreadVariants`]), in the order of [`Candidate::variants`]. The diagnosis then forms
    /// its products with the variants over the variable's distinct values instead of the
    /// observations, and a variant's columns only where it needs them. `None` (the default):
    /// from the variants' columns.
    fn spread(&self) -> Option<SpreadVariants> {
        None
    }

    /// What the diagnosis does with the candidate: a cause to search for (the default), a
    /// completion of the base, or a structure probe.
    fn role(&self) -> Role {
        Role::Cause
    }

    /// The candidate on the observations `rows` of `obs` only: a long record is searched on an
    /// evenly thinned copy, and the variant chosen there is evaluated again on all observations
    /// ([`Candidate::at`], or [`Candidate::variants`] for a cause without a hyper-parameter).
    /// The variants keep their order. The default evaluates every variant on all observations
    /// and keeps the rows (no refinement on the thinned copy); override it where that is costly.
    fn on_rows(&self, obs: &Observations, rows: &[usize]) -> Box<dyn Candidate> {
        Box::new(Restricted {
            variants: self
                .variants(obs)
                .iter()
                .map(|t| t.select_rows(rows))
                .collect(),
            requires: self.requires().map(str::to_string),
            role: self.role(),
        })
    }
}

/// A candidate's variants as functions of one variable seen through a spread
/// ([`Candidate::spread`]): variant `v` is `headers[v]` with the columns
/// `spread.expand(&bases[v])`.
pub struct SpreadVariants {
    /// The spread of the variable over the observations.
    pub spread: std::sync::Arc<Spread>,
    /// Each variant's functions at the spread's distinct values (one row per value, one column
    /// per design column).
    pub bases: Vec<DMat>,
    /// Each variant as [`Candidate::variants`] gives it but for its columns: none (0 rows, as
    /// many columns as the variant has).
    pub headers: Vec<Term>,
}

/// What a refinement minimises ([`Candidate::refine`]): the weighted residual sum of squares a
/// term leaves — of its columns, or, for functions of one variable seen through a [`Spread`],
/// of their values at the spread's values, which the diagnosis can score without the columns.
pub struct Score<'a> {
    term: Box<dyn Fn(&Term) -> f64 + 'a>,
    spread: Option<Box<SpreadScore<'a>>>,
}

/// The score of functions at a spread's values ([`Score::of_spread`]).
type SpreadScore<'a> = dyn Fn(&Spread, &DMat) -> Option<f64> + 'a;

impl<'a> Score<'a> {
    /// The score `term` of a term's columns.
    pub fn new(term: impl Fn(&Term) -> f64 + 'a) -> Score<'a> {
        Score {
            term: Box::new(term),
            spread: None,
        }
    }

    /// With the score `spread` of functions at a spread's values (`None` where it cannot tell).
    pub(crate) fn with_spread(
        mut self,
        spread: impl Fn(&Spread, &DMat) -> Option<f64> + 'a,
    ) -> Score<'a> {
        self.spread = Some(Box::new(spread));
        self
    }

    /// The score of `term`.
    pub fn of(&self, term: &Term) -> f64 {
        (self.term)(term)
    }

    /// The score of the term whose columns are `spread.expand(values)`, without forming them;
    /// `None` where only [`Score::of`] can tell.
    pub fn of_spread(&self, spread: &Spread, values: &DMat) -> Option<f64> {
        self.spread.as_ref().and_then(|f| f(spread, values))
    }
}

/// What the diagnosis does with a candidate ([`Candidate::role`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// A cause the search may name.
    Cause,
    /// A higher order of a component error the base already has ([`Completion`]): it
    /// completes the base (before the search, or once a cause that hid it is in) and is no
    /// cause.
    Completion,
    /// All the orders of a component error beyond the base's at once, up to the highest it is
    /// completed to ([`Completion`] with `span`): it completes the base as a [`Role::Completion`]
    /// does — its columns the model does not have yet — where the remainder of a smooth error
    /// (a waviness of a few cycles over the stroke) spreads over more orders than one block and
    /// no block alone is significant. It is not *the next order* a cause's separation from the
    /// base is judged against.
    CompletionSpan,
    /// A shape of the residuals that no cause has (the library's: a component error changing
    /// with two linear axes at once): one more structure test, never fitted; when significant
    /// the report shows it as structure nothing in the library explains.
    Probe,
}

impl Role {
    /// Whether a candidate of this role completes the base ([`Role::Completion`],
    /// [`Role::CompletionSpan`]) rather than being a cause or a probe.
    pub fn completes(self) -> bool {
        matches!(self, Role::Completion | Role::CompletionSpan)
    }
}

/// A candidate's variants on a subset of the observations ([`Candidate::on_rows`]).
struct Restricted {
    variants: Vec<Term>,
    requires: Option<String>,
    role: Role,
}

impl Candidate for Restricted {
    fn variants(&self, _obs: &Observations) -> Vec<Term> {
        self.variants.clone()
    }

    fn requires(&self) -> Option<&str> {
        self.requires.as_deref()
    }

    fn role(&self) -> Role {
        self.role
    }
}

/// A cause that is a candidate only once the term it builds on is in the model.
pub struct Requires {
    /// Name of the term it needs.
    pub term: String,
    /// The cause.
    pub inner: Box<dyn Candidate>,
}

impl Candidate for Requires {
    fn variants(&self, obs: &Observations) -> Vec<Term> {
        self.inner.variants(obs)
    }

    fn refine(&self, best: usize, score: &Score) -> Option<Term> {
        self.inner.refine(best, score)
    }

    fn at(&self, variant: usize, value: f64) -> Option<Term> {
        self.inner.at(variant, value)
    }

    fn requires(&self) -> Option<&str> {
        Some(&self.term)
    }

    fn columns(&self, obs: &Observations) -> usize {
        self.inner.columns(obs)
    }

    fn on_rows(&self, obs: &Observations, rows: &[usize]) -> Box<dyn Candidate> {
        Box::new(Requires {
            term: self.term.clone(),
            inner: self.inner.on_rows(obs, rows),
        })
    }
}

impl Candidate for Term {
    fn variants(&self, _obs: &Observations) -> Vec<Term> {
        vec![self.clone()]
    }

    fn on_rows(&self, _obs: &Observations, rows: &[usize]) -> Box<dyn Candidate> {
        Box::new(self.select_rows(rows))
    }
}

/// How a kinematic error slot depends on the machine's state.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SlotRole {
    /// A constant: location error of a rotary axis, assembly or setup error.
    Constant {
        /// Location, Setup or Squareness.
        family: Family,
    },
    /// A component error of the axis named `axis`, a function of its coordinate.
    Component {
        /// Axis (covariate) name.
        axis: String,
        /// The positioning error along the axis' own direction (EXX, EYY, ECC …).
        positioning: bool,
        /// A straightness error (its linear part is a squareness, named separately).
        straightness: bool,
    },
}

/// One kinematic error slot as the observations see it.
#[derive(Debug, Clone)]
pub struct SlotEffect {
    /// ISO 230-1 name (`EXX`, `EX0C`, `EC0Y`).
    pub name: String,
    /// What engineers call it.
    pub label: String,
    /// One sentence of physical meaning.
    pub meaning: String,
    /// mm or rad.
    pub quantity: Quantity,
    /// How it depends on the state.
    pub role: SlotRole,
    /// First-order change of every observation per unit error (n).
    pub column: DVec,
    /// The measurement that would separate it from what it is confounded with, if known.
    pub separated_by: Option<String>,
    /// For instruments set up at a reference pose (an R-test centred at each setup's start):
    /// how every observation sees the slot's value there ([`Reference`]).
    pub reference: Option<Reference>,
}

/// Where an instrument was zeroed: each observation's setup reference pose (an R-test's
/// centring). An error function g of the slot's axis coordinate s acts as
/// `column·g(s) + reference.column·g(s_ref)`; an error that changes in time, d(t), as
/// `column·d(t) + reference.column·d(t_ref)` — a drift since the centring, not since the start.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Sensitivity of every observation to the slot's value at its setup's reference pose.
    pub column: DVec,
    /// The slot's axis coordinate at the reference pose (one per observation).
    pub coordinate: Vec<f64>,
    /// The time of the reference pose, s (one per observation).
    pub time_s: Vec<f64>,
}

impl SlotEffect {
    /// The effect of a constant error.
    fn constant_column(&self) -> DVec {
        match &self.reference {
            Some(r) => &self.column + &r.column,
            None => self.column.clone(),
        }
    }

    /// The effect of the error `g(s)` whose basis functions `basis` evaluates on the axis
    /// coordinates `s` (one column per basis function); reference poses included. The basis is
    /// evaluated once per distinct coordinate ([`SlotEffect::spread`]; one basis over rows and
    /// references together, so a range-normalised basis (Legendre) is the same function at
    /// both): runs and program cycles repeat their positions.
    fn modulated(&self, values: &[f64], basis: &dyn Fn(&[f64]) -> DMat) -> DMat {
        let spread = self.spread(values);
        spread.expand(&basis(spread.values()))
    }

    /// How the observations see a function of the slot's axis coordinate, given the rows'
    /// `values` ([`SlotEffect::modulated`] through their distinct values): at their own pose,
    /// and at their setup's reference pose when there is one.
    fn spread(&self, values: &[f64]) -> Spread {
        let own = (values, self.column.as_slice());
        match &self.reference {
            None => Spread::new(&[own]),
            Some(r) => Spread::new(&[own, (&r.coordinate, r.column.as_slice())]),
        }
    }
}

/// The library of physical effects on a set of kinematic error slots: missing constants
/// (location, squareness, setup), component errors as low-order polynomials, scale errors,
/// periodic positioning errors with unknown period, reversal errors, and thermal drift (linear
/// and first-order exponential) of constants. `drifting` lists further terms (usually the base
/// model's constants) whose drift in time is a candidate too, each with its reference pose where
/// the instrument was zeroed ([`SlotEffect::reference`]).
pub fn physical_effects(
    obs: &Observations,
    slots: &[SlotEffect],
    drifting: &[(&Term, Option<&Reference>)],
) -> Vec<Box<dyn Candidate>> {
    use rayon::prelude::*;
    // Time effects only where a pose is measured again later: otherwise a drift cannot be told
    // from a dependence on the pose. Its time constant may be shorter than the interval between
    // the visits that reveal it, down to a fraction of it ([`shortest_time_constant`]).
    let time = obs
        .variable_of_kind(VariableKind::Time)
        .filter(|t| varies(&t.values))
        .and_then(|t| {
            Some((
                t.values.clone(),
                shortest_time_constant(obs.revisit_interval()?),
            ))
        });
    let direction = obs
        .variable_of_kind(VariableKind::Direction)
        .filter(|d| varies(&d.values))
        .map(|d| d.values.clone());
    let settling = time.as_ref().map(|(t, floor)| Settling::new(t, *floor));
    // Each slot's candidates are independent of the others': built in parallel, collected in
    // order.
    let per_slot: Vec<Vec<Box<dyn Candidate>>> = slots
        .par_iter()
        .map(|slot| slot_candidates(obs, slot, drifting, settling.as_ref(), direction.as_deref()))
        .collect();
    let mut out: Vec<Box<dyn Candidate>> = per_slot.into_iter().flatten().collect();
    if let Some(settling) = &settling {
        for &(t, reference) in drifting {
            if t.width() == 1 && !matches!(t.family, Family::Drift { .. }) {
                out.extend(drift_candidates(t, reference, settling));
            }
        }
    }
    out
}

/// The candidates of one slot's error ([`physical_effects`]): its constant and drifts for a
/// constant error; for a component error its polynomials, a linear axis' scale and its drifts,
/// a positioning error's periodic errors along the axis and reversals, a rotary axis' error
/// motions as harmonics of a turn. `drifting`: the base terms that drift (an axis' zero among
/// them, about which its scale expands); `settling`: the drifts' time course where a pose is
/// measured again later; `direction`: each reading's direction of approach where it varies.
fn slot_candidates(
    obs: &Observations,
    slot: &SlotEffect,
    drifting: &[(&Term, Option<&Reference>)],
    settling: Option<&Settling>,
    direction: Option<&[f64]>,
) -> Vec<Box<dyn Candidate>> {
    let n = obs.len();
    let mut out: Vec<Box<dyn Candidate>> = Vec::new();
    if slot.column.iter().all(|v| v.abs() < 1e-15) {
        return out;
    }
    let term =
        |suffix: &str, label: String, meaning: String, family: Family, cols: DMat, q: Quantity| {
            Term {
                name: format!("{}{suffix}", slot.name),
                label,
                meaning,
                family,
                coefficients: (0..cols.ncols())
                    .map(|k| (coefficient_name(&slot.name, suffix, k, cols.ncols()), q))
                    .collect(),
                columns: cols,
                summary: Summary::EachCoefficient,
                exposed_by: None,
                separated_by: slot.separated_by.clone(),
            }
        };
    match &slot.role {
        SlotRole::Constant { family } => {
            let t = term(
                "",
                slot.label.clone(),
                slot.meaning.clone(),
                family.clone(),
                column_matrix(&slot.constant_column()),
                slot.quantity,
            );
            // A squareness shows along the axis it tilts, a rotary axis' location error
            // against that axis' angle.
            let t = match located_axis(&slot.name)
                .filter(|a| obs.variable(a).is_some_and(|v| varies(&v.values)))
            {
                Some(axis) => t.exposed_by(axis),
                None => t,
            };
            if let Some(settling) = settling {
                for drift in drift_candidates(&t, slot.reference.as_ref(), settling) {
                    out.push(Box::new(Requires {
                        term: t.name.clone(),
                        inner: drift,
                    }));
                }
            }
            out.push(Box::new(t));
        }
        SlotRole::Component {
            axis,
            positioning,
            straightness,
        } => {
            let Some(v) = obs.variable(axis).filter(|v| varies(&v.values)) else {
                return out;
            };
            let rotary = v.kind == VariableKind::RotaryAxis;
            let values = v.values.clone();
            if *positioning && !rotary {
                let cols = slot.modulated(&values, &|s| DMat::from_column_slice(s.len(), 1, s));
                let scale = term(
                    " scale",
                    format!("scale error of {axis} ({})", slot.name),
                    format!("positioning error of {axis} growing linearly with position: a scale (pitch or thermal expansion) error of its measuring system"),
                    Family::Scale,
                    cols,
                    Quantity::Ratio,
                )
                .exposed_by(axis.clone());
                // The scale changing in time: the screw or scale expands as the machine
                // warms, about the axis' zero (or about a fixed bearing elsewhere, below).
                if let Some(settling) = settling {
                    let reference = slot.reference.as_ref().map(|r| Reference {
                        column: r
                            .column
                            .component_mul(&DVec::from_column_slice(&r.coordinate)),
                        ..r.clone()
                    });
                    for drift in drift_candidates(&scale, reference.as_ref(), settling) {
                        out.push(Box::new(Requires {
                            term: scale.name.clone(),
                            inner: drift,
                        }));
                    }
                    // The screw fixed at a bearing away from the axis' zero: its scale and
                    // the axis' zero settle together, with one time constant.
                    if slot.reference.is_none() {
                        let zero = zero_of(slot, drifting);
                        out.push(Box::new(Requires {
                            term: scale.name.clone(),
                            inner: Box::new(expansion_about_a_point(
                                slot, &zero, axis, &values, settling,
                            )),
                        }));
                    }
                }
                out.push(Box::new(scale));
            }
            // The linear part of a straightness is a squareness, which the catalogue names.
            let first = if *straightness || (*positioning && !rotary) {
                2
            } else {
                1
            };
            // An error of a rotary axis that turns a full turn repeats every turn: its
            // harmonics are the periodic candidates; a polynomial in the angle is no error
            // motion there.
            let (lo, hi) = crate::basis::range(&values);
            let full_turn = rotary && hi - lo > 0.8 * std::f64::consts::TAU;
            let top = CAUSE_DEGREE.min(highest_order(&values, false));
            for degree in (first..=top).filter(|_| !full_turn) {
                let cols = slot.modulated(&values, &|s| legendre_columns(s, first..=degree));
                out.push(Box::new(
                    term(
                        &format!(" poly{degree}"),
                        format!("{}, polynomial in {axis} up to degree {degree}", slot.label),
                        format!("{} varying smoothly along {axis}", slot.meaning),
                        Family::Component { degree },
                        cols,
                        slot.quantity,
                    )
                    .exposed_by(axis.clone()),
                ));
            }
            // A positioning error repeating along the axis; over a full turn, every error
            // motion of a rotary axis as its harmonics (the form of a bearing race, a
            // wobble), where no polynomial in the angle is searched.
            if *positioning || full_turn {
                let (name, axis_name, quantity) = (slot.name.clone(), axis.clone(), slot.quantity);
                let (label, what, cause) = if *positioning {
                    (
                        format!("periodic positioning error of {axis} ({})", slot.name),
                        format!("positioning error of {axis}"),
                        if rotary {
                            "encoder eccentricity or graduation error, worm-gear tooth error"
                        } else {
                            "ball-screw pitch, encoder or gear error"
                        },
                    )
                } else {
                    (
                        format!("{}, periodic over a turn ({})", slot.label, slot.name),
                        slot.label.clone(),
                        "the form of a bearing race, a wobble of the axis, an eccentric part",
                    )
                };
                let separated_by = slot.separated_by.clone();
                let make = move |p: f64, cols: DMat| Term {
                    name: format!("{name} periodic"),
                    label: label.clone(),
                    meaning: format!(
                        "{what} repeating every {} ({cause})",
                        format_period(p, rotary),
                    ),
                    family: Family::Periodic { period: p },
                    columns: cols,
                    coefficients: vec![
                        (format!("{name} periodic sin"), quantity),
                        (format!("{name} periodic cos"), quantity),
                    ],
                    summary: Summary::Amplitude,
                    exposed_by: Some(axis_name.clone()),
                    separated_by: separated_by.clone(),
                };
                let grid = periods_to_scan(&v.values, rotary);
                if !grid.is_empty() {
                    // The sines at each distinct position once (repeated runs and cycles).
                    out.push(Box::new(Scan::spread(
                        grid,
                        !rotary,
                        slot.spread(&values),
                        sin_cos_columns,
                        make,
                    )));
                }
                if let Some(d) = direction.filter(|_| *positioning) {
                    let cols = DMat::from_fn(n, 1, |i, _| slot.column[i] * 0.5 * d[i]);
                    out.push(Box::new(
                        term(
                            " reversal",
                            format!("reversal error of {axis} ({})", slot.name),
                            format!("{axis} stops short by a different amount depending on the direction of approach (backlash, friction, encoder hysteresis); the value is the + minus − difference"),
                            Family::Reversal,
                            cols,
                            slot.quantity,
                        )
                        .exposed_by("direction"),
                    ));
                    // A reversal that changes along the axis (the backlash of a screw worn
                    // where the axis works most, friction that varies along the guideway),
                    // beside the reversal itself: its change as a polynomial in the axis
                    // coordinate (ISO 230-2 states the reversal at every target). (Over a
                    // full turn a rotary axis' reversal would change as harmonics: not
                    // searched.)
                    let top = if full_turn {
                        0
                    } else {
                        2.min(highest_order(&values, false))
                    };
                    for degree in 1..=top {
                        let along = legendre_columns(&values, 1..=degree);
                        let cols = DMat::from_fn(n, degree, |i, j| {
                            slot.column[i] * 0.5 * d[i] * along[(i, j)]
                        });
                        let changing = term(
                            &format!(" reversal poly{degree}"),
                            format!("reversal error of {axis} changing along {axis}, polynomial up to degree {degree}"),
                            format!("the reversal of {axis} is not the same at every position: larger where the screw is worn or the guideway's friction higher (the coefficients are Legendre's over the measured travel: the first is half the reversal's change from one end to the other)"),
                            Family::Reversal,
                            cols,
                            slot.quantity,
                        )
                        .exposed_by(axis.clone());
                        out.push(Box::new(Requires {
                            term: format!("{} reversal", slot.name),
                            inner: Box::new(changing),
                        }));
                    }
                }
            }
        }
    }
    out
}

/// The base model a user states: which of the machine's ordinary errors the model already has,
/// as a shorthand (`"base_model": {"components": {"degree": 3}, "squareness": true, "location": true}`
/// in a dataset manifest) plus terms named one by one from the candidate library.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct BaseModelSpec {
    /// Every component error of every axis the data move: a Legendre polynomial in the axis
    /// coordinate up to this degree over the observed range for a linear axis (from degree 2
    /// for a straightness, whose linear part is the squareness), harmonics of a turn up to
    /// ⌈degree / 2⌉ for a rotary axis (an error motion repeats every turn).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub components: Option<ComponentSpec>,
    /// The squareness errors of every pair of linear axes.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub squareness: bool,
    /// The location errors of every rotary axis: the position of its line across the axis and
    /// its orientation (ISO 230-7), as far as the setups can separate them.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub location: bool,
    /// Further terms by their library name (`EC0Y`, `EXX poly3`, `EXX reversal`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub terms: Vec<String>,
    /// Ordinary errors the shorthands above leave out, by ISO name (`ECC` for the angular
    /// positioning error of C, `EC0Y`, `EA0B`): "every component error but C's positioning".
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub except: Vec<String>,
}

/// The ordinary errors a [`BaseModelSpec`] holds by a shorthand ([`BaseModelSpec::would_hold`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shorthand {
    /// `components`.
    Components,
    /// `squareness`.
    Squareness,
    /// `location`.
    Location,
}

impl Shorthand {
    /// The shorthand that stands for an ordinary error every machine has, of family `family`:
    /// a component error of an axis (a polynomial in its coordinate, a linear axis' scale), an
    /// error motion of a rotary axis over a turn (a periodic error of `per_turn` whole cycles
    /// per turn, up to [`MAX_COMPONENT_HARMONIC`]), a squareness or a location error. `None`
    /// for anything else: a pitch, a reversal, a drift, an instrument's error.
    pub fn of_ordinary(family: &Family, per_turn: Option<usize>) -> Option<Shorthand> {
        match family {
            Family::Component { .. } | Family::Scale => Some(Shorthand::Components),
            Family::Periodic { .. } if per_turn.is_some_and(|k| k <= MAX_COMPONENT_HARMONIC) => {
                Some(Shorthand::Components)
            }
            Family::Squareness => Some(Shorthand::Squareness),
            Family::Location => Some(Shorthand::Location),
            _ => None,
        }
    }
}

/// Whether the variable `exposed_by` is a rotary axis of `obs`.
pub(crate) fn is_rotary(obs: &Observations, exposed_by: Option<&str>) -> bool {
    exposed_by
        .and_then(|v| obs.variable(v))
        .is_some_and(|v| v.kind == VariableKind::RotaryAxis)
}

/// The whole number of cycles per turn of a periodic effect of family `family` along the
/// variable `exposed_by`, where that is a rotary axis and the period divides a turn.
pub(crate) fn per_turn(
    obs: &Observations,
    family: &Family,
    exposed_by: Option<&str>,
) -> Option<usize> {
    match *family {
        Family::Periodic { period } if is_rotary(obs, exposed_by) && period > 0.0 => {
            let k = std::f64::consts::TAU / period;
            ((k - k.round()).abs() < 1e-6 * k).then_some(k.round() as usize)
        }
        _ => None,
    }
}

/// The component errors of a [`BaseModelSpec`].
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ComponentSpec {
    /// Polynomial degree (1–8).
    pub degree: usize,
}

impl BaseModelSpec {
    /// The spec of a manifest's `base_model` field: an object of this form, or (the older form)
    /// a list of term names.
    ///
    /// # Errors
    /// What is wrong, for the caller to wrap with the file and field.
    pub fn from_json(value: &serde_json::Value) -> std::result::Result<Self, String> {
        let spec: BaseModelSpec = match value {
            serde_json::Value::Array(_) => BaseModelSpec {
                terms: serde_json::from_value(value.clone()).map_err(|e| e.to_string())?,
                ..BaseModelSpec::default()
            },
            _ => serde_json::from_value(value.clone()).map_err(|e| e.to_string())?,
        };
        if let Some(c) = &spec.components {
            if !(1..=8).contains(&c.degree) {
                return Err(format!(
                    "`components.degree`: {}, expected 1 to 8",
                    c.degree
                ));
            }
        }
        Ok(spec)
    }

    /// The base terms of the spec: component errors and squareness from the slot effects, the
    /// location errors named in `location` (the rotary axes' errors the instrument can see), and
    /// the named terms from `candidates` (each must have a single variant: a period or time
    /// constant to choose is the search's job).
    ///
    /// # Errors
    /// An unknown or scanned term name, with the closest names of the library.
    pub fn terms(
        &self,
        obs: &Observations,
        slots: &[SlotEffect],
        location: &[String],
        candidates: &[Box<dyn Candidate>],
    ) -> std::result::Result<Vec<Term>, String> {
        let known: Vec<String> = slots.iter().map(|s| s.name.clone()).collect();
        if let Some(name) = self.except.iter().find(|n| !known.contains(n)) {
            let close: Vec<String> = mte_linalg::text::closest(name, &known, 5)
                .into_iter()
                .map(|n| format!("`{n}`"))
                .collect();
            return Err(format!(
                "`except`: `{name}` is not an error of this machine; closest: {}",
                close.join(", ")
            ));
        }
        let mut out: Vec<Term> = Vec::new();
        // A squareness not in the axis ISO 230-1 names it by (`EC0X` for `EC0Y`) comes after
        // the others: where the data see only the angle between the axes, the base keeps the
        // ISO one and lists the other as not separable.
        let (mut deferred, mut absolute): (Vec<Term>, Vec<Term>) = (Vec::new(), Vec::new());
        for slot in slots {
            // An exception holds in either representation (`EA0B` leaves out `EA0B abs` too).
            let relative = crate::instruments::relative_form(&slot.name);
            let name = relative.unwrap_or(&slot.name);
            if slot.column.iter().all(|v| v.abs() < 1e-15) || self.except.iter().any(|e| e == name)
            {
                continue;
            }
            let constant = |family: Family| Term {
                name: slot.name.clone(),
                label: slot.label.clone(),
                meaning: slot.meaning.clone(),
                family,
                columns: column_matrix(&slot.constant_column()),
                coefficients: vec![(slot.name.clone(), slot.quantity)],
                summary: Summary::EachCoefficient,
                exposed_by: None,
                separated_by: slot.separated_by.clone(),
            };
            match &slot.role {
                SlotRole::Constant {
                    family: Family::Squareness,
                } if self.squareness => {
                    if squareness_plane(&slot.name).is_some_and(|(_, later)| later) {
                        out.push(constant(Family::Base));
                    } else {
                        deferred.push(constant(Family::Base));
                    }
                }
                // A location error in the absolute representation after all the others: the
                // base has it where the relative form and the next axis' do not hold it.
                SlotRole::Constant { .. } if self.location && location.contains(&slot.name) => {
                    if relative.is_some() {
                        absolute.push(constant(Family::Base));
                    } else {
                        out.push(constant(Family::Base));
                    }
                }
                SlotRole::Component { .. } => {
                    let Some(degree) = self.components.as_ref().map(|c| c.degree) else {
                        continue;
                    };
                    let Some((lo, hi, rotary)) = component_orders(obs, slot, degree) else {
                        continue;
                    };
                    let Some(cols) = component_columns(obs, slot, lo, hi) else {
                        continue;
                    };
                    let what = if rotary {
                        format!("harmonics of a turn up to {hi}")
                    } else {
                        format!("polynomial up to degree {hi}")
                    };
                    out.push(
                        component_term(slot, format!("{} poly{degree}", slot.name), &what, cols)
                            .separated_by_opt(slot.separated_by.clone()),
                    );
                }
                _ => {}
            }
        }
        out.append(&mut deferred);
        out.append(&mut absolute);
        for name in &self.terms {
            if out.iter().any(|t| &t.name == name) {
                continue;
            }
            let found = candidates
                .iter()
                .map(|c| c.variants(obs))
                .find(|v| v.first().is_some_and(|t| &t.name == name));
            match found {
                Some(v) if v.len() == 1 => {
                    let mut t = v.into_iter().next().unwrap_or_else(|| unreachable!());
                    t.family = Family::Base;
                    out.push(t);
                }
                Some(_) => {
                    return Err(format!(
                        "`{name}` has a period or time constant to choose from the data: leave it to the search"
                    ));
                }
                None => {
                    let known: Vec<String> = candidates
                        .iter()
                        .filter_map(|c| c.variants(obs).into_iter().next().map(|t| t.name))
                        .chain(location.iter().cloned())
                        .collect();
                    let close: Vec<String> = mte_linalg::text::closest(name, &known, 5)
                        .into_iter()
                        .map(|n| format!("`{n}`"))
                        .collect();
                    return Err(format!(
                        "`{name}` is not an effect of this dataset; closest: {}",
                        close.join(", ")
                    ));
                }
            }
        }
        Ok(out)
    }
}

impl BaseModelSpec {
    /// The spec in words, for a report: the ordinary errors it holds of the axes `obs` moves.
    /// `location`: the location errors `"location": true` stands for on the dataset.
    pub fn describe(&self, obs: &Observations, location: &[String]) -> String {
        let axes = |kind: VariableKind| -> Vec<&str> {
            obs.variables
                .iter()
                .filter(|v| v.kind == kind)
                .map(|v| v.name.as_str())
                .collect()
        };
        let (linear, rotary) = (
            axes(VariableKind::LinearAxis),
            axes(VariableKind::RotaryAxis),
        );
        let mut parts = Vec::new();
        if let Some(c) = &self.components {
            let mut of = Vec::new();
            if !linear.is_empty() {
                of.push(format!(
                    "of {} (polynomials up to degree {})",
                    linear.join(", "),
                    c.degree
                ));
            }
            if !rotary.is_empty() {
                of.push(format!(
                    "of {} (harmonics 1–{} of a turn)",
                    rotary.join(", "),
                    c.degree.div_ceil(2)
                ));
            }
            if !of.is_empty() {
                parts.push(format!("every component error {}", of.join(" and ")));
            }
        }
        if self.squareness && linear.len() >= 2 {
            parts.push(format!(
                "the squareness errors between {}",
                linear.join(", ")
            ));
        }
        // One name per error: the absolute form (`EX0B abs`) is the same error.
        let mut names: Vec<&str> = Vec::new();
        for n in location {
            let n = crate::instruments::relative_form(n).unwrap_or(n);
            if !names.contains(&n) {
                names.push(n);
            }
        }
        // (A machine without rotary axes, or set-ups that separate none: nothing to say.)
        if self.location && !names.is_empty() {
            parts.push(format!(
                "the location errors of the rotary axes that the set-ups separate ({})",
                names.join(", ")
            ));
        }
        parts.extend(self.terms.iter().cloned());
        let mut text = match parts.split_last() {
            None => "no machine errors".to_string(),
            Some((last, [])) => last.clone(),
            Some((last, rest)) => format!("{} and {last}", rest.join("; ")),
        };
        if !self.except.is_empty() {
            text += &format!(", except {}", self.except.join(", "));
        }
        text
    }

    /// Which shorthand of the spec would hold a finding of family `family` named `name` that
    /// the spec leaves out, for an ordinary error every machine has ([`Shorthand::of_ordinary`];
    /// `per_turn`: a periodic finding's whole number of cycles per turn of a rotary axis).
    /// `None` for anything else and for an error the spec leaves out on purpose (`except`).
    pub fn would_hold(
        &self,
        family: &Family,
        name: &str,
        per_turn: Option<usize>,
    ) -> Option<Shorthand> {
        let iso = name.split_whitespace().next().unwrap_or(name);
        if self.except.iter().any(|e| e == iso) {
            return None;
        }
        let shorthand = Shorthand::of_ordinary(family, per_turn)?;
        let held = match shorthand {
            Shorthand::Components => self.components.is_some(),
            Shorthand::Squareness => self.squareness,
            Shorthand::Location => self.location,
        };
        (!held).then_some(shorthand)
    }

    /// The spec with `shorthand` set too (`components` at degree 3).
    pub fn with(mut self, shorthand: Shorthand) -> Self {
        match shorthand {
            Shorthand::Components => {
                self.components.get_or_insert(ComponentSpec { degree: 3 });
            }
            Shorthand::Squareness => self.squareness = true,
            Shorthand::Location => self.location = true,
        }
        self
    }

    /// The completions of the component errors of linear axes the spec leaves out, for when the
    /// search finds one as a cause (`… poly1` to `… poly3`): its higher orders, as
    /// [`BaseModelSpec::completions`] completes the base's, in blocks after the degree found. A
    /// real component error is a smooth function, not a polynomial of the degree that was
    /// significant first (a wave of half the stroke has no cubic part to speak of); without its
    /// higher orders the rest of it stays in the residuals, where a periodic error at a free
    /// period would take it for its own.
    pub fn cause_completions(
        &self,
        obs: &Observations,
        slots: &[SlotEffect],
    ) -> Vec<Box<dyn Candidate>> {
        use rayon::prelude::*;
        let held =
            |slot: &SlotEffect| self.components.is_some() && !self.except.contains(&slot.name);
        slots
            .par_iter()
            .filter(|slot| !held(slot) && slot.column.iter().any(|v| v.abs() >= 1e-15))
            .flat_map_iter(|slot| {
                // The causes' lowest degree: a positioning error's linear part is its scale.
                let positioning = matches!(
                    slot.role,
                    SlotRole::Component {
                        positioning: true,
                        ..
                    }
                );
                component_orders(obs, slot, CAUSE_DEGREE)
                    .filter(|&(_, hi, rotary)| !rotary && hi == CAUSE_DEGREE)
                    .into_iter()
                    .flat_map(move |(lo, hi, _)| (if positioning { 2 } else { lo })..=hi)
                    .flat_map(|degree| {
                        let cause = format!("{} poly{degree}", slot.name);
                        linear_completions(obs, slot, degree, Some(cause))
                    })
            })
            .collect()
    }

    /// The completions of the spec's component errors, each block after the one before: for
    /// every component error of a linear axis in the base, its next polynomial degrees (up to
    /// [`MAX_COMPONENT_DEGREE`], [`COMPLETION_BLOCK`] at a time), and all its degrees beyond the
    /// base's at once (up to [`MAX_DENSE_COMPONENT_DEGREE`] on a densely sampled axis, a
    /// [`Role::CompletionSpan`]), tested where no block is significant; for every rotary axis,
    /// the next harmonic of a turn (up to [`MAX_COMPONENT_HARMONIC`]) of all its error motions
    /// at once. Real component errors are smooth functions, not polynomials of the degree a user
    /// happens to state; the diagnosis adds these when the data ask for them, before it looks
    /// for causes. A rotary axis' error motions are completed together because a harmonic of a
    /// turn (the form of a bearing race, a wobble) shows in all of them, each by a little, and
    /// at a point the translations and tilts are partly confounded: one at a time, none would
    /// be significant while together they are.
    pub fn completions(&self, obs: &Observations, slots: &[SlotEffect]) -> Vec<Box<dyn Candidate>> {
        let Some(degree) = self.components.as_ref().map(|c| c.degree) else {
            return Vec::new();
        };
        // Rotary axes in the order their first slot appears, with their slots and base order;
        // the linear axes' slots with theirs.
        let mut rotary_axes: Vec<(String, usize, Vec<&SlotEffect>)> = Vec::new();
        let mut linear: Vec<(&SlotEffect, usize)> = Vec::new();
        for slot in slots {
            if slot.column.iter().all(|v| v.abs() < 1e-15) || self.except.contains(&slot.name) {
                continue;
            }
            let Some((_, hi, rotary)) = component_orders(obs, slot, degree) else {
                continue;
            };
            if rotary {
                let axis = component_axis(slot).unwrap_or_default();
                match rotary_axes.iter_mut().find(|(a, _, _)| *a == axis) {
                    Some((_, _, group)) => group.push(slot),
                    None => rotary_axes.push((axis, hi, vec![slot])),
                }
            } else {
                linear.push((slot, hi));
            }
        }
        // Each slot's and each rotary axis' columns are independent: built in parallel,
        // collected in order.
        use rayon::prelude::*;
        let linear: Vec<Vec<Box<dyn Candidate>>> = linear
            .into_par_iter()
            .map(|(slot, hi)| linear_completions(obs, slot, hi, None))
            .collect();
        let rotary: Vec<Vec<Box<dyn Candidate>>> = rotary_axes
            .into_par_iter()
            .map(|(axis, hi, group)| {
                // Harmonics `first..=last` of every error motion of the axis, as one term.
                let harmonics = |first: usize, last: usize| -> Option<Term> {
                    let parts: Vec<(&SlotEffect, DMat)> = group
                        .iter()
                        .filter_map(|s| component_columns(obs, s, first, last).map(|c| (*s, c)))
                        .collect();
                    if parts.is_empty() {
                        return None;
                    }
                    let (tag, which) = if first == last {
                        (format!("H{first}"), format!("harmonic {first}"))
                    } else {
                        (
                            format!("H{first}-{last}"),
                            format!("harmonics {first} to {last}"),
                        )
                    };
                    let mut columns =
                        DMat::zeros(obs.len(), parts.iter().map(|(_, c)| c.ncols()).sum());
                    let mut at = 0;
                    for (_, c) in &parts {
                        columns.columns_mut(at, c.ncols()).copy_from(c);
                        at += c.ncols();
                    }
                    Some(Term {
                        coefficients: parts
                            .iter()
                            .flat_map(|(s, c)| {
                                (0..c.ncols())
                                    .map(|k| (format!("{} {tag}[{k}]", s.name), s.quantity))
                            })
                            .collect(),
                        label: format!("error motions of {axis}, {which} of a turn"),
                        meaning: format!(
                            "a higher harmonic of the error motions of {axis} ({}): the form of a \
                             bearing race or a wobble repeats every turn",
                            parts
                                .iter()
                                .map(|(s, _)| s.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                        name: format!("{axis} {tag}"),
                        family: Family::Base,
                        columns,
                        summary: Summary::EachCoefficient,
                        exposed_by: Some(axis.clone()),
                        separated_by: None,
                    })
                };
                let mut out: Vec<Box<dyn Candidate>> = Vec::new();
                // Every harmonic beyond the base's at once ([`Role::CompletionSpan`]): a form
                // of several harmonics, none alone significant (a wavier race, an encoder's
                // higher harmonics), would otherwise be left to the search as a cause.
                if hi + 1 < MAX_COMPONENT_HARMONIC
                    && let Some(term) = harmonics(hi + 1, MAX_COMPONENT_HARMONIC)
                {
                    out.push(Box::new(Completion {
                        term,
                        after: None,
                        span: true,
                    }));
                }
                let mut after: Option<String> = None;
                for h in hi + 1..=MAX_COMPONENT_HARMONIC {
                    let Some(term) = harmonics(h, h) else {
                        break;
                    };
                    let name = term.name.clone();
                    out.push(Box::new(Completion {
                        term,
                        after: after.replace(name),
                        span: false,
                    }));
                }
                out
            })
            .collect();
        linear.into_iter().chain(rotary).flatten().collect()
    }
}

/// A structure probe ([`Role::Probe`]): fixed columns, tested, never fitted.
struct Probe(Term);

impl Candidate for Probe {
    fn variants(&self, _obs: &Observations) -> Vec<Term> {
        vec![self.0.clone()]
    }

    fn role(&self) -> Role {
        Role::Probe
    }
}

/// Structure probes for errors that depend on two linear axes at once: for each pair of
/// linear axes the data move and each direction in which a component error of either
/// translates the tool (a positioning or straightness error), that translation as a smooth
/// function of both coordinates, products `P_i(a)·P_j(b)` of Legendre polynomials with
/// `i, j ≥ 1` and `i + j ≤ 4`. The rigid-body model has only functions of one axis there
/// (through lever arms, an angular error of one axis times the other's coordinate, which the
/// probe's increment over the model leaves out), so what the probe finds is a deformation
/// (a table that bends or warms unevenly, a gantry that twists) that no candidate has.
/// Translations along the same direction share their columns: one probe per direction and pair.
pub(crate) fn interaction_probes(
    obs: &Observations,
    slots: &[SlotEffect],
) -> Vec<Box<dyn Candidate>> {
    const TOTAL_DEGREE: usize = 4;
    let linear: Vec<&Variable> = obs
        .variables
        .iter()
        .filter(|v| v.kind == VariableKind::LinearAxis && varies(&v.values))
        .collect();
    let translations: Vec<&SlotEffect> = slots
        .iter()
        .filter(|s| {
            s.quantity == Quantity::Length
                && s.reference.is_none()
                && matches!(&s.role, SlotRole::Component { axis, positioning, straightness }
                    if (*positioning || *straightness) && linear.iter().any(|v| &v.name == axis))
        })
        .collect();
    let orders: Vec<(usize, usize)> = (1..TOTAL_DEGREE)
        .flat_map(|i| (1..=TOTAL_DEGREE - i).map(move |j| (i, j)))
        .collect();
    let mut out: Vec<Box<dyn Candidate>> = Vec::new();
    for (k, a) in linear.iter().enumerate() {
        let pa = legendre_columns(&a.values, 1..=TOTAL_DEGREE - 1);
        for b in &linear[k + 1..] {
            let pb = legendre_columns(&b.values, 1..=TOTAL_DEGREE - 1);
            let mut directions: Vec<&DVec> = Vec::new();
            for slot in &translations {
                let SlotRole::Component { axis, .. } = &slot.role else {
                    continue;
                };
                let scale = slot.column.amax();
                if (axis != &a.name && axis != &b.name)
                    || scale == 0.0
                    || directions
                        .iter()
                        .any(|d| (*d - &slot.column).amax() <= 1e-9 * scale)
                {
                    continue;
                }
                directions.push(&slot.column);
                let columns = DMat::from_fn(obs.len(), orders.len(), |r, c| {
                    let (i, j) = orders[c];
                    slot.column[r] * pa[(r, i - 1)] * pb[(r, j - 1)]
                });
                // The direction the slot translates the tool in: the second letter of its ISO
                // name (EYX: the Y straightness of X).
                let direction = slot.name.chars().nth(1).unwrap_or('?');
                let name = format!("{direction} error along {} and {}", a.name, b.name);
                out.push(Box::new(Probe(Term {
                    coefficients: orders
                        .iter()
                        .map(|(i, j)| (format!("{name} P{i}·P{j}"), slot.quantity))
                        .collect(),
                    label: format!(
                        "{direction} error changing with {} and {} jointly",
                        a.name, b.name
                    ),
                    meaning: format!(
                        "the error in {direction} depends on {} and {} together, which no component error of one axis does (a structure bending or warming unevenly)",
                        a.name, b.name
                    ),
                    name,
                    family: Family::Custom,
                    columns,
                    summary: Summary::EachCoefficient,
                    exposed_by: Some(a.name.clone()),
                    separated_by: None,
                })));
            }
        }
    }
    out
}

/// Highest polynomial degree the base's component errors of a linear axis are completed to.
pub const MAX_COMPONENT_DEGREE: usize = 10;

/// Highest polynomial degree the component errors of a densely sampled linear axis are
/// completed to: one degree per four distinct positions beyond [`MAX_COMPONENT_DEGREE`], up to
/// this.
pub const MAX_DENSE_COMPONENT_DEGREE: usize = 15;

/// Distinct positions along a linear axis per polynomial degree its component errors may be
/// completed to beyond [`MAX_COMPONENT_DEGREE`].
const POSITIONS_PER_DEGREE: usize = 4;

/// The highest polynomial degree a component error of a linear axis is completed to:
/// [`MAX_COMPONENT_DEGREE`], or on an axis with many distinct positions (tracker targets,
/// points, R-test paths) one degree per [`POSITIONS_PER_DEGREE`] of them, up to
/// [`MAX_DENSE_COMPONENT_DEGREE`] — a smooth error with a few waves over the stroke needs
/// about π degrees per wave, still far fewer than a ball screw's pitch error has waves — and
/// never beyond what the positions carry ([`highest_order`]).
fn highest_completion_degree(obs: &Observations, slot: &SlotEffect) -> usize {
    let positions = match &slot.role {
        SlotRole::Component { axis, .. } => obs
            .variable(axis)
            .map_or(0, |v| crate::basis::distinct_sorted(&v.values).len()),
        SlotRole::Constant { .. } => 0,
    };
    (positions / POSITIONS_PER_DEGREE)
        .clamp(MAX_COMPONENT_DEGREE, MAX_DENSE_COMPONENT_DEGREE)
        .min(positions.saturating_sub(1))
}

/// Highest polynomial degree of a component error searched as a cause (`… poly3`).
pub const CAUSE_DEGREE: usize = 3;

/// Polynomial degrees a completion adds at once.
pub const COMPLETION_BLOCK: usize = 3;

/// Highest harmonic of a turn the base's component errors of a rotary axis are completed to.
pub const MAX_COMPONENT_HARMONIC: usize = 6;

/// The completions of a linear axis' component error `slot` beyond degree `hi`
/// ([`BaseModelSpec::completions`]): its higher orders in blocks, each after the one before, and
/// for the base's own error (`builds_on` `None`) all of them at once. `builds_on`: the cause the
/// first block builds on.
fn linear_completions(
    obs: &Observations,
    slot: &SlotEffect,
    hi: usize,
    builds_on: Option<String>,
) -> Vec<Box<dyn Candidate>> {
    let mut out: Vec<Box<dyn Candidate>> = Vec::new();
    // All the orders beyond the base's at once, up to a higher degree where the axis
    // has the positions for it ([`Role::CompletionSpan`]): a waviness of a few
    // cycles over the stroke spreads over more orders than a block holds, each block
    // too little of it to be significant alone. (Not for a cause: on an R-test, whose
    // held-out blocks leave out ranges of the linear axes, a polynomial of degree 15 in Z
    // predicted them hundreds of µm off, and no cause after it could earn its place.)
    let top = highest_completion_degree(obs, slot);
    if builds_on.is_none()
        && hi + COMPLETION_BLOCK < top
        && let Some(cols) = component_columns(obs, slot, hi + 1, top)
    {
        let name = format!("{} P{}-{top}", slot.name, hi + 1);
        let what = format!("degrees {} to {top} together", hi + 1);
        out.push(Box::new(Completion {
            term: component_term(slot, name, &what, cols),
            after: None,
            span: true,
        }));
    }
    // Orders in blocks: a smooth error's remainder spreads over several orders, which
    // one at a time would not reveal.
    let mut after = builds_on;
    for first in (hi + 1..=MAX_COMPONENT_DEGREE).step_by(COMPLETION_BLOCK) {
        let last = (first + COMPLETION_BLOCK - 1)
            .min(MAX_COMPONENT_DEGREE)
            .min(top);
        if first > last {
            break;
        }
        let Some(cols) = component_columns(obs, slot, first, last) else {
            break;
        };
        let (name, what) = if first == last {
            (format!("{} P{first}", slot.name), format!("degree {first}"))
        } else {
            (
                format!("{} P{first}-{last}", slot.name),
                format!("degrees {first} to {last}"),
            )
        };
        let term = component_term(slot, name.clone(), &what, cols);
        out.push(Box::new(Completion {
            term,
            after: after.replace(name),
            span: false,
        }));
    }
    out
}

/// A base term of a component slot's basis columns.
fn component_term(slot: &SlotEffect, name: String, what: &str, cols: DMat) -> Term {
    Term {
        coefficients: (0..cols.ncols())
            .map(|k| (format!("{name}[{k}]"), slot.quantity))
            .collect(),
        name,
        label: format!("{}, {what}", slot.label),
        meaning: slot.meaning.clone(),
        family: Family::Base,
        columns: cols,
        summary: Summary::EachCoefficient,
        exposed_by: component_axis(slot),
        separated_by: None,
    }
}

/// The axis of a component slot.
fn component_axis(slot: &SlotEffect) -> Option<String> {
    match &slot.role {
        SlotRole::Component { axis, .. } => Some(axis.clone()),
        SlotRole::Constant { .. } => None,
    }
}

/// The plane of a squareness by its ISO 230-1 name — the index (0–2) of the direction it turns
/// about — and whether its axis is the plane's later one (X, Y, Z order), the axis ISO 230-1
/// names it by: `EC0Y` → (2, true), `EC0X` → (2, false); `None` for other names.
pub(crate) fn squareness_plane(name: &str) -> Option<(usize, bool)> {
    let (c, axis) = mte_errors::catalogue::parse_location_error_name(name)?;
    let about = c.index().checked_sub(3)?;
    let axis = ["X", "Y", "Z"].iter().position(|&a| a == axis)?;
    (axis != about && about < 3).then_some((about, axis > 3 - about - axis))
}

/// The axis of a location or squareness error by its ISO 230-1 name: `Y` of `EC0Y`, `B` of
/// `EX0B` (and of `EX0B abs`).
fn located_axis(name: &str) -> Option<&str> {
    let relative = crate::instruments::relative_form(name).unwrap_or(name);
    mte_errors::catalogue::parse_location_error_name(relative).map(|(_, axis)| axis)
}

/// For a component slot whose axis the data move, the orders of a base of `degree`: the lowest
/// and highest polynomial degree (from 2 for a straightness, whose linear part is the
/// squareness) or harmonic (1 to ⌈degree / 2⌉ for a rotary axis), and whether it is rotary.
fn component_orders(
    obs: &Observations,
    slot: &SlotEffect,
    degree: usize,
) -> Option<(usize, usize, bool)> {
    let SlotRole::Component {
        axis, straightness, ..
    } = &slot.role
    else {
        return None;
    };
    let v = obs.variable(axis).filter(|v| varies(&v.values))?;
    let rotary = v.kind == VariableKind::RotaryAxis;
    let top = highest_order(&v.values, rotary);
    if rotary {
        Some((1, degree.div_ceil(2).min(top), true))
    } else {
        let lo = if *straightness { 2 } else { 1 };
        let hi = degree.min(top);
        (lo <= hi).then_some((lo, hi, false))
    }
}

/// The highest order a function of an axis sampled at `values` can have apart from its lower
/// orders: at n distinct positions a polynomial of degree n − 1 takes any values, and a higher
/// degree is a combination of the lower ones — its linear part a squareness or scale, its
/// constant an offset; over a turn, n distinct angles carry harmonics up to (n − 1) / 2.
fn highest_order(values: &[f64], rotary: bool) -> usize {
    let n = crate::basis::distinct_sorted(values)
        .len()
        .saturating_sub(1);
    if rotary { n / 2 } else { n }
}

/// The effect of a component slot's basis functions of orders `lo..=hi` (Legendre degrees over
/// the observed range for a linear axis, harmonics of a turn for a rotary one); `None` where
/// the axis' positions cannot carry order `hi` apart from the lower ones ([`highest_order`]).
fn component_columns(obs: &Observations, slot: &SlotEffect, lo: usize, hi: usize) -> Option<DMat> {
    let SlotRole::Component { axis, .. } = &slot.role else {
        return None;
    };
    let v = obs.variable(axis)?;
    if hi > highest_order(&v.values, v.kind == VariableKind::RotaryAxis) {
        return None;
    }
    let cols = if v.kind == VariableKind::RotaryAxis {
        slot.modulated(&v.values, &|s| {
            let mut m = DMat::zeros(s.len(), 2 * (hi + 1 - lo));
            for h in lo..=hi {
                let sc = sin_cos_columns(s, std::f64::consts::TAU / h as f64);
                m.columns_mut(2 * (h - lo), 2).copy_from(&sc);
            }
            m
        })
    } else {
        slot.modulated(&v.values, &|s| legendre_columns(s, lo..=hi))
    };
    (cols.ncols() > 0 && cols.amax() > 1e-15).then_some(cols)
}

/// A higher order of a component error the base model already has (see
/// [`BaseModelSpec::completions`]): the base is completed with it when the data ask for it,
/// before the search for causes or once a cause that hid it is in; it is never reported as a
/// cause.
pub struct Completion {
    /// The term.
    pub term: Term,
    /// The completion it follows (the previous order), if any.
    pub after: Option<String>,
    /// Every order beyond the base's at once ([`Role::CompletionSpan`]), not the next block.
    pub span: bool,
}

impl Candidate for Completion {
    fn variants(&self, _obs: &Observations) -> Vec<Term> {
        vec![self.term.clone()]
    }

    fn requires(&self) -> Option<&str> {
        self.after.as_deref()
    }

    fn role(&self) -> Role {
        if self.span {
            Role::CompletionSpan
        } else {
            Role::Completion
        }
    }

    fn on_rows(&self, _obs: &Observations, rows: &[usize]) -> Box<dyn Candidate> {
        Box::new(Completion {
            term: self.term.select_rows(rows),
            after: self.after.clone(),
            span: self.span,
        })
    }
}

/// The term of a [`Scan`] for one value of its hyper-parameter, on all observations (`None`) or
/// on the given rows only.
pub type ScanTerm = dyn Fn(f64, Option<&[usize]>) -> Term + Send + Sync;

/// The basis functions of a [`Scan::spread`] for one value of its hyper-parameter, at the given
/// values of the variable.
pub type SpreadBasis = dyn Fn(&[f64], f64) -> DMat + Send + Sync;

/// One cause with a hyper-parameter scanned over a grid (a period, a time constant); the best
/// grid value is refined by golden-section search between its neighbours.
pub struct Scan {
    /// Values of the hyper-parameter, increasing.
    pub grid: Vec<f64>,
    /// Refine the best grid value (off for values that must stay on the grid, e.g. harmonics).
    pub refine_grid: bool,
    terms: ScanTerms,
}

/// How a [`Scan`] makes its terms.
#[derive(Clone)]
enum ScanTerms {
    /// Any term, on the observations `rows` (`None`: all).
    Rows {
        make: std::sync::Arc<ScanTerm>,
        rows: Option<std::sync::Arc<[usize]>>,
    },
    /// Functions of one variable spread over the observations: the term `make(value, S B)`
    /// with `B = basis(values, value)`.
    Spread {
        spread: std::sync::Arc<Spread>,
        basis: std::sync::Arc<SpreadBasis>,
        make: std::sync::Arc<dyn Fn(f64, DMat) -> Term + Send + Sync>,
    },
}

impl Scan {
    /// A scan over `grid` of the terms `make` gives, on all observations.
    pub fn new(
        grid: Vec<f64>,
        refine_grid: bool,
        make: impl Fn(f64, Option<&[usize]>) -> Term + Send + Sync + 'static,
    ) -> Scan {
        Scan {
            grid,
            refine_grid,
            terms: ScanTerms::Rows {
                make: std::sync::Arc::new(make),
                rows: None,
            },
        }
    }

    /// A scan over `grid` of functions of one variable seen through `spread`: the term of a
    /// value is `make(value, columns)` with the columns `spread.expand(basis(values, value))`
    /// ([`Candidate::spread`]). `make` places the columns in the term as they are (the
    /// diagnosis forms a term without them and adds them where it needs them).
    pub fn spread(
        grid: Vec<f64>,
        refine_grid: bool,
        spread: Spread,
        basis: impl Fn(&[f64], f64) -> DMat + Send + Sync + 'static,
        make: impl Fn(f64, DMat) -> Term + Send + Sync + 'static,
    ) -> Scan {
        Scan {
            grid,
            refine_grid,
            terms: ScanTerms::Spread {
                spread: std::sync::Arc::new(spread),
                basis: std::sync::Arc::new(basis),
                make: std::sync::Arc::new(make),
            },
        }
    }

    fn term(&self, value: f64) -> Term {
        match &self.terms {
            ScanTerms::Rows { make, rows } => make(value, rows.as_deref()),
            ScanTerms::Spread {
                spread,
                basis,
                make,
            } => make(value, spread.expand(&basis(spread.values(), value))),
        }
    }
}

impl Candidate for Scan {
    fn variants(&self, _obs: &Observations) -> Vec<Term> {
        self.grid.iter().map(|&p| self.term(p)).collect()
    }

    fn spread(&self) -> Option<SpreadVariants> {
        let ScanTerms::Spread {
            spread,
            basis,
            make,
        } = &self.terms
        else {
            return None;
        };
        let bases: Vec<DMat> = self
            .grid
            .iter()
            .map(|&p| basis(spread.values(), p))
            .collect();
        let headers = self
            .grid
            .iter()
            .zip(&bases)
            .map(|(&p, b)| make(p, DMat::zeros(0, b.ncols())))
            .collect();
        Some(SpreadVariants {
            spread: spread.clone(),
            bases,
            headers,
        })
    }

    fn refine(&self, best: usize, score: &Score) -> Option<Term> {
        if !self.refine_grid || self.grid.len() < 3 {
            return None;
        }
        let lo = self.grid[best.saturating_sub(1)];
        let hi = self.grid[(best + 1).min(self.grid.len() - 1)];
        let f = |p: f64| {
            if let ScanTerms::Spread { spread, basis, .. } = &self.terms
                && let Some(s) = score.of_spread(spread, &basis(spread.values(), p))
            {
                return s;
            }
            score.of(&self.term(p))
        };
        // To 1e-5 of the bracket (two grid steps): far below the uncertainty of a period or
        // time constant the data can tell.
        let (p, fp) = crate::basis::bounded_minimum(lo, hi, 1e-5 * (hi - lo).abs(), f);
        (fp < f(self.grid[best])).then(|| self.term(p))
    }

    /// The term at `value`; where the values stay on the grid (harmonics of a turn: a whole
    /// number of cycles per turn) only at a grid value, the hyper-parameter being discrete (it
    /// adds no uncertainty to the size).
    fn at(&self, _variant: usize, value: f64) -> Option<Term> {
        let on_grid = || {
            self.grid
                .iter()
                .any(|&g| (g - value).abs() <= 1e-9 * g.abs().max(value.abs()))
        };
        (self.refine_grid || on_grid()).then(|| self.term(value))
    }

    fn columns(&self, _obs: &Observations) -> usize {
        self.grid
            .first()
            .map_or(0, |&p| self.grid.len() * self.term(p).columns.ncols())
    }

    fn on_rows(&self, _obs: &Observations, rows: &[usize]) -> Box<dyn Candidate> {
        let terms = match &self.terms {
            ScanTerms::Rows { make, rows: mine } => ScanTerms::Rows {
                make: make.clone(),
                rows: Some(match mine {
                    Some(mine) => rows.iter().map(|&i| mine[i]).collect(),
                    None => rows.into(),
                }),
            },
            ScanTerms::Spread {
                spread,
                basis,
                make,
            } => ScanTerms::Spread {
                spread: std::sync::Arc::new(spread.select_rows(rows)),
                basis: basis.clone(),
                make: make.clone(),
            },
        };
        Box::new(Scan {
            grid: self.grid.clone(),
            refine_grid: self.refine_grid,
            terms,
        })
    }
}

/// A set of alternative terms for one cause.
pub struct Alternatives(pub Vec<Term>);

impl Candidate for Alternatives {
    fn variants(&self, _obs: &Observations) -> Vec<Term> {
        self.0.clone()
    }

    fn on_rows(&self, _obs: &Observations, rows: &[usize]) -> Box<dyn Candidate> {
        Box::new(Alternatives(
            self.0.iter().map(|t| t.select_rows(rows)).collect(),
        ))
    }
}

/// Linear and first-order thermal drift of a constant; time constants from `floor` (the
/// interval between repeated visits of a pose) up. With a `reference` pose, the constant's
/// column is its effect at the reading and at the reference together, and the drift acts at
/// each at its own time: `(constant − reference)·d(t) + reference·d(t_ref)`.
fn drift_candidates(
    constant: &Term,
    reference: Option<&Reference>,
    settling: &Settling,
) -> Vec<Box<dyn Candidate>> {
    let (t, t0) = (&settling.times[..], settling.t0);
    // Per observation: the constant's column, its reference part and the reference time (the
    // reading's own time where there is none: the drift then acts at the reading alone).
    let reference_part: Vec<f64> = match reference {
        Some(r) => r.column.iter().copied().collect(),
        None => vec![0.0; t.len()],
    };
    let t_ref: Vec<f64> = match reference {
        Some(r) => r.time_s.clone(),
        None => t.to_vec(),
    };
    let q = constant.coefficients[0].1;
    let rate = match q {
        Quantity::Angle => Quantity::AngleRate,
        Quantity::Ratio => Quantity::RatioRate,
        _ => Quantity::LengthRate,
    };
    let col = constant.columns.column(0);
    let linear = Term {
        name: format!("{} drift", constant.name),
        label: format!("thermal drift of {} (linear in time)", constant.name),
        meaning: format!(
            "{} changes steadily during the measurement: the machine warms up",
            constant.label
        ),
        family: Family::Drift {
            time_constant_s: None,
        },
        columns: DMat::from_fn(t.len(), 1, |i, _| {
            col[i] * (t[i] - t0) - reference_part[i] * (t[i] - t_ref[i])
        }),
        coefficients: vec![(format!("{} rate", constant.name), rate)],
        summary: Summary::EachCoefficient,
        exposed_by: Some("t".into()),
        separated_by: None,
    };
    let (name, label) = (constant.name.clone(), constant.label.clone());
    let make = move |tau: f64, columns: DMat| Term {
        name: format!("{name} drift exp"),
        label: format!("thermal drift of {name} (first-order)"),
        meaning: format!("{label} settles towards a new value with a thermal time constant"),
        family: Family::Drift {
            time_constant_s: Some(tau),
        },
        columns,
        coefficients: vec![(format!("{name} change"), q)],
        summary: Summary::EachCoefficient,
        exposed_by: Some("t".into()),
        separated_by: None,
    };
    // The settling d(t) at the reading, with the constant's column less its reference part,
    // and at the reference pose's time, with the reference part.
    let at_reading: Vec<f64> = col
        .iter()
        .zip(&reference_part)
        .map(|(c, r)| c - r)
        .collect();
    let spread = match reference {
        Some(_) => Spread::new(&[(t, &at_reading), (&t_ref, &reference_part)]),
        None => Spread::new(&[(t, &at_reading)]),
    };
    let exponential = Scan::spread(
        settling.grid.clone(),
        true,
        spread,
        move |t: &[f64], tau: f64| Settling::at(t0, t, tau),
        make,
    );
    vec![Box::new(linear), Box::new(exponential)]
}

/// The name of the parameter that holds the positioning slot's constant — the axis' zero as the
/// readings see it: the drifting term (the instrument's zero, `EXX offset`) whose effect is the
/// slot's, else `{slot} zero`. A drift of the zero found in two candidates (an offset drift and
/// an expansion about a point) is then one parameter's drift by name ([`drifted_parameters`]).
fn zero_of(slot: &SlotEffect, drifting: &[(&Term, Option<&Reference>)]) -> String {
    let scale = slot.column.norm().max(1e-300);
    drifting
        .iter()
        .find(|(t, _)| {
            t.width() == 1 && (t.columns.column(0) - &slot.column).norm() <= 1e-9 * scale
        })
        .map_or_else(|| format!("{} zero", slot.name), |(t, _)| t.name.clone())
}

/// The parameters whose drift in time a drift term describes, by its coefficients' names: a
/// linear drift's `… rate`, a first-order one's `… change` (an expansion about a point drifts
/// two, the scale and the axis' zero).
pub(crate) fn drifted_parameters(term: &Term) -> Vec<&str> {
    term.coefficients
        .iter()
        .filter_map(|(name, _)| {
            name.strip_suffix(" change")
                .or_else(|| name.strip_suffix(" rate"))
        })
        .collect()
}

/// The first-order thermal expansion of a linear axis about a fixed point its data do not
/// state (a screw's fixed bearing away from the axis' zero): the positioning error
/// `(s·x + z)·(1 − e^(−(t − t₀)/τ))` with the axis coordinate x, the final scale change s and
/// zero change z (the fixed point at x = −z/s), scanned over τ as the first-order drifts are.
/// `zero` names the parameter that holds the axis' zero ([`zero_of`]).
fn expansion_about_a_point(
    slot: &SlotEffect,
    zero: &str,
    axis: &str,
    values: &[f64],
    settling: &Settling,
) -> Scan {
    let (name, quantity, zero) = (slot.name.clone(), slot.quantity, zero.to_string());
    let axis = axis.to_string();
    let column = slot.column.clone();
    let values = values.to_vec();
    let (t, t0) = (settling.times.clone(), settling.t0);
    Scan::new(settling.grid.clone(), true, move |tau, rows| {
        let all: Vec<usize>;
        let rows = match rows {
            Some(r) => r,
            None => {
                all = (0..t.len()).collect();
                &all
            }
        };
        let columns = DMat::from_fn(rows.len(), 2, |i, j| {
            let r = rows[i];
            column[r] * settled(t[r] - t0, tau) * if j == 0 { values[r] } else { 1.0 }
        });
        Term {
            name: format!("{name} scale drift exp about a point"),
            label: format!("thermal expansion of {axis} about a fixed point (first-order)"),
            meaning: format!(
                "the screw or scale of {axis} expands as the machine warms about its fixed bearing, away from the axis' zero: its scale and the zero of {axis} settle together with one time constant (the fixed point lies at {axis} = −{zero} change ÷ {name} scale change)"
            ),
            family: Family::Drift {
                time_constant_s: Some(tau),
            },
            columns,
            coefficients: vec![
                (format!("{name} scale change"), Quantity::Ratio),
                (format!("{zero} change"), quantity),
            ],
            summary: Summary::FixedPoint(format!("{name} fixed point")),
            exposed_by: Some("t".into()),
            separated_by: None,
        }
    })
}

/// The readings' times and the time constants the first-order drifts scan over them
/// ([`time_constants_to_scan`]): the same for every drift of a dataset.
struct Settling {
    times: Vec<f64>,
    /// The first reading's time.
    t0: f64,
    grid: Vec<f64>,
}

impl Settling {
    /// The readings at `times`, the shortest time constant scanned `floor`.
    fn new(times: &[f64], floor: f64) -> Settling {
        Settling {
            times: times.to_vec(),
            t0: times.iter().copied().fold(f64::INFINITY, f64::min),
            grid: time_constants_to_scan(times, floor),
        }
    }

    /// The first-order settling `1 − exp(−(t − t₀)/τ)` at the times `t` for the time
    /// constant `tau` (one column).
    fn at(t0: f64, t: &[f64], tau: f64) -> DMat {
        DMat::from_fn(t.len(), 1, |i, _| settled(t[i] - t0, tau))
    }
}

/// How far a first-order drift of time constant `tau` has settled `elapsed` s after it began:
/// `1 − e^(−elapsed/τ)`.
fn settled(elapsed: f64, tau: f64) -> f64 {
    1.0 - (-elapsed / tau).exp()
}

fn coefficient_name(name: &str, suffix: &str, k: usize, width: usize) -> String {
    if width == 1 {
        format!("{name}{suffix}")
    } else {
        format!("{name}{suffix}[{k}]")
    }
}

fn column_matrix(c: &DVec) -> DMat {
    DMat::from_column_slice(c.len(), 1, c.as_slice())
}

pub(crate) fn varies(v: &[f64]) -> bool {
    let (lo, hi) = crate::basis::range(v);
    hi > lo
}

/// The shortest time constant a first-order drift is searched at, where a pose is revisited
/// every `revisit` s. A pose-independent drift shows in the differences between a pose's
/// consecutive visits; the poses of one programme cycle are visited one after another, so these
/// differences, from the first pose's to the last's, trace how the drift settles over the cycle
/// even when it settles faster than the cycle: a time constant of a third of it leaves the last
/// pose e^−3 = 5 % of the first's difference. Faster than that, the drift is over before most
/// poses are seen twice.
pub(crate) fn shortest_time_constant(revisit: f64) -> f64 {
    revisit / 3.0
}

/// A period as the report names it: mm along a linear axis, degrees of a turn.
pub(crate) fn format_period(p: f64, rotary: bool) -> String {
    if rotary {
        format!("{:.1}°", p.to_degrees())
    } else {
        format!("{p:.2} mm")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slot_sees_a_function_of_its_axis_at_each_row_and_at_its_reference_pose() {
        // Six rows at three positions (repeated, as runs repeat them), each seen with its own
        // sensitivity and, with the opposite one, at its set-up's reference position.
        let values = [10.0, -5.0, 10.0, 2.5, -5.0, 10.0];
        let slot = SlotEffect {
            name: "EXX".into(),
            label: "positioning of X".into(),
            meaning: String::new(),
            quantity: Quantity::Length,
            role: SlotRole::Component {
                axis: "X".into(),
                positioning: true,
                straightness: false,
            },
            column: DVec::from_column_slice(&[1.0, 0.5, -1.0, 2.0, 0.25, 1.5]),
            separated_by: None,
            reference: Some(Reference {
                column: DVec::from_column_slice(&[-1.0, -0.5, 1.0, -2.0, -0.25, -1.5]),
                coordinate: vec![0.0, 0.0, 0.0, -10.0, -10.0, -10.0],
                time_s: vec![0.0; 6],
            }),
        };
        // g(s) = (s, s²): by definition, column·g(s) + reference column·g(s_ref).
        let basis = |s: &[f64]| DMat::from_fn(s.len(), 2, |i, j| s[i].powi(j as i32 + 1));
        let m = slot.modulated(&values, &basis);
        let r = slot.reference.as_ref().expect("a reference");
        for (i, &s) in values.iter().enumerate() {
            for j in 0..2 {
                let g = |s: f64| s.powi(j as i32 + 1);
                let expected = slot.column[i] * g(s) + r.column[i] * g(r.coordinate[i]);
                assert_eq!(m[(i, j)], expected, "row {i}, function {j}");
            }
        }
        // A range-normalised basis is one function over rows and references together: Legendre's
        // first degree is −1 at the lowest of all (the reference's −10) and 1 at the highest.
        let legendre = slot.modulated(&values, &|s| crate::basis::legendre_columns(s, 1..=1));
        let unit = |v: f64| 2.0 * (v + 10.0) / 20.0 - 1.0;
        assert!((legendre[(3, 0)] - (2.0 * unit(2.5) - 2.0 * unit(-10.0))).abs() < 1e-12);
    }

    #[test]
    fn a_base_model_is_described_in_its_own_terms_and_knows_which_ordinary_errors_it_lacks() {
        let location = ["EX0C".to_string(), "EY0C".into(), "EX0C abs".into()];
        let r_test = BaseModelSpec {
            location: true,
            ..BaseModelSpec::default()
        };
        let variable = |name: &str, kind| Variable {
            name: name.into(),
            kind,
            values: vec![0.0],
        };
        let obs = Observations {
            values: DVec::zeros(1),
            sigma: None,
            variables: vec![
                variable("X", VariableKind::LinearAxis),
                variable("Y", VariableKind::LinearAxis),
                variable("C", VariableKind::RotaryAxis),
                variable("t", VariableKind::Time),
            ],
            setup: vec![0],
            setup_names: vec!["a".into()],
            channel: vec![0],
            channel_names: vec!["d".into()],
            setup_kind: "setup".into(),
            quantity: Quantity::Length,
        };
        assert_eq!(
            r_test.describe(&obs, &location),
            "the location errors of the rotary axes that the set-ups separate (EX0C, EY0C)"
        );
        let full = BaseModelSpec {
            components: Some(ComponentSpec { degree: 3 }),
            squareness: true,
            location: true,
            terms: vec!["EXX reversal".into()],
            except: vec!["EC0Y".into()],
        };
        assert_eq!(
            full.describe(&obs, &[]),
            "every component error of X, Y (polynomials up to degree 3) and of C (harmonics \
             1–2 of a turn); the squareness errors between X, Y and EXX reversal, except EC0Y"
        );
        assert_eq!(
            BaseModelSpec::default().describe(&obs, &location),
            "no machine errors"
        );
        // Ordinary errors the location-only base lacks: component errors, a rotary axis'
        // error motion over a whole number of cycles per turn (not a worm gear's), squareness.
        let poly = Family::Component { degree: 3 };
        assert_eq!(
            r_test.would_hold(&poly, "EAZ poly3", None),
            Some(Shorthand::Components)
        );
        let wave = Family::Periodic { period: 1.0 };
        assert_eq!(
            r_test.would_hold(&wave, "EXC periodic", Some(2)),
            Some(Shorthand::Components)
        );
        assert_eq!(r_test.would_hold(&wave, "ECC periodic", Some(40)), None);
        assert_eq!(r_test.would_hold(&wave, "EXX periodic", None), None);
        assert_eq!(
            r_test.would_hold(&Family::Squareness, "EC0Y", None),
            Some(Shorthand::Squareness)
        );
        assert_eq!(r_test.would_hold(&Family::Location, "EX0C", None), None);
        assert_eq!(
            r_test.would_hold(&Family::Reversal, "EXX reversal", None),
            None
        );
        // Left out on purpose: not pointed at.
        assert_eq!(full.would_hold(&Family::Squareness, "EC0Y", None), None);
        // The shorthand as a manifest states it, without what it does not set.
        assert_eq!(
            serde_json::to_string(&r_test).unwrap(),
            r#"{"location":true}"#
        );
        assert_eq!(
            serde_json::to_string(&r_test.with(Shorthand::Squareness)).unwrap(),
            r#"{"squareness":true,"location":true}"#
        );
    }

    #[test]
    fn no_order_beyond_what_the_positions_carry_apart_from_the_lower_ones() {
        // Three distinct positions (repeated): a quadratic takes any values there, a cubic is
        // a combination of degrees 0–2 (its linear part a scale or squareness).
        assert_eq!(highest_order(&[0.0, 0.0, 100.0, 200.0, 200.0], false), 2);
        // Twelve angles over a turn carry harmonics 1–5 apart from each other and a constant.
        let angles: Vec<f64> = (0..12).map(|k| f64::from(k) * 30f64.to_radians()).collect();
        assert_eq!(highest_order(&angles, true), 5);
    }

    #[test]
    fn a_drift_acts_since_the_reference_pose_where_the_instrument_was_zeroed() {
        // Four readings in two setups, each zeroed at its start (t_ref 0 and 100 s): a drift
        // d(t) of the error acts as column·d(t) + reference·d(t_ref).
        let t = [0.0, 50.0, 100.0, 150.0];
        let column = DVec::from_vec(vec![1.0, 0.5, -0.3, 2.0]);
        let reference = Reference {
            column: DVec::from_vec(vec![-0.2, -0.2, 0.7, 0.7]),
            coordinate: vec![0.0; 4],
            time_s: vec![0.0, 0.0, 100.0, 100.0],
        };
        let constant = Term::single(
            "E",
            "an error",
            "",
            Family::Location,
            &column + &reference.column,
            Quantity::Length,
        );
        let drifts = drift_candidates(&constant, Some(&reference), &Settling::new(&t, 10.0));
        let obs = Observations {
            values: DVec::zeros(4),
            sigma: None,
            variables: Vec::new(),
            setup: vec![0, 0, 1, 1],
            setup_names: vec!["a".into(), "b".into()],
            channel: vec![0; 4],
            channel_names: vec!["d".into()],
            setup_kind: "setup".into(),
            quantity: Quantity::Length,
        };
        let expect = |d: &dyn Fn(f64) -> f64| -> Vec<f64> {
            (0..4)
                .map(|i| column[i] * d(t[i]) + reference.column[i] * d(reference.time_s[i]))
                .collect()
        };
        let linear = drifts[0].variants(&obs).remove(0);
        let tau = 80.0;
        let first_order = drifts[1].at(0, tau).expect("a time constant");
        for (term, d) in [
            (&linear, &(|t: f64| t) as &dyn Fn(f64) -> f64),
            (&first_order, &|t: f64| 1.0 - (-t / tau).exp()),
        ] {
            for (got, want) in term.columns.iter().zip(expect(d)) {
                approx::assert_abs_diff_eq!(*got, want, epsilon = 1e-12);
            }
        }
    }
}
