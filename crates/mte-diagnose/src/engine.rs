//! The diagnosis loop: fit the base model, test the residuals for structure, try every candidate
//! effect on data the fit did not see, name the cause, extend the model, repeat; then re-test
//! every cause in the complete model, and measure the gain of the whole search on data it did
//! not see.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};

use mte_linalg::progress::{NoProgress, Progress};
use mte_linalg::{DMat, DVec, stats};
use rayon::prelude::*;
use serde::Serialize;

use crate::candidate::{Candidate, Role, Score, Spread, SpreadVariants};
use crate::data::{Observations, VariableKind};
use crate::fit::{
    Directions, FoldBasis, Folds, Increment, Projector, SEPARABILITY_TOLERANCE, Solution,
    SpreadProducts, block_grams, design, fit_on_rows, max_abs, rms, separable_columns, solve,
    tr_mul, weighted_products, weighted_products_by_rows, whitened_r, whitening,
};
use crate::structure::{StructureTest, structure_tests};
use crate::term::{Estimate, Family, Interval, Quantity, Summary, Term};
use crate::{DiagnoseError, Result};

/// Settings of the diagnosis (builder).
#[derive(Debug, Clone)]
pub struct DiagnoseParams {
    /// Family-wise significance level of a discovery (Bonferroni over every candidate variant
    /// tried in a step), in (0, 0.5). Default 0.001.
    pub alpha: f64,
    /// Number of cross-validation folds inside the search. Default 5.
    pub folds: usize,
    /// Contiguous blocks per fold. Default 10.
    pub blocks_per_fold: usize,
    /// Smallest relative fall of the cross-validated RMS for an effect to be kept. Default 0.02.
    pub min_gain: f64,
    /// Most causes added beyond the ordinary errors the base model leaves out. Default 10. When
    /// the search would have gone on, the diagnosis says it is incomplete.
    pub max_effects: usize,
    /// Most ordinary errors (component, squareness and location errors, error motions of a
    /// rotary axis over a turn) added where the base model leaves them out; the search adds
    /// them before any drift or periodic error at a free period. Default 40. When the search
    /// would have gone on, the diagnosis says it is incomplete.
    pub max_ordinary: usize,
    /// Candidates examined by cross-validation in each step (the most significant ones).
    /// Default 8.
    pub shortlist: usize,
    /// Outer folds of the honest held-out figures: the whole search (choice of terms, periods,
    /// time constants) is repeated without each fold and predicts it. Default 5; 0 skips them.
    pub outer_folds: usize,
    /// Memory the candidates' designs may take, GB; a larger problem is refused before anything
    /// is allocated ([`DiagnoseError::TooLarge`]). Default 4.
    pub max_memory_gb: f64,
    /// Most observations the search for causes runs on. A longer record (a continuous log) is
    /// searched on every k-th observation in acquisition order; the completed base and the
    /// causes found are then fitted to all observations, and the sizes, uncertainties, structure
    /// tests and verdict come from all of them (the report says so). Default 10 000.
    pub search_rows: usize,
}

impl Default for DiagnoseParams {
    fn default() -> Self {
        DiagnoseParams {
            alpha: 1e-3,
            folds: 5,
            blocks_per_fold: 10,
            min_gain: 0.02,
            max_effects: 10,
            max_ordinary: 40,
            shortlist: 8,
            outer_folds: 5,
            max_memory_gb: 4.0,
            search_rows: 10_000,
        }
    }
}

/// σ0 up to which residuals count as consistent with a stated noise even when the χ² test,
/// with thousands of observations, rejects it: a stated standard uncertainty is rarely known
/// better than ±50 %.
pub const STATED_NOISE_TOLERANCE: f64 = 1.5;

/// How well one model explains the data.
#[derive(Debug, Clone, Serialize)]
pub struct FitQuality {
    /// RMS of the residuals of the fit to all data, mm.
    pub rms: f64,
    /// Largest absolute residual of the fit, mm.
    pub max_abs: f64,
    /// RMS of the cross-validated residuals of this model with its terms fixed, mm (for the
    /// base model an honest held-out figure; for the extended model not, since the terms were
    /// chosen on the same folds — see [`Diagnosis::held_out`]).
    pub cv_rms: f64,
    /// Largest absolute cross-validated residual, mm.
    pub cv_max_abs: f64,
    /// A-posteriori standard deviation of unit weight √(RSS_w / dof) (≈ 1 when the residuals
    /// match the stated noise; the residual RMS in mm when none is stated).
    pub sigma0: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// p-value of the χ² test of the residuals against the stated noise (`None` without one).
    pub chi2_p_value: Option<f64>,
}

/// The gain of the diagnosis on data it did not see: the observations are cut into
/// [`DiagnoseParams::outer_folds`] folds of contiguous blocks; for each, the base model is fitted
/// and the whole search run on the other folds, and both predict the fold.
#[derive(Debug, Clone, Serialize)]
pub struct HeldOut {
    /// Number of outer folds.
    pub folds: usize,
    /// RMS of the base model's held-out residuals, mm.
    pub base_rms: f64,
    /// Largest absolute held-out residual of the base model, mm.
    pub base_max_abs: f64,
    /// RMS of the diagnosed model's held-out residuals, mm.
    pub diagnosed_rms: f64,
    /// Largest absolute held-out residual of the diagnosed model, mm.
    pub diagnosed_max_abs: f64,
    /// The causes each fold's search named (a stable diagnosis names the same in every fold).
    pub per_fold: Vec<Vec<String>>,
}

/// An estimated model parameter.
#[derive(Debug, Clone, Serialize)]
pub struct ParameterEstimate {
    /// Term name.
    pub term: String,
    /// Its estimates.
    pub estimates: Vec<Estimate>,
}

/// A named cause found in the data.
#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    /// Short name (ISO 230-1 where there is one).
    pub name: String,
    /// What engineers call it.
    pub label: String,
    /// Physical meaning.
    pub meaning: String,
    /// Family of effect.
    pub family: Family,
    /// Estimated size with standard uncertainty, in the final model (the uncertainty includes
    /// that of the period or time constant, and is widened to the cluster-robust one over
    /// repeated poses where that is larger).
    pub estimates: Vec<Estimate>,
    /// The period or time constant with its standard uncertainty, where the effect has one.
    pub hyper_parameter: Option<Estimate>,
    /// Bonferroni-adjusted p-value when it was added.
    pub p_value: f64,
    /// Bonferroni-adjusted p-value of removing it from the complete model.
    pub p_value_final: f64,
    /// Cross-validated RMS inside the search before adding it, mm (a selection score: the
    /// terms were chosen on these folds).
    pub cv_rms_before: f64,
    /// Cross-validated RMS inside the search after adding it, mm.
    pub cv_rms_after: f64,
    /// Other candidates that explain the same residual equally well with this data.
    pub alternatives: Vec<String>,
    /// Other causes that explain the data nearly as well, in other ways: in its place in the
    /// complete model each leaves χ² higher (or lower) by less than what would exchange the two
    /// (6.63, χ² 99 % with one degree of freedom): the data hardly tell them apart.
    pub rivals: Vec<Rival>,
    /// The measurement that would tell it apart from the alternatives and rivals.
    pub separated_by: Option<String>,
    /// The covariate that exposes it.
    pub exposed_by: Option<String>,
    /// For a linear drift: where the first-order drift of the same parameter would settle (its
    /// time constant did not lower χ² by enough for the data to choose it).
    pub first_order: Option<FirstOrderFit>,
    /// Whether it is an ordinary error every machine has (a component, squareness or location
    /// error, an error motion of a rotary axis over a turn: [`crate::Shorthand::of_ordinary`]),
    /// which the search adds before any drift or periodic error at a free period where the
    /// base model leaves it out.
    pub ordinary: bool,
}

/// A cause that explains the data nearly as well as a finding, in another way ([`Finding::rivals`]).
#[derive(Debug, Clone, Serialize)]
pub struct Rival {
    /// Its name.
    pub name: String,
    /// What engineers call it.
    pub label: String,
    /// How much higher χ² is with it in the finding's place in the complete model, in units of
    /// the model's residual variance (negative: lower, by less than would exchange them).
    pub chi2_excess: f64,
}

/// Where a drift found linear would settle if it is a first-order one: the first-order drift of
/// the same parameter profiled over time constants from a thirtieth of the record, fitted
/// beside the rest of the final model. A drift that has not settled within the record fits as
/// well at every longer time constant, and then has no final value the data bound (an open end).
#[derive(Debug, Clone, Serialize)]
pub struct FirstOrderFit {
    /// The first-order drift's name.
    pub name: String,
    /// 95 % interval of its time constant, s.
    pub time_constant_s: Interval,
    /// 95 % interval of the value it settles to (its first coefficient), internal units.
    pub final_value: Interval,
    /// What kind of quantity the final value is.
    pub quantity: Quantity,
}

impl FirstOrderFit {
    /// The sentence the report's notes give it, for the linear drift `linear`.
    pub fn note(&self, linear: &str) -> String {
        let stem = linear.strip_suffix(" drift").unwrap_or(linear);
        format!(
            "{linear}: a first-order drift of {stem} fits these data as well (95 %: time constant {}, final value {}){}",
            self.time_constant_s.describe(Quantity::Duration),
            self.final_value.describe(self.quantity),
            if self.final_value.lower.is_none() || self.final_value.upper.is_none() {
                "; the drift has not settled within the record, and where it ends the data do not say"
            } else {
                ""
            }
        )
    }
}

/// A reading the final model misses by far more than the rest: its residual, in units of the
/// residuals' robust scatter, is beyond what the largest of as many normal residuals reaches at
/// the discovery level. An isolated one points to a fault of the measurement (a beam break, a
/// lost lock, a sensor glitch), several at one pose or time to an effect the model lacks.
#[derive(Debug, Clone, Serialize)]
pub struct Outlier {
    /// Row of the observation.
    pub observation: usize,
    /// Its set-up (run, station, ball position).
    pub setup: String,
    /// Its channel.
    pub channel: String,
    /// Where it was taken: each variable's name and value (mm, rad, s or ±1).
    pub at: Vec<(String, f64)>,
    /// The same as engineers read it (`X = 53.100 mm, t = 708 s, direction +`).
    pub place: String,
    /// The final model's residual, in the observations' unit.
    pub residual: f64,
    /// The residual as engineers read it (µm, µrad).
    pub text: String,
    /// The residual over the robust scatter of the residuals (studentized).
    pub z: f64,
}

/// A candidate (or base parameter) the data cannot separate from the model.
#[derive(Debug, Clone, Serialize)]
pub struct NotSeparable {
    /// Candidate or parameter name.
    pub name: String,
    /// What engineers call it.
    pub label: String,
    /// The model terms it is (nearly) a combination of.
    pub confounded_with: Vec<String>,
    /// The measurement that would separate it.
    pub separated_by: Option<String>,
    /// Found by the search, but separable only through the orders the base stops at: the
    /// combination above is with the next order of every base error in the model.
    pub rests_on_orders: bool,
}

/// The smallest size at which a library cause the search did not find would have been found:
/// what these data could show, not an estimate of the cause. The size is the one the search's
/// own tests (the Bonferroni-adjusted F test at `alpha` and the held-out gain of `min_gain`)
/// accept with probability [`DETECTION_POWER`], given how much of the cause's effect the
/// complete model leaves visible and the residual scatter of that model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DetectionLimit {
    /// Candidate name.
    pub name: String,
    /// What engineers call it.
    pub label: String,
    /// Unit of the size.
    pub quantity: Quantity,
    /// How the size is read: the coefficient, or the amplitude of a sine and cosine pair.
    pub summary: Summary,
    /// Unit of the variants' period or time constant, where the cause has one.
    pub at_quantity: Option<Quantity>,
    /// The limit at each variant the search tested (each period or time constant on its grid;
    /// one for a cause without), in the order of the grid. At least one is separable.
    pub variants: Vec<VariantLimit>,
    /// The model terms that the variants not separable are combinations of (what holds the
    /// cause there), largest first.
    pub held_by: Vec<String>,
}

/// The detection limit of one variant of a cause.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VariantLimit {
    /// The variant's period (mm, or rad along a rotary axis) or time constant (s).
    pub at: Option<f64>,
    /// The size found with probability [`DETECTION_POWER`] (internal units: mm, rad, …);
    /// `None` where the data cannot separate the variant from the model.
    pub size: Option<f64>,
}

impl DetectionLimit {
    /// The separable variants, with their limits.
    fn separable(&self) -> impl Iterator<Item = (Option<f64>, f64)> + '_ {
        self.variants.iter().filter_map(|v| Some((v.at, v.size?)))
    }

    /// The separable variant these data are most sensitive to: its period or time constant
    /// and limit.
    pub fn smallest(&self) -> Option<(Option<f64>, f64)> {
        self.separable().min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// The separable variant these data are least sensitive to.
    pub fn largest(&self) -> Option<(Option<f64>, f64)> {
        self.separable().max_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// The limit at the variant whose period or time constant is nearest `at` (relatively; for
    /// a cause without one, its only variant); `None` if that variant is not separable.
    pub fn near(&self, at: f64) -> Option<f64> {
        self.variants
            .iter()
            .min_by(|a, b| {
                let d = |v: &VariantLimit| v.at.map_or(0.0, |h| (h / at).ln().abs());
                d(a).total_cmp(&d(b))
            })
            .and_then(|v| v.size)
    }
}

/// Probability with which a cause at its [`DetectionLimit`] is found.
pub const DETECTION_POWER: f64 = 0.8;

/// Variants not separable whose make-up [`DetectionLimit::held_by`] reads, at most.
const HELD_BY_SAMPLES: usize = 4;

/// The periods along one axis that the sampling let the diagnosis look for (the periodic
/// candidates and the structure tests scan the same range).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodicReach {
    /// The axis.
    pub variable: String,
    /// Whether it is a rotary axis (periods in rad, harmonics of a turn).
    pub rotary: bool,
    /// Distinct positions in the data.
    pub positions: usize,
    /// Shortest and longest period looked for (mm, or rad); `None`: none could be.
    pub periods: Option<(f64, f64)>,
    /// When the positions repeat on a regular step, that step (mm or rad): a shorter period
    /// cannot be told from a longer alias, which is what set the shortest period looked for.
    pub alias_step: Option<f64>,
}

impl PeriodicReach {
    /// Whether the sampling, not the library's range, limits the search: too few positions, or
    /// a regular step that hides the shorter periods.
    pub fn limited_by_sampling(&self) -> bool {
        self.periods.is_none() || self.alias_step.is_some()
    }

    /// Whether a periodic error of period `p` (mm or rad) lies inside the range looked for.
    pub fn covers(&self, p: f64) -> bool {
        self.periods.is_some_and(|(lo, hi)| (lo..=hi).contains(&p))
    }

    /// The sentence a report gives when the sampling limits the search.
    fn note(&self) -> Option<String> {
        let v = &self.variable;
        // (The alias step comes from a frequency scan: good to a few per cent.)
        let step = |a: f64| {
            if self.rotary {
                format!("about {:.0}°", a.to_degrees())
            } else {
                format!("about {a:.0} mm")
            }
        };
        match (self.periods, self.alias_step) {
            (None, _) if self.positions < crate::basis::LEAST_POSITIONS => Some(format!(
                "{v} takes only {} distinct positions: periodic errors along {v} (a ball-screw pitch, an encoder or gear error) could not be looked for, at least {} are needed; the base's polynomial carries what such an error does at these positions{}",
                self.positions,
                crate::basis::LEAST_POSITIONS,
                if self.rotary {
                    String::new()
                } else {
                    format!(
                        ". A squareness or scale along {v} is that of the least-squares line through these positions (ISO 230-1's reference line over them): over the whole travel it differs by what the errors do between them, which these data cannot show"
                    )
                }
            )),
            (None, Some(a)) => Some(format!(
                "the {v} positions repeat on a step of {}, too coarse for any period shorter than half the travel: periodic errors along {v} (a ball-screw pitch, an encoder or gear error) alias to smooth ones and could not be looked for; irregular steps, as ISO 230-2 prescribes, or more positions would show them",
                step(a)
            )),
            (None, None) => Some(format!(
                "{v}'s travel is too short for two periods of any period its sampling resolves: periodic errors along {v} could not be looked for"
            )),
            (Some((lo, _)), Some(a)) if self.rotary => Some(format!(
                "the {v} positions repeat on a step of {}: harmonics of a turn above the {} ({:.1}°) alias to lower ones and could not be looked for (worm-gear tooth errors among them); more, irregularly spaced angles would show them",
                step(a),
                ordinal((std::f64::consts::TAU / lo).round() as usize),
                lo.to_degrees()
            )),
            (Some((lo, _)), Some(a)) => Some(format!(
                "the {v} positions repeat on a step of {}: periodic errors along {v} shorter than {lo:.1} mm alias to longer ones and could not be looked for (a ball-screw pitch among them); irregular steps, as ISO 230-2 prescribes, or more positions would show them",
                step(a)
            )),
            (Some(_), None) => None,
        }
    }
}

fn ordinal(k: usize) -> String {
    let suffix = match (k % 10, k % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{k}{suffix}")
}

/// A scored candidate of one step.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateScore {
    /// Name.
    pub name: String,
    /// Bonferroni-adjusted p-value of its F test.
    pub p_value: f64,
    /// Share of the current residual it explains.
    pub share_of_residual: f64,
    /// Cross-validated RMS with it added, mm (for the shortlisted significant ones).
    pub cv_rms: Option<f64>,
    /// For a harmonic of a turn of a rotary axis, the harmonic (cycles per turn): a rotary
    /// axis' error motion is scored at its best ordinary harmonic and at its best of all.
    pub per_turn: Option<usize>,
}

/// A cause the search had chosen, replaced once the model was complete by one that, with the
/// other causes fitted, explains the data better, or by a simpler one the data do not tell from
/// it ([`Diagnosis::exchanged`]).
#[derive(Debug, Clone, Serialize)]
pub struct Exchange {
    /// The cause chosen when it entered.
    pub replaced: String,
    /// The cause that took its place.
    pub by: String,
    /// How much lower the complete model's χ² is with the replacement (in units of the model's
    /// residual variance); negative for a simpler cause, whose χ² is higher by less than the
    /// exchange threshold.
    pub chi2_drop: f64,
}

/// Terms of the final model whose estimates these data determine only together
/// ([`Diagnosis::determined_together`]): each is linked to another of the group by estimates
/// correlated beyond [`TOGETHER_CORRELATION`] in magnitude. What the data measure is a
/// combination of them; the sizes of each are one split of it among many that fit nearly as
/// well. (Terms the data cannot separate at all are left out of the fit and listed in
/// [`Diagnosis::base_not_separable`] or [`Diagnosis::not_separable`].)
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeterminedTogether {
    /// The terms (base parameters, completions, causes), in the model's order.
    pub terms: Vec<String>,
    /// The largest |correlation| between estimates of two of them.
    pub largest_correlation: f64,
}

/// The |correlation| of two estimates beyond which they are reported as determined only
/// together: the variance of each is then more than 50 times what it would be were the other
/// known.
pub const TOGETHER_CORRELATION: f64 = 0.99;

/// The groups of `terms` (in the order of `cov`'s rows, which may go on with rows of nonlinear
/// parameters) whose estimates are linked by correlations beyond [`TOGETHER_CORRELATION`]
/// ([`DeterminedTogether`]), largest group first.
fn determined_together(terms: &[Term], cov: &DMat) -> Vec<DeterminedTogether> {
    let term_of: Vec<usize> = terms
        .iter()
        .enumerate()
        .flat_map(|(k, t)| std::iter::repeat_n(k, t.width()))
        .collect();
    let p = term_of.len().min(cov.nrows());
    // Union–find over terms.
    let mut parent: Vec<usize> = (0..terms.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    let mut links: Vec<(usize, usize, f64)> = Vec::new();
    for i in 0..p {
        for j in i + 1..p {
            let (a, b) = (term_of[i], term_of[j]);
            let scale = (cov[(i, i)] * cov[(j, j)]).sqrt();
            if a == b || scale.is_nan() || scale <= 0.0 {
                continue;
            }
            let r = (cov[(i, j)] / scale).abs();
            if r >= TOGETHER_CORRELATION {
                links.push((a, b, r));
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let mut groups: Vec<DeterminedTogether> = Vec::new();
    let mut group_of: HashMap<usize, usize> = HashMap::new();
    for (k, term) in terms.iter().enumerate() {
        // (A term is in a group exactly when a link names it.)
        if !links.iter().any(|l| l.0 == k || l.1 == k) {
            continue;
        }
        let r = root(&mut parent, k);
        let g = *group_of.entry(r).or_insert_with(|| {
            groups.push(DeterminedTogether {
                terms: Vec::new(),
                largest_correlation: 0.0,
            });
            groups.len() - 1
        });
        groups[g].terms.push(term.name.clone());
    }
    for (a, _, r) in links {
        let g = group_of[&root(&mut parent, a)];
        groups[g].largest_correlation = groups[g].largest_correlation.max(r);
    }
    groups.sort_by_key(|g| std::cmp::Reverse(g.terms.len()));
    groups
}

/// A cause the search added and the complete model let go again ([`Diagnosis::pruned`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pruned {
    /// The cause (`EBY poly2`).
    pub name: String,
    /// Why it left.
    pub reason: PruneReason,
}

/// Why a cause the search added left the model ([`Pruned`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum PruneReason {
    /// Re-tested in the search's complete model, it failed its removal F test (`p_value`,
    /// Bonferroni-adjusted as at entry, not below the level) or lowered the cross-validated RMS
    /// by too little (`held_out_ratio`: the RMS without it ÷ with it).
    NotEarned {
        /// Adjusted p-value of its removal.
        p_value: f64,
        /// Cross-validated RMS without it ÷ with it.
        held_out_ratio: f64,
    },
    /// The search's reduction: the other causes, exchanged, say as well what it said.
    Redundant,
    /// In the final model, fitted to all observations, the base and the other causes hold it.
    HeldByModel,
    /// In the final model, the next orders of the base's errors would hold it or leave its size
    /// undetermined (also listed in [`Diagnosis::not_separable`]).
    RestsOnOrders,
    /// In the final model, every estimate of it lies within 2 u of zero once the uncertainty of
    /// its period or time constant is counted.
    Undetermined,
    /// In the final model, its removal F test (Bonferroni-adjusted `p_value`) is not below the
    /// level, after another cause had left.
    NotSignificant {
        /// Adjusted p-value of its removal in the final model.
        p_value: f64,
    },
    /// It builds on the cause named (a drift or harmonic of a term), which left.
    BuildsOn(String),
}

impl PruneReason {
    /// The reason in words, for the report.
    pub fn text(&self) -> String {
        match self {
            PruneReason::NotEarned {
                p_value,
                held_out_ratio,
            } => format!(
                "not earned in the complete model: {}, held-out RMS ×{held_out_ratio:.3} without it",
                crate::report::p_text(*p_value)
            ),
            PruneReason::Redundant => "the other causes say as well what it said".into(),
            PruneReason::HeldByModel => "the base and the other causes hold it".into(),
            PruneReason::RestsOnOrders => {
                "rests on the base's orders (listed as not separable)".into()
            }
            PruneReason::Undetermined => {
                "its size is undetermined once its period or time constant is counted".into()
            }
            PruneReason::NotSignificant { p_value } => format!(
                "no longer significant in the final model, {}",
                crate::report::p_text(*p_value)
            ),
            PruneReason::BuildsOn(cause) => format!("builds on {cause}, which left"),
        }
    }
}

/// A periodic error at a free period along a linear axis that the search passed over: it fitted
/// the residuals and lowered their held-out RMS, but did not predict the readings at positions
/// of its axis it was not fitted to ([`Diagnosis::passed_over`]).
#[derive(Debug, Clone, Serialize)]
pub struct PassedOver {
    /// The cause (`EYY periodic`).
    pub name: String,
    /// The axis whose positions were held out.
    pub axis: String,
    /// The residuals' RMS at held-out positions with its prediction (its period chosen on the
    /// other positions' residuals) taken off, as a fraction of theirs.
    pub ratio: f64,
}

/// One step of the search.
#[derive(Debug, Clone, Serialize)]
pub struct Step {
    /// Candidates ranked, best first (the shortlist).
    pub ranking: Vec<CandidateScore>,
    /// What was added, if anything.
    pub added: Option<String>,
    /// Number of candidate variants tested (the Bonferroni factor).
    pub variants_tested: usize,
}

/// The evidence of one finding (or of unexplained structure) for a plot: the residuals of the
/// final model without the finding against the covariate that exposes it, and the finding's
/// fitted effect. At most 20 000 points: a longer record is shown by every k-th observation.
#[derive(Debug, Clone, Serialize)]
pub struct ResidualSeries {
    /// Covariate name.
    pub variable: String,
    /// The finding shown, `None` for unexplained structure.
    pub finding: Option<String>,
    /// Covariate values (mm, rad, s or ±1).
    pub x: Vec<f64>,
    /// Channel of each point.
    pub channel: Vec<usize>,
    /// Residuals of the final model with this finding left out, mm.
    pub residual: Vec<f64>,
    /// The finding's fitted effect at each observation, mm; for unexplained structure, the
    /// dependence its structure test found, fitted to the final residuals.
    pub effect: Vec<f64>,
    /// For unexplained structure, the structure test shown (`periodic`, `Y error changing with
    /// X and Y jointly` …).
    pub structure: Option<String>,
}

/// Findings that together describe one effect of a form no single candidate has: the harmonics
/// of a periodic error that is not a sine, or a linear and a first-order drift of one parameter.
#[derive(Debug, Clone, Serialize)]
pub struct Compound {
    /// The sentence the report prints.
    pub note: String,
    /// The findings, by name.
    pub findings: Vec<String>,
    /// Their size together, where one is defined: a drift's change over the measured time.
    pub estimate: Option<Estimate>,
}

/// The verdict of a diagnosis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[non_exhaustive]
pub enum Verdict {
    /// Nothing found and the base model's residuals are consistent with the noise.
    NoDiscrepancy,
    /// Causes found, and the extended model's residuals are consistent with the noise.
    Explained,
    /// Structure remains that no candidate explains (with or without findings): see
    /// [`Diagnosis::remaining_structure`].
    Unexplained,
}

/// Everything the diagnosis found; serialises to the JSON report.
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosis {
    /// Number of scalar observations.
    pub observations: usize,
    /// Channel names.
    pub channels: Vec<String>,
    /// Setup names.
    pub setups: Vec<String>,
    /// What a setup is.
    pub setup_kind: String,
    /// What the observations are (lengths in mm or angles in rad): the unit of every RMS,
    /// maximum and noise figure below.
    pub quantity: Quantity,
    /// Stated noise (RMS of σ), mm (or rad), if any.
    pub stated_noise: Option<f64>,
    /// The verdict.
    pub verdict: Verdict,
    /// Why the search is incomplete, when a limit (not its own criterion) stopped it.
    pub incomplete: Option<String>,
    /// What these data cannot test (e.g. no pose measured twice: no time effects).
    pub notes: Vec<String>,
    /// The periods along each axis that the sampling let the search and the structure tests
    /// look for ([`Diagnosis::notes`] states where the sampling limits them).
    pub periodic_reach: Vec<PeriodicReach>,
    /// Base model parameters as fitted.
    pub base_parameters: Vec<ParameterEstimate>,
    /// Higher orders of the base's component errors that the data asked for (e.g. `EXX P5`),
    /// added to the base before the search for causes, or during it once a cause that hid
    /// them was in.
    pub base_completed: Vec<String>,
    /// Parameters of the stated base model that these data cannot separate from the rest of it
    /// (left out of the fit; their effect is carried by the ones they are confounded with).
    pub base_not_separable: Vec<NotSeparable>,
    /// Base model quality.
    pub base: FitQuality,
    /// Residual RMS of the base model per setup, mm.
    pub base_rms_per_setup: Vec<f64>,
    /// Residual RMS of the base model per channel, mm.
    pub base_rms_per_channel: Vec<f64>,
    /// Structure tests of the base residuals.
    pub structure: Vec<StructureTest>,
    /// The search, step by step.
    pub steps: Vec<Step>,
    /// The named causes, in the order found.
    pub findings: Vec<Finding>,
    /// Findings that together describe one effect of a form no candidate has (also in
    /// [`Diagnosis::notes`]): the cause is named, its shape is not one of the library's.
    pub compound: Vec<Compound>,
    /// Causes the search chose and replaced in the complete model by a rival that explains the
    /// data better with the others fitted.
    pub exchanged: Vec<Exchange>,
    /// Causes added by the search and removed again when re-tested in the complete model, with
    /// why.
    pub pruned: Vec<Pruned>,
    /// Periodic errors at a free period that fitted the residuals but did not predict the
    /// readings between the positions they were fitted to: not named.
    pub passed_over: Vec<PassedOver>,
    /// Candidates the data cannot separate from the model.
    pub not_separable: Vec<NotSeparable>,
    /// Groups of the final model's terms whose estimates the data determine only together
    /// (correlated beyond [`TOGETHER_CORRELATION`]): the sizes are one split of a combination.
    pub determined_together: Vec<DeterminedTogether>,
    /// For each library cause not found (and separable): the size from which these data would
    /// have shown it. Empty when the search stopped at a limit.
    pub detection_limits: Vec<DetectionLimit>,
    /// Extended model quality.
    pub extended: FitQuality,
    /// All parameters of the extended model.
    pub extended_parameters: Vec<ParameterEstimate>,
    /// Significant structure tests of the extended model's residuals: what nothing in the
    /// library explains.
    pub remaining_structure: Vec<StructureTest>,
    /// Readings the final model misses by far more than the rest, largest first.
    pub outliers: Vec<Outlier>,
    /// σ0 of the final model fitted without the outliers, and its χ² p-value when the noise is
    /// stated (`None` without outliers).
    pub without_outliers: Option<(f64, Option<f64>)>,
    /// Gain on data the search did not see (`None` when outer folds are off).
    pub held_out: Option<HeldOut>,
    /// Evidence for plots: one series per finding, or per unexplained structure.
    pub residual_series: Vec<ResidualSeries>,
    /// Significance level used.
    pub alpha: f64,
    /// Smallest relative fall of the held-out RMS a cause had to show ([`DiagnoseParams::min_gain`]).
    pub min_gain: f64,
    /// The base model in the user's terms (set by [`crate::Prepared::diagnose`]; `None` from
    /// [`diagnose`] on terms alone).
    pub base_model: Option<crate::model::BaseModelUsed>,
}

impl Diagnosis {
    /// `true` when nothing was found and the base model explains the data to the noise.
    pub fn no_discrepancy(&self) -> bool {
        self.verdict == Verdict::NoDiscrepancy
    }

    /// The finding called `name`.
    pub fn finding(&self, name: &str) -> Option<&Finding> {
        self.findings.iter().find(|f| f.name == name)
    }
}

/// Runs the diagnosis.
///
/// # Errors
/// [`DiagnoseError::InvalidData`] for bad observations or settings;
/// [`DiagnoseError::TooFewObservations`] when there are not enough observations for the base
/// model and cross-validation. Base parameters the data cannot separate are not an error: they
/// are left out and listed in [`Diagnosis::base_not_separable`].
pub fn diagnose(
    obs: &Observations,
    base: Vec<Term>,
    candidates: &[Box<dyn Candidate>],
    params: &DiagnoseParams,
) -> Result<Diagnosis> {
    diagnose_with_progress(obs, base, candidates, params, &NoProgress)
}

/// The work units [`diagnose_with_progress`] reports with `params`: the preparation (the base's
/// fit and every candidate's products), the search on all data, each outer fold's search, and
/// the final model with its tests and intervals.
pub fn progress_units(params: &DiagnoseParams) -> u64 {
    let outer = if runs_outer_folds(params) {
        params.outer_folds
    } else {
        0
    };
    3 + outer as u64
}

/// Whether the honest held-out figures' outer folds run (`outer_folds` 0 turns them off).
fn runs_outer_folds(params: &DiagnoseParams) -> bool {
    params.outer_folds >= 2
}

/// [`diagnose`], reporting to `progress` each of its [`progress_units`] as it finishes (the
/// search on all data and the outer folds' run at once: their units come as each ends).
///
/// # Errors
/// As [`diagnose`].
pub fn diagnose_with_progress(
    obs: &Observations,
    base: Vec<Term>,
    candidates: &[Box<dyn Candidate>],
    params: &DiagnoseParams,
    progress: &dyn Progress,
) -> Result<Diagnosis> {
    obs.validate()?;
    check_params(params)?;
    let n = obs.len();
    let w = whitening(obs);
    // A long record is searched on an evenly thinned copy; what it finds is fitted to all.
    let thinned =
        (n > params.search_rows).then(|| thin_rows(&obs.acquisition_order(), params.search_rows));
    let base_width: usize = base.iter().map(Term::width).sum();
    let n_search = thinned.as_ref().map_or(n, Vec::len);
    // Every variant's design is kept for the search: refuse before allocating what the machine
    // cannot hold (the base as given: its separable part is no wider).
    let columns: usize = candidates.iter().map(|c| c.columns(obs)).sum();
    let needed_gb = ((n_search * columns) as f64 + (n * 4 * base_width) as f64) * 8.0 / 1e9;
    if needed_gb > params.max_memory_gb {
        return Err(DiagnoseError::TooLarge {
            observations: n,
            columns,
            needed_gb,
            limit_gb: params.max_memory_gb,
        });
    }
    let thin = thinned.as_ref().map(|rows| {
        (
            obs.select(rows),
            candidates
                .iter()
                .map(|c| c.on_rows(obs, rows))
                .collect::<Vec<_>>(),
        )
    });
    let (obs_s, candidates_s) = match &thin {
        Some((o, c)) => (o, &c[..]),
        None => (obs, candidates),
    };
    // The base's fit on all observations is the search's start unless the record is thinned.
    // The candidates' variants do not depend on the base: built meanwhile.
    let ((base, left_out, full_fit), built) = rayon::join(
        || separable_base(base, &obs.values, &w, thinned.is_none()),
        || Pool::variants_of(obs_s, candidates_s),
    );
    let base_width: usize = base.iter().map(Term::width).sum();
    let needed = base_width + 2 * params.folds.max(params.outer_folds) + 2;
    if n < needed {
        return Err(DiagnoseError::TooFewObservations {
            observations: n,
            needed,
        });
    }
    let base_thinned = thinned
        .as_ref()
        .map(|rows| base.iter().map(|t| t.select_rows(rows)).collect::<Vec<_>>());
    let base_s = base_thinned.as_deref().unwrap_or(&base);
    let w_s = whitening(obs_s);
    let x_base = design(&base_s.iter().collect::<Vec<_>>(), n_search);
    // The base's fit on the searched observations: the full search's start, and the outer
    // folds' after downdating their held-out rows.
    let base_fit = match full_fit.filter(|_| thinned.is_none()) {
        Some(fit) => fit,
        None => Projector::fit(&x_base, &obs_s.values, &w_s),
    };
    // The outer folds of the honest held-out figures ([`Searcher::held_out`]).
    let outer = runs_outer_folds(params).then(|| {
        Folds::blocked(
            obs_s,
            &vec![true; n_search],
            params.outer_folds,
            params.blocks_per_fold,
        )
    });
    let pool = Pool::new(
        obs_s,
        built,
        base_s,
        x_base,
        &w_s,
        outer.as_ref().map_or(&[][..], |o| &o.test[..]),
    );
    let searcher = Searcher {
        obs: obs_s,
        base: base_s,
        pool: &pool,
        candidates: candidates_s,
        params,
    };
    let folds_s = Folds::blocked(
        obs_s,
        &vec![true; n_search],
        params.folds,
        params.blocks_per_fold,
    );
    progress.inc(1);
    // The search on all data and the outer folds' searches are independent: run them together.
    // The conclusions from the search on all data (the final fits, tests and report) need not
    // wait for the outer folds either.
    let (concluded, held_out) = rayon::join(
        || {
            let (search, _) = searcher.search(&w_s, &folds_s, None, base_fit.clone());
            progress.inc(1);
            let concluded = conclude(
                obs,
                &base,
                left_out.not_separable,
                &left_out.terms,
                candidates,
                params,
                &w,
                thinned.as_deref(),
                search,
            );
            progress.inc(1);
            concluded
        },
        || {
            outer
                .as_ref()
                .map(|outer| searcher.held_out(&w_s, &base_fit, outer, progress))
        },
    );
    let mut diagnosis = concluded?;
    diagnosis.held_out = held_out;
    Ok(diagnosis)
}

/// The diagnosis from the search on all data: the completed base and the causes found fitted
/// to all observations (a long record is searched on the thinned rows `thinned`), pruned of
/// causes the final fit does not determine, with their sizes, uncertainties, structure tests,
/// notes and verdict. The held-out figures are the outer folds' ([`Searcher::held_out`]).
#[allow(clippy::too_many_arguments)]
fn conclude(
    obs: &Observations,
    base: &[Term],
    base_not_separable: Vec<NotSeparable>,
    left_out: &[Term],
    candidates: &[Box<dyn Candidate>],
    params: &DiagnoseParams,
    w: &DVec,
    thinned: Option<&[usize]>,
    mut search: SearchResult,
) -> Result<Diagnosis> {
    let n = obs.len();
    if thinned.is_some() {
        // The terms found, on all observations (the thinned candidates are the full ones'
        // restrictions, in the same order).
        search.completed = search
            .completed
            .iter()
            .filter_map(|t| full_completion(candidates, obs, &t.name))
            .collect();
        for c in &mut search.chosen {
            c.term = full_variant(candidates[c.candidate].as_ref(), obs, c);
        }
    }
    // The structure probes, on all observations.
    let probes: Vec<Term> = candidates
        .iter()
        .filter(|c| c.role() == Role::Probe)
        .flat_map(|c| c.variants(obs))
        .collect();
    let everything = vec![true; n];
    let folds = Folds::blocked(obs, &everything, params.folds, params.blocks_per_fold);
    let no_pool = Pool::default();
    let searcher = Searcher {
        obs,
        base,
        pool: &no_pool,
        candidates,
        params,
    };

    // The base as completed by the search's data.
    let base_completed: Vec<String> = search.completed.iter().map(|t| t.name.clone()).collect();
    let base: Vec<Term> = base.iter().chain(&search.completed).cloned().collect();
    let searcher = Searcher {
        base: &base,
        ..searcher
    };
    let x0 = design(&base.iter().collect::<Vec<_>>(), n);
    let base_fit = Projector::fit(&x0, &obs.values, w);
    let base_sol = base_fit
        .solution(&x0, &obs.values)
        .unwrap_or_else(|| solve(&x0, &obs.values, w));
    let base_cv = base_fit
        .fold_fits(&folds, &x0, &obs.values, None)
        .residuals();
    let base_quality = quality(obs, &base_sol, &base_cv);
    let base_parameters = parameters(
        &base,
        &base_sol.coef,
        &covariance(obs, &base_sol.cofactor, base_quality.sigma0),
    );
    let structure = structure_tests(
        obs,
        &base_fit,
        &x0,
        &base_sol.residuals,
        w,
        base_sol.rss_w,
        base_sol.dof(),
        thinned,
        &probes,
    );

    // The final model. A cause whose size the data do not determine once the uncertainty of its
    // period or time constant is counted (every estimate within 2 u of zero) is not earned: it
    // leaves, the least determined first. What builds on it and was earned beside it stays, to
    // be judged by its own size: a scale that is zero while the machine is cold and drifts as
    // it warms is the drift alone. (A cause the model or the base's orders hold leaves with what
    // builds on it.)
    let mut chosen = search.chosen;
    if thinned.is_some() {
        // Periods and time constants found on the thinned copy, refined on all observations.
        gauss_newton_hyper(&searcher, &mut chosen, w);
    }
    let mut pruned = search.pruned;
    // The next order of every base error, its design and the base's fit with it, for the
    // uncertainty of the base's orders (only once there is a cause to widen).
    let with_next = std::cell::OnceCell::new();
    let with_next = || {
        with_next.get_or_init(|| {
            let terms = next_orders(candidates, obs, &base);
            let x = design(&terms.iter().collect::<Vec<_>>(), n);
            let fit = base_fit.extended(&x);
            (terms, x, fit)
        })
    };
    let mut not_separable = search.not_separable;
    let mut rests_on_orders: Vec<String> = Vec::new();
    let mut exchanged = search.exchanged;
    let span = record_span(obs);
    let (terms, x, sol, fit, extended, cov, hyper_rows, extended_parameters, finals) = loop {
        if let Some(span) = span {
            exchanged.extend(drift_courses(&searcher, &mut chosen, &base_fit, span));
        }
        let terms: Vec<Term> = searcher.with(&chosen, None).into_iter().cloned().collect();
        let (x, fit) = searcher.fit_of(&base_fit, &terms.iter().collect::<Vec<_>>());
        let sol = fit
            .solution(&x, &obs.values)
            .unwrap_or_else(|| solve(&x, &obs.values, w));
        let cv = fit.fold_fits(&folds, &x, &obs.values, None).residuals();
        let extended = quality(obs, &sol, &cv);
        let scale = covariance_scale(obs, extended.sigma0);
        let (mut cov, hyper_rows) =
            covariance_with_hyper(&searcher, &chosen, &terms, &x, &sol, w, scale);
        // The uncertainty of the base's orders: each cause's cofactor widened by what the next
        // order of every base error would add.
        let plain = cov.clone();
        let causes = &terms[base.len()..];
        let mut held = vec![None; causes.len()];
        let mut at = x0.ncols();
        let widening = if causes.is_empty() {
            Vec::new()
        } else {
            order_widening(
                &base_fit,
                &with_next().2,
                &causes.iter().collect::<Vec<_>>(),
            )
        };
        for (k, widening) in widening.into_iter().enumerate() {
            let width = causes[k].width();
            match widening {
                Ok((narrow, wide)) => {
                    let mut block = cov.view_mut((at, at), (width, width));
                    block += (wide - narrow) * scale;
                }
                Err(h) => held[k] = Some(h),
            }
            at += width;
        }
        let extended_parameters = parameters(&terms, &sol.coef, &cov);
        // How well the data determine a cause's size: its largest |estimate| ÷ u; for a drift
        // also its change over the measured time, which the data determine far better than a
        // first-order drift's final value beyond them (a slow drift strongly in the data can
        // have a final value within 2 u of zero).
        let offsets = column_offsets(x0.ncols(), causes);
        let z = |p: &[ParameterEstimate], cov: &DMat, k: usize| {
            let own = largest_z(&p[base.len() + k].estimates, causes[k].width());
            let changes: Vec<Estimate> = match causes[k].family {
                Family::Drift { .. } => crate::candidate::drifted_parameters(&causes[k])
                    .into_iter()
                    .filter_map(|stem| {
                        drift_change(
                            obs,
                            &chosen,
                            &[k],
                            stem,
                            &offsets,
                            &sol.coef,
                            cov,
                            &hyper_rows,
                        )
                    })
                    .collect(),
                _ => Vec::new(),
            };
            own.max(largest_z(&changes, changes.len()))
        };
        // Every cause passes the search's removal test (its F test) in the final model too.
        // Where a cause left above, the residual scatter grows, and one that passed narrowly in
        // the search can fail now (a pitch of X at p = 1.5e-6 in the search, 0.065 once a roll
        // of Y the base and the other causes hold had left): it leaves as pruned, with what
        // builds on it.
        // (The removal tests only once no cause leaves by the rules above.)
        let (k, held, insignificant) = match leaving(&held, |k| z(&extended_parameters, &cov, k)) {
            Some((k, held)) => (k, held, None),
            None => {
                let finals = searcher.removal_p_values(&chosen, &base_fit, &fit);
                let Some(k) = least_significant(&finals, params.alpha) else {
                    break (
                        terms,
                        x,
                        sol,
                        fit,
                        extended,
                        cov,
                        hyper_rows,
                        extended_parameters,
                        finals,
                    );
                };
                (k, None, Some(finals[k]))
            }
        };
        // A cause the base's next orders would hold, or whose size they leave undetermined,
        // rests on the base's orders alone: the report lists it as not separable from them.
        // (One the base and the other causes hold without those orders — two components of a
        // periodic error drawn to one period — leaves as pruned.)
        let on_orders = insignificant.is_none()
            && match held {
                Some(held) => held == Held::ByOrders,
                None => z(&parameters(&terms, &sol.coef, &plain), &plain, k) >= 2.0,
            };
        if on_orders {
            let others: Vec<&Term> = causes
                .iter()
                .enumerate()
                .filter_map(|(j, t)| (j != k).then_some(t))
                .collect();
            let x_others = design(&others, n);
            let (next, x_next, base_and_next) = with_next();
            let model: Vec<Term> = base
                .iter()
                .chain(next)
                .chain(others.iter().copied())
                .cloned()
                .collect();
            let t = &causes[k];
            not_separable.push(NotSeparable {
                name: t.name.clone(),
                label: t.label.clone(),
                confounded_with: confounded_with(
                    &t.columns.columns(0, 1).into_owned(),
                    &model,
                    &hcat(&hcat(&x0, x_next), &x_others),
                    &base_and_next.extended(&x_others),
                )
                .pop()
                .unwrap_or_default(),
                separated_by: t.separated_by.clone(),
                rests_on_orders: true,
            });
            rests_on_orders.push(causes[k].name.clone());
        }
        let reason = match (insignificant, held) {
            (Some(p_value), _) => PruneReason::NotSignificant { p_value },
            _ if on_orders => PruneReason::RestsOnOrders,
            (None, Some(_)) => PruneReason::HeldByModel,
            (None, None) => PruneReason::Undetermined,
        };
        let dependents = held.is_some() || insignificant.is_some();
        pruned.extend(pruned_for(
            searcher.remove(&mut chosen, k, &base_fit, dependents),
            reason,
        ));
    };
    let mut findings: Vec<Finding> = chosen
        .iter()
        .enumerate()
        .map(|(k, c)| Finding {
            name: c.term.name.clone(),
            label: c.term.label.clone(),
            meaning: c.term.meaning.clone(),
            family: c.term.family.clone(),
            estimates: extended_parameters[base.len() + k].estimates.clone(),
            hyper_parameter: hyper_of(&c.term.family, exposed_by_rotary(obs, &c.term)).and_then(
                |(v, q)| {
                    let name = if q == Quantity::Duration {
                        "time constant"
                    } else {
                        "period"
                    };
                    let (uncertainty, text) = match hyper_rows[k] {
                        Some(r) => {
                            let u = cov[(r, r)].sqrt();
                            (u, q.format(v, u))
                        }
                        // A harmonic of a turn: a whole number of cycles per turn, exactly.
                        None if q == Quantity::AxisAngle => (
                            0.0,
                            format!(
                                "{}: {} per turn",
                                q.format_value(v),
                                (std::f64::consts::TAU / v).round()
                            ),
                        ),
                        None => return None,
                    };
                    Some(Estimate {
                        text,
                        ..Estimate::new(name, v, uncertainty, q)
                    })
                },
            ),
            p_value: c.p_value,
            p_value_final: finals[k],
            cv_rms_before: c.cv_before,
            cv_rms_after: c.cv_after,
            alternatives: c.alternatives.clone(),
            rivals: Vec::new(),
            separated_by: c.separated_by.clone(),
            exposed_by: c.term.exposed_by.clone(),
            first_order: None,
            ordinary: is_ordinary(obs, &c.term),
        })
        .collect();
    // A drift's size over the data: the change of its parameter from the first reading to the
    // last (a first-order drift's own size is the asymptote, beyond the data; a linear one's
    // is a rate).
    let offsets = column_offsets(x0.ncols(), chosen.iter().map(|c| &c.term));
    let change = |members: &[usize], stem: &str| {
        drift_change(
            obs,
            &chosen,
            members,
            stem,
            &offsets,
            &sol.coef,
            &cov,
            &hyper_rows,
        )
    };
    for (k, f) in findings.iter_mut().enumerate() {
        if matches!(chosen[k].term.family, Family::Drift { .. }) {
            for stem in crate::candidate::drifted_parameters(&chosen[k].term) {
                f.estimates.extend(change(&[k], stem));
            }
        }
    }
    // The fit of the final model without each finding: its rivals are measured against it.
    let rests: Vec<Projector> = (0..chosen.len())
        .map(|k| searcher.fit_without(&chosen, k, &base_fit))
        .collect();
    // A first-order drift's final value lies beyond the record, through a time constant the
    // data may bound on one side only: its 95 % interval by profile likelihood.
    let mut unsettled = Vec::new();
    let yw = obs.values.component_mul(w);
    let scale = covariance_scale(obs, extended.sigma0);
    if let Some(span) = span {
        for (k, c) in chosen.iter().enumerate() {
            let profile = |drift: &Tunable<'_>| {
                settling_intervals(drift, &rests[k], &yw, fit.rss_w(), scale, span)
            };
            let tau = match c.term.family {
                Family::Drift {
                    time_constant_s: Some(tau),
                } => tau,
                // A linear drift: where a first-order one of the same parameter would settle,
                // and what its change over the record may be if it is one.
                Family::Drift {
                    time_constant_s: None,
                } => {
                    let Some((fit, changes)) = first_order_fit(candidates, obs, c, span, profile)
                    else {
                        continue;
                    };
                    unsettled.push(fit.note(&c.term.name));
                    let f = &mut findings[k];
                    f.first_order = Some(fit);
                    with_change_intervals(f, &c.term, changes);
                    continue;
                }
                _ => continue,
            };
            let Some(profiled) = profile(&Tunable {
                candidate: searcher.chosen_candidate(c),
                variant: c.variant,
                component: c.component,
                value: tau,
            }) else {
                continue;
            };
            let f = &mut findings[k];
            with_change_intervals(f, &c.term, profiled.changes);
            let (tau, coefficients) = (profiled.time_constant, profiled.final_values);
            for (e, profile) in f.estimates.iter_mut().zip(coefficients) {
                *e = with_profile_interval(e, profile);
            }
            if let Some(h) = f.hyper_parameter.take() {
                f.hyper_parameter = Some(h.with_interval(tau));
            }
        }
    }
    // Rivals the data hardly tell from a finding: in its place in the complete model, χ²
    // within the exchange threshold of the model's.
    let variance = fit.residual_variance();
    for (k, c) in chosen.iter().enumerate() {
        let alternatives = &findings[k].alternatives;
        let mut close: Vec<(&Term, f64)> = c
            .rivals
            .iter()
            .filter(|t| {
                !chosen.iter().any(|c| c.term.name == t.name)
                    && !base.iter().any(|b| b.name == t.name)
                    && !alternatives.contains(&t.name)
            })
            .map(|t| {
                let with_it = rests[k].rss_w() - rests[k].increment(&t.columns).delta_rss;
                (t, (with_it - fit.rss_w()) / variance)
            })
            .filter(|(_, excess)| excess.abs() < EXCHANGE_CHI2)
            .collect();
        close.sort_by(|a, b| a.1.total_cmp(&b.1));
        // Each rival cause once, in the form that fits best.
        let f = &mut findings[k];
        let mut kept: Vec<&Term> = Vec::new();
        for (t, chi2_excess) in close {
            if kept.iter().any(|k| k.name == t.name || one_cause(k, t)) {
                continue;
            }
            kept.push(t);
            f.rivals.push(Rival {
                name: t.name.clone(),
                label: t.label.clone(),
                chi2_excess,
            });
        }
        if !f.rivals.is_empty() {
            // The measurements that would separate the rivals too, beside the alternatives'.
            let names: Vec<String> = f.rivals.iter().map(|r| r.name.clone()).collect();
            let mut hints: Vec<String> = (f.separated_by.iter())
                .flat_map(|h| h.split("; or "))
                .map(String::from)
                .collect();
            for h in separating_hint(&c.term, &names, &searcher.pool.variants)
                .iter()
                .flat_map(|h| h.split("; or "))
            {
                if !hints.iter().any(|g| g == h) {
                    hints.push(h.to_string());
                }
            }
            f.separated_by = (!hints.is_empty()).then(|| hints.join("; or "));
        }
    }
    // A drift the data cannot tell from two others together; a constant error from two or
    // three others together.
    let in_model = |name: &str| {
        chosen.iter().any(|c| c.term.name == name) || base.iter().any(|b| b.name == name)
    };
    let singles = single_constants(obs, candidates);
    for (k, c) in chosen.iter().enumerate() {
        findings[k].alternatives.extend(
            equivalent_drifts(obs, &rests[k], &c.term, candidates)
                .into_iter()
                .map(|(a, b)| format!("{a} and {b} together (same time dependence)")),
        );
        findings[k].alternatives.extend(equivalent_constants(
            &rests[k], &c.term, &singles, &in_model,
        ));
    }
    // A period the positions cannot pin down: other periods that fit about as well widen the
    // amplitude's uncertainty and are named. (A long record samples densely: not needed there.)
    let mut ambiguity_notes = Vec::new();
    // Findings whose period these positions cannot tell from others (by name).
    let mut ambiguous: Vec<String> = Vec::new();
    if thinned.is_none() {
        for (k, c) in chosen.iter().enumerate() {
            let modes = period_modes(obs, &rests[k], &sol, &c.term, searcher.chosen_candidate(c));
            let Some(h) = findings[k]
                .hyper_parameter
                .clone()
                .filter(|_| !modes.is_empty())
            else {
                continue;
            };
            let rotary = h.quantity == Quantity::AxisAngle;
            let f = &mut findings[k];
            ambiguous.push(f.name.clone());
            let amplitude_quantity = f
                .estimates
                .iter()
                .find(|e| e.name == "amplitude")
                .map_or(Quantity::Length, |e| e.quantity);
            if let Some(amp) = f.estimates.iter_mut().find(|e| e.name == "amplitude") {
                let weights: Vec<f64> = modes.iter().map(|m| (-0.5 * m.delta_chi2).exp()).collect();
                let spread = modes
                    .iter()
                    .zip(&weights)
                    .map(|(m, w)| w * (m.amplitude - amp.value).powi(2))
                    .sum::<f64>()
                    / (1.0 + weights.iter().sum::<f64>());
                amp.uncertainty = (amp.uncertainty.powi(2) + spread).sqrt();
                amp.text = amp.quantity.format(amp.value, amp.uncertainty);
            }
            // The best few are named; the spread above takes them all.
            const NAMED: usize = 3;
            let others: Vec<String> = modes
                .iter()
                .take(NAMED)
                .map(|m| {
                    format!(
                        "{} (Δχ² = {:.1}, amplitude {})",
                        crate::candidate::format_period(m.period, rotary),
                        m.delta_chi2,
                        amplitude_quantity.format_value(m.amplitude)
                    )
                })
                .collect();
            f.alternatives.extend(modes.iter().take(NAMED).map(|m| {
                format!(
                    "{} at a period of {}",
                    f.name,
                    crate::candidate::format_period(m.period, rotary)
                )
            }));
            let more = match modes.len().saturating_sub(NAMED) {
                0 => String::new(),
                k => format!(" and {k} more"),
            };
            ambiguity_notes.push(format!(
                "the period of {} is ambiguous with these positions: {}{more} fit{} about as well as {} (Δχ² < {MODE_CHI2}); its amplitude's uncertainty includes their spread; positions at a finer or different spacing would tell them apart",
                f.name,
                others.join(", "),
                if modes.len() == 1 { "s" } else { "" },
                h.text,
            ));
        }
    }
    // A period the data determine poorly within its main lobe: the period's and the amplitude's
    // 95 % intervals by the profile over it, stated where they reach beyond the linearisation's.
    for (k, c) in chosen.iter().enumerate() {
        let Some((period, span)) =
            period_and_span(obs, &c.term).filter(|_| hyper_rows[k].is_some())
        else {
            continue;
        };
        let periodic = Tunable {
            candidate: searcher.chosen_candidate(c),
            variant: c.variant,
            component: c.component,
            value: period,
        };
        let Some((period, amplitude)) =
            period_intervals(&periodic, &rests[k], &yw, fit.rss_w(), scale, span)
        else {
            continue;
        };
        let f = &mut findings[k];
        let Some(amp) = f.estimates.iter_mut().find(|e| e.name == "amplitude") else {
            continue;
        };
        if reaches_beyond(amp, &amplitude) {
            *amp = with_profile_interval(amp, amplitude);
            if let Some(h) = f.hyper_parameter.take() {
                f.hyper_parameter = Some(with_profile_interval(&h, period));
            }
        }
    }
    let remaining_structure: Vec<StructureTest> = structure_tests(
        obs,
        &fit,
        &x,
        &sol.residuals,
        w,
        sol.rss_w,
        sol.dof(),
        thinned,
        &probes,
    )
    .into_iter()
    .filter(|t| t.is_significant(params.alpha))
    .collect();
    let outliers = outlying_readings(obs, w, &sol, &fit, params.alpha);
    let without_outliers = (!outliers.is_empty()).then(|| {
        let mut w_kept = w.clone();
        for o in &outliers {
            w_kept[o.observation] = 0.0;
        }
        let kept = solve(&x, &obs.values, &w_kept);
        let q = quality(obs, &kept, &DVec::zeros(0));
        (q.sigma0, q.chi2_p_value)
    });
    let consistent_with_noise = extended.chi2_p_value.is_none_or(|p| p >= params.alpha)
        || extended.sigma0 <= STATED_NOISE_TOLERANCE;
    let verdict = if !remaining_structure.is_empty() || !consistent_with_noise {
        Verdict::Unexplained
    } else if findings.is_empty() {
        Verdict::NoDiscrepancy
    } else {
        Verdict::Explained
    };
    let capped = search.capped.as_ref().map(|(name, p, most)| {
        format!(
            "{name} was still significant ({}) and improved the cross-validated RMS, but one error takes at most {most} periodic components in the search: more periods may remain (a base model with the axes' smooth errors, `components`, leaves the periods to what lies beyond them)",
            crate::report::p_text(*p)
        )
    });
    let limit = search.hit_limit.map(|ordinary| {
        if ordinary {
            format!(
                "the search stopped at its limit of {} ordinary errors the base model leaves out while a further one was still significant and improved the cross-validated RMS; more may remain, and the search did not look past them for other causes",
                params.max_ordinary
            )
        } else {
            format!(
                "the search stopped at its limit of {} causes while a further candidate was still significant and improved the cross-validated RMS; more causes may remain",
                params.max_effects
            )
        }
    });
    let incomplete = match (limit, capped) {
        (Some(a), Some(b)) => Some(format!("{a}; and {b}")),
        (a, b) => a.or(b),
    };
    let mut notes = Vec::new();
    if !rests_on_orders.is_empty() {
        const NAMED: usize = 6;
        let names: Vec<&str> = with_next().0.iter().map(|t| t.name.as_str()).collect();
        notes.push(format!(
            "{} found by the search but left out: these data tell {} from the base model only through the orders the base stops at. With the next order of every base error in the model ({}{}), {} size is not determined: it rests on the assumption that the base errors have no higher orders, not on the data",
            rests_on_orders.join(", "),
            if rests_on_orders.len() == 1 { "it" } else { "them" },
            names[..names.len().min(NAMED)].join(", "),
            if names.len() > NAMED {
                format!(" and {} more", names.len() - NAMED)
            } else {
                String::new()
            },
            if rests_on_orders.len() == 1 { "its" } else { "their" },
        ));
    }
    notes.extend(drifts_at_the_shortest(&searcher, &chosen));
    for v in &obs.variables {
        if !crate::candidate::varies(&v.values) {
            notes.push(match v.kind {
                crate::data::VariableKind::Time => "the data have a single time value: time-dependent effects (thermal drift) cannot be tested".to_string(),
                crate::data::VariableKind::Direction => "every reading approaches from the same direction: reversal errors cannot be tested".to_string(),
                _ => format!("{} has a single value in these data: errors that depend on it cannot be tested (only their value there, which the base absorbs)", v.name),
            });
        }
    }
    let periodic_reach: Vec<PeriodicReach> = obs
        .variables
        .iter()
        .filter(|v| {
            matches!(
                v.kind,
                crate::data::VariableKind::LinearAxis | crate::data::VariableKind::RotaryAxis
            ) && crate::candidate::varies(&v.values)
        })
        .map(|v| {
            let rotary = v.kind == crate::data::VariableKind::RotaryAxis;
            let reach = crate::basis::periodic_reach(&v.values, rotary);
            PeriodicReach {
                variable: v.name.clone(),
                rotary,
                positions: reach.positions,
                periods: reach.periods,
                alias_step: reach.alias,
            }
        })
        .collect();
    notes.extend(periodic_reach.iter().filter_map(PeriodicReach::note));
    if obs.setup_names.len() == 1 {
        notes.push(format!(
            "one {}: errors that differ between {}s cannot be told from errors common to all",
            obs.setup_kind, obs.setup_kind
        ));
    }
    // (A time without spread has its own sentence above.)
    if obs
        .variable_of_kind(crate::data::VariableKind::Time)
        .is_some_and(|t| crate::candidate::varies(&t.values))
        && obs.revisit_interval().is_none()
    {
        notes.push("no pose is measured twice: time-dependent effects (thermal drift) cannot be told from pose-dependent ones and were not tested".to_string());
    }
    if let Some(rows) = &thinned {
        notes.push(format!(
            "a long record: the search for causes (and its held-out figures) ran on {} of the {n} observations, evenly spread in acquisition order (DiagnoseParams::search_rows); the completed base and the causes found were then fitted to all {n}, which give the sizes, uncertainties, structure tests and verdict",
            rows.len()
        ));
    }
    let mut compound: Vec<Compound> = harmonic_families(&findings);
    if thinned.is_none() {
        // (A long record samples densely: its harmonics show at their own periods.)
        let covered: Vec<String> = compound.iter().flat_map(|c| c.findings.clone()).collect();
        let s2 = (sol.rss_w / sol.dof().max(1) as f64).max(1e-300);
        compound.extend(aliased_harmonic_families(
            &searcher, &chosen, &terms, w, s2, &covered,
        ));
    }
    let covered: Vec<String> = compound.iter().flat_map(|c| c.findings.clone()).collect();
    compound.extend(periodic_shapes(
        &searcher, &chosen, &fit, &covered, &ambiguous,
    ));
    let drifts = compound_drifts(&findings, &chosen, change);
    let covered: Vec<String> = drifts.iter().flat_map(|c| c.findings.clone()).collect();
    compound.extend(drifts);
    compound.extend(drift_shapes(
        obs, candidates, &chosen, &terms, left_out, &fit, &covered,
    ));
    notes.extend(ambiguity_notes);
    notes.extend(unsettled);
    notes.extend(compound.iter().map(|c| c.note.clone()));
    let residual_series = residual_series(
        obs,
        &findings,
        &terms[base.len()..],
        &sol,
        base.iter().map(Term::width).sum(),
        &remaining_structure,
        &fit,
        &probes,
    );
    Ok(Diagnosis {
        observations: n,
        channels: obs.channel_names.clone(),
        setups: obs.setup_names.clone(),
        setup_kind: obs.setup_kind.clone(),
        quantity: obs.quantity,
        stated_noise: obs.sigma.as_ref().map(rms),
        verdict,
        incomplete,
        notes,
        periodic_reach,
        base_parameters,
        base_completed,
        base_not_separable,
        base_rms_per_setup: group_rms(&base_sol.residuals, &obs.setup, obs.setup_names.len()),
        base_rms_per_channel: group_rms(&base_sol.residuals, &obs.channel, obs.channel_names.len()),
        base: base_quality,
        structure,
        steps: search.steps,
        findings,
        compound,
        exchanged,
        pruned,
        passed_over: search.passed_over,
        not_separable,
        determined_together: determined_together(&terms, &cov),
        detection_limits: search.detection_limits,
        extended,
        extended_parameters,
        remaining_structure,
        outliers,
        without_outliers,
        held_out: None,
        residual_series,
        alpha: params.alpha,
        min_gain: params.min_gain,
        base_model: None,
    })
}

/// About `most` of the observations in acquisition order `order`, evenly spread and irregular:
/// one at a pseudo-random place (a hash of the block's index: deterministic) in each block of
/// consecutive ones. A regular stride would sample a continuous log at nearly regular positions,
/// which aliases periodic errors; the irregular choice does not. Sorted by row.
fn thin_rows(order: &[usize], most: usize) -> Vec<usize> {
    let step = order.len().div_ceil(most.max(1));
    let mut rows: Vec<usize> = order
        .chunks(step)
        .enumerate()
        .map(|(b, block)| block[(crate::basis::splitmix64(b as u64) % block.len() as u64) as usize])
        .collect();
    rows.sort_unstable();
    rows
}

fn check_params(p: &DiagnoseParams) -> Result<()> {
    let bad = |field: &str, detail: String| {
        Err(DiagnoseError::InvalidData {
            field: field.into(),
            detail,
        })
    };
    if !(p.alpha > 0.0 && p.alpha < 0.5) {
        return bad(
            "alpha",
            format!("{}: expected a level in (0, 0.5)", p.alpha),
        );
    }
    if p.folds < 2 || p.outer_folds == 1 {
        return bad(
            "folds",
            format!(
                "{} folds, {} outer folds: cross-validation needs at least 2 (0 outer folds skips them)",
                p.folds, p.outer_folds
            ),
        );
    }
    if !(p.min_gain.is_finite() && (0.0..1.0).contains(&p.min_gain)) {
        return bad("min_gain", format!("{}: expected [0, 1)", p.min_gain));
    }
    if !(p.max_memory_gb.is_finite() && p.max_memory_gb > 0.0) {
        return bad(
            "max_memory_gb",
            format!("{}: expected a positive number of GB", p.max_memory_gb),
        );
    }
    Ok(())
}

/// The candidates' variants on these observations, with the candidate each came from.
/// Candidates named like a base term are the base's own: they are not searched.
#[derive(Default)]
struct Pool {
    /// The variants by entry; those of an entry with a spread without their columns
    /// ([`Pool::term`]).
    variants: Vec<Vec<Term>>,
    /// Of an entry whose variants are functions of one variable ([`Candidate::spread`]): the
    /// spread and the variants' functions at its values side by side.
    spreads: Vec<Option<EntrySpread>>,
    source: Vec<usize>,
    /// Entry by the name of its first variant.
    by_name: HashMap<String, usize>,
    /// Column of each variant in the variants' columns side by side (pool order).
    offsets: Vec<Vec<usize>>,
    /// The products of the base's design and the observations with every variant.
    products: Products,
    /// Their shares of the outer folds' test rows ([`Searcher::held_out`]).
    fold_shares: Vec<Products>,
    /// The weights' squares and the outer folds' test rows the products were formed with.
    w2: DVec,
    /// Terms of the base the products are of (a search's base is these, then completions).
    base_terms: usize,
    outer: Vec<Vec<usize>>,
    /// The products of a completion's columns with every variant, by pool entry, formed by the
    /// first search that completes its base with it and shared by the others (the main search
    /// and the outer folds' mostly complete with the same orders).
    completion_products: std::sync::Mutex<HashMap<usize, std::sync::Arc<EntryProducts>>>,
}

/// A pool entry holds its variants through their spread ([`Candidate::spread`]) where the
/// observations are at least this many times its distinct values.
const SPREAD_VALUES_PER_ROW: usize = 4;

/// A pool entry's variants as functions of one variable: `spread.expand(values)` are their
/// columns side by side.
type EntrySpread = (std::sync::Arc<Spread>, DMat);

/// `Cᵢᵀ W² C` of one pool entry's first variant `Cᵢ` with every variant's columns `C` side by
/// side: on all rows, and the share of each outer fold's test rows.
struct EntryProducts {
    all: DMat,
    shares: Vec<DMat>,
}

/// `Xᵀ W² C`, `yᵀ W² C` and each variant's `Cᵀ W² C`: the base design `X` and the
/// observations `y` (weights `W`) against every variant's columns `C` side by side, formed
/// once on all observations. A search scores a variant from these products and its model's
/// basis ([`Projector::increment_from_products`]) instead of a pass over the observations per
/// variant and step; an outer fold's search (weights zero on its held-out rows) subtracts
/// those rows' share.
#[derive(Default, Clone)]
struct Products {
    /// `Xᵀ W² C` (rows: the model's design columns).
    x: DMat,
    /// `yᵀ W² C`.
    y: DVec,
    /// `Cᵀ W² C` of each variant, in pool order.
    gram: Vec<Vec<DMat>>,
}

impl Pool {
    /// The variants of `candidates` on `obs` that a pool holds (none for a probe), by
    /// candidate, with their spread where they have one ([`Candidate::spread`]). Building them
    /// (a scan's columns for every period) is independent per candidate; collected in order,
    /// so the pool is the same for any thread count.
    fn variants_of(
        obs: &Observations,
        candidates: &[Box<dyn Candidate>],
    ) -> Vec<(Vec<Term>, Option<EntrySpread>)> {
        let n = obs.len();
        candidates
            .par_iter()
            .map(|c| {
                if c.role() == Role::Probe {
                    return (Vec::new(), None);
                }
                // A spread pays where its distinct values are few against the observations
                // (the products of each outer fold's rows go over all of them): otherwise, or
                // where it does not match its variants' widths, the products come from the
                // columns.
                let matches = |v: &SpreadVariants| {
                    v.spread.values().len() * SPREAD_VALUES_PER_ROW <= n
                        && v.bases.len() == v.headers.len()
                        && v.spread.rows() == n
                        && v.bases.iter().zip(&v.headers).all(|(b, t)| {
                            b.nrows() == v.spread.values().len()
                                && b.ncols() == t.width()
                                && t.columns.nrows() == 0
                        })
                };
                let Some(v) = c.spread().filter(matches) else {
                    let kept = |t: &Term| !t.is_invisible() && t.columns.nrows() == n;
                    return (c.variants(obs).into_iter().filter(kept).collect(), None);
                };
                // The variants the observations see, without their columns.
                let (headers, bases): (Vec<Term>, Vec<DMat>) = v
                    .headers
                    .into_iter()
                    .zip(v.bases)
                    .filter(|(_, b)| !v.spread.sees_nothing(b))
                    .unzip();
                let width = headers.iter().map(Term::width).sum();
                let mut values = DMat::zeros(v.spread.values().len(), width);
                let mut at = 0;
                for b in bases {
                    values.columns_mut(at, b.ncols()).copy_from(&b);
                    at += b.ncols();
                }
                (headers, Some((v.spread, values)))
            })
            .collect()
    }

    /// The pool of the candidates' variants `built` ([`Pool::variants_of`]) on `obs`, with
    /// the products of the base's design `x_base` and the observations (weights `w`) with
    /// every variant, as the sum of the shares of the outer folds' test rows `outer` (none: of
    /// all rows). A candidate named like a base term is the base's own: not in the pool.
    fn new(
        obs: &Observations,
        built: Vec<(Vec<Term>, Option<EntrySpread>)>,
        base: &[Term],
        x_base: DMat,
        w: &DVec,
        outer: &[Vec<usize>],
    ) -> Pool {
        let n = obs.len();
        let mut variants = Vec::new();
        let mut spreads = Vec::new();
        let mut source = Vec::new();
        for (k, (v, spread)) in built.into_iter().enumerate() {
            if v.is_empty() || base.iter().any(|b| b.name == v[0].name) {
                continue;
            }
            variants.push(v);
            spreads.push(spread);
            source.push(k);
        }
        let by_name = variants
            .iter()
            .enumerate()
            .map(|(k, v)| (v[0].name.clone(), k))
            .collect();
        let mut at = 0;
        let offsets = variants
            .iter()
            .map(|v| {
                v.iter()
                    .map(|t| {
                        at += t.width();
                        at - t.width()
                    })
                    .collect()
            })
            .collect();
        let mut pool = Pool {
            variants,
            spreads,
            source,
            by_name,
            offsets,
            products: Products::default(),
            fold_shares: Vec::new(),
            w2: w.component_mul(w),
            base_terms: base.len(),
            outer: outer.to_vec(),
            completion_products: Default::default(),
        };
        // The outer folds' test rows partition the observations: the products are formed per
        // fold (a fold's search subtracts its own share) and summed.
        let mut group = vec![0; n];
        for (k, rows) in outer.iter().enumerate() {
            for &i in rows {
                group[i] = k;
            }
        }
        let grams = pool.variant_grams(&group, outer.len().max(1));
        let p0 = x_base.ncols();
        let mut xy = x_base.resize_horizontally(p0 + 1, 0.0);
        xy.set_column(p0, &obs.values);
        let shares: Vec<Products> = grams
            .into_iter()
            .zip(pool.fold_products(&xy))
            .map(|(gram, a)| Products {
                x: a.rows(0, p0).into_owned(),
                y: a.row(p0).transpose(),
                gram: pool.per_variant(gram),
            })
            .collect();
        let mut all = shares[0].clone();
        for share in &shares[1..] {
            all.add(share, 1.0);
        }
        pool.products = all;
        if shares.len() > 1 {
            pool.fold_shares = shares;
        }
        pool
    }

    /// `xᵀ W² C` with every variant's columns `C`, per outer fold's test rows (one share: all
    /// rows when there are no outer folds).
    fn fold_products(&self, x: &DMat) -> Vec<DMat> {
        self.products_of(x, &self.w2, &self.outer)
    }

    /// The columns of every variant of the entries without a spread, in pool order.
    fn dense_columns(&self) -> Vec<&DMat> {
        self.variants
            .iter()
            .zip(&self.spreads)
            .filter(|(_, s)| s.is_none())
            .flat_map(|(v, _)| v.iter().map(|t| &t.columns))
            .collect()
    }

    /// `xᵀ diag(w2) C` with every variant's columns `C` side by side, over each of the groups
    /// of rows `groups` (none: one product, of all rows): from the columns, or through the
    /// distinct values of an entry's spread (`Sᵀ diag(w2) x`, formed once for all its variants).
    fn products_of(&self, x: &DMat, w2: &DVec, groups: &[Vec<usize>]) -> Vec<DMat> {
        let rows: Vec<Option<&[usize]>> = if groups.is_empty() {
            vec![None]
        } else {
            groups.iter().map(|g| Some(&g[..])).collect()
        };
        let with_spread: Vec<usize> = (0..self.spreads.len())
            .filter(|&ci| self.spreads[ci].is_some())
            .collect();
        // The columns' products, and beside them one job per spread entry and group (a few
        // entries, of unequal cost), in group-major order.
        let (dense, spread_parts) = rayon::join(
            || {
                let dense = self.dense_columns();
                if groups.is_empty() {
                    vec![weighted_products(x, w2, &dense)]
                } else {
                    weighted_products_by_rows(x, w2, groups, &dense)
                }
            },
            || {
                (0..rows.len() * with_spread.len())
                    .into_par_iter()
                    .map(|job| {
                        let (g, ci) = (
                            job / with_spread.len(),
                            with_spread[job % with_spread.len()],
                        );
                        let (spread, values) =
                            self.spreads[ci].as_ref().expect("an entry with one");
                        tr_mul(&spread.weighted_sums(x, w2, rows[g]), values)
                    })
                    .collect::<Vec<_>>()
            },
        );
        let total = self.variants.iter().flatten().map(Term::width).sum();
        let mut spread_parts = spread_parts.into_iter();
        dense
            .into_iter()
            .map(|dense| {
                let mut out = DMat::zeros(x.ncols(), total);
                let mut from = 0;
                for (ci, spread) in self.spreads.iter().enumerate() {
                    let at = self.offsets[ci][0];
                    let width: usize = self.variants[ci].iter().map(Term::width).sum();
                    if spread.is_some() {
                        let part = spread_parts.next().expect("one per spread entry and group");
                        out.columns_mut(at, part.ncols()).copy_from(&part);
                    } else {
                        out.columns_mut(at, width)
                            .copy_from(&dense.columns(from, width));
                        from += width;
                    }
                }
                out
            })
            .collect()
    }

    /// `xᵀ W² C` with every variant's columns `C` over all rows, under weights `w`.
    fn products(&self, x: &DMat, w: &DVec) -> DMat {
        let mut all = self.products_of(x, &w.component_mul(w), &[]);
        all.pop().expect("one product")
    }

    /// Variant `vi` of entry `ci` with its columns: an entry with a spread holds its
    /// variants without them (its functions' values at the spread's values instead, which is
    /// all its products need), formed here.
    fn term(&self, ci: usize, vi: usize) -> Cow<'_, Term> {
        let t = &self.variants[ci][vi];
        match &self.spreads[ci] {
            None => Cow::Borrowed(t),
            Some(_) => Cow::Owned(Term {
                columns: self.columns(ci, vi).into_owned(),
                ..t.clone()
            }),
        }
    }

    /// The columns of variant `vi` of entry `ci` ([`Pool::term`]).
    fn columns(&self, ci: usize, vi: usize) -> Cow<'_, DMat> {
        match self.spread_values(ci, vi) {
            None => Cow::Borrowed(&self.variants[ci][vi].columns),
            Some((spread, b)) => Cow::Owned(spread.expand(&b)),
        }
    }

    /// Of entry `ci` with a spread: the spread and variant `vi`'s functions at its values.
    fn spread_values(&self, ci: usize, vi: usize) -> Option<(&Spread, DMat)> {
        let (spread, values) = self.spreads[ci].as_ref()?;
        let at = self.offsets[ci][vi] - self.offsets[ci][0];
        let b = values.columns(at, self.variants[ci][vi].width());
        Some((spread, b.into_owned()))
    }

    /// Each variant's Gram `Cᵀ W² C` over the rows of each group (`group[i]` < `groups`: row
    /// `i`'s), `[group][variant in pool order]`: of an entry with a spread as `Bᵀ (Sᵀ W² S) B`
    /// from its distinct values ([`Spread::gram`]), of the others from their columns
    /// ([`block_grams`]).
    fn variant_grams(&self, group: &[usize], groups: usize) -> Vec<Vec<DMat>> {
        let dense = self.dense_columns();
        // Each spread entry's `Sᵀ W² S` on each group's rows, then its variants' functions:
        // one job per entry and group (a few entries, of unequal cost), beside the columns'.
        let with_spread: Vec<usize> = (0..self.spreads.len())
            .filter(|&ci| self.spreads[ci].is_some())
            .collect();
        let (dense, spread_grams) = rayon::join(
            || block_grams(&dense, &self.w2, group, groups),
            || {
                (0..with_spread.len() * groups)
                    .into_par_iter()
                    .map(|job| {
                        let (ci, g) = (with_spread[job / groups], job % groups);
                        let (spread, _) = self.spreads[ci].as_ref().expect("an entry with one");
                        let w2 = DVec::from_iterator(
                            self.w2.len(),
                            self.w2
                                .iter()
                                .zip(group)
                                .map(|(&w, &h)| if h == g { w } else { 0.0 }),
                        );
                        let m = spread.gram(&w2);
                        (0..self.variants[ci].len())
                            .filter_map(|vi| self.spread_values(ci, vi))
                            .map(|(_, b)| Spread::quadratic(&m, &b))
                            .collect::<Vec<_>>()
                    })
                    .collect::<Vec<_>>()
            },
        );
        let mut dense = dense.into_iter().map(Vec::into_iter).collect::<Vec<_>>();
        let mut spread_grams = spread_grams.into_iter();
        let mut out: Vec<Vec<DMat>> = vec![Vec::new(); groups];
        for (v, s) in self.variants.iter().zip(&self.spreads) {
            if s.is_some() {
                for out in &mut out {
                    out.extend(spread_grams.next().expect("one per spread entry and group"));
                }
            } else {
                for (out, grams) in out.iter_mut().zip(&mut dense) {
                    out.extend(grams.by_ref().take(v.len()));
                }
            }
        }
        out
    }

    /// Values in pool order (one per variant) as the pool's nesting.
    fn per_variant<T>(&self, flat: Vec<T>) -> Vec<Vec<T>> {
        let mut flat = flat.into_iter();
        self.variants
            .iter()
            .map(|v| {
                v.iter()
                    .map(|_| flat.next().expect("one per variant"))
                    .collect()
            })
            .collect()
    }

    /// The products of the model's design with every variant under weights `w`: those of its
    /// first columns `fixed` (rows of `Xᵀ W² C`, [`Pool::search_products`]), then those of the
    /// terms `beyond` them. A term's rows are kept in `formed` (by its columns) and read again
    /// at the search's next steps: only the terms a step adds or a refinement changed are formed,
    /// together in one pass over the variants.
    fn model_products(
        &self,
        fixed: &DMat,
        beyond: &[Term],
        w: &DVec,
        formed: &mut Vec<(DMat, DMat)>,
    ) -> DMat {
        // Each term's entry in `formed`; those not there yet are formed below, in order.
        let mut index: Vec<Option<usize>> = beyond
            .iter()
            .map(|t| formed.iter().position(|(c, _)| *c == t.columns))
            .collect();
        let new: Vec<&Term> = beyond
            .iter()
            .zip(&index)
            .filter_map(|(t, i)| i.is_none().then_some(t))
            .collect();
        if !new.is_empty() {
            let columns = design(&new, w.len());
            let rows = self.products(&columns, w);
            let mut at = 0;
            for (t, i) in beyond.iter().zip(&mut index).filter(|(_, i)| i.is_none()) {
                *i = Some(formed.len());
                formed.push((t.columns.clone(), rows.rows(at, t.width()).into_owned()));
                at += t.width();
            }
        }
        let p = fixed.nrows() + beyond.iter().map(Term::width).sum::<usize>();
        let mut out = DMat::zeros(p, fixed.ncols());
        out.rows_mut(0, fixed.nrows()).copy_from(fixed);
        let mut at = fixed.nrows();
        for i in index {
            let rows = &formed[i.expect("formed above")].1;
            out.rows_mut(at, rows.nrows()).copy_from(rows);
            at += rows.nrows();
        }
        out
    }

    /// The products for a search whose base is the pool's base then the terms `completed`
    /// (design `x`), under the pool's weights `w` except on the rows of the outer fold
    /// `held_out` (weight zero): the pool's products less that fold's share, plus the
    /// completions' rows — from [`Pool::entry_products`] where a completion is a pool entry's
    /// columns, formed directly otherwise.
    fn search_products(
        &self,
        completed: &[Term],
        x: &DMat,
        w: &DVec,
        held_out: Option<usize>,
    ) -> Products {
        let mut products = self.products.clone();
        if let Some(k) = held_out {
            products.add(&self.fold_shares[k], -1.0);
        }
        let mut rows = vec![std::mem::take(&mut products.x)];
        for t in completed {
            match self.completion_rows(t, held_out) {
                Some(r) => rows.push(r),
                None => {
                    let p = rows.iter().map(DMat::nrows).sum::<usize>();
                    let c = x.columns(p, t.width()).into_owned();
                    rows.push(self.products(&c, w));
                }
            }
        }
        let total = rows.iter().map(DMat::nrows).sum();
        let mut x_products = DMat::zeros(total, rows[0].ncols());
        let mut at = 0;
        for r in rows {
            x_products.rows_mut(at, r.nrows()).copy_from(&r);
            at += r.nrows();
        }
        products.x = x_products;
        products
    }

    /// The rows `tᵀ W² C` of a completion `t` whose columns are some of a pool entry's first
    /// variant's ([`keep_columns`]), for the search without the outer fold `held_out`; `None`
    /// when `t` is no such entry's.
    fn completion_rows(&self, t: &Term, held_out: Option<usize>) -> Option<DMat> {
        let &ci = self.by_name.get(&t.name)?;
        let entry = self.columns(ci, 0);
        let columns: Vec<usize> = t
            .columns
            .column_iter()
            .map(|c| entry.column_iter().position(|e| e == c))
            .collect::<Option<_>>()?;
        let products = self.entry_products(ci);
        let mut rows = products.all.select_rows(&columns);
        if let Some(k) = held_out {
            rows -= products.shares[k].select_rows(&columns);
        }
        Some(rows)
    }

    /// The products of the pool entries `entries` (their first variants `C`) for a search
    /// whose base fit is `base_fit` — the pool's base under the pool's weights but those of the
    /// outer fold `held_out`'s rows (zero) — from the pool's products: `Qᵀ W C` on the base's
    /// directions ([`Projector::basis_products_of`]) and `(CᵀW²C, CᵀW²y)`. The start of the
    /// search's [`CompletionRows`]: its [`Searcher::next_completion`] makes no pass over the
    /// observations but for the directions beyond the base's.
    fn base_rows(
        &self,
        entries: &[usize],
        base_fit: &Projector,
        held_out: Option<usize>,
    ) -> CompletionRows {
        let stable = base_fit.rank();
        let mut rows = CompletionRows {
            stable,
            ..Default::default()
        };
        for &ci in entries {
            let (at, k) = (self.offsets[ci][0], self.variants[ci][0].width());
            let mut xtc = self.products.x.columns(at, k).into_owned();
            let mut gram = self.products.gram[ci][0].clone();
            let mut cy = self.products.y.rows(at, k).into_owned();
            if let Some(f) = held_out {
                let share = &self.fold_shares[f];
                xtc -= share.x.columns(at, k);
                gram -= &share.gram[ci][0];
                cy -= share.y.rows(at, k);
            }
            rows.rows
                .insert(ci, base_fit.basis_products_of(0..stable, &xtc));
            rows.own.insert(ci, (gram, cy));
        }
        rows
    }

    /// The products of pool entry `ci`'s first variant with every variant ([`EntryProducts`]),
    /// formed on first use. Formed outside the lock (a search that meets an entry another is
    /// forming forms it too: the same numbers, kept once), so no search waits on another.
    fn entry_products(&self, ci: usize) -> std::sync::Arc<EntryProducts> {
        let cache = || self.completion_products.lock().expect("no search panicked");
        if let Some(p) = cache().get(&ci) {
            return p.clone();
        }
        let shares = self.fold_products(&self.columns(ci, 0));
        // Summed in fold order, as the pool's own products are.
        let mut all = shares[0].clone();
        for share in &shares[1..] {
            all += share;
        }
        let formed = std::sync::Arc::new(EntryProducts { all, shares });
        cache().entry(ci).or_insert(formed).clone()
    }
}

impl Products {
    /// `self += sign · other`.
    fn add(&mut self, other: &Products, sign: f64) {
        let add = |a: &mut f64, b: f64| *a += sign * b;
        self.x.zip_apply(&other.x, add);
        self.y.zip_apply(&other.y, add);
        for (g, o) in self
            .gram
            .iter_mut()
            .flatten()
            .zip(other.gram.iter().flatten())
        {
            g.zip_apply(o, add);
        }
    }
}

/// The products `Qᵀ W C` of the completions' columns with the bases of a search's fits
/// ([`Searcher::next_completion`], [`Projector::increments_knowing`]), by pool entry: of each,
/// the rows of the first `stable` directions stay valid while the model grows (the basis of
/// the base and its completions, which every later fit extends); those beyond are formed again.
#[derive(Default)]
struct CompletionRows {
    stable: usize,
    rows: HashMap<usize, DMat>,
    /// `(CᵀW²C, CᵀW²y)` of each entry under the search's weights ([`Pool::base_rows`]).
    own: HashMap<usize, (DMat, DVec)>,
}

/// The score of a refinement against `projector` ([`Score`]): `rss` less a trial's increment,
/// from its columns or, for functions seen through a spread on the projector's rows, from the
/// spread's products with the projector, formed once per spread (a golden-section search then
/// costs the spread's distinct values per trial, not the observations).
fn refine_score(projector: &Projector, rss: f64) -> Score<'_> {
    let formed: std::cell::RefCell<Option<(*const Spread, SpreadProducts)>> = Default::default();
    Score::new(move |t: &Term| rss - projector.increment(&t.columns).delta_rss).with_spread(
        move |spread, values| {
            if spread.rows() != projector.rows() {
                return None;
            }
            let mut formed = formed.borrow_mut();
            if !formed
                .as_ref()
                .is_some_and(|(p, _)| std::ptr::eq(*p, spread))
            {
                *formed = Some((spread, projector.spread_products(spread)));
            }
            let (_, products) = formed.as_ref().expect("formed above");
            Some(rss - projector.increment_spread(products, values).delta_rss)
        },
    )
}

/// A term the search added, with where it came from.
#[derive(Clone)]
struct Chosen {
    term: Term,
    /// The candidate it came from, and the variant.
    candidate: usize,
    variant: usize,
    /// Which component of a recurring cause (0 = first).
    component: usize,
    p_value: f64,
    variants_tested: usize,
    cv_before: f64,
    cv_after: f64,
    alternatives: Vec<String>,
    /// Causes that explained the residuals at its entry nearly as well, in other ways: measured
    /// again in the complete model ([`Finding::rivals`]). Only in the search on all data.
    rivals: Vec<Term>,
    separated_by: Option<String>,
}

struct SearchResult {
    /// Higher orders of the base's component errors the data asked for.
    completed: Vec<Term>,
    chosen: Vec<Chosen>,
    steps: Vec<Step>,
    not_separable: Vec<NotSeparable>,
    detection_limits: Vec<DetectionLimit>,
    exchanged: Vec<Exchange>,
    pruned: Vec<Pruned>,
    passed_over: Vec<PassedOver>,
    /// The limit that stopped the search, if one did: `true` for the ordinary errors' one.
    hit_limit: Option<bool>,
    /// A periodic cause that already had its most components ([`most_periodic_components`])
    /// when the search stopped, yet a further one was significant and improved the
    /// cross-validated RMS: its name, adjusted p-value and that number.
    capped: Option<(String, f64, usize)>,
}

/// The pool's variants as one search sees them (the pool is shared): those a refinement of
/// this search changed, and a recurring cause's under the name of its next component
/// ([`nth_component`]).
struct SearchVariants<'p> {
    pool: &'p Pool,
    refined: HashMap<(usize, usize), Term>,
    /// Of each entry: which component its variants would be (0: the first).
    component: Vec<usize>,
}

impl<'p> SearchVariants<'p> {
    fn new(pool: &'p Pool) -> Self {
        SearchVariants {
            pool,
            refined: HashMap::new(),
            component: vec![0; pool.variants.len()],
        }
    }

    /// Whether a refinement changed variant `vi` of entry `ci` (its products are not the
    /// pool's).
    fn is_refined(&self, ci: usize, vi: usize) -> bool {
        self.refined.contains_key(&(ci, vi))
    }

    /// The variant as scored: the refined one (with its columns), else the pool's (under its
    /// first component's name, and without its columns where the pool holds none,
    /// [`Pool::term`]).
    fn as_scored(&self, ci: usize, vi: usize) -> &Term {
        self.refined
            .get(&(ci, vi))
            .unwrap_or(&self.pool.variants[ci][vi])
    }

    /// The variant under its name, perhaps without its columns.
    fn header(&self, ci: usize, vi: usize) -> Cow<'_, Term> {
        match (self.refined.get(&(ci, vi)), self.component[ci]) {
            (Some(t), _) => Cow::Borrowed(t),
            (None, 0) => Cow::Borrowed(&self.pool.variants[ci][vi]),
            (None, k) => Cow::Owned(nth_component(self.pool.variants[ci][vi].clone(), k)),
        }
    }

    /// The variant under its name, with its columns.
    fn term(&self, ci: usize, vi: usize) -> Term {
        match self.refined.get(&(ci, vi)) {
            Some(t) => t.clone(),
            None => nth_component(self.pool.term(ci, vi).into_owned(), self.component[ci]),
        }
    }

    /// The variant's columns.
    fn columns(&self, ci: usize, vi: usize) -> Cow<'_, DMat> {
        match self.refined.get(&(ci, vi)) {
            Some(t) => Cow::Borrowed(&t.columns),
            None => self.pool.columns(ci, vi),
        }
    }

    /// Variant `vi` of entry `ci` refined to `term`.
    fn refine(&mut self, ci: usize, vi: usize, term: Term) {
        let term = nth_component(term, self.component[ci]);
        self.refined.insert((ci, vi), term);
    }

    /// Entry `ci`'s variants are its `k`-th further component from now on.
    fn next_component(&mut self, ci: usize, k: usize) {
        self.component[ci] = k;
        for (_, t) in self.refined.iter_mut().filter(|((c, _), _)| *c == ci) {
            *t = nth_component(t.clone(), k);
        }
    }
}

/// The search over candidates, on the observations whose weight is not zero.
#[derive(Clone, Copy)]
struct Searcher<'a> {
    obs: &'a Observations,
    base: &'a [Term],
    pool: &'a Pool,
    candidates: &'a [Box<dyn Candidate>],
    params: &'a DiagnoseParams,
}

/// What a unit size of each variant of a pool entry would show beyond the model: (entry,
/// [(variant, `E`, `None` where not separable)]), `E` its increment or the extremes of its
/// energy ([`Increment::beyond`]).
type Sensitivity<E = (f64, f64)> = (usize, Vec<(usize, Option<E>)>);

/// A candidate's best variant in one step: (pool entry, variant, adjusted p, share of residual).
type Scored = (usize, usize, f64, f64);

impl Searcher<'_> {
    fn candidate(&self, entry: usize) -> &dyn Candidate {
        self.candidates[self.pool.source[entry]].as_ref()
    }

    /// The candidate a chosen term came from.
    fn chosen_candidate(&self, c: &Chosen) -> &dyn Candidate {
        self.candidates[c.candidate].as_ref()
    }

    /// Completes the base ([`Searcher::next_completion`], one at a time while one is
    /// significant), then searches for causes on top of it. Observations of weight zero take
    /// no part: those of the outer fold `held_out` (`None`: the search on all data, which also
    /// records which candidates the data cannot separate from the base, for the report; an
    /// outer fold's search only needs its causes). `base_fit`: the fit of the base under the
    /// weights `w`. With the search's result, the fit of the base and the completions it found.
    fn search(
        &self,
        w: &DVec,
        folds: &Folds,
        held_out: Option<usize>,
        base_fit: Projector,
    ) -> (SearchResult, Projector) {
        let mut completed: Vec<Term> = Vec::new();
        let completions: Vec<usize> = (0..self.pool.variants.len())
            .filter(|&ci| self.candidate(ci).role().completes())
            .collect();
        let mut rows = self.pool.base_rows(&completions, &base_fit, held_out);
        let mut fit = base_fit;
        while let Some(t) = self.next_completion(&completed, &fit, &mut rows, fit.rank()) {
            fit = fit.extended(&t.columns);
            completed.push(t);
        }
        let base: Vec<Term> = self.base.iter().chain(&completed).cloned().collect();
        let mut found = Searcher {
            base: &base,
            ..*self
        }
        .search_causes(w, folds, held_out, &fit, rows);
        for t in &found.completed {
            fit = fit.extended(&t.columns);
        }
        completed.append(&mut found.completed);
        found.completed = completed;
        (found, fit)
    }

    /// The next completion of the model whose fit is `fit` (its terms: the base's and
    /// `model`): the most significant higher order of a base component error
    /// ([`Role::Completion`]) not in the model, if significant at [`COMPLETION_LEVEL`]
    /// (Bonferroni over those eligible); only its columns the model does not have yet.
    /// `rows`: the entries' products with the basis of earlier calls, of which the first
    /// `stable` directions stay the first of every later fit of the search.
    fn next_completion(
        &self,
        model: &[Term],
        fit: &Projector,
        rows: &mut CompletionRows,
        stable: usize,
    ) -> Option<Term> {
        let (rss, dof) = (fit.rss_w(), fit.dof());
        let terms: Vec<&Term> = self.base.iter().chain(model).collect();
        let entries = self.next_order_entries(&terms, true);
        let mut known: Vec<DMat> = entries
            .iter()
            .map(|ci| match rows.rows.remove(ci) {
                Some(r) => r.rows(0, rows.stable.min(r.nrows())).into_owned(),
                None => DMat::zeros(0, 0),
            })
            .collect();
        let columns: Vec<Cow<DMat>> = entries.iter().map(|&ci| self.pool.columns(ci, 0)).collect();
        let columns: Vec<&DMat> = columns.iter().map(|c| c.as_ref()).collect();
        let own = entries.iter().map(|ci| rows.own[ci].clone()).collect();
        let increments =
            fit.increments_knowing(&columns, &mut known, own, &fit.basis_of(&self.obs.values));
        rows.rows.extend(entries.iter().copied().zip(known));
        rows.stable = stable;
        // A block of orders may hold some the model already has (confounded components of a
        // point measurement): it is tested on the new directions it brings.
        let mut tested: Vec<(usize, f64)> = entries
            .iter()
            .zip(&increments)
            .filter(|(_, inc)| inc.new_rank > 0)
            .map(|(&ci, inc)| (ci, f_test(rss, inc.delta_rss, inc.new_rank, dof)))
            .collect();
        let eligible = tested.len();
        // Most significant first. Two higher orders the data cannot tell apart (the straightness
        // of an axis and its angular error times a constant offset, on tracker lengths) have
        // the same p-value but for rounding: they rank by their place in the library, so that
        // rounding (another CPU, another summation order) does not decide between them.
        // The next blocks first: a span of every order at once only where no block alone is
        // significant (it would otherwise often win with orders the data do not ask for).
        let is_span = |ci: usize| self.candidate(ci).role() == Role::CompletionSpan;
        tested.sort_by(|a, b| {
            is_span(a.0)
                .cmp(&is_span(b.0))
                .then(rounding_free(a.1).total_cmp(&rounding_free(b.1)))
        });
        tested
            .into_iter()
            .filter(|&(_, p)| p * (eligible as f64) < COMPLETION_LEVEL)
            .find_map(|(ci, _)| {
                let t = self.pool.term(ci, 0);
                let keep = fit.separable_columns(&t.columns);
                (!keep.is_empty()).then(|| keep_columns(t.into_owned(), &keep))
            })
    }

    /// The pool entries that are a next order of an error of the model `terms` and not in it
    /// ([`is_next_order`]); with `spans`, the spans of every order beyond the base's too
    /// ([`Role::CompletionSpan`]: completions, but not the next order).
    fn next_order_entries(&self, terms: &[&Term], spans: bool) -> Vec<usize> {
        let in_model = |name: &str| terms.iter().any(|t| t.name == name);
        (0..self.pool.variants.len())
            .filter(|&ci| {
                let c = self.candidate(ci);
                let role = c.role();
                (role == Role::Completion || spans && role.completes())
                    && c.requires().is_none_or(in_model)
                    && self.pool.variants[ci]
                        .first()
                        .is_some_and(|t| !in_model(&t.name))
            })
            .collect()
    }

    /// The next orders of the errors of the model `terms`, from the pool
    /// ([`Searcher::next_order_entries`]).
    fn next_orders(&self, terms: &[Term]) -> Vec<Term> {
        self.next_order_entries(&terms.iter().collect::<Vec<_>>(), false)
            .into_iter()
            .map(|ci| self.pool.term(ci, 0).into_owned())
            .collect()
    }

    /// Forward search, then backward pruning. `held_out` as in [`Searcher::search`];
    /// `base_fit`: the fit of the base (this searcher's) under the weights `w`. A large cause
    /// inflates the residuals the base's completion was tested on and can hide an ordinary
    /// higher order (a rotary axis' 3rd harmonic under a pivot drift), which a periodic cause
    /// would then stand in for: once a cause is in, the completions are tested again before
    /// the next cause, and one that enters joins the base (returned as `completed`).
    fn search_causes(
        &self,
        w: &DVec,
        folds: &Folds,
        held_out: Option<usize>,
        base_fit: &Projector,
        mut completion_rows: CompletionRows,
    ) -> SearchResult {
        let explain = held_out.is_none();
        let obs = self.obs;
        let params = self.params;
        let y = &obs.values;
        let entries = self.pool.variants.len();
        let mut variants = SearchVariants::new(self.pool);
        let mut used = vec![false; entries];
        let mut times_chosen = vec![0usize; entries];
        // Periodic causes at their most components: still tested, never added; one still
        // significant when the search stops makes it incomplete.
        let mut capped = vec![false; entries];
        let mut capped_significant = None;
        let mut chosen: Vec<Chosen> = Vec::new();
        let mut steps = Vec::new();
        let mut not_separable = Vec::new();
        let mut detection_limits = Vec::new();
        let mut hit_limit = None;
        let mut passed_over: Vec<PassedOver> = Vec::new();
        // Completions that became significant once causes were in: part of the base from then.
        let mut late: Vec<Term> = Vec::new();
        let model_terms = |late: &[Term], chosen: &[Chosen]| -> Vec<Term> {
            let mut t = self.base.to_vec();
            t.extend(late.iter().cloned());
            t.extend(chosen.iter().map(|c| c.term.clone()));
            t
        };
        let mut terms = model_terms(&late, &chosen);
        let mut x = design(&terms.iter().collect::<Vec<_>>(), obs.len());
        let poses = obs.poses();
        // The base's products with every variant, for this search's weights; the chosen terms'
        // rows are added at each step.
        let products =
            self.pool
                .search_products(&self.base[self.pool.base_terms..], &x, w, held_out);
        // The products of the terms beyond the base with every variant ([`Pool::model_products`]).
        let mut formed = Vec::new();

        // The variants' products with the base's directions (see below).
        let mut stable_qc: Option<DMat> = None;
        // The base's directions on the folds' test rows, shared by the fold fits of every model
        // of the search (all extend the base's fit).
        let fold_basis = base_fit.fold_basis(folds);
        let last = loop {
            // (The base alone: its fit itself.)
            let projector = if x.ncols() == base_fit.design_columns() {
                Cow::Borrowed(base_fit)
            } else {
                Cow::Owned(base_fit.extended_to(&x))
            };
            // With causes in, a completion the causes' size hid may show: it joins the base
            // before the next cause is sought. (The causes' periods and time constants are not
            // refined again for it: a higher order of an ordinary error moves them by a small
            // fraction of their uncertainty — τ 3289 → 3288 s, u = 59 s, on the 8-cycle bench
            // dataset — and the next cause's entry refines them all.)
            if !chosen.is_empty() {
                if let Some(t) = self.next_completion(
                    &terms[self.base.len()..],
                    &projector,
                    &mut completion_rows,
                    base_fit.rank(),
                ) {
                    late.push(t);
                    terms = model_terms(&late, &chosen);
                    x = design(&terms.iter().collect::<Vec<_>>(), obs.len());
                    continue;
                }
            }
            let rss = projector.rss_w();
            // Every variant's `Qᵀ W c`, from the products; a variant a refinement changed is
            // projected directly. The rows of the base's directions are the same at every step
            // (every fit of the search extends the base's): formed once.
            let xtc =
                self.pool
                    .model_products(&products.x, &terms[self.base.len()..], w, &mut formed);
            let stable = base_fit.rank();
            let stable_rows =
                stable_qc.get_or_insert_with(|| projector.basis_products_of(0..stable, &xtc));
            let mut qc = DMat::zeros(projector.rank(), xtc.ncols());
            qc.rows_mut(0, stable).copy_from(stable_rows);
            qc.rows_mut(stable, projector.rank() - stable)
                .copy_from(&projector.basis_products_of(stable..projector.rank(), &xtc));
            let qty = projector.basis_of(y);
            // (A variant a refinement changed is not the pool's: no products.)
            let increment = |ci: usize, vi: usize, t: &Term| {
                if variants.is_refined(ci, vi) {
                    projector.increment(&t.columns)
                } else {
                    let (at, k) = (self.pool.offsets[ci][vi], t.width());
                    projector.increment_from_products(
                        &products.gram[ci][vi],
                        products.y.rows(at, k).into_owned(),
                        qc.columns(at, k),
                        &qty,
                    )
                }
            };
            let fold_fits = projector.fold_fits(folds, &x, y, Some(&fold_basis));
            let cv_rms = fold_fits.rms();
            let dof = projector.dof();
            // A cause that builds on a term needs the term in the model: by name, or as a
            // combination of model terms (an absolute location error when the relative ones
            // are in the base).
            let present = |name: &str| {
                terms.iter().any(|t| t.name == name)
                    || self.pool.by_name.get(name).is_some_and(|&k| {
                        increment(k, 0, variants.as_scored(k, 0)).separability
                            < SEPARABILITY_TOLERANCE
                    })
            };
            let eligible: Vec<usize> = (0..entries)
                .filter(|&ci| {
                    !used[ci]
                        && self.candidate(ci).role() == Role::Cause
                        && self.candidate(ci).requires().is_none_or(present)
                })
                .collect();
            let variants_tested: usize = eligible
                .iter()
                .map(|&ci| self.pool.variants[ci].len())
                .sum();
            // Each candidate's best variant on the grid, and the grid's other peaks that may
            // beat it once refined.
            let mut graded: Vec<(usize, usize, Increment, Vec<usize>)> = Vec::new();
            // What a unit size of each variant of a cause not in the model would show
            // ([`Increment::beyond`]): the step that ends the search turns it into the
            // detection limits.
            let mut sensitivity: Vec<Sensitivity<Increment>> = Vec::new();
            for &ci in &eligible {
                let mut best: Option<(usize, Increment)> = None;
                // The best of the variants that are an ordinary error (a rotary axis' error
                // motion at a harmonic up to the components'), graded beside a best variant
                // that is not ([`is_ordinary`]).
                let mut best_ordinary: Option<(usize, Increment)> = None;
                let mut profile: Vec<(usize, f64)> = Vec::new();
                let tried: Vec<(usize, &Term)> = (0..self.pool.variants[ci].len())
                    .map(|vi| (vi, variants.as_scored(ci, vi)))
                    .filter(|(_, t)| {
                        times_chosen[ci] == 0
                            || !near_a_component(obs, t, &chosen, self.pool.source[ci], None)
                    })
                    .collect();
                let mut energies = Vec::new();
                for &(vi, t) in &tried {
                    let inc = increment(ci, vi, t);
                    if inc.separability < SEPARABILITY_TOLERANCE || inc.new_rank < t.width() {
                        energies.push((vi, None));
                        continue;
                    }
                    energies.push((vi, Some(inc.clone())));
                    profile.push((vi, inc.delta_rss));
                    if is_ordinary(obs, t)
                        && best_ordinary
                            .as_ref()
                            .is_none_or(|(_, b)| inc.delta_rss > b.delta_rss)
                    {
                        best_ordinary = Some((vi, inc.clone()));
                    }
                    if best
                        .as_ref()
                        .is_none_or(|(_, b)| inc.delta_rss > b.delta_rss)
                    {
                        best = Some((vi, inc));
                    }
                }
                if explain && times_chosen[ci] == 0 && energies.iter().any(|e| e.1.is_some()) {
                    sensitivity.push((ci, energies));
                }
                let Some((vi, inc)) = best else {
                    if explain && steps.is_empty() {
                        record_not_separable(
                            &mut not_separable,
                            &self.pool.term(ci, 0),
                            &terms,
                            &x,
                            &projector,
                        );
                    }
                    continue;
                };
                if dof <= inc.new_rank + 1 {
                    continue;
                }
                let peaks = grid_peaks(&profile, vi, inc.delta_rss);
                // A harmonic of a turn far above what the angles resolve is a pattern of its own
                // at each handful of angles, and can fit the residuals of a missing error motion
                // better than the error's own low harmonic (ECC at 105 per turn for its 4th, at
                // 24 angles jittered about a 30° step): the ordinary harmonic is graded too, so
                // that it enters before such a pattern, as every ordinary error does.
                if let Some((vo, ordinary)) = best_ordinary.filter(|(vo, _)| *vo != vi) {
                    graded.push((ci, vo, ordinary, vec![vo]));
                }
                graded.push((ci, vi, inc, peaks));
            }
            // Refining a period or time constant between its grid neighbours is worth it only
            // where the grid's best comes near significance, and only for the candidates that
            // can reach the shortlist: the most significant on the grid.
            let p_of = |inc: &Increment| {
                (f_test(rss, inc.delta_rss, inc.new_rank, dof) * variants_tested as f64).min(1.0)
            };
            // (Candidates the data cannot tell apart rank by their place in the library, and
            // a cut takes them all: [`rank_by_significance`].)
            let key = |g: &usize| (p_of(&graded[*g].2), graded[*g].2.delta_rss);
            let mut order: Vec<usize> = (0..graded.len()).collect();
            rank_by_significance(&mut order, key);
            // (Independent of each other: in parallel, applied in order.)
            let to_refine: Vec<usize> = first_through_ties(order, params.shortlist, key)
                .into_iter()
                .filter(|&g| p_of(&graded[g].2) < REFINE_LEVEL * params.alpha)
                .collect();
            // Every peak is refined and the best refined one kept: a grid point can sit up to a
            // quarter of the Fourier resolution off its optimum and lose a fifth of what the
            // effect explains, more than tells a period from its aliases.
            let better: Vec<Option<(usize, Term, Increment)>> = to_refine
                .par_iter()
                .map(|&g| {
                    let (ci, vi, inc, peaks) = &graded[g];
                    let score = refine_score(&projector, rss);
                    // Each peak refined (the grid's best only when refining improves it); the
                    // first with the largest reduction, if it beats the grid's best.
                    peaks
                        .iter()
                        .filter_map(|&peak| {
                            let term = match self.candidate(*ci).refine(peak, &score) {
                                Some(t) => t,
                                None if peak == *vi => return None,
                                None => variants.term(*ci, peak),
                            };
                            let inc = projector.increment(&term.columns);
                            Some((peak, term, inc))
                        })
                        .reduce(|a, b| if b.2.delta_rss > a.2.delta_rss { b } else { a })
                        .filter(|b| b.2.delta_rss > inc.delta_rss)
                })
                .collect();
            for (&g, better) in to_refine.iter().zip(better) {
                let Some((peak, term, better)) = better else {
                    continue;
                };
                let (ci, vi, inc, _) = &mut graded[g];
                *vi = peak;
                *inc = better;
                variants.refine(*ci, *vi, term);
            }
            let mut scored: Vec<Scored> = graded
                .iter()
                .map(|(ci, vi, inc, _)| (*ci, *vi, p_of(inc), inc.delta_rss / rss.max(1e-300)))
                .collect();
            let key = |s: &Scored| (s.2, s.3);
            rank_by_significance(&mut scored, key);
            let mut ranking = Vec::new();
            let mut best_capped: Option<(String, f64, usize)> = None;
            // The held-out RMS of the significant ones (independent: in parallel): the most
            // significant causes and the most significant of those that do not wait for the
            // ordinary errors ([`waits_for_ordinary`]).
            // (A capped cause does not take an open one's place: the best of them beside.)
            let rigid = |s: &Scored| !waits_for_ordinary(obs, &variants.header(s.0, s.1));
            let mut shortlisted: Vec<Scored> = first_through_ties(
                scored.iter().filter(|s| !capped[s.0]).copied(),
                params.shortlist,
                key,
            );
            let rigid_shortlisted = shortlisted.iter().filter(|s| rigid(s)).count();
            let more: Vec<Scored> = first_through_ties(
                scored
                    .iter()
                    .filter(|s| !capped[s.0] && rigid(s) && !shortlisted.contains(s))
                    .copied(),
                params.shortlist.saturating_sub(rigid_shortlisted),
                key,
            )
            .into_iter()
            .chain(scored.iter().find(|s| capped[s.0]).copied())
            .collect();
            shortlisted.extend(more);
            // A drift must show in the differences between visits of the same pose: over a
            // single pass, a drift of a time constant fitted to the order the poses were
            // measured in takes what the model lacks as a function of the pose for its own
            // (a drift of EB0Z on a clean R-test against its location-only default).
            shortlisted.retain(|&(ci, vi, _, _)| {
                !matches!(variants.header(ci, vi).family, Family::Drift { .. })
                    || projector
                        .within_poses(&variants.columns(ci, vi), &poses)
                        .is_some_and(|(rss, explained, dof)| {
                            f_test(rss, explained, variants.header(ci, vi).width(), dof)
                                < params.alpha
                        })
            });
            let cvs: Vec<Option<f64>> = shortlisted
                .par_iter()
                .map(|&(ci, vi, p, _)| {
                    (p < params.alpha).then(|| fold_fits.rms_with(&variants.columns(ci, vi)))
                })
                .collect();
            // (entry, variant, cv rms) of the open causes with a held-out RMS.
            let mut evaluated: Vec<(usize, usize, f64)> = Vec::new();
            for (&(ci, vi, p, share), cv) in shortlisted.iter().zip(cvs) {
                let t = variants.header(ci, vi);
                if capped[ci] {
                    // (The shortlist's one capped cause.)
                    if cv.is_some_and(|r| r < cv_rms * (1.0 - params.min_gain)) {
                        best_capped = Some((t.name.clone(), p, most_periodic_components(obs, &t)));
                    }
                } else if let Some(r) = cv {
                    evaluated.push((ci, vi, r));
                }
                ranking.push(CandidateScore {
                    name: t.name.clone(),
                    p_value: p,
                    share_of_residual: share,
                    cv_rms: cv,
                    per_turn: crate::candidate::per_turn(obs, &t.family, t.exposed_by.as_deref()),
                });
            }
            // While an ordinary error the base leaves out earns its place, no drift, periodic
            // error at a free period or set-up error goes in ([`waits_for_ordinary`]): a machine
            // has all the ordinary errors, and while the model lacks one its shape stands in the
            // residuals, where such a cause (a pitch at any of hundreds of periods, a drift over
            // a single pass, an offset of one set-up's poses) would take it for its own. Each
            // group's pick is its most parsimonious ([`most_parsimonious`]), and it must earn its
            // place: an ordinary error earns it only when the simplest of the best ordinary
            // errors does. A periodic error at a free period along a linear axis must also
            // predict the readings at positions of the axis it was not fitted to
            // ([`Searcher::between_positions`]); one that does not is passed over.
            let accepted = loop {
                let best = |keep: &dyn Fn(&Term) -> bool| {
                    most_parsimonious(
                        evaluated
                            .iter()
                            .copied()
                            .filter(|&(ci, vi, _)| keep(&variants.header(ci, vi))),
                        |ci, vi| complexity(&variants.header(ci, vi)),
                    )
                    .filter(|(_, _, r)| *r < cv_rms * (1.0 - params.min_gain))
                };
                let pick = match best(&|t| is_ordinary(obs, t)) {
                    Some(ordinary) => best(&|t| !waits_for_ordinary(obs, t)).or(Some(ordinary)),
                    None => best(&|_| true),
                };
                let Some((ci, vi, _)) = pick else { break None };
                let t = variants.header(ci, vi);
                if !matches!(t.family, Family::Periodic { .. })
                    || !is_flexible(obs, &t)
                    || exposed_by_rotary(obs, &t)
                {
                    break pick;
                }
                let Some(ratio) = self.between_positions(&variants, ci, &projector, w) else {
                    break pick;
                };
                if ratio < 1.0 - params.min_gain {
                    break pick;
                }
                if explain && !passed_over.iter().any(|p| p.name == t.name) {
                    passed_over.push(PassedOver {
                        name: t.name.to_string(),
                        axis: t.exposed_by.clone().unwrap_or_default(),
                        ratio,
                    });
                }
                evaluated.retain(|e| e.0 != ci);
            };
            let Some((ci, vi, new_cv)) = accepted else {
                capped_significant = best_capped;
                if explain {
                    detection_limits = self.limits_beyond_next_orders(
                        &sensitivity,
                        &variants,
                        (&terms, &x, &projector, w),
                        &xtc,
                        (rss, dof),
                        variants_tested,
                    );
                }
                steps.push(Step {
                    ranking,
                    added: None,
                    variants_tested,
                });
                break (x, projector.into_owned());
            };
            let ordinary = is_ordinary(obs, &variants.header(ci, vi));
            let limit = if ordinary {
                params.max_ordinary
            } else {
                params.max_effects
            };
            if chosen
                .iter()
                .filter(|c| is_ordinary(obs, &c.term) == ordinary)
                .count()
                == limit
            {
                hit_limit = Some(ordinary);
                steps.push(Step {
                    ranking,
                    added: None,
                    variants_tested,
                });
                break (x, projector.into_owned());
            }
            let mut term = variants.term(ci, vi);
            // Alternatives: shortlisted candidates that explain the same residual direction about
            // as well on held-out data (within 2 %).
            let chosen_perp = projector.residual_part(&term.columns);
            let mut alternatives: Vec<(String, usize, usize, f64)> = Vec::new();
            for score in ranking.iter().filter(|c| c.name != term.name) {
                let Some(r) = score.cv_rms else { continue };
                if r > new_cv * 1.02 {
                    continue;
                }
                let Some(&(cj, vj, _, _)) = scored
                    .iter()
                    .find(|s| variants.header(s.0, s.1).name == score.name)
                else {
                    continue;
                };
                let other = projector.residual_part(&variants.columns(cj, vj));
                if max_cosine(&chosen_perp, &other) > 0.99
                    && !alternatives.iter().any(|a| a.0 == score.name)
                {
                    alternatives.push((score.name.clone(), cj, vj, r));
                }
            }
            // Of a squareness and its equivalent on the plane's other axis, which the data cannot
            // tell apart, the one ISO 230-1 names (EC0Y rather than EC0X).
            let (ci, vi, new_cv) = match alternatives
                .iter()
                .position(|a| is_iso_squareness_of(&a.0, &term))
            {
                Some(k) => {
                    let (_, cj, vj, r) = alternatives.remove(k);
                    alternatives.push((term.name.clone(), ci, vi, new_cv));
                    term = variants.term(cj, vj);
                    (cj, vj, r)
                }
                None => (ci, vi, new_cv),
            };
            let alternatives: Vec<String> = alternatives.into_iter().map(|a| a.0).collect();
            // Rivals: causes that explain the residuals nearly as well in another direction (at
            // entry within twice the exchange threshold; the complete model decides).
            let rivals: Vec<Term> = if explain {
                let share_of = |name: &str| {
                    ranking
                        .iter()
                        .find(|r| r.name == name)
                        .map_or(0.0, |r| r.share_of_residual)
                };
                let share = share_of(&term.name);
                let dof = projector.dof().saturating_sub(term.width()).max(1);
                let variance = rss * (1.0 - share) / dof as f64;
                ranking
                    .iter()
                    .filter(|r| {
                        r.cv_rms.is_some()
                            && r.name != term.name
                            && !alternatives.contains(&r.name)
                            && (share - r.share_of_residual) * rss < 2.0 * EXCHANGE_CHI2 * variance
                    })
                    .filter_map(|r| {
                        scored
                            .iter()
                            .find(|s| variants.header(s.0, s.1).name == r.name)
                    })
                    .map(|s| variants.term(s.0, s.1))
                    .filter(|t| !one_cause(t, &term))
                    .collect()
            } else {
                Vec::new()
            };
            let separated_by = separating_hint(&term, &alternatives, &self.pool.variants);
            let p_value = scored.iter().find(|s| s.0 == ci).map_or(1.0, |s| s.2);
            steps.push(Step {
                ranking,
                added: Some(term.name.clone()),
                variants_tested,
            });
            // A drift or a polynomial of the same cause is a different candidate; the chosen
            // one's own alternatives (other degrees of the same slot) are retired with it. A
            // periodic error stays open for another period: a ball screw shows its pitch and a
            // longer wave of the screw, a rotary table its eccentricity and its worm-gear tooth
            // error. The period already in the model is no longer separable, so the next one is
            // another.
            times_chosen[ci] += 1;
            let recurs = matches!(term.family, Family::Periodic { .. });
            capped[ci] = recurs && times_chosen[ci] >= most_periodic_components(obs, &term);
            // (By the pool's name: a second component is named `… #2`.)
            let pool_name = &self.pool.variants[ci][0].name;
            for (cj, variants) in self.pool.variants.iter().enumerate() {
                if variants[0].name == *pool_name {
                    used[cj] = true;
                }
            }
            if recurs {
                used[ci] = false;
                variants.next_component(ci, times_chosen[ci]);
            }
            chosen.push(Chosen {
                term,
                candidate: self.pool.source[ci],
                variant: vi,
                component: times_chosen[ci] - 1,
                p_value,
                variants_tested,
                cv_before: cv_rms,
                cv_after: new_cv,
                alternatives,
                rivals,
                separated_by,
            });
            // Hyper-parameters found with the other effects still in the residuals are biased (an
            // undersampled pitch leaks into the long periods of an irregular grid): refine each
            // scanned term again with all the others fitted. (A single cause was refined with
            // the same model in this step.)
            if chosen.len() > 1 {
                let base: Vec<Term> = self.base.iter().chain(&late).cloned().collect();
                Searcher {
                    base: &base,
                    ..*self
                }
                .refit_scanned(&mut chosen, base_fit);
            }
            terms = model_terms(&late, &chosen);
            x = design(&terms.iter().collect::<Vec<_>>(), obs.len());
        };
        let base: Vec<Term> = self.base.iter().chain(&late).cloned().collect();
        let complete = Searcher {
            base: &base,
            ..*self
        };
        let mut exchanged = complete.exchange(&mut chosen, &steps, base_fit, &last.1);
        let split = complete.split(&mut chosen, base_fit);
        // The reduction changes what the model says, not how well it fits (χ² within the
        // exchange threshold), so the outer folds' searches, which only predict, leave it out:
        // it exchanges every cause again in each smaller model, seconds on an R-test with three
        // drifts. After a split, what stands in for nothing is the pruning's.
        let (reduced_by, mut pruned) = if explain && split.is_empty() {
            complete.reduce(&mut chosen, &steps, base_fit)
        } else {
            (Vec::new(), Vec::new())
        };
        exchanged.extend(split);
        exchanged.extend(reduced_by);
        let last = if exchanged.is_empty() {
            last
        } else {
            complete.fit_of(base_fit, &complete.with(&chosen, None))
        };
        pruned.extend(complete.prune(&mut chosen, folds, &fold_basis, base_fit, last));
        SearchResult {
            completed: late,
            chosen,
            steps,
            not_separable,
            detection_limits,
            exchanged,
            pruned,
            passed_over,
            hit_limit,
            capped: capped_significant,
        }
    }

    /// The detection limits at the step that ends the search ([`Searcher::detection_limits`]),
    /// from each variant's increment over the model (`terms`, its design, fit and weights): a
    /// cause the base's next orders would hold does not stay in the final model
    /// ([`order_widening`]), so they are against the model with the next order of every base
    /// error in it. Each variant's energy beyond those orders too comes from its products with
    /// the directions they add: for the pool's variants, from their products with the model's
    /// design (`xtc`, the search's) and with the next orders' (one pass over the observations,
    /// through the values of an entry's spread where it has one), as the search's increments
    /// do; a variant a refinement changed, from its columns.
    fn limits_beyond_next_orders(
        &self,
        sensitivity: &[Sensitivity<Increment>],
        variants: &SearchVariants,
        (terms, x, projector, w): (&[Term], &DMat, &Projector, &DVec),
        xtc: &DMat,
        rss_dof: (f64, usize),
        variants_tested: usize,
    ) -> Vec<DetectionLimit> {
        let obs = self.obs;
        let next = self.next_orders(terms);
        let x_next = design(&next.iter().collect::<Vec<_>>(), obs.len());
        let fit = projector.extended(&x_next);
        let (r, m) = (projector.rank(), fit.rank() - projector.rank());
        // (None without next orders: the energies beyond the model itself.)
        let from_products = (m > 0).then(|| {
            let mut all = DMat::zeros(xtc.nrows() + x_next.ncols(), xtc.ncols());
            all.rows_mut(0, xtc.nrows()).copy_from(xtc);
            all.rows_mut(xtc.nrows(), x_next.ncols())
                .copy_from(&self.pool.products(&x_next, w));
            fit.basis_products_of(r..r + m, &all)
        });
        let directions = fit.directions_beyond(projector);
        let beyond: HashMap<(usize, usize), (f64, f64)> = sensitivity
            .iter()
            .flat_map(|(ci, incs)| {
                incs.iter()
                    .filter_map(move |(vi, inc)| inc.as_ref().map(|i| (*ci, *vi, i)))
            })
            .collect::<Vec<_>>()
            .par_iter()
            .filter_map(|&(ci, vi, inc)| {
                let k = variants.as_scored(ci, vi).width();
                let b = match &from_products {
                    None => DMat::zeros(0, k),
                    Some(b) if !variants.is_refined(ci, vi) => {
                        b.columns(self.pool.offsets[ci][vi], k).into_owned()
                    }
                    Some(_) => {
                        let mut c = variants.columns(ci, vi).into_owned();
                        for mut column in c.column_iter_mut() {
                            column.component_mul_assign(w);
                        }
                        tr_mul(&directions, &c)
                    }
                };
                inc.beyond(&b).map(|e| ((ci, vi), e))
            })
            .collect();
        let sensitivity: Vec<Sensitivity> = sensitivity
            .iter()
            .map(|(ci, incs)| {
                let energies = incs
                    .iter()
                    .map(|(vi, _)| (*vi, beyond.get(&(*ci, *vi)).copied()))
                    .collect();
                (*ci, energies)
            })
            .collect();
        let model: Vec<Term> = terms.iter().chain(&next).cloned().collect();
        let x_model = hcat(x, &x_next);
        self.detection_limits(
            &sensitivity,
            variants,
            |c| confounded_with(c, &model, &x_model, &fit),
            rss_dof,
            variants_tested,
        )
    }

    /// The detection limits of the causes in `sensitivity` (each with the energy a unit size of
    /// each variant tested leaves beyond the model, [`Increment::beyond`]; `variants` the
    /// search's variants; `held_by(term)` the model terms a variant not separable is made of)
    /// against the model whose weighted residual sum of squares is `rss` on `dof` degrees of
    /// freedom, in a step that tested `variants_tested` variants (`None`: a variant the data
    /// cannot separate from the model). Set-up terms get none. The search
    /// adds a cause when its F test passes at `alpha` after the Bonferroni adjustment and it
    /// lowers the held-out RMS by `min_gain`: with the noise variance σ² estimated by the
    /// model's, a cause of noncentrality λ passes both when ΔRSS/σ² ~ χ²(k, λ) exceeds
    /// k·F(level; k, dof − k) and (1 − (1 − min_gain)²)·dof. The limit is the size whose λ
    /// makes that happen with probability [`DETECTION_POWER`]; for an amplitude (a sine and a
    /// cosine), whose phase decides how much of it the model holds, with that probability over
    /// a phase drawn uniformly ([`PowerCurve::amplitude_limit`]). Causes summarised by more than one number
    /// have no single size and get none.
    fn detection_limits(
        &self,
        sensitivity: &[Sensitivity],
        variants: &SearchVariants,
        held_by: impl Fn(&DMat) -> Vec<Vec<String>>,
        (rss, dof): (f64, usize),
        variants_tested: usize,
    ) -> Vec<DetectionLimit> {
        let params = self.params;
        let sigma2 = rss / dof as f64;
        let gain = (1.0 - (1.0 - params.min_gain).powi(2)) * dof as f64;
        let mut critical_of: BTreeMap<usize, f64> = BTreeMap::new();
        let mut lambda_of: BTreeMap<usize, f64> = BTreeMap::new();
        // What holds the variants not separable: a few of each cause's, evenly spread, all
        // regressed on the model at once.
        let mut sampled: Vec<(usize, DVec)> = Vec::new();
        // One power curve for every amplitude (its critical value depends on k = 2 alone).
        let curve = std::cell::OnceCell::new();
        let mut limits: Vec<DetectionLimit> = sensitivity
            .iter()
            .filter_map(|(ci, energies)| {
                let t0 = &self.pool.variants[*ci][0];
                let k = t0.width();
                if dof <= k + 1
                    || (k > 1 && t0.summary != Summary::Amplitude)
                    || t0.family == Family::Setup
                {
                    return None;
                }
                let critical = *critical_of.entry(k).or_insert_with(|| {
                    let level = (params.alpha / variants_tested.max(1) as f64).min(1.0);
                    (k as f64 * stats::f_isf(level, k as f64, (dof - k) as f64)).max(gain)
                });
                let rotary = exposed_by_rotary(self.obs, t0);
                let limits = energies
                    .iter()
                    .map(|&(vi, e)| VariantLimit {
                        at: hyper_of(&variants.as_scored(*ci, vi).family, rotary).map(|h| h.0),
                        size: e.map(|(lo, hi)| {
                            if k == 1 {
                                let lambda = *lambda_of.entry(k).or_insert_with(|| {
                                    stats::noncentral_chi2_power_noncentrality(
                                        critical,
                                        1.0,
                                        DETECTION_POWER,
                                    )
                                });
                                (lambda * sigma2 / hi).sqrt()
                            } else {
                                curve
                                    .get_or_init(|| PowerCurve::new(critical))
                                    .amplitude_limit((lo, hi), sigma2)
                            }
                        }),
                    })
                    .collect();
                let hidden: Vec<usize> = energies
                    .iter()
                    .filter(|e| e.1.is_none())
                    .map(|e| e.0)
                    .collect();
                for &vi in hidden
                    .iter()
                    .step_by(hidden.len().div_ceil(HELD_BY_SAMPLES).max(1))
                {
                    sampled.push((*ci, variants.columns(*ci, vi).column(0).into_owned()));
                }
                Some(DetectionLimit {
                    name: t0.name.clone(),
                    label: t0.label.clone(),
                    quantity: t0.coefficients[0].1,
                    summary: t0.summary.clone(),
                    at_quantity: hyper_of(&t0.family, rotary).map(|h| h.1),
                    variants: limits,
                    held_by: Vec::new(),
                })
            })
            .collect();
        if sampled.is_empty() {
            return limits;
        }
        let columns = DMat::from_columns(&sampled.iter().map(|s| s.1.clone()).collect::<Vec<_>>());
        for ((ci, _), names) in sampled.iter().zip(held_by(&columns)) {
            let name = &self.pool.variants[*ci][0].name;
            if let Some(l) = limits.iter_mut().find(|l| &l.name == name) {
                for n in names {
                    if !l.held_by.contains(&n) {
                        l.held_by.push(n);
                    }
                }
            }
        }
        limits
    }

    /// The fit of the base and every chosen term but `j` (those that build on it stay): a trial
    /// term in `j`'s place has that fit's RSS less its increment.
    fn fit_without(&self, chosen: &[Chosen], j: usize, base_fit: &Projector) -> Projector {
        let terms: Vec<&Term> = self
            .base
            .iter()
            .chain(
                chosen
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| *k != j)
                    .map(|(_, c)| &c.term),
            )
            .collect();
        self.fit_of(base_fit, &terms).1
    }

    /// Refines the hyper-parameter of every chosen term with all other terms fitted; keeps a
    /// refinement only when it lowers the weighted residual sum of squares.
    fn refit_scanned(&self, chosen: &mut [Chosen], base_fit: &Projector) {
        for j in 0..chosen.len() {
            // The model without term j, fitted once (when the candidate refines at all): a trial
            // term's RSS is that model's minus the trial's increment.
            let others = std::cell::OnceCell::new();
            let rss_with = |t: &Term| {
                let (rss, projector) = others.get_or_init(|| {
                    let projector = self.fit_without(chosen, j, base_fit);
                    (projector.rss_w(), projector)
                });
                rss - projector.increment(&t.columns).delta_rss
            };
            let Some(refined) = self
                .chosen_candidate(&chosen[j])
                .refine(chosen[j].variant, &Score::new(rss_with))
            else {
                continue;
            };
            if near_a_component(self.obs, &refined, chosen, chosen[j].candidate, Some(j))
                || rss_with(&refined) >= rss_with(&chosen[j].term)
            {
                continue;
            }
            chosen[j].term = nth_component(refined, chosen[j].component);
        }
    }

    /// Exchange (the replacement step of stepwise selection): once the search has chosen two
    /// causes or more, each is tried against the causes of its family (a drift against drifts,
    /// a location error against location errors) that competed in the search's steps (their
    /// shortlists), each at its best time constant or form, the other chosen causes' chosen
    /// again beside it. One that leaves the complete model's χ² lower by more than
    /// [`EXCHANGE_CHI2`], with no more coefficients, takes its place. Entry by entry, the search
    /// takes the cause that best explains the residuals alone: the lines of B and C drifting in
    /// X the same way first look like the tool drifting, and with that in the model the second
    /// line's drift is fitted beside it, though the two lines explain the data and the tool
    /// does not. A rival of fewer coefficients (with one cause or more) takes the place of a
    /// chosen cause when it leaves χ² higher by less than that threshold: what the data cannot
    /// tell apart, the simpler cause says (the zero of an axis settling, not the axis expanding
    /// about a point with a scale the data do not need). Periodic causes (whose components
    /// build on each other) and a component error's polynomial forms (nested orders of one
    /// error) are not exchanged.
    /// `fit`: the model's fit; returns the exchanges made.
    fn exchange(
        &self,
        chosen: &mut Vec<Chosen>,
        steps: &[Step],
        base_fit: &Projector,
        fit: &Projector,
    ) -> Vec<Exchange> {
        let mut exchanged = Vec::new();
        if chosen.is_empty() {
            return exchanged;
        }
        // (A periodic cause's components build on each other; a component error's forms are
        // nested orders of one error.)
        let recurs =
            |t: &Term| matches!(t.family, Family::Periodic { .. } | Family::Component { .. });
        let same_family =
            |a: &Family, b: &Family| std::mem::discriminant(a) == std::mem::discriminant(b);
        let variance = fit.residual_variance();
        let pool = &self.pool.variants;
        let mut rss = fit.rss_w();
        for j in 0..chosen.len() {
            let name = chosen[j].term.name.clone();
            let required = chosen
                .iter()
                .any(|c| self.chosen_candidate(c).requires() == Some(name.as_str()));
            // With other causes, a rival of its family may explain the data better; alone (the
            // search chose it as the best alone) only a simpler rival may take its place.
            let simpler_only = chosen.len() < 2;
            if recurs(&chosen[j].term) || required {
                continue;
            }
            let in_model = |n: &str| {
                self.base.iter().any(|t| t.name == n) || chosen.iter().any(|c| c.term.name == n)
            };
            // The shortlisted, and the drift of each one's (and this cause's) parameter in the
            // other form: a rotary axis' line moving with or without what it carries, which a
            // step's shortlist may leave out when the other form stood ahead of it.
            let shortlisted: Vec<usize> = steps
                .iter()
                .flat_map(|s| &s.ranking)
                .filter(|r| r.cv_rms.is_some())
                .filter_map(|r| self.pool.by_name.get(&r.name).copied())
                .collect();
            let other_forms: Vec<usize> = shortlisted
                .iter()
                .map(|&ci| &pool[ci][0])
                .chain([&chosen[j].term])
                .filter_map(|t| self.other_form_of(t))
                .collect();
            let mut rivals: Vec<usize> = shortlisted
                .into_iter()
                .chain(other_forms)
                .filter(|&ci| !in_model(&pool[ci][0].name))
                .filter(|&ci| {
                    let width = pool[ci][0].width();
                    same_family(&pool[ci][0].family, &chosen[j].term.family)
                        && (width < chosen[j].term.width()
                            || (!simpler_only && width == chosen[j].term.width()))
                        && self.candidate(ci).requires() != Some(name.as_str())
                })
                .collect();
            rivals.sort_unstable();
            rivals.dedup();
            if rivals.is_empty() {
                continue;
            }
            let best = rivals
                .iter()
                .map(|&ci| {
                    let mut trial = chosen.clone();
                    self.take_entry(&mut trial[j], ci);
                    (self.rechoose_around(&mut trial, &[j], base_fit), trial)
                })
                .min_by(|a, b| a.0.total_cmp(&b.0));
            // A rival of as many coefficients must leave χ² lower by more than the threshold; a
            // simpler one must not leave it higher by as much (parsimony: what the data cannot
            // tell apart, the simpler cause says).
            let takes_its_place = |b: &(f64, Vec<Chosen>)| {
                if b.1[j].term.width() < chosen[j].term.width() {
                    b.0 < rss + EXCHANGE_CHI2 * variance
                } else {
                    b.0 < rss - EXCHANGE_CHI2 * variance
                }
            };
            let Some((trial_rss, mut trial)) = best.filter(takes_its_place) else {
                continue;
            };
            let before = &chosen[j].term;
            let projector = self.fit_without(chosen, j, base_fit);
            let old = projector.residual_part(&before.columns);
            let new = projector.residual_part(&trial[j].term.columns);
            let c = &mut trial[j];
            c.alternatives.retain(|a| *a != c.term.name);
            c.rivals.retain(|r| r.name != c.term.name);
            c.rivals.push(before.clone());
            if max_cosine(&new, &old) > 0.99 {
                c.alternatives.insert(0, before.name.clone());
            }
            // What the replaced cause could not be told from, in another form than the one
            // that took its place (a linear drift's, where a first-order one fits better), the
            // exchange has told apart.
            c.alternatives.retain(|a| {
                self.pool
                    .by_name
                    .get(a)
                    .is_none_or(|&ci| same_form(&pool[ci][0].family, &c.term.family))
            });
            c.separated_by = separating_hint(&c.term, &c.alternatives, pool);
            exchanged.push(Exchange {
                replaced: before.name.clone(),
                by: c.term.name.clone(),
                chi2_drop: (rss - trial_rss) / variance,
            });
            rss = trial_rss;
            *chosen = trial;
        }
        exchanged
    }

    /// Split: with two causes or more, a drift the search chose that two other drifts with its
    /// time dependence give together ([`equivalent_drifts`]) — the tool drifting where the lines
    /// of both rotary axes drift the same way — is tried as those two, each then free in its
    /// own time constant, the other causes chosen again beside them. Two lines drifting with
    /// time constants of their own first look like the tool drifting (their common part) and
    /// leave the rest to a cause that stands in for the difference. The split takes the place
    /// of the drift where it lowers χ² — against the drift unsplit, the others' time constants
    /// chosen again the same way — by more than the F test at `alpha` admits for its two more
    /// parameters (Bonferroni over the splits tried), and by as much in the differences
    /// between visits of the same pose ([`Searcher::within_poses_gain`]; against a base
    /// without the machine's ordinary errors a head's spindle growth was split into drifts of
    /// both lines, one of them 23 µm, on what those errors leave as a function of the pose);
    /// what then stands in for nothing leaves by the pruning. Each of the two is tried in the
    /// other form of its parameter too
    /// (a line moving with or without what it carries: the exact equivalents are of one form,
    /// the lines' drifts may be the other). Returns the splits made (each as the exchange of
    /// the drift for the first of the two).
    fn split(&self, chosen: &mut Vec<Chosen>, base_fit: &Projector) -> Vec<Exchange> {
        let mut made = Vec::new();
        if chosen.len() < 2 {
            return made;
        }
        let (_, fit) = self.fit_of(base_fit, &self.with(chosen, None));
        let splits: Vec<(usize, usize, usize)> = (0..chosen.len())
            .filter(|&j| chosen[j].term.width() == 1)
            .flat_map(|j| {
                let rest = self.fit_without(chosen, j, base_fit);
                equivalent_drifts(self.obs, &rest, &chosen[j].term, self.candidates)
                    .into_iter()
                    .filter_map(|(a, b)| {
                        let (&a, &b) = (self.pool.by_name.get(&a)?, self.pool.by_name.get(&b)?);
                        Some((j, a, b))
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        let in_model = |chosen: &[Chosen], ci: usize| {
            let name = &self.pool.variants[ci][0].name;
            chosen.iter().any(|c| &c.term.name == name)
        };
        let best = splits
            .iter()
            .filter(|&&(_, a, b)| !in_model(chosen, a) && !in_model(chosen, b))
            .map(|&(j, a, b)| {
                let mut trial = chosen.clone();
                let mut second = trial[j].clone();
                self.take_entry(&mut trial[j], a);
                self.take_entry(&mut second, b);
                for c in [&mut trial[j], &mut second] {
                    c.alternatives.clear();
                    c.rivals.clear();
                }
                trial.push(second);
                let added = trial.len() - 1;
                let mut rss = self.rechoose_around(&mut trial, &[j, added], base_fit);
                // Each of the two in the form that fits best.
                for k in [j, added] {
                    let Some(ci) = self
                        .other_form_of(&trial[k].term)
                        .filter(|&ci| !in_model(&trial, ci))
                    else {
                        continue;
                    };
                    let mut other = trial.clone();
                    self.take_entry(&mut other[k], ci);
                    let other_rss = self.rechoose_around(&mut other, &[k], base_fit);
                    if other_rss < rss {
                        (rss, trial) = (other_rss, other);
                    }
                }
                // Against the drift unsplit with the time constants chosen again the same way:
                // the split must earn its drop, not the others' time constants chosen anew.
                let mut unsplit_model = chosen.clone();
                let unsplit = self.rechoose_around(&mut unsplit_model, &[j], base_fit);
                (unsplit, rss, j, trial, unsplit_model)
            })
            .max_by(|a, b| (a.0 - a.1).total_cmp(&(b.0 - b.1)));
        let Some((unsplit, rss, j, mut trial, unsplit_model)) = best else {
            return made;
        };
        let added = trial.len() - 1;
        let p = f_test(unsplit, unsplit - rss, 2, fit.dof()) * splits.len() as f64;
        if p >= self.params.alpha {
            return made;
        }
        // The drop must show in the differences between visits of the same pose too, where what
        // the model lacks as a function of the pose drops out: against a base without the
        // machine's ordinary errors, their leftover passes the test above.
        if self.within_poses_gain(&unsplit_model, &trial, base_fit) * splits.len() as f64
            >= self.params.alpha
        {
            return made;
        }
        for k in [j, added] {
            let c = &mut trial[k];
            c.separated_by = separating_hint(&c.term, &[], &self.pool.variants);
        }
        made.push(Exchange {
            replaced: chosen[j].term.name.clone(),
            by: trial[j].term.name.clone(),
            chi2_drop: (unsplit - rss) / fit.residual_variance(),
        });
        *chosen = trial;
        made
    }

    /// How well the periodic cause `ci` (at a free period along a linear axis) predicts the
    /// residuals of the step's model (its fit `projector`) at positions of its axis it was not
    /// fitted to: the axis' distinct positions among the observations of nonzero weight `w` in
    /// [`DiagnoseParams::folds`] interleaved folds ([`Folds::by_position`]); for each, the cause's
    /// part beyond the model is fitted to the residuals outside the fold, its period chosen
    /// again on them alone (the grid's best and its other peaks, refined), and predicts the
    /// fold's. The RMS of the fold's residuals with that prediction taken off, as a fraction of
    /// theirs; `None` when the axis is not known.
    ///
    /// Hundreds of periods, each a different pattern at a few dozen positions, hold nearly any
    /// structure of the residuals for a while: the shape of ordinary errors a model lacks, seen
    /// at the poses an R-test's ball path visits, fitted by a pitch of 1.37 mm on positions
    /// 6 mm apart. A pitch error the axis has predicts between them; such a fit does not.
    fn between_positions(
        &self,
        variants: &SearchVariants,
        ci: usize,
        projector: &Projector,
        w: &DVec,
    ) -> Option<f64> {
        let t = variants.header(ci, 0);
        let axis = t.exposed_by.as_deref().and_then(|v| self.obs.variable(v))?;
        let include: Vec<bool> = w.iter().map(|&v| v > 0.0).collect();
        let folds = Folds::by_position(&axis.values, &include, self.params.folds);
        let trained: Vec<Vec<usize>> = folds
            .test
            .iter()
            .map(|test| {
                (0..include.len())
                    .filter(|&i| include[i] && test.binary_search(&i).is_err())
                    .collect()
            })
            .collect();
        let r = projector.weighted_residuals();
        // Each fold's profile of the grid: the fall of the training rows' residuals.
        let mut profiles = vec![Vec::new(); folds.test.len()];
        for v in 0..self.pool.variants[ci].len() {
            let beyond = projector.residual_part(&self.pool.columns(ci, v));
            for (profile, rows) in profiles.iter_mut().zip(&trained) {
                profile.push((v, fit_on_rows(&beyond, r, rows).0));
            }
        }
        let (mut without, mut with) = (0.0, 0.0);
        for ((test, rows), profile) in folds.test.iter().zip(&trained).zip(&profiles) {
            // Each peak's part beyond the model and its fit on the training rows, once.
            let fitted = |c: &DMat| {
                let beyond = projector.residual_part(c);
                let (gain, coefficients) = fit_on_rows(&beyond, r, rows);
                (gain, beyond, coefficients)
            };
            let score = Score::new(|t: &Term| -fitted(&t.columns).0);
            let &(best, top) = profile.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
            let (_, beyond, coefficients) = grid_peaks(profile, best, top)
                .into_iter()
                .map(|peak| match self.candidate(ci).refine(peak, &score) {
                    Some(t) => fitted(&t.columns),
                    None => fitted(&self.pool.columns(ci, peak)),
                })
                .max_by(|a, b| a.0.total_cmp(&b.0))?;
            for &i in test {
                without += r[i] * r[i];
                with += (r[i] - beyond.row(i).transpose().dot(&coefficients)).powi(2);
            }
        }
        (without > 0.0).then(|| (with / without).sqrt())
    }

    /// The F test's p-value that what the model `larger` fits better than `smaller` (two
    /// parameters fewer) within the poses is noise: the weighted residual sums of squares less
    /// their means over each pose ([`Projector::rss_within_poses`]), on the repeat visits less
    /// the drifts' parameters. Only an effect of time shows there.
    fn within_poses_gain(
        &self,
        smaller: &[Chosen],
        larger: &[Chosen],
        base_fit: &Projector,
    ) -> f64 {
        let poses = self.obs.poses();
        let within = |model: &[Chosen]| {
            self.fit_of(base_fit, &self.with(model, None))
                .1
                .rss_within_poses(&poses)
        };
        let ((before, repeats), (after, _)) = (within(smaller), within(larger));
        let drift_parameters: usize = larger
            .iter()
            .filter(|c| matches!(c.term.family, Family::Drift { .. }))
            .map(|c| c.term.width() + 1)
            .sum();
        f_test(
            before,
            before - after,
            2,
            repeats.saturating_sub(drift_parameters),
        )
    }

    /// Chosen term `c` replaced by pool entry `ci` (its first variant; its time constant or
    /// period to be chosen again).
    fn take_entry(&self, c: &mut Chosen, ci: usize) {
        (c.term, c.candidate, c.variant, c.component) = (
            self.pool.term(ci, 0).into_owned(),
            self.pool.source[ci],
            0,
            0,
        );
    }

    /// The time constants or periods of the chosen terms `first` chosen with the others fitted,
    /// then the others' beside them (over their grids: the value a cause took beside one
    /// replaced need not be near its best now), then theirs again; returns the weighted RSS of
    /// the model that results.
    fn rechoose_around(&self, chosen: &mut [Chosen], first: &[usize], base_fit: &Projector) -> f64 {
        let order = first
            .iter()
            .copied()
            .chain((0..chosen.len()).filter(|i| !first.contains(i)))
            .chain(first.iter().copied());
        for i in order {
            self.rechoose(chosen, i, base_fit);
        }
        self.fit_of(base_fit, &self.with(chosen, None)).1.rss_w()
    }

    /// The pool entry of a drift's twin in the other form of its parameter: a rotary axis' line
    /// moving with or without what it carries (`EX0B abs drift exp` of `EX0B drift exp`).
    fn other_form_of(&self, t: &Term) -> Option<usize> {
        let [p] = crate::candidate::drifted_parameters(t)[..] else {
            return None;
        };
        let other = t.name.replacen(p, &crate::instruments::other_form(p), 1);
        self.pool.by_name.get(&other).copied()
    }

    /// Reduction: entry by entry, the search may say with three causes what two say as well —
    /// two lines of a trunnion drifting apart first look like the tool drifting (their common
    /// part), then need two drifts of one line for the rest. Each cause in turn is taken out
    /// (with what builds on it) and the others exchanged ([`Searcher::exchange`]) in the
    /// smaller model; where that leaves χ² higher than the complete model's by less than
    /// [`EXCHANGE_CHI2`] (in units of its residual variance), the smaller model takes its place
    /// (the best such, again while three causes or more remain). A cause that leaves without an
    /// exchange is the pruning's to remove. Exchanges consider the other form of each
    /// shortlisted drift too, which the shortlist may have left out. Returns the exchanges made
    /// and the causes removed.
    fn reduce(
        &self,
        chosen: &mut Vec<Chosen>,
        steps: &[Step],
        base_fit: &Projector,
    ) -> (Vec<Exchange>, Vec<Pruned>) {
        let (mut exchanged, mut removed) = (Vec::new(), Vec::new());
        while chosen.len() >= 3 {
            let (_, fit) = self.fit_of(base_fit, &self.with(chosen, None));
            let limit = fit.rss_w() + EXCHANGE_CHI2 * fit.residual_variance();
            let best = (0..chosen.len())
                .filter_map(|j| {
                    let mut trial = chosen.clone();
                    let gone = self.remove(&mut trial, j, base_fit, true);
                    let (_, smaller) = self.fit_of(base_fit, &self.with(&trial, None));
                    let exchanges = self.exchange(&mut trial, steps, base_fit, &smaller);
                    if exchanges.is_empty() {
                        return None;
                    }
                    let (_, f) = self.fit_of(base_fit, &self.with(&trial, None));
                    (f.rss_w() < limit).then(|| (f.rss_w(), trial, gone, exchanges))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((_, trial, gone, exchanges)) = best else {
                break;
            };
            *chosen = trial;
            removed.extend(pruned_for(gone, PruneReason::Redundant));
            exchanged.extend(exchanges);
        }
        (exchanged, removed)
    }

    /// Chooses the period or time constant of chosen term `j` again, over all its candidate's
    /// variants and then refined, with the other chosen terms fitted, as the component it now is
    /// (the components of its candidate that stay, in order of entry). After a cause it was
    /// chosen and refined beside has left the model, the value it took there need not be the
    /// data's best without it: two periodic components drawn to one period on sparse positions
    /// each hold part of the other, and the one that stays must be found again alone.
    fn rechoose(&self, chosen: &mut [Chosen], j: usize, base_fit: &Projector) {
        let c = &chosen[j];
        let Some((value, _)) = hyper_of(&c.term.family, false) else {
            return;
        };
        let candidate = self.chosen_candidate(c);
        // A search's pool holds the variants; the final model's searcher has no pool.
        let entry = self.pool.source.iter().position(|&s| s == c.candidate);
        let built;
        let variants: &[Term] = match entry {
            Some(entry) => &self.pool.variants[entry],
            None => {
                built = candidate.variants(self.obs);
                &built
            }
        };
        let columns = |v: usize| match entry {
            Some(entry) => self.pool.columns(entry, v),
            None => Cow::Borrowed(&variants[v].columns),
        };
        let component = chosen[..j]
            .iter()
            .filter(|o| o.candidate == c.candidate)
            .count();
        let projector = self.fit_without(chosen, j, base_fit);
        let rss_with = |t: &Term| projector.rss_w() - projector.increment(&t.columns).delta_rss;
        let free = |t: &Term| !near_a_component(self.obs, t, chosen, c.candidate, Some(j));
        let increments = projector.increments(variants.len(), columns);
        let Some(best) = (0..variants.len())
            .filter(|&v| free(&variants[v]))
            .max_by(|&a, &b| increments[a].delta_rss.total_cmp(&increments[b].delta_rss))
        else {
            return;
        };
        let best_term = match entry {
            Some(entry) => self.pool.term(entry, best).into_owned(),
            None => variants[best].clone(),
        };
        let rechosen = candidate
            .refine(best, &Score::new(rss_with))
            .filter(|r| free(r) && rss_with(r) < rss_with(&best_term))
            .unwrap_or(best_term);
        let (term, variant) = if rss_with(&rechosen) < rss_with(&c.term) {
            (rechosen, best)
        } else if component != c.component {
            // The same period or time constant, under the name of the component it now is.
            let Some(same) = candidate.at(c.variant, value) else {
                return;
            };
            (same, c.variant)
        } else {
            return;
        };
        let c = &mut chosen[j];
        (c.term, c.variant, c.component) = (nth_component(term, component), variant, component);
    }

    /// Backward pruning: every cause is re-tested in the complete model (F test of removing it,
    /// Bonferroni-adjusted as when it entered, and its cross-validated gain); the weakest that
    /// fails leaves, with the causes that build on it, until all pass. Returns the names removed.
    /// `last`: the design and fit of the model `chosen` as the search left it; `fold_basis`: the
    /// base's fit on the test rows of `folds` ([`Projector::fold_basis`]).
    fn prune(
        &self,
        chosen: &mut Vec<Chosen>,
        folds: &Folds,
        fold_basis: &FoldBasis,
        base_fit: &Projector,
        last: (DMat, Projector),
    ) -> Vec<Pruned> {
        let y = &self.obs.values;
        let mut pruned = Vec::new();
        let mut last = Some(last);
        while !chosen.is_empty() {
            let (x, fit) = match last.take() {
                Some(last) => last,
                None => self.fit_of(base_fit, &self.with(chosen, None)),
            };
            let cv_full = fit.fold_fits(folds, &x, y, Some(fold_basis)).rms();
            let mut weakest: Option<(usize, f64, f64)> = None; // (index, p, cv ratio)
            for j in 0..chosen.len() {
                let (xr, reduced, p) = self.removal_test(chosen, j, base_fit, &fit);
                let ratio =
                    reduced.fold_fits(folds, &xr, y, Some(fold_basis)).rms() / cv_full.max(1e-300);
                let fails = p >= self.params.alpha || ratio < 1.0 + 0.5 * self.params.min_gain;
                if fails && weakest.is_none_or(|(_, bp, br)| p > bp || (p == bp && ratio < br)) {
                    weakest = Some((j, p, ratio));
                }
            }
            let Some((j, p_value, held_out_ratio)) = weakest else {
                break;
            };
            let gone = self.remove(chosen, j, base_fit, true);
            pruned.extend(pruned_for(
                gone,
                PruneReason::NotEarned {
                    p_value,
                    held_out_ratio,
                },
            ));
        }
        pruned
    }

    /// The design of `terms` (the base's, then others) and its fit, from the base's fit.
    fn fit_of(&self, base_fit: &Projector, terms: &[&Term]) -> (DMat, Projector) {
        let x = design(terms, self.obs.len());
        let fit = base_fit.extended_to(&x);
        (x, fit)
    }

    /// Removes chosen term `j` and, with `dependents`, what builds on it, and chooses the period
    /// or time constant of each term that stays again without them ([`Searcher::rechoose`]);
    /// returns the names removed, `j`'s first. `base_fit`: the fit of this searcher's base, or
    /// of a first part of it.
    fn remove(
        &self,
        chosen: &mut Vec<Chosen>,
        j: usize,
        base_fit: &Projector,
        dependents: bool,
    ) -> Vec<String> {
        let name = chosen.remove(j).term.name;
        let mut removed = vec![name];
        chosen.retain(|c| {
            let dependent =
                dependents && self.chosen_candidate(c).requires() == Some(removed[0].as_str());
            if dependent {
                removed.push(c.term.name.clone());
            }
            !dependent
        });
        for k in 0..chosen.len() {
            self.rechoose(chosen, k, base_fit);
        }
        removed
    }

    /// The model without chosen term `j` (and what builds on it): its design and fit, and the
    /// Bonferroni-adjusted p-value of the removal against the complete model's fit `full`.
    fn removal_test(
        &self,
        chosen: &[Chosen],
        j: usize,
        base_fit: &Projector,
        full: &Projector,
    ) -> (DMat, Projector, f64) {
        let (xr, fit) = self.fit_of(base_fit, &self.with(chosen, Some(j)));
        let k = full.rank().saturating_sub(fit.rank()).max(1);
        let p = (f_test(fit.rss_w(), fit.rss_w() - full.rss_w(), k, full.dof())
            * chosen[j].variants_tested as f64)
            .min(1.0);
        (xr, fit, p)
    }

    /// Base terms and chosen terms, without the chosen term `skip` and those that build on it.
    fn with<'c>(&'c self, chosen: &'c [Chosen], skip: Option<usize>) -> Vec<&'c Term> {
        let skipped = skip.map(|j| chosen[j].term.name.as_str());
        let mut t: Vec<&Term> = self.base.iter().collect();
        for (k, c) in chosen.iter().enumerate() {
            if Some(k) == skip
                || (skipped.is_some() && self.chosen_candidate(c).requires() == skipped)
            {
                continue;
            }
            t.push(&c.term);
        }
        t
    }

    /// Adjusted p-value of removing each chosen term from the complete model (fit `full`;
    /// `base_fit`: the base's).
    fn removal_p_values(
        &self,
        chosen: &[Chosen],
        base_fit: &Projector,
        full: &Projector,
    ) -> Vec<f64> {
        (0..chosen.len())
            .map(|j| self.removal_test(chosen, j, base_fit, full).2)
            .collect()
    }

    /// Removes, one at a time (the least determined first, with what builds on it), the causes
    /// that rest on the base's orders alone ([`order_widening`]): those the next order of every
    /// base error would hold, or whose size, with its cofactor widened by those orders, is within
    /// 2 u of zero. `base_fit`: the fit of this searcher's base under the weights the search
    /// ran with; returns the design and fit of the model that remains. The final model applies
    /// the same rule with the uncertainties of periods and time constants added
    /// ([`conclude`]); an outer fold's search, whose causes only predict its held-out rows,
    /// uses the cofactor alone.
    fn drop_resting_on_orders(
        &self,
        chosen: &mut Vec<Chosen>,
        base_fit: &Projector,
    ) -> (DMat, Projector) {
        let next = self.next_orders(self.base);
        let wide = (!chosen.is_empty() && !next.is_empty())
            .then(|| base_fit.extended(&design(&next.iter().collect::<Vec<_>>(), self.obs.len())));
        loop {
            let terms = self.with(chosen, None);
            let (x, fit) = self.fit_of(base_fit, &terms);
            let Some(wide) = wide.as_ref().filter(|_| !chosen.is_empty()) else {
                return (x, fit);
            };
            let causes = &terms[self.base.len()..];
            let coef = fit.coefficients(&self.obs.values);
            let scale = covariance_scale(self.obs, fit.residual_variance().sqrt());
            let mut at: usize = self.base.iter().map(Term::width).sum();
            let (z, held): (Vec<f64>, Vec<Option<Held>>) = causes
                .iter()
                .zip(order_widening(base_fit, wide, causes))
                .map(|(t, widening)| {
                    let k = t.width();
                    let c = coef.rows(at, k).into_owned();
                    at += k;
                    match widening {
                        Ok((_, wide)) => {
                            let estimates = t.estimates(c.as_slice(), &(wide * scale));
                            (largest_z(&estimates, t.width()), None)
                        }
                        Err(held) => (0.0, Some(held)),
                    }
                })
                .unzip();
            let Some((k, _)) = leaving(&held, |k| z[k]) else {
                return (x, fit);
            };
            self.remove(chosen, k, base_fit, true);
        }
    }

    /// The outer folds: for each, the base model and the whole search on the other folds
    /// predict it. `base_fit`: the base's fit under `w`, which
    /// each fold downdates for its held-out rows.
    fn held_out(
        &self,
        w: &DVec,
        base_fit: &Projector,
        outer: &Folds,
        progress: &dyn Progress,
    ) -> HeldOut {
        let obs = self.obs;
        let n = obs.len();
        // Per fold: (observation, base residual, diagnosed residual) of its held-out rows, and
        // the causes its search named.
        type FoldRun = (Vec<(usize, f64, f64)>, Vec<String>);
        let runs: Vec<FoldRun> = outer
            .test
            .par_iter()
            // One fold a job: a thread that finishes the search on all data takes a fold
            // another has not started (by default a thread takes a run of folds as one job).
            .with_max_len(1)
            .enumerate()
            .map(|(fold, test)| {
                let mut include = vec![true; n];
                let mut w_train = w.clone();
                for &i in test {
                    include[i] = false;
                    w_train[i] = 0.0;
                }
                let inner = Folds::blocked(
                    obs,
                    &include,
                    self.params.folds,
                    self.params.blocks_per_fold,
                );
                let fold_fit = base_fit.without_rows(test, &obs.values);
                let (found, completed_fit) =
                    self.search(&w_train, &inner, Some(fold), fold_fit.clone());
                // The fits of the training rows (the held-out ones have weight zero), extended
                // from the fold's base fit; their predictions at the held-out rows.
                let completed: Vec<Term> =
                    self.base.iter().chain(&found.completed).cloned().collect();
                let searcher = Searcher {
                    base: &completed,
                    ..*self
                };
                // As the final model does, a linear drift takes its first-order course where the
                // data say so, and the causes that rest on the base's orders alone leave.
                let mut chosen = found.chosen;
                if let Some(span) = record_span(obs) {
                    drift_courses(&searcher, &mut chosen, &completed_fit, span);
                }
                let x_base = design(&completed.iter().collect::<Vec<_>>(), n);
                let (x, fit) = searcher.drop_resting_on_orders(&mut chosen, &completed_fit);
                let held_out_residuals = |x: &DMat, fit: &Projector| -> Vec<f64> {
                    let coef = fit.coefficients(&obs.values);
                    test.iter()
                        .map(|&i| obs.values[i] - x.row(i).transpose().dot(&coef))
                        .collect()
                };
                let base = held_out_residuals(&x_base, &completed_fit);
                let diagnosed = held_out_residuals(&x, &fit);
                let residuals = test
                    .iter()
                    .enumerate()
                    .map(|(k, &i)| (i, base[k], diagnosed[k]))
                    .collect();
                let names = chosen.iter().map(|c| c.term.name.clone()).collect();
                progress.inc(1);
                (residuals, names)
            })
            .collect();
        let mut base = DVec::zeros(n);
        let mut diagnosed = DVec::zeros(n);
        let mut per_fold = Vec::new();
        for (residuals, names) in runs {
            for (i, b, d) in residuals {
                base[i] = b;
                diagnosed[i] = d;
            }
            per_fold.push(names);
        }
        HeldOut {
            folds: outer.test.len(),
            base_rms: rms(&base),
            base_max_abs: max_abs(&base),
            diagnosed_rms: rms(&diagnosed),
            diagnosed_max_abs: max_abs(&diagnosed),
            per_fold,
        }
    }
}

/// Upper-tail probability of the F test that `delta_rss` (on `k` new directions) is noise, given
/// the residual sum of squares `rss` before with `dof` degrees of freedom.
fn f_test(rss: f64, delta_rss: f64, k: usize, dof: usize) -> f64 {
    if dof <= k {
        return 1.0;
    }
    let rss_new = (rss - delta_rss).max(1e-300);
    let f = (delta_rss.max(0.0) / k as f64) / (rss_new / (dof - k) as f64);
    stats::f_sf(f, k as f64, (dof - k) as f64)
}

/// Highest harmonic order [`harmonic_families`] considers: a higher one is as likely a chance
/// ratio of two unrelated periods (the ratio's tolerance grows with the order).
const MAX_HARMONIC_ORDER: f64 = 6.0;

/// Periodic findings of one linear axis whose periods are the first's divided by 2, 3, … (at
/// most [`MAX_HARMONIC_ORDER`]) and whose amplitudes are not larger than the first's: harmonics
/// of one periodic error that is not a sine (a sawtooth, a pitch error with a sharp profile,
/// whose harmonics fall off — a sawtooth's as 1/k), said in one sentence so the reader does not
/// take them for independent causes. A component stronger than the wave it would belong to is
/// not its harmonic.
fn harmonic_families(findings: &[Finding]) -> Vec<Compound> {
    let amplitude = |f: &Finding| {
        f.estimates
            .iter()
            .find(|e| e.name == "amplitude")
            .map(|e| (e.value.abs(), e.uncertainty))
    };
    // (Along a rotary axis every error is a function over a turn and its harmonics are the
    // candidates' own form: they are not grouped.)
    let mut periodic: Vec<(&Finding, f64, f64)> = findings
        .iter()
        .filter_map(|f| {
            let h = f.hyper_parameter.as_ref()?;
            (matches!(f.family, Family::Periodic { .. }) && h.quantity != Quantity::AxisAngle)
                .then_some((f, h.value, h.uncertainty))
        })
        .collect();
    // Longest period first: the search may find a harmonic before its fundamental.
    periodic.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut notes = Vec::new();
    let mut used = vec![false; periodic.len()];
    for (i, &(f, p, u)) in periodic.iter().enumerate() {
        if used[i] {
            continue;
        }
        let mut members = vec![(1, f)];
        for (j, &(g, q, v)) in periodic.iter().enumerate().skip(i + 1) {
            if used[j] || g.exposed_by != f.exposed_by {
                continue;
            }
            let ratio = p / q;
            let k = ratio.round();
            // The ratio's uncertainty from both periods', and never tighter than 1 %.
            let u_ratio = (ratio * ((u / p).powi(2) + (v / q).powi(2)).sqrt()).max(0.01 * ratio);
            let weaker = match (amplitude(f), amplitude(g)) {
                (Some((a, ua)), Some((b, ub))) => b <= a + 2.0 * ua.hypot(ub),
                _ => false,
            };
            if (2.0..=MAX_HARMONIC_ORDER).contains(&k)
                && (ratio - k).abs() <= 2.0 * u_ratio
                && weaker
            {
                members.push((k as usize, g));
                used[j] = true;
            }
        }
        if members.len() > 1 {
            let names: Vec<String> = members
                .iter()
                .map(|(k, g)| format!("{} (harmonic {k})", g.name))
                .collect();
            let period = f
                .hyper_parameter
                .as_ref()
                .map(|h| h.quantity.format(h.value, h.uncertainty))
                .unwrap_or_default();
            notes.push(Compound {
                note: format!(
                    "{} are one periodic error of period {period} that is not a sine (its harmonics): a sawtooth or sharp-profiled pitch error, not independent causes",
                    names.join(", ")
                ),
                findings: members.iter().map(|(_, g)| g.name.clone()).collect(),
                estimate: None,
            });
        }
    }
    notes
}

/// Highest harmonic [`periodic_shapes`] tests: a sawtooth's 4th has a quarter of its
/// fundamental's amplitude, and higher ones alias onto lower ones at the spacings of practice.
const SHAPE_HARMONICS: usize = 4;

/// Fewest repeats over the travel measured for a periodic finding along a linear axis to be told
/// from a smooth component error ([`periodic_shapes`]): a ball screw's pitch or an encoder's
/// period (5–40 mm) repeats a dozen times or more over common strokes, while the base's
/// polynomial completion holds about one wave per π degrees (3–5 waves at degree 10–15), so a
/// wave of fewer repeats may be either.
const LONG_WAVE_PERIODS: f64 = 6.0;

/// Periodic findings along a linear axis (free period, not in a family: `covered`) whose shape
/// the data say is not a sine, or cannot say. Two cases, each said in one sentence:
/// - the series of its harmonics 2..K at the finding's period (K = 2 to [`SHAPE_HARMONICS`],
///   nested) explains significantly more once the final model (`fit`) holds the finding (F test,
///   Bonferroni over the findings and series tested, at [`COMPLETION_LEVEL`]: a statement about
///   the shape of a cause already earned, which like a completion costs little when wrong and
///   leaves a confident wrong shape when missed). A sawtooth seen at positions too few for its
///   harmonics to be found as causes of their own (each scanned over every period) comes out as
///   one sine whose period its harmonics' aliases may pull;
/// - else, when it repeats fewer than [`LONG_WAVE_PERIODS`] times over the travel measured:
///   a wave that long is also a smooth component error (a waviness the base's polynomial
///   completion does not reach), which these data cannot tell from a periodic error;
/// - else, when its period is one of several that fit about as well (`ambiguous`, by name) and
///   shorter than twice the mean step between the positions: there a sine of a free period fits
///   a periodic error of almost any period and shape, and the finding names the axis' periodic
///   error, not its period or shape.
fn periodic_shapes(
    searcher: &Searcher<'_>,
    chosen: &[Chosen],
    fit: &Projector,
    covered: &[String],
    ambiguous: &[String],
) -> Vec<Compound> {
    let obs = searcher.obs;
    let tested: Vec<(&Chosen, f64)> = chosen
        .iter()
        .filter(|c| !covered.contains(&c.term.name) && !exposed_by_rotary(obs, &c.term))
        .filter_map(|c| match c.term.family {
            Family::Periodic { period } => Some((c, period)),
            _ => None,
        })
        .collect();
    let tests = (tested.len() * (SHAPE_HARMONICS - 1)) as f64;
    tested
        .into_iter()
        .filter_map(|(c, period)| {
            let candidate = searcher.chosen_candidate(c);
            let harmonics: Vec<DMat> = (2..=SHAPE_HARMONICS)
                .map_while(|h| candidate.at(c.variant, period / h as f64).map(|t| t.columns))
                .collect();
            let series = (2..=harmonics.len() + 1)
                .map(|k| {
                    let columns = harmonics[..k - 1]
                        .iter()
                        .cloned()
                        .reduce(|a, b| hcat(&a, &b))
                        .expect("one harmonic");
                    let inc = fit.increment(&columns);
                    let p = f_test(fit.rss_w(), inc.delta_rss, inc.new_rank, fit.dof());
                    ((p * tests).min(1.0), k)
                })
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let name = &c.term.name;
            let note = match series {
                Some((p, k)) if p < COMPLETION_LEVEL => format!(
                    "{name} is one wave of a periodic error of period about {} that is not a sine (a sawtooth or sharp-profiled pitch error): {} significantly more ({}); the amplitude and period stated are those of the sine closest to it, and its harmonics' aliases at these positions may pull the period",
                    Quantity::Distance.format_value(period),
                    if k == 2 {
                        "its 2nd harmonic explains".to_string()
                    } else {
                        format!("its harmonics 2–{k} explain")
                    },
                    crate::report::p_text(p)
                ),
                _ => {
                    let (v, count, step) = position_step(obs, &[&c.term])?;
                    let travel = step * (count - 1) as f64;
                    if period * LONG_WAVE_PERIODS > travel {
                        format!(
                            "{name} repeats only {:.1} times over the {} of {} measured: a wave that long is also a smooth positioning error of {} of that shape (a waviness of the screw or guideway, a thermal bow), and these data cannot tell a periodic error from it; a measurement over a longer travel, where a periodic error repeats and a smooth error does not, would",
                            travel / period,
                            Quantity::Distance.format_value(travel),
                            v.name,
                            v.name
                        )
                    } else if ambiguous.contains(name) && period < 2.0 * step {
                        format!(
                        "{name} stands for a periodic error of {} whose period and shape these data do not determine: at {count} positions a mean step of {} apart, a sine of a period shorter than twice the step fits about as well at several periods, and so would a periodic error of another shape (a sawtooth, a stepped scale) seen through aliases; positions at a finer spacing would tell them apart",
                        v.name,
                        Quantity::Distance.format_value(step)
                    )
                    } else {
                        return None;
                    }
                }
            };
            Some(Compound {
                note,
                findings: vec![name.clone()],
                estimate: None,
            })
        })
        .collect()
}

/// The variable that exposes the terms `terms` (the first's), the number of its distinct values
/// where any of them acts and the mean step between those values.
fn position_step<'o>(
    obs: &'o Observations,
    terms: &[&Term],
) -> Option<(&'o crate::data::Variable, usize, f64)> {
    let v = obs.variable(terms.first()?.exposed_by.as_deref()?)?;
    let acting: Vec<f64> = (0..obs.len())
        .filter(|&i| {
            terms
                .iter()
                .any(|t| t.columns.row(i).iter().any(|x| *x != 0.0))
        })
        .map(|i| v.values[i])
        .collect();
    let positions = crate::basis::distinct_sorted(&acting);
    let step = (positions.last()? - positions.first()?) / (positions.len().max(2) - 1) as f64;
    Some((v, positions.len(), step))
}

/// Periodic components of one cause along a linear axis whose periods are no simple fractions
/// of each other, yet may be a single periodic error that is not a sine: at irregular but
/// coarse positions a sawtooth's harmonics show at alias periods, which [`harmonic_families`]'s
/// ratio test cannot see. For each group of two or more periodic components of one candidate
/// (not already in a family), the fundamental of a series of harmonics 1..K (K up to
/// [`MAX_HARMONIC_ORDER`]) is scanned over the cause's periods and refined at the series'
/// resolution; the group is said to be one non-sine error of that period when the series'
/// Akaike criterion (χ² in units of the final model's σ0² plus twice its parameters: two per
/// harmonic and the period) is no larger than the components' own (three each). Failing that,
/// when two or more components are shorter than twice the mean step between the positions, the
/// report says that these positions cannot tell one non-sine error from independent ones. The
/// components stay as found.
fn aliased_harmonic_families(
    searcher: &Searcher<'_>,
    chosen: &[Chosen],
    terms: &[Term],
    w: &DVec,
    s2: f64,
    covered: &[String],
) -> Vec<Compound> {
    let obs = searcher.obs;
    let n = obs.len();
    let base_len = terms.len() - chosen.len();
    let mut groups: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (k, c) in chosen.iter().enumerate() {
        if matches!(c.term.family, Family::Periodic { .. })
            && !covered.contains(&c.term.name)
            && !exposed_by_rotary(obs, &c.term)
        {
            groups.entry(c.candidate).or_default().push(k);
        }
    }
    let mut out = Vec::new();
    for group in groups.values().filter(|g| g.len() >= 2) {
        let rest: Vec<&Term> = terms
            .iter()
            .enumerate()
            .filter(|(i, _)| *i < base_len || !group.contains(&(i - base_len)))
            .map(|(_, t)| t)
            .collect();
        let projector = Projector::fit(&design(&rest, n), &obs.values, w);
        let rss_without = projector.rss_w();
        let members = group
            .iter()
            .map(|&k| chosen[k].term.columns.clone())
            .reduce(|a, b| hcat(&a, &b))
            .expect("two members");
        let rss_found = rss_without - projector.increment(&members).delta_rss;
        let aic_found = rss_found / s2 + 2.0 * (3 * group.len()) as f64;
        // The fundamental: any period of the cause's scan (an alias of the true one is as good
        // a start as the true one), refined at the series' own resolution.
        let c = &chosen[group[0]];
        let Some((_, span)) = period_and_span(obs, &c.term) else {
            continue;
        };
        let candidate = searcher.chosen_candidate(c);
        let grid: Vec<f64> = candidate
            .variants(obs)
            .into_iter()
            .filter_map(|t| match t.family {
                Family::Periodic { period } => Some(period),
                _ => None,
            })
            .collect();
        let series = |period: f64, harmonics: usize| -> Option<DMat> {
            (1..=harmonics)
                .map(|h| {
                    candidate
                        .at(c.variant, period / h as f64)
                        .map(|t| t.columns)
                })
                .collect::<Option<Vec<DMat>>>()?
                .into_iter()
                .reduce(|a, b| hcat(&a, &b))
        };
        let profile = |periods: &[f64], harmonics: usize| -> Vec<f64> {
            let columns: Vec<Option<DMat>> =
                periods.iter().map(|&p| series(p, harmonics)).collect();
            let empty = DMat::zeros(n, 0);
            projector
                .increments(periods.len(), |i| {
                    Cow::Borrowed(columns[i].as_ref().unwrap_or(&empty))
                })
                .into_iter()
                .zip(&columns)
                .map(|(inc, c)| match c {
                    Some(_) => rss_without - inc.delta_rss,
                    None => f64::INFINITY,
                })
                .collect()
        };
        let argmin = |v: &[f64]| (0..v.len()).min_by(|&a, &b| v[a].total_cmp(&v[b]));
        let mut best: Option<(f64, f64, usize)> = None; // (aic, period, K)
        for harmonics in 2..=MAX_HARMONIC_ORDER as usize {
            let coarse = profile(&grid, harmonics);
            let Some(i) = argmin(&coarse) else {
                continue;
            };
            // Between the best grid point's neighbours, a quarter of the series' resolution
            // apart in frequency.
            let (f_lo, f_hi) = (
                1.0 / grid[(i + 1).min(grid.len() - 1)].max(grid[i.saturating_sub(1)]),
                1.0 / grid[(i + 1).min(grid.len() - 1)].min(grid[i.saturating_sub(1)]),
            );
            let step = 1.0 / (4.0 * harmonics as f64 * span);
            let steps = ((f_hi - f_lo) / step).ceil().max(1.0) as usize;
            let fine: Vec<f64> = (0..=steps)
                .map(|j| 1.0 / (f_lo + (f_hi - f_lo) * j as f64 / steps as f64))
                .collect();
            let scores = profile(&fine, harmonics);
            let Some(j) = argmin(&scores) else {
                continue;
            };
            let (a, b) = (fine[j.saturating_sub(1)], fine[(j + 1).min(fine.len() - 1)]);
            let rss = |p: f64| profile(&[p], harmonics)[0];
            let (refined, r) = crate::basis::bounded_minimum(a, b, 1e-6 * (a - b).abs(), rss);
            let (period, r) = if r < scores[j] {
                (refined, r)
            } else {
                (fine[j], scores[j])
            };
            let aic = r / s2 + 2.0 * (2 * harmonics + 1) as f64;
            if best.is_none_or(|b| aic < b.0) {
                best = Some((aic, period, harmonics));
            }
        }
        let names: Vec<String> = group.iter().map(|&k| chosen[k].term.name.clone()).collect();
        let quantity = Quantity::Distance;
        let note = match best.filter(|b| b.0 <= aic_found) {
            Some((aic, period, harmonics)) => format!(
                "{} may be one periodic error of period {} that is not a sine (a sawtooth or sharp-profiled pitch error): the series of its harmonics 1–{harmonics} fits these data as well (Akaike criterion {aic:.1} against {aic_found:.1}), and at these positions its harmonics show at the periods found (aliases); positions at a finer or different spacing would tell the two readings apart",
                names.join(", "),
                quantity.format_value(period)
            ),
            None => {
                // Two or more components shorter than twice the mean step between the
                // positions: a non-sine error's harmonics alias there, and a few sines at free
                // periods fit almost any error at so few positions.
                let terms: Vec<&Term> = group.iter().map(|&k| &chosen[k].term).collect();
                let Some((v, count, step)) = position_step(obs, &terms) else {
                    continue;
                };
                let short = group
                    .iter()
                    .filter(|&&k| {
                        matches!(chosen[k].term.family, Family::Periodic { period } if period < 2.0 * step)
                    })
                    .count();
                if short < 2 {
                    continue;
                }
                format!(
                    "{} may be one periodic error that is not a sine (a sawtooth, a stepped scale) seen through aliases, or independent periodic errors: at {} positions of {} a mean step of {} apart, periods below twice the step are aliases of each other and of a non-sine error's harmonics, and a few sines at free periods fit almost any error there; positions at a finer spacing would tell them apart",
                    names.join(", "),
                    count,
                    v.name,
                    quantity.format_value(step)
                )
            }
        };
        out.push(Compound {
            note,
            findings: names,
            estimate: None,
        });
    }
    out
}

/// Drifts of one parameter found in two forms (linear and first-order, or a first-order drift
/// of the axis' zero beside an expansion about a point, which drifts the zero too): together
/// they describe a course neither has — a drift that rises and falls, or speeds up — over the
/// measured time only, which the report says in one sentence. `chosen[k]` is `findings[k]`'s
/// term; `change` gives the members' change of a parameter over the measured time.
fn compound_drifts(
    findings: &[Finding],
    chosen: &[Chosen],
    change: impl Fn(&[usize], &str) -> Option<Estimate>,
) -> Vec<Compound> {
    let drifted: Vec<Vec<&str>> = chosen
        .iter()
        .map(|c| match c.term.family {
            Family::Drift { .. } => crate::candidate::drifted_parameters(&c.term),
            _ => Vec::new(),
        })
        .collect();
    let mut stems: Vec<&str> = Vec::new();
    for &stem in drifted.iter().flatten() {
        if !stems.contains(&stem) {
            stems.push(stem);
        }
    }
    stems
        .into_iter()
        .filter_map(|stem| {
            let members: Vec<usize> = (0..chosen.len())
                .filter(|&k| drifted[k].contains(&stem))
                .collect();
            if members.len() < 2 {
                return None;
            }
            let names: Vec<String> = members.iter().map(|&k| findings[k].name.clone()).collect();
            let estimate = change(&members, stem);
            Some(Compound {
                note: format!(
                    "{} are one drift of {stem} whose course is neither linear nor a first-order settling (it may rise and fall): together they describe it over the measured time, not beyond it{}",
                    names.join(" and "),
                    estimate.as_ref().map_or(String::new(), |e| format!(
                        "; together they change {stem} by {} over the measured time",
                        e.text
                    ))
                ),
                findings: names,
                estimate,
            })
        })
        .collect()
}

/// The readings the final fit (`sol`, `fit`, weights `w`) misses by far more than the rest:
/// whitened residuals over `√(1 − leverage)`, in units of their robust scatter (1.4826 × the
/// median absolute deviation, which a few gross errors do not inflate), beyond the two-sided
/// normal quantile at `alpha` / n — the level at which the largest of n normal residuals would
/// pass by chance. Largest first.
fn outlying_readings(
    obs: &Observations,
    w: &DVec,
    sol: &Solution,
    fit: &Projector,
    alpha: f64,
) -> Vec<Outlier> {
    let h = fit.leverages();
    let rows: Vec<usize> = (0..obs.len()).filter(|&i| w[i] > 0.0).collect();
    if rows.len() < 10 {
        return Vec::new();
    }
    let u: Vec<f64> = (0..obs.len())
        .map(|i| w[i] * sol.residuals[i] / (1.0 - h[i]).max(1e-12).sqrt())
        .collect();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let m = v.len() / 2;
        if v.len() % 2 == 0 {
            0.5 * (v[m - 1] + v[m])
        } else {
            v[m]
        }
    };
    let centre = median(rows.iter().map(|&i| u[i]).collect());
    let scatter = 1.4826 * median(rows.iter().map(|&i| (u[i] - centre).abs()).collect());
    if scatter.is_nan() || scatter <= 0.0 {
        return Vec::new();
    }
    let limit = stats::normal_quantile(1.0 - 0.5 * alpha / rows.len() as f64);
    let mut out: Vec<Outlier> = rows
        .iter()
        .map(|&i| (i, (u[i] - centre) / scatter))
        .filter(|(_, z)| z.abs() > limit)
        .map(|(i, z)| Outlier {
            observation: i,
            setup: obs.setup_names[obs.setup[i]].clone(),
            channel: obs.channel_names[obs.channel[i]].clone(),
            at: obs
                .variables
                .iter()
                .map(|v| (v.name.clone(), v.values[i]))
                .collect(),
            place: obs
                .variables
                .iter()
                .map(|v| {
                    let x = v.values[i];
                    match v.kind {
                        VariableKind::LinearAxis => format!("{} = {x:.3} mm", v.name),
                        VariableKind::RotaryAxis => format!("{} = {:.3}°", v.name, x.to_degrees()),
                        VariableKind::Time => format!("{} = {x:.0} s", v.name),
                        VariableKind::Direction => {
                            format!("{} {}", v.name, if x > 0.0 { "+" } else { "−" })
                        }
                    }
                })
                .collect::<Vec<_>>()
                .join(", "),
            residual: sol.residuals[i],
            text: crate::report::level(obs.quantity, sol.residuals[i]),
            z,
        })
        .collect();
    out.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
    out
}

/// Share of a finding's own effect (what the rest of the final model does not hold) that other
/// causes together may leave for them all to give the same readings: an identity of the
/// machine's geometry on these poses, not a near miss of the data.
const EQUIVALENT_SHARE: f64 = 1e-9;

/// Most sets of causes [`equivalent_sets`] names.
const EQUIVALENT_SETS: usize = 3;

/// Pairs of drifts of other parameters, with the same time dependence, that together give the
/// readings the drift finding `term` gives ([`equivalent_sets`]). On an R-test the ball sees
/// only the tool relative to the table: the lines of both rotary axes drifting together in X
/// are the tool drifting the other way. The pairs' names, in the library's order.
fn equivalent_drifts(
    obs: &Observations,
    rest: &Projector,
    term: &Term,
    candidates: &[Box<dyn Candidate>],
) -> Vec<(String, String)> {
    let Family::Drift { time_constant_s } = term.family else {
        return Vec::new();
    };
    // Every other drift cause with the finding's time dependence.
    let others: Vec<Term> = candidates
        .iter()
        .filter(|c| c.role() == Role::Cause)
        .filter_map(|c| match time_constant_s {
            Some(tau) => c.at(0, tau),
            None => (c.columns(obs) == 1)
                .then(|| c.variants(obs).pop())
                .flatten(),
        })
        .filter(|t| {
            t.width() == 1
                && t.name != term.name
                && matches!(t.family, Family::Drift { time_constant_s: tc } if tc == time_constant_s)
        })
        .collect();
    equivalent_sets(rest, term, &others.iter().collect::<Vec<_>>(), 2)
        .into_iter()
        .map(|set| (others[set[0]].name.clone(), others[set[1]].name.clone()))
        .collect()
}

/// The causes constant in time of one shape and one column among `candidates`: what
/// [`equivalent_constants`] combines.
fn single_constants(obs: &Observations, candidates: &[Box<dyn Candidate>]) -> Vec<Term> {
    candidates
        .iter()
        .filter(|c| c.role() == Role::Cause && c.requires().is_none() && c.columns(obs) == 1)
        .filter_map(|c| c.variants(obs).pop())
        .filter(constant_in_time)
        .collect()
}

/// Whether a term's effect does not change in time nor with a period the data choose.
fn constant_in_time(t: &Term) -> bool {
    !matches!(
        t.family,
        Family::Drift { .. } | Family::Periodic { .. } | Family::Base
    )
}

/// Sets of two or three of the causes `singles` ([`single_constants`]) outside the final model
/// (`in_model`), that together give the readings the constant finding `term` gives
/// ([`equivalent_sets`]: pairs, or triples where no pair does): from tracker lengths with the
/// stations free, the tracker's length scale is a common scale error of X, Y and Z,
/// `EXX scale`, `EYY scale` and `EZZ scale` alike. Each set's names joined, in the library's
/// order.
fn equivalent_constants(
    rest: &Projector,
    term: &Term,
    singles: &[Term],
    in_model: &dyn Fn(&str) -> bool,
) -> Vec<String> {
    if !constant_in_time(term) || term.width() != 1 {
        return Vec::new();
    }
    let others: Vec<&Term> = singles
        .iter()
        .filter(|t| t.name != term.name && !in_model(&t.name))
        .collect();
    equivalent_sets(rest, term, &others, 3)
        .into_iter()
        .map(|set| {
            let names: Vec<&str> = set.iter().map(|&i| others[i].name.as_str()).collect();
            let (last, first) = names.split_last().expect("a set has two or three");
            format!("{} and {last} together", first.join(", "))
        })
        .collect()
}

/// The smallest sets, of two or up to `largest` (at most 3) of the single-column terms
/// `others`, that together give the readings the single-column finding `term` gives: beyond the
/// rest of the final model (its fit `rest`), all but [`EQUIVALENT_SHARE`] of the finding's
/// effect is theirs, and no smaller part of a set holds it. Pairs where there are any, else
/// triples; the sets as indices into `others`, in their order, at most [`EQUIVALENT_SETS`].
fn equivalent_sets(
    rest: &Projector,
    term: &Term,
    others: &[&Term],
    largest: usize,
) -> Vec<Vec<usize>> {
    if others.len() < 2 || term.width() != 1 {
        return Vec::new();
    }
    let mut d = DMat::zeros(term.columns.nrows(), others.len() + 1);
    d.set_column(0, &term.columns.column(0));
    for (k, t) in others.iter().enumerate() {
        d.set_column(k + 1, &t.columns.column(0));
    }
    // Beyond the rest of the model: the finding's effect (column 0) and each other's.
    let r = rest.residual_part(&d);
    let g = tr_mul(&r, &r);
    let own = g[(0, 0)];
    if own <= 0.0 {
        return Vec::new();
    }
    let tolerance = EQUIVALENT_SHARE * own;
    // What is left of the finding's effect after the best combination of a set of design
    // columns; a set whose columns are nearly dependent beyond the rest holds nothing (its
    // combination would carry rounding far above the share asked for).
    let left = |set: &[usize]| {
        let k = set.len();
        let gs = DMat::from_fn(k, k, |i, j| g[(set[i], set[j])]);
        let gv = DVec::from_fn(k, |i, _| g[(set[i], 0)]);
        let scale: f64 = set.iter().map(|&a| g[(a, a)]).product();
        if gs.determinant() <= 1e-6 * scale {
            return own;
        }
        gs.cholesky().map_or(own, |ch| own - gv.dot(&ch.solve(&gv)))
    };
    let holds = |set: &[usize]| left(set) < tolerance;
    // Columns something is left of beyond the rest, that do not hold the effect alone.
    let free: Vec<usize> = (1..=others.len())
        .filter(|&a| g[(a, a)] > 1e-12 * d.column(a).norm_squared() && !holds(&[a]))
        .collect();
    let sets_of = |size: usize| {
        let mut sets: Vec<Vec<usize>> = Vec::new();
        'search: for (x, &a) in free.iter().enumerate() {
            for (y, &b) in free.iter().enumerate().skip(x + 1) {
                if size == 2 {
                    if holds(&[a, b]) {
                        sets.push(vec![a, b]);
                    }
                } else if !holds(&[a, b]) {
                    for &c in &free[y + 1..] {
                        if !holds(&[a, c]) && !holds(&[b, c]) && holds(&[a, b, c]) {
                            sets.push(vec![a, b, c]);
                        }
                    }
                }
                if sets.len() >= EQUIVALENT_SETS {
                    break 'search;
                }
            }
        }
        sets
    };
    (2..=largest.min(3))
        .map(sets_of)
        .find(|sets| !sets.is_empty())
        .unwrap_or_default()
        .into_iter()
        .take(EQUIVALENT_SETS)
        .map(|set| set.into_iter().map(|a| a - 1).collect())
        .collect()
}

/// A note for each first-order drift whose time constant is the shortest its candidate searches
/// (within 1 %): the drift may be faster than the data can follow, and its change larger than
/// stated.
fn drifts_at_the_shortest(searcher: &Searcher<'_>, chosen: &[Chosen]) -> Vec<String> {
    let obs = searcher.obs;
    let tau_of = |t: &Term| match t.family {
        Family::Drift {
            time_constant_s: Some(tau),
        } => Some(tau),
        _ => None,
    };
    chosen
        .iter()
        .filter_map(|c| {
            let tau = tau_of(&c.term)?;
            let shortest = searcher
                .chosen_candidate(c)
                .variants(obs)
                .iter()
                .filter_map(tau_of)
                .fold(f64::INFINITY, f64::min);
            (tau <= 1.01 * shortest).then(|| {
                let revisit = obs.revisit_interval();
                let why = if revisit.map(crate::candidate::shortest_time_constant) == Some(shortest) {
                    "a third of the interval between two visits of a pose, below which the drift is over before most poses are seen twice"
                } else {
                    "a twentieth of the measured time"
                };
                format!(
                    "the time constant of {} is the shortest searched ({shortest:.0} s, {why}): the drift may be faster, and then its change over the measured time is larger in size than stated",
                    c.term.name
                )
            })
        })
        .collect()
}

/// The change over the measured time (first reading to last) of the parameter `stem` whose
/// drift the findings `members` (indices into `chosen`) describe together, with its standard
/// uncertainty by the delta method over the final model's covariance `cov` of the coefficients
/// (each chosen term's columns from `offsets`; of each member the coefficient that drifts
/// `stem`, [`crate::candidate::drifted_parameters`]) and of the time constants (`hyper_rows`):
/// a linear drift's rate × T, a first-order one's `A (1 − e^(−T/τ))`. `None` where no member
/// drifts `stem` or the data have no time.
#[allow(clippy::too_many_arguments)]
fn drift_change(
    obs: &Observations,
    chosen: &[Chosen],
    members: &[usize],
    stem: &str,
    offsets: &[usize],
    coef: &DVec,
    cov: &DMat,
    hyper_rows: &[Option<usize>],
) -> Option<Estimate> {
    let t = &obs.variable_of_kind(VariableKind::Time)?.values;
    let span = t.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - t.iter().copied().fold(f64::INFINITY, f64::min);
    let mut g = DVec::zeros(cov.nrows());
    let (mut value, mut quantity) = (0.0, None);
    for &k in members {
        let term = &chosen[k].term;
        let Family::Drift { time_constant_s } = term.family else {
            continue;
        };
        let Some(j) = crate::candidate::drifted_parameters(term)
            .iter()
            .position(|&p| p == stem)
        else {
            continue;
        };
        let at = offsets[k] + j;
        let a = coef[at];
        quantity = Some(accumulated(term.coefficients[j].1));
        match time_constant_s {
            None => {
                value += a * span;
                g[at] = span;
            }
            Some(tau) => {
                let e = (-span / tau).exp();
                value += a * (1.0 - e);
                g[at] = 1.0 - e;
                if let Some(r) = hyper_rows[k] {
                    g[r] = -a * span * e / (tau * tau);
                }
            }
        }
    }
    let quantity = quantity?;
    let u = g.dot(&(cov * &g)).max(0.0).sqrt();
    Some(Estimate::new(
        format!("{stem} change over the measured time"),
        value,
        u,
        quantity,
    ))
}

/// The first design column of each of `terms`, laid out one after another from column `first`.
fn column_offsets<'a>(first: usize, terms: impl IntoIterator<Item = &'a Term>) -> Vec<usize> {
    terms
        .into_iter()
        .scan(first, |at, t| {
            let start = *at;
            *at += t.width();
            Some(start)
        })
        .collect()
}

/// What a rate of `q` accumulates to over time (a length for a length rate); other quantities
/// as they are.
fn accumulated(q: Quantity) -> Quantity {
    match q {
        Quantity::LengthRate => Quantity::Length,
        Quantity::AngleRate => Quantity::Angle,
        Quantity::RatioRate => Quantity::Ratio,
        q => q,
    }
}

/// For a drift found linear (`c`, over a record of `span` s): where the first-order drift of the
/// same parameter (its twin in the library, [`drift_twin`]) would settle, by its profile over
/// time constants from a thirtieth of the record (`profile`, [`settling_intervals`]), and the
/// 95 % intervals of its parameters' changes over the record, a linear course (the longest
/// time constants) among those admitted. `None` where the library has no such candidate.
fn first_order_fit(
    candidates: &[Box<dyn Candidate>],
    obs: &Observations,
    c: &Chosen,
    span: f64,
    profile: impl Fn(&Tunable<'_>) -> Option<Profiled>,
) -> Option<(FirstOrderFit, Vec<Interval>)> {
    let (twin, term) = drift_twin(candidates, obs, c, span)?;
    let profiled = profile(&Tunable {
        candidate: candidates[twin].as_ref(),
        variant: 0,
        component: 0,
        value: span,
    })?;
    let fit = FirstOrderFit {
        name: term.name,
        time_constant_s: profiled.time_constant,
        final_value: *profiled.final_values.first()?,
        quantity: accumulated(c.term.coefficients.first()?.1),
    };
    Some((fit, profiled.changes))
}

/// The time from the first reading to the last, s (`None` without a time column).
fn record_span(obs: &Observations) -> Option<f64> {
    obs.variable_of_kind(VariableKind::Time).map(|t| {
        let (lo, hi) = crate::basis::range(&t.values);
        hi - lo
    })
}

/// The other form of drift `c` on the observations `obs` (`span`: the record's, s): for a
/// linear drift `"{stem} drift"` the first-order one `"{stem} drift exp"` that builds on the same
/// term (its candidate, and its term at a time constant of the span), and the other way round;
/// `None` for any other term, or where the candidates have no such twin.
fn drift_twin(
    candidates: &[Box<dyn Candidate>],
    obs: &Observations,
    c: &Chosen,
    span: f64,
) -> Option<(usize, Term)> {
    let (twin, first_order) = match c.term.name.strip_suffix(" drift exp") {
        Some(stem) => (format!("{stem} drift"), false),
        None => (
            format!("{} drift exp", c.term.name.strip_suffix(" drift")?),
            true,
        ),
    };
    let required = candidates.get(c.candidate)?.requires();
    candidates
        .iter()
        .enumerate()
        .filter(|(_, k)| k.requires() == required)
        .find_map(|(i, k)| {
            // (A linear drift has no time constant to set: its one variant.)
            let t = match k.at(0, span) {
                Some(t) => first_order.then_some(t),
                None if !first_order => k.variants(obs).into_iter().next(),
                None => None,
            }?;
            (t.name == twin).then_some((i, t))
        })
}

/// Each drift in the form its data earn: a first-order drift's time constant is one parameter
/// more than its linear twin ([`drift_twin`], the limit of a time constant beyond the record),
/// and the first-order form holds only where, with the rest of the model fitted, it leaves χ²
/// lower than the linear one by more than [`EXCHANGE_CHI2`] (in the model's residual
/// variance) — the search's exchange threshold. A linear drift is offered its first-order twin
/// (the time constant chosen over the candidate's grid and refined): the search's exchange
/// offers that rival only while a first-order drift of the same displacement that entered later
/// is still in the model, and once the final model lets that one go (its size undetermined
/// beside the linear one, the two being nearly one column) the linear drift would be left to
/// carry a course it does not have. A first-order drift is offered its linear twin: it entered
/// on a cross-validated RMS a little better than the linear one's, which on a few hundred
/// readings is a smaller gain than a time constant must earn. Each drift takes the form the
/// test gives in `chosen` (`span`: the record's, s); returns the exchanges.
fn drift_courses(
    searcher: &Searcher<'_>,
    chosen: &mut Vec<Chosen>,
    base_fit: &Projector,
    span: f64,
) -> Vec<Exchange> {
    let mut exchanged = Vec::new();
    let is_drift = |c: &Chosen| matches!(c.term.family, Family::Drift { .. });
    if !chosen.iter().any(is_drift) {
        return exchanged;
    }
    let (_, fit) = searcher.fit_of(base_fit, &searcher.with(chosen, None));
    let variance = fit.residual_variance();
    let mut rss = fit.rss_w();
    for k in 0..chosen.len() {
        let Some((twin, term)) = drift_twin(searcher.candidates, searcher.obs, &chosen[k], span)
        else {
            continue;
        };
        let to_first_order = term.name.ends_with(" drift exp");
        let mut trial = chosen.clone();
        (
            trial[k].term,
            trial[k].candidate,
            trial[k].variant,
            trial[k].component,
        ) = (term, twin, 0, 0);
        if to_first_order {
            searcher.rechoose(&mut trial, k, base_fit);
        }
        let (_, trial_fit) = searcher.fit_of(base_fit, &searcher.with(&trial, None));
        let drop = rss - trial_fit.rss_w();
        let earned = EXCHANGE_CHI2 * variance;
        if (to_first_order && drop > earned) || (!to_first_order && drop > -earned) {
            let by = trial[k].term.name.clone();
            // The data told the forms apart: the linear drifts listed as alternatives of a
            // first-order one go too.
            trial[k]
                .alternatives
                .retain(|a| *a != by && !(to_first_order && a.ends_with(" drift")));
            exchanged.push(Exchange {
                replaced: chosen[k].term.name.clone(),
                by,
                chi2_drop: drop / variance,
            });
            rss = trial_fit.rss_w();
            *chosen = trial;
        }
    }
    exchanged
}

/// Gives each change over the measured time of the drift finding `f` (of the term `drift`) its
/// 95 % interval by the profile over the time constant (`changes`, one per drifted parameter,
/// [`Profiled::changes`]; [`with_profile_interval`]): what the change may be in either form of
/// drift, with the time constant the data leave open. (A drift found linear whose course is
/// first-order, of a time constant near the record's, has a change the straight line misses by
/// more than its u.)
fn with_change_intervals(f: &mut Finding, drift: &Term, changes: Vec<Interval>) {
    for (stem, profile) in crate::candidate::drifted_parameters(drift)
        .into_iter()
        .zip(changes)
    {
        let name = format!("{stem} change over the measured time");
        if let Some(e) = f.estimates.iter_mut().find(|e| e.name == name) {
            *e = with_profile_interval(e, profile);
        }
    }
}

/// The estimate `e` with its 95 % interval by a profile: a closed interval never narrower than
/// the linearisation's ± 2 u (which holds the widenings for repeated poses and the base's
/// orders); an open one the profile's (the linearisation says nothing of a drift that need not
/// settle).
fn with_profile_interval(e: &Estimate, profile: Interval) -> Estimate {
    let interval = match (profile.lower, profile.upper) {
        (Some(l), Some(u)) => Interval {
            lower: Some(l.min(e.value - 2.0 * e.uncertainty)),
            upper: Some(u.max(e.value + 2.0 * e.uncertainty)),
        },
        _ => profile,
    };
    e.clone().with_interval(interval)
}

/// A term to profile over its hyper-parameter ([`settling_intervals`], [`period_intervals`]): a
/// candidate's variant (and the component of a recurring cause) re-evaluated at any time
/// constant or period, from `value`, the one found.
struct Tunable<'a> {
    candidate: &'a dyn Candidate,
    variant: usize,
    component: usize,
    value: f64,
}

/// One point of a profile over a hyper-parameter ([`Tunable::profile_point`]).
struct ProfilePoint {
    /// The hyper-parameter's value.
    at: f64,
    /// Weighted RSS of the model with the term at that value.
    rss: f64,
    /// The term's coefficients there.
    coef: DVec,
    /// Their cofactor conditional on the value (times the covariance scale: their covariance).
    cofactor: DMat,
}

impl Tunable<'_> {
    /// The term at the hyper-parameter value `at` fitted beside the rest of the model (`rest`,
    /// the fit without it; `yw` the whitened observations). `None` where the candidate cannot
    /// re-evaluate it or its columns are singular beside the rest.
    fn profile_point(&self, rest: &Projector, yw: &DVec, at: f64) -> Option<ProfilePoint> {
        let term = nth_component(self.candidate.at(self.variant, at)?, self.component);
        let cw = rest.residual_part(&term.columns);
        let cofactor = cw.tr_mul(&cw).try_inverse()?;
        let b = cw.tr_mul(yw);
        let coef = &cofactor * &b;
        Some(ProfilePoint {
            at,
            rss: rest.rss_w() - b.dot(&coef),
            coef,
            cofactor,
        })
    }
}

/// A coordinate of a hyper-parameter (log τ, a period's frequency) and back.
type Coordinate = (fn(f64) -> f64, fn(f64) -> f64);

/// Where a profile crosses `limit` between an admitted point and its neighbour outside, in the
/// coordinate `coordinate` of the hyper-parameter (the profile taken as linear in it).
fn profile_crossing(
    inner: &ProfilePoint,
    outer: &ProfilePoint,
    limit: f64,
    coordinate: Coordinate,
) -> f64 {
    let (to, from) = coordinate;
    let f = ((limit - inner.rss) / (outer.rss - inner.rss)).clamp(0.0, 1.0);
    from(to(inner.at) + f * (to(outer.at) - to(inner.at)))
}

/// What the profile of a first-order drift over its time constant bounds
/// ([`settling_intervals`]), each a 95 % interval.
struct Profiled {
    /// The time constant, s.
    time_constant: Interval,
    /// Each coefficient: the value its parameter settles to, beyond the record.
    final_values: Vec<Interval>,
    /// Each coefficient's change over the record, `A (1 − e^(−T/τ))`: closed, as the course
    /// of a drift that need not settle tends to a linear one's.
    changes: Vec<Interval>,
}

/// A first-order drift's time constant and coefficients (the values it settles to, beyond the
/// record) by profile likelihood: the `drift` at each time constant of a log grid from a
/// thirtieth of the one found to a thousand records (`span`, s), fitted beside the rest of the
/// final model (`rest`, the fit without it; `yw` the whitened observations): the weighted RSS
/// and the coefficients at each. The 95 % intervals hold the values whose profile χ² lies within
/// 4 · `scale` of the least (`rss_final` at the time constant found, or below it on the grid):
/// for a coefficient, at each admitted time constant its conditional interval narrowed by the
/// RSS that time constant costs. The time constant's interval is open at an end of the grid the
/// profile still admits; a coefficient's only where the longest time constant is admitted (a
/// drift that need not settle within the record has no final value on that side; towards the
/// shortest, a drift becomes a step of bounded size). The change over the record, the same
/// interval scaled at each time constant by how far the drift has come, `1 − e^(−T/τ)`, is
/// always closed. `None` where the candidate cannot re-evaluate the drift.
fn settling_intervals(
    drift: &Tunable<'_>,
    rest: &Projector,
    yw: &DVec,
    rss_final: f64,
    scale: f64,
    span: f64,
) -> Option<Profiled> {
    const COARSE: usize = 48;
    const FINE: usize = 64;
    let tau = drift.value;
    let at = |t: f64| drift.profile_point(rest, yw, t);
    let log_grid = |lo: f64, hi: f64, m: usize| {
        (0..m).map(move |i| lo * (hi / lo).powf(i as f64 / (m - 1) as f64))
    };
    // A coarse grid over the whole range, then a fine one over the admitted part and a step
    // beyond each end.
    let (lo, hi) = (tau / 30.0, (1000.0 * span).max(30.0 * tau));
    let coarse: Vec<_> = log_grid(lo, hi, COARSE)
        .map(at)
        .collect::<Option<Vec<_>>>()?;
    let least = coarse.iter().map(|p| p.rss).fold(rss_final, f64::min);
    let inside = |p: &ProfilePoint| p.rss - least < 4.0 * scale;
    let first = coarse.iter().position(inside).unwrap_or(0);
    let last = coarse.iter().rposition(inside).unwrap_or(COARSE - 1);
    let (from, to) = (
        coarse[first.saturating_sub(1)].at,
        coarse[(last + 1).min(COARSE - 1)].at,
    );
    let mut profile: Vec<_> = log_grid(from, to, FINE)
        .chain([tau])
        .map(at)
        .collect::<Option<Vec<_>>>()?;
    profile.extend(coarse);
    profile.sort_by(|a, b| a.at.total_cmp(&b.at));
    profile.dedup_by(|a, b| (a.at - b.at).abs() <= 1e-9 * b.at);
    let least = profile.iter().map(|p| p.rss).fold(least, f64::min);
    let inside = |p: &ProfilePoint| p.rss - least < 4.0 * scale;
    let admitted: Vec<_> = profile.iter().filter(|p| inside(p)).collect();
    let first = profile.iter().position(inside)?;
    let last = profile.iter().rposition(inside)?;
    let n = profile.len();
    let open_high = last == n - 1;
    // An end of the time constant's interval: where the profile crosses 4 between the admitted
    // point and its neighbour outside (linear in RSS against log τ).
    let limit = least + 4.0 * scale;
    let log: Coordinate = (f64::ln, f64::exp);
    let tau_interval = Interval {
        lower: (first > 0)
            .then(|| profile_crossing(&profile[first], &profile[first - 1], limit, log)),
        upper: (!open_high)
            .then(|| profile_crossing(&profile[last], &profile[last + 1], limit, log)),
    };
    // Coefficient j times `factor(τ)` over the admitted time constants: (least, greatest).
    let bounds = |j: usize, factor: &dyn Fn(f64) -> f64| {
        let (mut lower, mut upper) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &admitted {
            let half = ((4.0 * scale - (p.rss - least)) * p.cofactor[(j, j)])
                .max(0.0)
                .sqrt();
            lower = lower.min((p.coef[j] - half) * factor(p.at));
            upper = upper.max((p.coef[j] + half) * factor(p.at));
        }
        (lower, upper)
    };
    let coefficients = 0..profile[0].coef.len();
    let final_values = coefficients
        .clone()
        .map(|j| {
            let (lower, upper) = bounds(j, &|_| 1.0);
            // Open where the admitted range reaches the longest time constant, towards where
            // the coefficient goes as the time constant grows.
            let grows = profile[n - 1].coef[j] > profile[n - 2].coef[j];
            Interval {
                lower: (!open_high || grows).then_some(lower),
                upper: (!open_high || !grows).then_some(upper),
            }
        })
        .collect();
    let changes = coefficients
        .map(|j| {
            let (lower, upper) = bounds(j, &|tau| 1.0 - (-span / tau).exp());
            Interval {
                lower: Some(lower),
                upper: Some(upper),
            }
        })
        .collect();
    Some(Profiled {
        time_constant: tau_interval,
        final_values,
        changes,
    })
}

/// Whether the 95 % interval `profile` reaches beyond the estimate's linearised ± 2 u by more
/// than a twentieth of it on either side (a quadratic profile gives that interval itself).
fn reaches_beyond(e: &Estimate, profile: &Interval) -> bool {
    let margin = 2.1 * e.uncertainty;
    profile.lower.is_none_or(|l| l < e.value - margin)
        || profile.upper.is_none_or(|u| u > e.value + margin)
}

/// The 95 % intervals of a periodic finding's period and amplitude by profile likelihood: the
/// term (`periodic`, from the period found) at the periods of a fine grid in frequency over its
/// main lobe, within one Fourier resolution (1/`span`, the range its exposing variable covers)
/// of the one found, fitted beside the rest of the final model (`rest`, the fit without it;
/// `yw` the whitened observations). The linearisation's ± u holds where that profile is
/// quadratic; at a few irregular positions, beside a smooth base of high order, it can be flat
/// or hold two shallow minima, and the period found is then one of many the data allow (periods
/// farther off are the ambiguous modes, [`period_modes`]). Both intervals hold the values whose
/// profile χ² lies within 4 · `scale` of the least (`rss_final` at the period found, or below it
/// on the grid); the amplitude's, at each admitted period, its conditional interval narrowed
/// by the RSS that period costs. `None` where the candidate cannot re-evaluate the term or its
/// size is not the amplitude of a sine and a cosine.
fn period_intervals(
    periodic: &Tunable<'_>,
    rest: &Projector,
    yw: &DVec,
    rss_final: f64,
    scale: f64,
    span: f64,
) -> Option<(Interval, Interval)> {
    const GRID: usize = 81;
    let f0 = 1.0 / periodic.value;
    let mut profile: Vec<ProfilePoint> = (0..GRID)
        .map(|i| f0 + (2.0 * i as f64 / (GRID - 1) as f64 - 1.0) / span)
        .filter(|f| *f > 0.0)
        .map(f64::recip)
        .chain([periodic.value])
        .map(|p| periodic.profile_point(rest, yw, p))
        .collect::<Option<_>>()?;
    if profile.iter().any(|p| p.coef.len() != 2) {
        return None;
    }
    profile.sort_by(|a, b| a.at.total_cmp(&b.at));
    let least = profile.iter().map(|p| p.rss).fold(rss_final, f64::min);
    let limit = least + 4.0 * scale;
    let inside = |p: &ProfilePoint| p.rss < limit;
    let first = profile.iter().position(inside)?;
    let last = profile.iter().rposition(inside)?;
    // Linear in frequency; an admitted end of the grid bounds the interval there (farther off
    // are other modes).
    let frequency: Coordinate = (f64::recip, f64::recip);
    let end = |i: usize, outside: Option<usize>| match outside {
        Some(o) => profile_crossing(&profile[i], &profile[o], limit, frequency),
        None => profile[i].at,
    };
    let period = Interval {
        lower: Some(end(first, first.checked_sub(1))),
        upper: Some(end(last, (last + 1 < profile.len()).then_some(last + 1))),
    };
    let (mut lower, mut upper) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in profile.iter().filter(|p| inside(p)) {
        let (amplitude, cofactor) =
            crate::term::amplitude_and_variance(p.coef[0], p.coef[1], &p.cofactor);
        let half = ((limit - p.rss) * cofactor).max(0.0).sqrt();
        lower = lower.min(amplitude - half);
        upper = upper.max(amplitude + half);
    }
    let amplitude = Interval {
        lower: Some(lower.max(0.0)),
        upper: Some(upper),
    };
    Some((period, amplitude))
}

/// Drifts found in one form (linear or first-order) whose course the data say is another: a
/// smooth curve of the same parameter in time (its column times Legendre polynomials of degree
/// 1–4 in t; of both parameters an expansion about a point drifts) still explains significantly
/// more once the final model holds them (F test,
/// Bonferroni over the drifts tested, at [`COMPLETION_LEVEL`] as for a periodic finding's shape
/// in [`periodic_shapes`]; `fit`: the final model's). Said in one sentence: the finding
/// describes a drift of that parameter, not its course.
fn drift_shapes(
    obs: &Observations,
    candidates: &[Box<dyn Candidate>],
    chosen: &[Chosen],
    terms: &[Term],
    left_out: &[Term],
    fit: &Projector,
    covered: &[String],
) -> Vec<Compound> {
    let Some(t) = obs.variable_of_kind(crate::data::VariableKind::Time) else {
        return Vec::new();
    };
    let drifts: Vec<&Term> = chosen
        .iter()
        .map(|c| &c.term)
        .filter(|t| matches!(t.family, Family::Drift { .. }) && !covered.contains(&t.name))
        .collect();
    if drifts.is_empty() {
        return Vec::new();
    }
    let curve = crate::basis::legendre_columns(&t.values, 1..=4);
    drifts
        .iter()
        .filter_map(|d| {
            // The drifting terms (an expansion about a point drifts the scale and the zero): in
            // the model, or a combination of model terms (an absolute location error when the
            // relative ones are in the base: a candidate, or a base term left out as such).
            let (stems, constants): (Vec<&str>, Vec<DVec>) =
                crate::candidate::drifted_parameters(d)
                    .into_iter()
                    .filter_map(|stem| {
                        let constant = match terms.iter().chain(left_out).find(|t| t.name == stem)
                        {
                            Some(t) => t.columns.column(0).into_owned(),
                            None => library_constant(candidates, obs, stem)?,
                        };
                        Some((stem, constant))
                    })
                    .unzip();
            if stems.is_empty() {
                return None;
            }
            let stem = stems.join(" and ");
            let mut cols = DMat::zeros(obs.len(), curve.ncols() * constants.len());
            for (j, constant) in constants.iter().enumerate() {
                for (k, c) in curve.column_iter().enumerate() {
                    cols.set_column(j * curve.ncols() + k, &c.component_mul(constant));
                }
            }
            let inc = fit.increment(&cols);
            let p = (f_test(fit.rss_w(), inc.delta_rss, inc.new_rank, fit.dof())
                * drifts.len() as f64)
                .min(1.0);
            (inc.new_rank > 0 && p < COMPLETION_LEVEL).then(|| Compound {
                note: format!(
                    "{} describes a drift of {stem} whose course is neither linear nor a first-order settling (it may rise and fall): a smooth curve of {stem} in time explains significantly more ({}); the estimate holds over the measured time only",
                    d.name,
                    crate::report::p_text(p)
                ),
                findings: vec![d.name.clone()],
                estimate: None,
            })
        })
        .collect()
}

/// Whether `t` is an ordinary error every machine has ([`crate::Shorthand::of_ordinary`]): a
/// component error of an axis, an error motion of a rotary axis over a turn, a squareness, a
/// location error. The search adds those the base leaves out before any drift or periodic
/// error at a free period ([`is_flexible`]).
fn is_ordinary(obs: &Observations, t: &Term) -> bool {
    let per_turn = crate::candidate::per_turn(obs, &t.family, t.exposed_by.as_deref());
    crate::candidate::Shorthand::of_ordinary(&t.family, per_turn).is_some()
}

/// Whether `t` is a drift or a periodic error that is not an ordinary error motion over a turn
/// ([`is_ordinary`]): a cause whose shape the data choose (its period or time constant among
/// hundreds, its course in time along the order the poses were measured in), which can take
/// the shape of an ordinary error the model lacks for its own.
fn is_flexible(obs: &Observations, t: &Term) -> bool {
    matches!(t.family, Family::Drift { .. } | Family::Periodic { .. }) && !is_ordinary(obs, t)
}

/// Whether `t` waits while an ordinary error the base leaves out earns its place: a flexible
/// cause ([`is_flexible`]), or an error of the instrument's set-up (a ball's centring, the
/// nest's offset), whose readings, one set-up's poses each, take the part of the shape a
/// missing ordinary error leaves at those poses (on clean R-tests against the location-only
/// default, a nest or centring offset entered at the first steps).
fn waits_for_ordinary(obs: &Observations, t: &Term) -> bool {
    is_flexible(obs, t) || t.family == Family::Setup
}

/// Whether the variable that exposes `t` is a rotary axis (its periods are angles).
fn exposed_by_rotary(obs: &Observations, t: &Term) -> bool {
    crate::candidate::is_rotary(obs, t.exposed_by.as_deref())
}

/// The period or time constant of a term, with the quantity it is reported in (a period along a
/// rotary axis in degrees).
fn hyper_of(family: &Family, rotary: bool) -> Option<(f64, Quantity)> {
    match family {
        Family::Periodic { period } if rotary => Some((*period, Quantity::AxisAngle)),
        Family::Periodic { period } => Some((*period, Quantity::Distance)),
        Family::Drift {
            time_constant_s: Some(tau),
        } => Some((*tau, Quantity::Duration)),
        _ => None,
    }
}

/// The design augmented by hyper-parameter derivative columns ([`hyper_augmented`]): the
/// solution on it, the chosen term and hyper-parameter value of each added column, the design.
type Augmented = (Solution, Vec<(usize, f64)>, DMat);

/// The residuals of the model with design `x` (solution `sol`) regressed on that design
/// augmented by the derivative column of every chosen term's period or time constant: the
/// augmented solution, and for each added column the chosen term and its hyper-parameter, and
/// the augmented design. `None` when no chosen term has one the candidate can re-evaluate.
fn hyper_augmented(
    searcher: &Searcher<'_>,
    chosen: &[Chosen],
    x: &DMat,
    sol: &Solution,
    w: &DVec,
) -> Option<Augmented> {
    let p = x.ncols();
    let mut col = p - chosen.iter().map(|c| c.term.width()).sum::<usize>();
    let mut extra: Vec<(usize, f64, DVec)> = Vec::new(); // (chosen, value, derivative)
    for (k, c) in chosen.iter().enumerate() {
        let width = c.term.width();
        if let Some((h, _)) = hyper_of(&c.term.family, false) {
            let step = 1e-4 * h.abs().max(1e-12);
            let cand = searcher.chosen_candidate(c);
            if let (Some(plus), Some(minus)) =
                (cand.at(c.variant, h + step), cand.at(c.variant, h - step))
            {
                let coef = sol.coef.rows(col, width);
                extra.push((k, h, (plus.columns - minus.columns) * coef / (2.0 * step)));
            }
        }
        col += width;
    }
    if extra.is_empty() {
        return None;
    }
    let mut aug = DMat::zeros(x.nrows(), p + extra.len());
    aug.columns_mut(0, p).copy_from(x);
    for (e, (_, _, d)) in extra.iter().enumerate() {
        aug.column_mut(p + e).copy_from(d);
    }
    let aug_sol = solve(&aug, &sol.residuals, w);
    Some((
        aug_sol,
        extra.into_iter().map(|(k, h, _)| (k, h)).collect(),
        aug,
    ))
}

/// Δχ² below which another period explains the residual about as well as the chosen one.
const MODE_CHI2: f64 = 10.0;

/// Grid peaks refined at most, the best among them: in the search, of a scanned candidate
/// ([`grid_peaks`]), and when a finding's other periods are sought ([`period_modes`]). At a few
/// irregular positions a periodic error has dozens of aliases whose grid points come within
/// [`PEAK_SHARE`] of the best, and the true period, refined, is often not among the first few
/// on the grid (a handful refined found an alias of a third of the amplitude on 3 datasets in
/// 200 of the axis' 2 µm pitch cell).
const MAX_PEAKS: usize = 48;

/// Share of the best grid point's reduction of the RSS a peak must reach to be refined: a grid
/// point half a step (a quarter of the Fourier resolution) off a sine's optimum keeps about
/// sinc²(¼) ≈ 0.81 of it.
const PEAK_SHARE: f64 = 0.7;

/// Indices of the local maxima of `values`: not below either neighbour (an end, its one).
fn local_maxima(values: &[f64]) -> Vec<usize> {
    (0..values.len())
        .filter(|&i| {
            (i == 0 || values[i] >= values[i - 1])
                && (i + 1 == values.len() || values[i] >= values[i + 1])
        })
        .collect()
}

/// The local maxima of a scanned candidate's profile `(variant, RSS reduction)` (variants in
/// grid order) that come within [`PEAK_SHARE`] of the best variant `best` (reduction `top`):
/// the best first, then the others by their reduction, at most [`MAX_PEAKS`] in all.
fn grid_peaks(profile: &[(usize, f64)], best: usize, top: f64) -> Vec<usize> {
    let reductions: Vec<f64> = profile.iter().map(|p| p.1).collect();
    let mut peaks: Vec<(usize, f64)> = local_maxima(&reductions)
        .into_iter()
        .map(|i| profile[i])
        .filter(|&(v, d)| v != best && d >= PEAK_SHARE * top)
        .collect();
    peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
    std::iter::once(best)
        .chain(peaks.into_iter().map(|p| p.0))
        .take(MAX_PEAKS)
        .collect()
}

/// Another period of a periodic finding that fits about as well (an alias of the positions).
struct PeriodMode {
    period: f64,
    /// Weighted RSS above the chosen period's, in units of σ0².
    delta_chi2: f64,
    /// Amplitude at that period, mm (or rad).
    amplitude: f64,
}

/// A periodic term's period and the range its exposing variable covers in the data.
fn period_and_span(obs: &Observations, t: &Term) -> Option<(f64, f64)> {
    let Family::Periodic { period } = t.family else {
        return None;
    };
    let v = obs.variable(t.exposed_by.as_deref()?)?;
    let (lo, hi) = crate::basis::range(&v.values);
    Some((period, hi - lo))
}

/// The local optima of the profile of the periodic term `term` of the final model (solution
/// `sol`; `projector`: the fit of the model without it) over its candidate's grid, away from
/// the chosen period by more than the Fourier resolution, whose fit is within [`MODE_CHI2`] of
/// the chosen one's; best first. Every grid optimum within [`PEAK_SHARE`] of the chosen
/// period's fit is refined (at most [`MAX_PEAKS`]): at few positions a periodic error has many
/// aliases, and the grid alone cannot rank them.
fn period_modes(
    obs: &Observations,
    projector: &Projector,
    sol: &Solution,
    term: &Term,
    candidate: &dyn Candidate,
) -> Vec<PeriodMode> {
    let Some((p0, span)) = period_and_span(obs, term) else {
        return Vec::new();
    };
    let rss_without = projector.rss_w();
    let delta0 = projector.increment(&term.columns).delta_rss;
    let s2 = (sol.rss_w / sol.dof().max(1) as f64).max(1e-300);
    let grid: Vec<(f64, Term)> = candidate
        .variants(obs)
        .into_iter()
        .filter_map(|t| match t.family {
            Family::Periodic { period } => Some((period, t)),
            _ => None,
        })
        .collect();
    // A period whose sine and cosine the rest of the model nearly holds has no determined
    // amplitude (it would take any size at no cost): not a rival mode (a reduction of zero).
    let reduction = |inc: &Increment, t: &Term| {
        if inc.new_rank == t.width() && inc.separability >= SEPARABILITY_TOLERANCE {
            inc.delta_rss
        } else {
            0.0
        }
    };
    let increments = projector.increments(grid.len(), |i| Cow::Borrowed(&grid[i].1.columns));
    let profile: Vec<(f64, f64, Term)> = grid
        .into_iter()
        .zip(increments)
        .map(|((period, t), inc)| (period, reduction(&inc, &t), t))
        .collect();
    // Local optima on the grid, away from the chosen period, the best few refined between their
    // grid neighbours (a grid point can sit half a step off its optimum).
    let reductions: Vec<f64> = profile.iter().map(|p| p.1).collect();
    let mut optima: Vec<usize> = local_maxima(&reductions)
        .into_iter()
        .filter(|&i| (1.0 / profile[i].0 - 1.0 / p0).abs() > 1.0 / span)
        .collect();
    optima.sort_by(|&a, &b| profile[b].1.total_cmp(&profile[a].1));
    optima.retain(|&i| profile[i].1 >= PEAK_SHARE * delta0);
    optima.truncate(MAX_PEAKS);
    let score = refine_score(projector, rss_without);
    let refined: Vec<(f64, f64, Term)> = optima
        .into_iter()
        .map(|i| {
            let (q, d, t) = &profile[i];
            match candidate.refine(i, &score) {
                Some(r) => match r.family {
                    Family::Periodic { period } => {
                        (period, reduction(&projector.increment(&r.columns), &r), r)
                    }
                    _ => (*q, *d, t.clone()),
                },
                None => (*q, *d, t.clone()),
            }
        })
        .collect();
    let mut modes: Vec<(f64, f64, &Term)> = refined
        .iter()
        .map(|(q, d, t)| (*q, (delta0 - d) / s2, t))
        .filter(|(q, chi2, _)| (1.0 / q - 1.0 / p0).abs() > 1.0 / span && *chi2 < MODE_CHI2)
        .collect();
    modes.sort_by(|a, b| a.1.total_cmp(&b.1));
    modes
        .into_iter()
        .map(|(period, delta_chi2, t)| {
            let coef = projector.extended(&t.columns).coefficients(&obs.values);
            let k = coef.len();
            PeriodMode {
                period,
                delta_chi2,
                amplitude: coef[k - 2].hypot(coef[k - 1]),
            }
        })
        .collect()
}

/// Refines the periods and time constants of the chosen terms by Gauss–Newton steps on the
/// searcher's observations (the coefficients of the derivative columns in
/// [`hyper_augmented`] are the steps); a step is kept while it lowers the weighted RSS.
fn gauss_newton_hyper(searcher: &Searcher<'_>, chosen: &mut [Chosen], w: &DVec) {
    let n = searcher.obs.len();
    let rss_of = |chosen: &[Chosen]| {
        let x = design(&searcher.with(chosen, None), n);
        let sol = solve(&x, &searcher.obs.values, w);
        (x, sol)
    };
    for _ in 0..3 {
        let (x, sol) = rss_of(chosen);
        let Some((steps, hyper, _)) = hyper_augmented(searcher, chosen, &x, &sol, w) else {
            return;
        };
        let mut moved = chosen.to_vec();
        for (e, (k, h)) in hyper.iter().enumerate() {
            let c = &mut moved[*k];
            if let Some(t) = searcher
                .chosen_candidate(c)
                .at(c.variant, h + steps.coef[x.ncols() + e])
            {
                c.term = nth_component(t, c.component);
            }
        }
        let rss = rss_of(&moved).1.rss_w;
        if rss.is_nan() || rss >= sol.rss_w {
            return;
        }
        chosen.clone_from_slice(&moved);
    }
}

/// Cofactor of the coefficients of the final model, widened by the uncertainty of the chosen
/// terms' periods and time constants: the design is augmented by each hyper-parameter's
/// derivative column (Gauss–Newton at the optimum, [`hyper_augmented`]), whose block of the
/// inverse normal matrix then carries its variance. Returns the covariance of the coefficients
/// (the first `x.ncols()` rows) and of the hyper-parameters after them, and each chosen term's
/// hyper-parameter row (`None` without one, or where the candidate cannot re-evaluate it;
/// rotary harmonics are exact and have none).
fn covariance_with_hyper(
    searcher: &Searcher<'_>,
    chosen: &[Chosen],
    terms: &[Term],
    x: &DMat,
    sol: &Solution,
    w: &DVec,
    scale: f64,
) -> (DMat, Vec<Option<usize>>) {
    let p = x.ncols();
    let mut hyper = vec![None; chosen.len()];
    let (cofactor, extra, aug) = match hyper_augmented(searcher, chosen, x, sol, w) {
        Some((aug_sol, extra, aug)) => (aug_sol.cofactor, extra, Cow::Owned(aug)),
        None => (sol.cofactor.clone(), Vec::new(), Cow::Borrowed(x)),
    };
    // One block per term, then one per hyper-parameter.
    let mut blocks: Vec<(usize, usize)> = Vec::new();
    let mut at = 0;
    for t in terms {
        blocks.push((at, t.width()));
        at += t.width();
    }
    blocks.extend((0..extra.len()).map(|e| (p + e, 1)));
    let factors = pose_widening(
        searcher.obs,
        &aug,
        &cofactor,
        &sol.residuals,
        w,
        &blocks,
        scale,
    );
    let mut d = DVec::from_element(cofactor.nrows(), scale.sqrt());
    for (&(start, width), f) in blocks.iter().zip(&factors) {
        for j in start..start + width {
            d[j] *= f.sqrt();
        }
    }
    let cov = DMat::from_fn(cofactor.nrows(), cofactor.ncols(), |i, j| {
        cofactor[(i, j)] * d[i] * d[j]
    });
    for (e, (k, _)) in extra.iter().enumerate() {
        if cov[(p + e, p + e)] > 0.0 {
            hyper[*k] = Some(p + e);
        }
    }
    (cov, hyper)
}

/// Per block of parameters (`(first, width)` in the design `a`, cofactor `cof`, residuals `r`),
/// the factor (at least 1) by which the variances of the classic covariance `cof · scale` are
/// widened where the residuals are not independent between observations of the same pose
/// ([`Observations::poses`]: a misfit of the model at a pose repeats in every visit, so the
/// effective number of observations is nearer the number of poses). The cluster-robust
/// (sandwich) covariance with poses as clusters, `cof · (Σ_g s_g s_gᵀ) · cof` with
/// `s_g = Σ_{i∈g} a_iᵀ w_i² r_i` and the small-sample factor `G/(G−1) · (n−1)/(n−p)`, is
/// compared with the classic one over each block: the factor is the largest ratio of their
/// variances over the block's directions. Data without a repeated pose keep the classic one
/// (one observation per cluster says nothing of dependence).
fn pose_widening(
    obs: &Observations,
    a: &DMat,
    cof: &DMat,
    r: &DVec,
    w: &DVec,
    blocks: &[(usize, usize)],
    scale: f64,
) -> Vec<f64> {
    let ones = vec![1.0; blocks.len()];
    let pose = obs.poses();
    let g = pose.iter().max().map_or(0, |m| m + 1);
    let n = w.iter().filter(|w| **w > 0.0).count();
    let pa = a.ncols();
    if g < 2 || g >= n || n <= pa + 1 {
        return ones;
    }
    let mut s = DMat::zeros(pa, g);
    for i in 0..a.nrows() {
        let f = w[i] * w[i] * r[i];
        if f != 0.0 {
            for j in 0..pa {
                s[(j, pose[i])] += a[(i, j)] * f;
            }
        }
    }
    let correction = g as f64 / (g - 1) as f64 * (n - 1) as f64 / (n - pa) as f64;
    let bread = cof * &s;
    let sandwich = &bread * bread.transpose() * correction;
    blocks
        .iter()
        .map(|&(start, width)| {
            let classic = cof.view((start, start), (width, width)) * scale;
            let robust = sandwich.view((start, start), (width, width)).into_owned();
            // Largest generalised eigenvalue of (robust, classic) over the directions the
            // classic covariance has.
            let eig = classic.symmetric_eigen();
            let top = eig.eigenvalues.max();
            if top.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return 1.0;
            }
            let keep: Vec<usize> = (0..width)
                .filter(|&k| eig.eigenvalues[k] > 1e-12 * top)
                .collect();
            let root = DMat::from_fn(width, keep.len(), |i, j| {
                eig.eigenvectors[(i, keep[j])] / eig.eigenvalues[keep[j]].sqrt()
            });
            let ratio = root.transpose() * robust * &root;
            let lambda = if ratio.nrows() == 0 {
                1.0
            } else {
                ratio.symmetric_eigen().eigenvalues.max()
            };
            if lambda.is_finite() {
                lambda.max(1.0)
            } else {
                1.0
            }
        })
        .collect()
}

/// The variant called `name` of the library's candidates that `admit` lets through, on all
/// observations.
fn library_variant(
    candidates: &[Box<dyn Candidate>],
    obs: &Observations,
    name: &str,
    admit: impl Fn(&dyn Candidate) -> bool,
) -> Option<Term> {
    candidates
        .iter()
        .filter(|c| admit(c.as_ref()))
        .flat_map(|c| c.variants(obs))
        .find(|t| t.name == name)
}

/// The power of the search's test against a sine-and-cosine cause: P(χ²(2, λ) > `critical`)
/// tabulated once per step on a grid of √λ and interpolated, so that averaging it over phases
/// ([`PowerCurve::amplitude_limit`]) for hundreds of variants costs no more than the scan.
struct PowerCurve {
    /// Grid step in √λ.
    step: f64,
    power: Vec<f64>,
}

impl PowerCurve {
    /// Grid points; the curve rises from its level to 1 within about ±8 of √`critical` in √λ,
    /// where linear interpolation is within 1e-4 of it.
    const POINTS: usize = 512;

    fn new(critical: f64) -> PowerCurve {
        let top = critical.sqrt() + 10.0;
        let step = top / (Self::POINTS - 1) as f64;
        let power = (0..Self::POINTS)
            .map(|i| stats::noncentral_chi2_sf(critical, 2.0, (i as f64 * step).powi(2)))
            .collect();
        PowerCurve { step, power }
    }

    fn at(&self, lambda: f64) -> f64 {
        let x = lambda.max(0.0).sqrt() / self.step;
        let i = x.floor() as usize;
        if i + 1 >= self.power.len() {
            return 1.0;
        }
        let f = x - i as f64;
        self.power[i] * (1.0 - f) + self.power[i + 1] * f
    }

    /// The amplitude found with probability [`DETECTION_POWER`] when its phase is drawn
    /// uniformly: with `lo`, `hi` the least and most whitened sum of squares a unit amplitude
    /// leaves beyond the model ([`Increment::beyond`]), one at phase φ leaves
    /// λ = a²·(hi·cos²φ + lo·sin²φ)/σ². The power is averaged over φ (midpoint rule on a quarter
    /// turn, which the symmetry of cos² makes the whole turn). Where the model holds one phase
    /// (`lo` ≈ 0), the causes at phases near it go unseen at any size and the limit is large.
    fn amplitude_limit(&self, (lo, hi): (f64, f64), sigma2: f64) -> f64 {
        const PHASES: usize = 16;
        let share: Vec<f64> = (0..PHASES)
            .map(|i| {
                let phi = (i as f64 + 0.5) / PHASES as f64 * std::f64::consts::FRAC_PI_2;
                phi.cos().powi(2) + lo / hi * phi.sin().powi(2)
            })
            .collect();
        let power = |u: f64| share.iter().map(|s| self.at(u * s)).sum::<f64>() / PHASES as f64;
        // u = a²·hi/σ².
        let u = stats::bisect_increasing(power, DETECTION_POWER, 0.0, 1.0);
        (u * sigma2 / hi).sqrt()
    }
}

/// The largest |estimate| / u of a term's estimates: below 2 its size is not determined.
fn largest_z(estimates: &[Estimate], width: usize) -> f64 {
    estimates
        .iter()
        .take(width)
        .map(|e| e.value.abs() / e.uncertainty.max(1e-300))
        .fold(0.0, f64::max)
}

/// A p-value's logarithm with its last digits dropped ([`rounded`]): a choice between
/// candidates whose tests differ by rounding alone is then made by their order, not by the
/// rounding. (Of the logarithm: a very significant test's, −150 and beyond, carries the
/// rounding of its F statistic in digits an absolute 1e-9 would keep.)
fn rounding_free(p: f64) -> f64 {
    rounded(p.max(f64::MIN_POSITIVE).ln())
}

/// `x` with its last digits dropped (to a relative 1e-9): what rounding alone (another CPU,
/// another summation order, another projection) can change of a figure is gone.
fn rounded(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let unit = 10f64.powi(x.abs().log10().floor() as i32 - 9);
    (x / unit).round() * unit
}

/// A candidate's place by significance, `(p-value, what it explains)`: the smallest p-value
/// first, then the most explained. What differs by rounding alone does not rank
/// ([`rounding_free`], [`rounded`]).
fn significance_rank((p, explained): (f64, f64)) -> (f64, f64) {
    (rounding_free(p), -rounded(explained))
}

/// Sorts candidates by significance ([`significance_rank`] of `key(c)`, worked out once per
/// candidate). Candidates the data cannot tell apart keep their order, the library's.
fn rank_by_significance<T: Copy>(candidates: &mut [T], key: impl Fn(&T) -> (f64, f64)) {
    let mut ranked: Vec<((f64, f64), T)> = candidates
        .iter()
        .map(|c| (significance_rank(key(c)), *c))
        .collect();
    ranked.sort_by(|(a, _), (b, _)| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    for (c, (_, r)) in candidates.iter_mut().zip(ranked) {
        *c = r;
    }
}

/// The first `n` of candidates ranked by [`rank_by_significance`] with `key`, and those after
/// them that rank alike with the last one taken: a cut never falls between candidates the data
/// cannot tell apart (an R-test's squareness EA0Z and the linear term of the angular error EAZ,
/// whose tests differ in the 14th digit, then both reach the shortlist, where the simpler wins).
fn first_through_ties<T>(
    ranked: impl IntoIterator<Item = T>,
    n: usize,
    key: impl Fn(&T) -> (f64, f64),
) -> Vec<T> {
    let mut taken: Vec<T> = Vec::new();
    for c in ranked {
        let alike = |last: &T| significance_rank(key(last)) == significance_rank(key(&c));
        if taken.len() >= n && !taken.last().is_some_and(alike) {
            break;
        }
        taken.push(c);
    }
    taken
}

/// Which of a model's causes leaves first ([`conclude`], [`Searcher::drop_resting_on_orders`]).
/// Of those the wider model holds (`held[k]`, from [`order_widening`]): the latest to enter of
/// those the base and the other causes hold — it made the model hold them; the earlier ones stay
/// and are found again without it ([`Searcher::rechoose`]) — else the first that the base's next
/// orders hold. Else the least determined, `z(k)` (largest |estimate| ÷ u) below 2. With the
/// cause, whether (and what) held it.
fn leaving(held: &[Option<Held>], z: impl Fn(usize) -> f64) -> Option<(usize, Option<Held>)> {
    let by_model = held.iter().rposition(|h| *h == Some(Held::ByModel));
    let by_orders = held.iter().position(|h| *h == Some(Held::ByOrders));
    if let Some(k) = by_model.or(by_orders) {
        return Some((k, held[k]));
    }
    (0..held.len())
        .map(|k| (k, z(k)))
        .filter(|(_, z)| *z < 2.0)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| (k, None))
}

/// The causes [`Searcher::remove`] took out (`gone`: the one removed, then what builds on it)
/// with why: the first for `reason`, the others because they build on it.
fn pruned_for(gone: Vec<String>, reason: PruneReason) -> Vec<Pruned> {
    let first = gone.first().cloned().unwrap_or_default();
    gone.into_iter()
        .enumerate()
        .map(|(k, name)| Pruned {
            name,
            reason: if k == 0 {
                reason.clone()
            } else {
                PruneReason::BuildsOn(first.clone())
            },
        })
        .collect()
}

/// The cause whose removal from the final model is least significant (the largest of the
/// Bonferroni-adjusted p-values `finals`, the first of equal ones), if that one is not below
/// `alpha` ([`conclude`]).
fn least_significant(finals: &[f64], alpha: f64) -> Option<usize> {
    let (k, p) = finals
        .iter()
        .enumerate()
        .fold(None, |best: Option<(usize, f64)>, (k, &p)| match best {
            Some((_, bp)) if bp >= p => best,
            _ => Some((k, p)),
        })?;
    (p >= alpha).then_some(k)
}

/// Whether `c` may be a next order of an error of a model (`in_model` tells its terms by
/// name): a completion ([`Role::Completion`]) whose term it builds on is in the model. The
/// caller checks that its own term is not in it yet.
fn is_next_order(c: &dyn Candidate, in_model: impl Fn(&str) -> bool) -> bool {
    c.role() == Role::Completion && c.requires().is_none_or(in_model)
}

/// The next order of every error of the (completed) base ([`is_next_order`]), evaluated on
/// `obs` (the final model's, which no pool holds; a search takes them from its pool,
/// [`Searcher::next_order_entries`]).
fn next_orders(candidates: &[Box<dyn Candidate>], obs: &Observations, base: &[Term]) -> Vec<Term> {
    let in_base = |name: &str| base.iter().any(|t| t.name == name);
    candidates
        .iter()
        .filter(|c| is_next_order(c.as_ref(), in_base))
        .filter_map(|c| c.variants(obs).into_iter().next())
        .filter(|t| !in_base(&t.name))
        .collect()
}

/// For each of the final model's `causes` (its terms after the base): the cofactor of its
/// coefficients, `G⁻¹`, and what it grows to when the next order of every base error is in the
/// model, `G_wide⁻¹` — `G` the Gram of its whitened columns once the base (fit `narrow`) and
/// the other causes are projected out, `G_wide` the same with the base's next orders in too
/// (fit `wide`). A cause is found against a base of finite orders; where the data
/// separate it from the base only through those orders (an R-test's angular positioning of C
/// against the linear axes' higher orders along the ball's circle), its size rests on them,
/// and this says by how much. [`Held`]: the wider model holds the cause — the base and the
/// other causes already (`ByModel`), or only with the next orders (`ByOrders`).
fn order_widening(
    narrow: &Projector,
    wide: &Projector,
    causes: &[&Term],
) -> Vec<std::result::Result<(DMat, DMat), Held>> {
    causes
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let others: Vec<&Term> = causes
                .iter()
                .enumerate()
                .filter_map(|(j, o)| (j != k).then_some(*o))
                .collect();
            let xo = design(&others, t.columns.nrows());
            let (narrow, wide) = (narrow.extended(&xo), wide.extended(&xo));
            let holds =
                |p: &Projector| p.increment(&t.columns).separability < SEPARABILITY_TOLERANCE;
            // The narrow model is within the wide one: what it holds, the wide one holds too.
            if holds(&wide) {
                return Err(if holds(&narrow) {
                    Held::ByModel
                } else {
                    Held::ByOrders
                });
            }
            let gram = |p: &Projector| {
                let r = p.residual_part(&t.columns);
                r.tr_mul(&r)
            };
            let inverse = |g: DMat| g.try_inverse().ok_or(Held::ByOrders);
            Ok((inverse(gram(&narrow))?, inverse(gram(&wide))?))
        })
        .collect()
}

/// What holds a cause whose widening by the base's next orders is not defined
/// ([`order_widening`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Held {
    /// The base and the other causes, without the next orders.
    ByModel,
    /// The next orders.
    ByOrders,
}

/// The base completion called `name` on all observations.
fn full_completion(
    candidates: &[Box<dyn Candidate>],
    obs: &Observations,
    name: &str,
) -> Option<Term> {
    library_variant(candidates, obs, name, |c| c.role().completes())
}

/// The column of the library's constant term `name` (a candidate of one single-column variant
/// that builds on nothing) on all observations.
fn library_constant(
    candidates: &[Box<dyn Candidate>],
    obs: &Observations,
    name: &str,
) -> Option<DVec> {
    library_variant(candidates, obs, name, |c| {
        c.requires().is_none() && c.role() == Role::Cause && c.columns(obs) == 1
    })
    .map(|t| t.columns.column(0).into_owned())
}

/// A chosen term (found on a thinned copy) on all observations: the candidate's variant at the
/// period or time constant the search found, as the same component of a recurring cause.
fn full_variant(candidate: &dyn Candidate, obs: &Observations, c: &Chosen) -> Term {
    let term = hyper_of(&c.term.family, false)
        .and_then(|(h, _)| candidate.at(c.variant, h))
        .or_else(|| candidate.variants(obs).into_iter().nth(c.variant))
        .expect("a chosen variant exists on all observations");
    nth_component(term, c.component)
}

/// Level (Bonferroni over the eligible ones) at which a higher order of a base component error
/// completes the base. Generous: an order too many costs a little power, one too few leaves
/// smooth structure that would be mistaken for a cause.
const COMPLETION_LEVEL: f64 = 0.01;

/// How much lower (χ², in units of the model's residual variance) a rival must leave the complete
/// model than a chosen cause to replace it ([`Searcher::exchange`]): the 99 % point of χ² with one
/// degree of freedom, so that two causes the data hardly tell apart are not swapped on noise.
const EXCHANGE_CHI2: f64 = 6.63;

/// How far above the significance level (as a factor) a scanned candidate's best grid value
/// still gets its hyper-parameter refined.
const REFINE_LEVEL: f64 = 1e3;

/// Periodic components one error may show along a linear axis (pitch, a longer wave of the
/// screw, a harmonic of the pitch).
const MAX_PERIODIC_COMPONENTS: usize = 3;

/// Periodic components one error may show along a rotary axis: its smooth part is harmonics of
/// a turn too (eccentricity, an elliptic bearing or encoder: 1, 2, 3 per turn), beside a worm
/// gear's tooth error and its harmonics.
const MAX_ROTARY_PERIODIC_COMPONENTS: usize = 6;

/// How many periodic components the search gives the error of periodic term `t`.
fn most_periodic_components(obs: &Observations, t: &Term) -> usize {
    if exposed_by_rotary(obs, t) {
        MAX_ROTARY_PERIODIC_COMPONENTS
    } else {
        MAX_PERIODIC_COMPONENTS
    }
}

/// `true` when the periodic term `t` of candidate `candidate` has a period within the Fourier
/// resolution (1 / range of its axis; along a rotary axis, the same harmonic of a turn) of a
/// component of the same cause already chosen (other than `skip`): two such components are one
/// wave with a slowly changing amplitude, not two causes, and their sizes would split one
/// effect.
fn near_a_component(
    obs: &Observations,
    t: &Term,
    chosen: &[Chosen],
    candidate: usize,
    skip: Option<usize>,
) -> bool {
    let Some((period, span)) = period_and_span(obs, t) else {
        return false;
    };
    // Along a rotary axis the periods are harmonics of a turn, which a turn's data tell apart
    // however close in frequency (the Fourier resolution of the span would merge the 1st and
    // 2nd): near means the same harmonic.
    let resolution = if exposed_by_rotary(obs, t) {
        0.5 / std::f64::consts::TAU
    } else {
        1.0 / span
    };
    chosen.iter().enumerate().any(|(k, c)| {
        Some(k) != skip
            && c.candidate == candidate
            && matches!(c.term.family, Family::Periodic { period: q }
                if (1.0 / period - 1.0 / q).abs() < resolution)
    })
}

/// The `k`-th further component of a recurring cause (`k` = 0 is the first, unchanged): its
/// own name and coefficient names, so reports and parameter tables tell the components apart.
fn nth_component(mut t: Term, k: usize) -> Term {
    if k == 0 {
        return t;
    }
    let ordinal = ["second", "third"].get(k - 1).copied().unwrap_or("further");
    let stem = t.name.split(" #").next().unwrap_or_default().to_string();
    t.name = format!("{stem} #{}", k + 1);
    let label = t.label.split(", ").next().unwrap_or_default().to_string();
    t.label = format!("{label}, {ordinal} period");
    for (c, _) in &mut t.coefficients {
        // "EXX periodic sin" → "EXX periodic #2 sin"
        let tail = c.rsplit(' ').next().unwrap_or_default().to_string();
        *c = format!("{} {tail}", t.name);
    }
    t
}

/// What would separate the chosen term from its alternatives: the hints of the chosen term and
/// of the alternatives, each once.
fn separating_hint(chosen: &Term, alternatives: &[String], pool: &[Vec<Term>]) -> Option<String> {
    if alternatives.is_empty() {
        return chosen.separated_by.clone();
    }
    let mut hints: Vec<String> = chosen.separated_by.iter().cloned().collect();
    for name in alternatives {
        if let Some(h) = pool
            .iter()
            .flatten()
            .find(|t| &t.name == name)
            .and_then(|t| t.separated_by.clone())
        {
            if !hints.contains(&h) {
                hints.push(h);
            }
        }
    }
    (!hints.is_empty()).then(|| hints.join("; or "))
}

/// Whether two families are one form: of one kind, and for drifts both linear or both first
/// order.
fn same_form(a: &Family, b: &Family) -> bool {
    match (a, b) {
        (
            Family::Drift {
                time_constant_s: ta,
            },
            Family::Drift {
                time_constant_s: tb,
            },
        ) => ta.is_some() == tb.is_some(),
        _ => std::mem::discriminant(a) == std::mem::discriminant(b),
    }
}

/// Whether two terms are forms of one cause, not rivals: drifts of one parameter (linear or
/// first order, whose choice the drift's own statements make), or one error of the same family
/// (a periodic error at another period, a component error at another degree).
fn one_cause(a: &Term, b: &Term) -> bool {
    match (&a.family, &b.family) {
        (Family::Drift { .. }, Family::Drift { .. }) => {
            let of_a = crate::candidate::drifted_parameters(a);
            crate::candidate::drifted_parameters(b)
                .iter()
                .any(|p| of_a.contains(p))
        }
        (fa, fb) => {
            std::mem::discriminant(fa) == std::mem::discriminant(fb)
                && a.name.split(' ').next() == b.name.split(' ').next()
        }
    }
}

/// Whether `name` is the squareness of the same plane as the squareness `t`, in the axis
/// ISO 230-1 names it by where `t` is not: the later axis of the plane (X, Y, Z order) against
/// the earlier one — `EC0Y` for `EC0X` (Y against X), `EB0Z` for `EB0X`, `EA0Z` for `EA0Y`.
fn is_iso_squareness_of(name: &str, t: &Term) -> bool {
    use crate::candidate::squareness_plane;
    t.family == Family::Squareness
        && matches!((squareness_plane(&t.name), squareness_plane(name)), (Some((a, false)), Some((b, true))) if a == b)
}

/// Of `(entry, variant, cv rms)` candidates in order, the one of lowest held-out RMS, save that
/// within 1 % of it the simpler cause wins (parsimony; `cost`: [`complexity`]). Of equally
/// simple ones whose RMS differ by rounding alone ([`rounded`]), the first.
fn most_parsimonious(
    candidates: impl Iterator<Item = (usize, usize, f64)>,
    cost: impl Fn(usize, usize) -> (usize, usize),
) -> Option<(usize, usize, f64)> {
    candidates.fold(None, |best, (ci, vi, r)| match best {
        None => Some((ci, vi, r)),
        Some((bc, bv, br)) => {
            let (b_cost, t_cost) = (cost(bc, bv), cost(ci, vi));
            let better = if (r - br).abs() <= 0.01 * br {
                t_cost < b_cost || (t_cost == b_cost && rounded(r) < rounded(br))
            } else {
                r < br
            };
            Some(if better { (ci, vi, r) } else { (bc, bv, br) })
        }
    })
}

/// How much a term asks of the data: coefficients first, then hyper-parameters and
/// dependence on time or polynomial degree (a constant location error is simpler than a drift
/// that happens to look constant).
fn complexity(t: &Term) -> (usize, usize) {
    let shape = match t.family {
        Family::Component { degree } => degree,
        Family::Periodic { .. } => 2,
        Family::Drift {
            time_constant_s: None,
        } => 1,
        Family::Drift {
            time_constant_s: Some(_),
        } => 3,
        _ => 0,
    };
    (t.width(), shape)
}

/// `t` with only its columns `keep` (itself when it keeps all); a term that lost some reports
/// each coefficient.
fn keep_columns(t: Term, keep: &[usize]) -> Term {
    if keep.len() == t.width() {
        return t;
    }
    Term {
        columns: DMat::from_fn(t.columns.nrows(), keep.len(), |i, k| {
            t.columns[(i, keep[k])]
        }),
        coefficients: keep.iter().map(|&k| t.coefficients[k].clone()).collect(),
        summary: Summary::EachCoefficient,
        ..t
    }
}

/// The base terms the data can separate: columns are kept in order while each adds a direction
/// (whitened, at least [`SEPARABILITY_TOLERANCE`] of its norm outside the kept ones); a term that
/// loses some columns keeps the others. The dropped ones are reported with what they are
/// confounded with, beside the terms left out whole. Also returns the fit of `y` by the kept
/// terms when `want_fit` (it is made anyway when a column is dropped, to say what it is
/// confounded with).
fn separable_base(
    base: Vec<Term>,
    y: &DVec,
    w: &DVec,
    want_fit: bool,
) -> (Vec<Term>, LeftOut, Option<Projector>) {
    // The whitened design is Q R: its columns' angles are those of R's, so the columns are
    // separated in R's space (width², not observations × width).
    let width = base.iter().map(Term::width).sum();
    let r = whitened_r(
        &design(&base.iter().collect::<Vec<_>>(), w.len()),
        &DVec::zeros(w.len()),
        w,
    )
    .0;
    let unweighted = DVec::from_element(width, 1.0);
    let mut basis = Directions::new(width, width); // orthonormal
    let mut kept: Vec<Term> = Vec::new();
    let mut dropped: Vec<(usize, usize)> = Vec::new(); // (term, column)
    let mut at = 0;
    for (k, t) in base.iter().enumerate() {
        let block = r.columns(at, t.width()).into_owned();
        at += t.width();
        let (keep, not) = separable_columns(&block, &unweighted, None, &mut basis);
        dropped.extend(not.into_iter().map(|j| (k, j)));
        if !keep.is_empty() {
            kept.push(keep_columns(t.clone(), &keep));
        }
    }
    let x = design(&kept.iter().collect::<Vec<_>>(), w.len());
    let fit = (want_fit || !dropped.is_empty()).then(|| Projector::fit(&x, y, w));
    let not_separable = dropped
        .par_iter()
        .map(|&(k, j)| {
            let t = &base[k];
            let column = Term {
                columns: t.columns.columns(j, 1).into_owned(),
                ..t.clone()
            };
            let mut out = Vec::new();
            let fit = fit.as_ref().expect("fitted when a column is dropped");
            record_not_separable(&mut out, &column, &kept, &x, fit);
            let mut ns = out.pop().unwrap_or(NotSeparable {
                name: String::new(),
                label: t.label.clone(),
                confounded_with: Vec::new(),
                separated_by: t.separated_by.clone(),
                rests_on_orders: false,
            });
            ns.name = t.coefficients[j].0.clone();
            ns
        })
        .collect();
    // The terms left out whole (a column of a wider term that the rest holds leaves the term).
    let left_out = base
        .into_iter()
        .enumerate()
        .filter(|(k, t)| dropped.iter().filter(|(d, _)| d == k).count() == t.width())
        .map(|(_, t)| t)
        .collect();
    (
        kept,
        LeftOut {
            not_separable,
            terms: left_out,
        },
        fit,
    )
}

/// What [`separable_base`] leaves out of the base: each dropped column with what it is
/// confounded with, and the terms left out whole.
struct LeftOut {
    not_separable: Vec<NotSeparable>,
    terms: Vec<Term>,
}

fn quality(obs: &Observations, sol: &Solution, cv: &DVec) -> FitQuality {
    let dof = sol.dof();
    let sigma0 = if dof > 0 {
        (sol.rss_w / dof as f64).sqrt()
    } else {
        f64::NAN
    };
    FitQuality {
        rms: rms(&sol.residuals),
        max_abs: max_abs(&sol.residuals),
        cv_rms: rms(cv),
        cv_max_abs: max_abs(cv),
        sigma0,
        dof,
        chi2_p_value: obs
            .sigma
            .as_ref()
            .map(|_| stats::chi2_sf(sol.rss_w, dof as f64)),
    }
}

/// Factor of the cofactor matrix: σ0² when no noise is stated, max(σ0², 1) when it is (a stated
/// noise that the residuals exceed is not trusted blindly).
fn covariance_scale(obs: &Observations, sigma0: f64) -> f64 {
    let s2 = sigma0 * sigma0;
    if obs.sigma.is_some() { s2.max(1.0) } else { s2 }
}

/// Covariance of the coefficients (see [`covariance_scale`]).
fn covariance(obs: &Observations, cofactor: &DMat, sigma0: f64) -> DMat {
    cofactor * covariance_scale(obs, sigma0)
}

fn parameters(terms: &[Term], coef: &DVec, cov: &DMat) -> Vec<ParameterEstimate> {
    let mut c = 0;
    terms
        .iter()
        .map(|t| {
            let k = t.width();
            let sub = cov.view((c, c), (k, k)).into_owned();
            let est = t.estimates(&coef.as_slice()[c..c + k], &sub);
            c += k;
            ParameterEstimate {
                term: t.name.clone(),
                estimates: est,
            }
        })
        .collect()
}

fn record_not_separable(
    out: &mut Vec<NotSeparable>,
    t: &Term,
    model: &[Term],
    x: &DMat,
    fit: &Projector,
) {
    if matches!(
        t.family,
        Family::Setup | Family::Drift { .. } | Family::Component { .. }
    ) {
        return;
    }
    if x.ncols() == 0 {
        return;
    }
    let confounded = confounded_with(&t.columns.columns(0, 1).into_owned(), model, x, fit)
        .pop()
        .unwrap_or_default();
    // An absolute location error that its relative form holds is that constant read another
    // way: nothing separates them.
    let representation = crate::instruments::relative_form(&t.name)
        .is_some_and(|relative| confounded.iter().any(|c| c == relative));
    out.push(NotSeparable {
        name: t.name.clone(),
        label: t.label.clone(),
        confounded_with: confounded,
        separated_by: t.separated_by.clone().filter(|_| !representation),
        rests_on_orders: false,
    });
}

/// For each column of `c`, the terms of the model (design `x`, fit `fit`) it is made of:
/// regressed on the model's columns, those carrying more than 5 % of the combination, largest
/// first.
fn confounded_with(c: &DMat, model: &[Term], x: &DMat, fit: &Projector) -> Vec<Vec<String>> {
    let coef = fit.coefficients_of(c);
    let norms: Vec<f64> = x.column_iter().map(|c| c.norm()).collect();
    (0..c.ncols())
        .map(|m| {
            let mut contributions: Vec<(String, f64)> = Vec::new();
            let mut at = 0;
            for t in model {
                let k = t.width();
                let share = (at..at + k).map(|j| (coef[(j, m)] * norms[j]).abs()).sum();
                contributions.push((t.name.clone(), share));
                at += k;
            }
            let total: f64 = contributions.iter().map(|c| c.1).sum();
            contributions.sort_by(|a, b| b.1.total_cmp(&a.1));
            contributions
                .into_iter()
                .filter(|c| c.1 > 0.05 * total)
                .map(|c| c.0)
                .collect()
        })
        .collect()
}

fn hcat(a: &DMat, b: &DMat) -> DMat {
    let mut m = DMat::zeros(a.nrows(), a.ncols() + b.ncols());
    m.columns_mut(0, a.ncols()).copy_from(a);
    m.columns_mut(a.ncols(), b.ncols()).copy_from(b);
    m
}

/// Largest cosine between the column spaces of `a` and `b` (first principal angle).
fn max_cosine(a: &DMat, b: &DMat) -> f64 {
    let qa = crate::fit::orthonormal_basis(a);
    let qb = crate::fit::orthonormal_basis(b);
    if qa.ncols() == 0 || qb.ncols() == 0 {
        return 0.0;
    }
    let m = qa.transpose() * qb;
    m.svd(false, false).singular_values.max()
}

fn group_rms(r: &DVec, group: &[usize], k: usize) -> Vec<f64> {
    (0..k)
        .map(|g| {
            let v: Vec<f64> = group
                .iter()
                .zip(r.iter())
                .filter(|(gi, _)| **gi == g)
                .map(|(_, r)| *r)
                .collect();
            if v.is_empty() {
                0.0
            } else {
                (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
            }
        })
        .collect()
}

/// The evidence behind each finding: the final model's residuals with the finding's fitted
/// effect added back, against the covariate that exposes it; and, for structure nothing
/// explains, the final residuals against the covariate of the most significant test.
#[allow(clippy::too_many_arguments)]
fn residual_series(
    obs: &Observations,
    findings: &[Finding],
    found_terms: &[Term],
    sol: &Solution,
    base_width: usize,
    remaining: &[StructureTest],
    fit: &Projector,
    probes: &[Term],
) -> Vec<ResidualSeries> {
    let covariate = |name: &str| -> Option<Vec<f64>> {
        if name == "setup" {
            Some(obs.setup.iter().map(|&s| s as f64).collect())
        } else {
            obs.variable(name).map(|v| v.values.clone())
        }
    };
    let mut out = Vec::new();
    let mut col = base_width;
    for (f, t) in findings.iter().zip(found_terms) {
        let width = t.width();
        let effect = &t.columns * sol.coef.rows(col, width);
        col += width;
        let Some(x) = f.exposed_by.as_deref().and_then(covariate) else {
            continue;
        };
        out.push(ResidualSeries {
            variable: f.exposed_by.clone().unwrap_or_default(),
            finding: Some(f.name.clone()),
            x,
            channel: obs.channel.clone(),
            residual: (&sol.residuals + &effect).as_slice().to_vec(),
            effect: effect.as_slice().to_vec(),
            structure: None,
        });
    }
    if let Some(s) = remaining
        .iter()
        .min_by(|a, b| a.p_value.total_cmp(&b.p_value))
    {
        if let Some(x) = covariate(&s.variable) {
            // The dependence the test found, as fitted to the final residuals.
            let effect = crate::structure::test_columns(obs, s, probes).map_or_else(
                || vec![0.0; obs.len()],
                |c| fit.fitted_along(&c).as_slice().to_vec(),
            );
            out.push(ResidualSeries {
                variable: s.variable.clone(),
                finding: None,
                x,
                channel: obs.channel.clone(),
                residual: sol.residuals.as_slice().to_vec(),
                effect,
                structure: Some(s.test.clone()),
            });
        }
    }
    for series in &mut out {
        series.thin(SERIES_POINTS);
    }
    out
}

/// Most points of a residual series (a longer record is shown by every k-th observation).
const SERIES_POINTS: usize = 20_000;

impl ResidualSeries {
    /// Keeps every k-th point so that at most `max` remain.
    fn thin(&mut self, max: usize) {
        let n = self.x.len();
        if n <= max {
            return;
        }
        let step = n.div_ceil(max);
        let keep = |v: &mut Vec<f64>| *v = v.iter().copied().step_by(step).collect();
        keep(&mut self.x);
        keep(&mut self.residual);
        keep(&mut self.effect);
        self.channel = self.channel.iter().copied().step_by(step).collect();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A periodic finding of X with `period` mm and `amplitude` µm (u 1 % of each).
    fn periodic(name: &str, period: f64, amplitude_um: f64) -> Finding {
        Finding {
            name: name.into(),
            label: String::new(),
            meaning: String::new(),
            family: Family::Periodic { period },
            estimates: vec![Estimate::new(
                "amplitude",
                amplitude_um * 1e-3,
                amplitude_um * 1e-5,
                Quantity::Length,
            )],
            hyper_parameter: Some(Estimate::new(
                "period",
                period,
                period * 1e-3,
                Quantity::Distance,
            )),
            p_value: 0.0,
            p_value_final: 0.0,
            cv_rms_before: 1.0,
            cv_rms_after: 0.5,
            alternatives: Vec::new(),
            rivals: Vec::new(),
            separated_by: None,
            exposed_by: Some("X".into()),
            first_order: None,
            ordinary: false,
        }
    }

    #[test]
    fn a_harmonic_found_before_its_fundamental_is_one_family() {
        // a sawtooth: harmonic k has amplitude A / k; the search found the second first
        let f = [
            periodic("EXX periodic", 15.0, 1.0),
            periodic("EXX periodic #2", 30.0, 2.0),
            periodic("EXX periodic #3", 10.0, 0.67),
        ];
        let c = harmonic_families(&f);
        assert_eq!(c.len(), 1);
        assert_eq!(
            c[0].findings,
            ["EXX periodic #2", "EXX periodic", "EXX periodic #3"]
        );
        assert!(c[0].note.contains("30.000 ± 0.030 mm"), "{}", c[0].note);
    }

    #[test]
    fn a_stronger_or_high_order_component_is_not_a_harmonic() {
        // a strong pitch error at 30 mm beside a weak long wave of 60 mm: not one sawtooth
        let stronger = [
            periodic("EXX periodic", 30.0, 2.0),
            periodic("EXX periodic #2", 60.0, 0.4),
        ];
        assert!(harmonic_families(&stronger).is_empty());
        // a ratio of 9 is as likely chance as a harmonic
        let high = [
            periodic("EXX periodic", 270.0, 2.0),
            periodic("EXX periodic #2", 30.0, 0.4),
        ];
        assert!(harmonic_families(&high).is_empty());
        // the same pair at a ratio of 3 is one
        let third = [
            periodic("EXX periodic", 90.0, 2.0),
            periodic("EXX periodic #2", 30.0, 0.4),
        ];
        assert_eq!(harmonic_families(&third).len(), 1);
    }

    /// An amplitude whose phase the model does not favour has the limit of a fixed
    /// noncentrality; one the model holds at one phase has a larger limit, and its power
    /// averaged over the phase (checked here by a finer quadrature) is 80 %.
    #[test]
    fn an_amplitude_limit_averages_the_power_over_the_phase() {
        let critical = 30.0;
        let curve = PowerCurve::new(critical);
        let lambda = stats::noncentral_chi2_power_noncentrality(critical, 2.0, DETECTION_POWER);
        let (sigma2, hi) = (0.7, 4.0);
        let even = curve.amplitude_limit((hi, hi), sigma2);
        approx::assert_relative_eq!(even, (lambda * sigma2 / hi).sqrt(), max_relative = 1e-3);
        let lo = 0.05 * hi;
        let uneven = curve.amplitude_limit((lo, hi), sigma2);
        assert!(uneven > 1.5 * even, "{uneven} against {even}");
        let phases = 2000;
        let power = (0..phases)
            .map(|i| {
                let phi = (i as f64 + 0.5) / phases as f64 * std::f64::consts::PI;
                let share = hi * phi.cos().powi(2) + lo * phi.sin().powi(2);
                stats::noncentral_chi2_sf(critical, 2.0, uneven * uneven * share / sigma2)
            })
            .sum::<f64>()
            / phases as f64;
        approx::assert_abs_diff_eq!(power, DETECTION_POWER, epsilon = 2e-3);
    }

    #[test]
    fn p_values_that_differ_by_rounding_alone_rank_alike() {
        // Two higher orders of tracker data the lengths cannot tell apart (ECX and EYX P4-6,
        // as they came out of one run).
        let (a, b) = (3.131_477_092_071_274_3e-3, 3.131_477_092_071_452e-3);
        assert!(a != b);
        assert_eq!(rounding_free(a), rounding_free(b));
        // A real difference, and an underflow to zero, still rank.
        assert!(rounding_free(3.1314e-3) < rounding_free(3.1315e-3));
        assert!(rounding_free(0.0) < rounding_free(1e-300));
        assert!(rounding_free(1e-300) < rounding_free(1e-299));
    }

    #[test]
    fn candidates_that_differ_by_rounding_keep_their_order_and_a_cut_takes_them_all() {
        // (id, p-value, share explained): EA0Z and the linear term of EAZ on an R-test, as
        // they came out of one run with their p-values 2e-14 apart, between two others.
        let key = |c: &(usize, f64, f64)| (c.1, c.2);
        let mut ranked = vec![
            (0, 1e-20, 0.05),
            (1, 6.524_022_127_708_914e-31, 0.072_745_485_909_747_36),
            (2, 6.524_022_127_707_5e-31, 0.072_745_485_909_747_61),
            (3, 1e-60, 0.2),
        ];
        rank_by_significance(&mut ranked, key);
        let ids = |v: &[(usize, f64, f64)]| v.iter().map(|c| c.0).collect::<Vec<_>>();
        // The rounder p-value of 2 does not put it ahead of 1.
        assert_eq!(ids(&ranked), [3, 1, 2, 0]);
        assert_eq!(ids(&first_through_ties(ranked.clone(), 1, key)), [3]);
        assert_eq!(ids(&first_through_ties(ranked.clone(), 2, key)), [3, 1, 2]);
        assert_eq!(ids(&first_through_ties(ranked.clone(), 3, key)), [3, 1, 2]);
        assert_eq!(
            ids(&first_through_ties(ranked.clone(), 0, key)),
            Vec::<usize>::new()
        );
        // Of two equally simple causes whose held-out RMS differ by rounding, the first.
        let pick = most_parsimonious(
            [
                (1, 0, 1.779_569_046_658_035e-3),
                (2, 0, 1.779_569_046_658_024_6e-3),
            ]
            .into_iter(),
            |_, _| (1, 0),
        );
        assert_eq!(pick.map(|p| p.0), Some(1));
        // A real difference still decides.
        let pick = most_parsimonious([(1, 0, 1.78e-3), (2, 0, 1.77e-3)].into_iter(), |_, _| {
            (1, 0)
        });
        assert_eq!(pick.map(|p| p.0), Some(2));
    }

    #[test]
    fn the_latest_cause_the_model_holds_leaves_before_one_on_the_orders_or_a_weak_one() {
        use Held::{ByModel, ByOrders};
        let z = [5.0, 1.5, 0.5, 3.0];
        let by = |k: usize| z[k];
        // Of the causes the base and the others hold, the latest to enter.
        assert_eq!(
            leaving(&[Some(ByModel), None, Some(ByModel), None], by),
            Some((2, Some(ByModel)))
        );
        assert_eq!(
            leaving(&[Some(ByOrders), None, None, Some(ByModel)], by),
            Some((3, Some(ByModel)))
        );
        // Else the first the orders hold.
        assert_eq!(
            leaving(&[None, Some(ByOrders), None, Some(ByOrders)], by),
            Some((1, Some(ByOrders)))
        );
        // Else the least determined below 2; none when every one is determined.
        assert_eq!(leaving(&[None; 4], by), Some((2, None)));
        assert_eq!(leaving(&[None; 2], |_| 2.5), None);
    }

    #[test]
    fn the_cause_least_significant_in_the_final_model_leaves_if_it_fails_the_test() {
        // The largest adjusted p-value, if not below the level; of equal ones (p capped at 1
        // by the Bonferroni factor) the first.
        assert_eq!(least_significant(&[1e-9, 0.065, 2e-4], 1e-3), Some(1));
        assert_eq!(least_significant(&[1.0, 1e-9, 1.0], 1e-3), Some(0));
        assert_eq!(least_significant(&[1e-9, 1e-3], 1e-3), Some(1));
        assert_eq!(least_significant(&[1e-9, 9.9e-4], 1e-3), None);
        assert_eq!(least_significant(&[], 1e-3), None);
    }

    #[test]
    fn terms_whose_estimates_are_correlated_beyond_the_limit_are_grouped() {
        // Four one-column terms and a two-column one (rows 4 and 5), then a row of a nonlinear
        // parameter. A–C at 0.995 and C–E's second column at −0.999 link A, C and E; B–D at
        // 0.98 stays below the limit, and so does the row beyond the terms (at 1.0 with B).
        let term = |name: &str| {
            Term::single(
                name,
                "",
                "",
                Family::Setup,
                DVec::zeros(3),
                Quantity::Length,
            )
        };
        let mut e = term("E");
        e.columns = DMat::zeros(3, 2);
        let terms = [term("A"), term("B"), term("C"), term("D"), e];
        let mut cov = DMat::identity(7, 7);
        let mut set = |i: usize, j: usize, r: f64| {
            cov[(i, j)] = r;
            cov[(j, i)] = r;
        };
        set(0, 2, 0.995);
        set(2, 5, -0.999);
        set(1, 3, 0.98);
        set(1, 6, 1.0);
        set(4, 5, 0.9999);
        let groups = determined_together(&terms, &cov);
        assert_eq!(
            groups,
            [DeterminedTogether {
                terms: vec!["A".into(), "C".into(), "E".into()],
                largest_correlation: 0.999,
            }]
        );
    }

    #[test]
    fn a_pruned_cause_carries_its_reason_and_what_builds_on_it_names_it() {
        let gone = vec!["EXX offset".to_string(), "EXX offset drift".to_string()];
        let pruned = pruned_for(gone, PruneReason::NotSignificant { p_value: 0.065 });
        assert_eq!(
            pruned,
            [
                Pruned {
                    name: "EXX offset".into(),
                    reason: PruneReason::NotSignificant { p_value: 0.065 },
                },
                Pruned {
                    name: "EXX offset drift".into(),
                    reason: PruneReason::BuildsOn("EXX offset".into()),
                },
            ]
        );
        assert!(
            pruned[0].reason.text().contains("0.065"),
            "{}",
            pruned[0].reason.text()
        );
        assert_eq!(pruned[1].reason.text(), "builds on EXX offset, which left");
    }
}
