//! The diagnosis loop: fit the base model, test the residuals for structure, try every candidate
//! effect on data the fit did not see, name the cause, extend the model, repeat.

use mte_linalg::lstsq::{RankTolerance, identifiability};
use mte_linalg::{DMat, DVec, stats};
use serde::Serialize;

use crate::candidate::Candidate;
use crate::data::Observations;
use crate::fit::{
    Folds, Projector, SEPARABILITY_TOLERANCE, design, max_abs, rms, solve, whitening,
};
use crate::structure::{StructureTest, structure_tests};
use crate::term::{Estimate, Family, Quantity, Term};
use crate::{DiagnoseError, Result};

/// Settings of the diagnosis (builder).
#[derive(Debug, Clone)]
pub struct DiagnoseParams {
    /// Family-wise significance level of a discovery (Bonferroni over every candidate variant
    /// tried in a step). Default 0.001.
    pub alpha: f64,
    /// Number of cross-validation folds. Default 5.
    pub folds: usize,
    /// Contiguous blocks per fold. Default 10.
    pub blocks_per_fold: usize,
    /// Smallest relative fall of the held-out RMS for an effect to be kept. Default 0.02.
    pub min_gain: f64,
    /// Most effects added. Default 6.
    pub max_effects: usize,
    /// Candidates examined by cross-validation in each step (the most significant ones).
    /// Default 8.
    pub shortlist: usize,
}

impl Default for DiagnoseParams {
    fn default() -> Self {
        DiagnoseParams {
            alpha: 1e-3,
            folds: 5,
            blocks_per_fold: 10,
            min_gain: 0.02,
            max_effects: 6,
            shortlist: 8,
        }
    }
}

/// How well one model explains the data.
#[derive(Debug, Clone, Serialize)]
pub struct FitQuality {
    /// RMS of the residuals of the fit to all data, mm.
    pub rms: f64,
    /// Largest absolute residual of the fit, mm.
    pub max_abs: f64,
    /// RMS of the held-out (cross-validated) residuals, mm.
    pub held_out_rms: f64,
    /// Largest absolute held-out residual, mm.
    pub held_out_max_abs: f64,
    /// A-posteriori standard deviation of unit weight √(RSS_w / dof) (≈ 1 when the residuals
    /// match the stated noise; the residual RMS in mm when none is stated).
    pub sigma0: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// p-value of the χ² test of the residuals against the stated noise (`None` without one).
    pub chi2_p_value: Option<f64>,
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
    /// Estimated size with standard uncertainty, in the final model.
    pub estimates: Vec<Estimate>,
    /// Bonferroni-adjusted p-value when it was added.
    pub p_value: f64,
    /// Held-out RMS before and after adding it, mm.
    pub held_out_rms_before: f64,
    /// Held-out RMS after adding it, mm.
    pub held_out_rms_after: f64,
    /// Other candidates that explain the same residual equally well with this data.
    pub alternatives: Vec<String>,
    /// The measurement that would tell it apart from the alternatives.
    pub separated_by: Option<String>,
    /// The covariate that exposes it.
    pub exposed_by: Option<String>,
}

/// A candidate the data cannot separate from the current model.
#[derive(Debug, Clone, Serialize)]
pub struct NotSeparable {
    /// Candidate name.
    pub name: String,
    /// What engineers call it.
    pub label: String,
    /// The model terms it is (nearly) a combination of.
    pub confounded_with: Vec<String>,
    /// The measurement that would separate it.
    pub separated_by: Option<String>,
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
    /// Held-out RMS with it added, mm (for the shortlisted ones).
    pub held_out_rms: Option<f64>,
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

/// Residuals against one covariate before and after the extension, for a plot.
#[derive(Debug, Clone, Serialize)]
pub struct ResidualSeries {
    /// Covariate name.
    pub variable: String,
    /// Covariate values (mm, rad, s or ±1).
    pub x: Vec<f64>,
    /// Channel of each point.
    pub channel: Vec<usize>,
    /// Held-out residuals of the base model, mm.
    pub before: Vec<f64>,
    /// Held-out residuals of the extended model, mm.
    pub after: Vec<f64>,
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
    /// Base model parameters as fitted.
    pub base_parameters: Vec<ParameterEstimate>,
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
    /// Candidates the data cannot separate from the model.
    pub not_separable: Vec<NotSeparable>,
    /// Extended model quality.
    pub extended: FitQuality,
    /// All parameters of the extended model.
    pub extended_parameters: Vec<ParameterEstimate>,
    /// Residuals for plots: against the covariate that exposes each finding (or the most
    /// significant structure when nothing was found).
    pub residual_series: Vec<ResidualSeries>,
    /// Significance level used.
    pub alpha: f64,
}

impl Diagnosis {
    /// `true` when nothing was found: the base model explains the data to the noise.
    pub fn no_discrepancy(&self) -> bool {
        self.findings.is_empty()
    }

    /// The finding called `name`.
    pub fn finding(&self, name: &str) -> Option<&Finding> {
        self.findings.iter().find(|f| f.name == name)
    }
}

struct ModelState {
    terms: Vec<Term>,
}

impl ModelState {
    fn design(&self, n: usize) -> DMat {
        design(&self.terms.iter().collect::<Vec<_>>(), n)
    }
}

/// Runs the diagnosis.
///
/// # Errors
/// [`DiagnoseError::InvalidData`] for bad observations; [`DiagnoseError::NotIdentifiable`] when
/// the base model itself is rank deficient on these data (the message names the combinations);
/// [`DiagnoseError::TooFewObservations`] when there are not enough observations for the base
/// model and cross-validation.
pub fn diagnose(
    obs: &Observations,
    base: Vec<Term>,
    candidates: &[Box<dyn Candidate>],
    params: &DiagnoseParams,
) -> Result<Diagnosis> {
    obs.validate()?;
    let n = obs.len();
    let w = whitening(obs);
    let base_width: usize = base.iter().map(Term::width).sum();
    if n < base_width + 2 * params.folds + 2 {
        return Err(DiagnoseError::TooFewObservations {
            observations: n,
            needed: base_width + 2 * params.folds + 2,
        });
    }
    check_identifiable(&base, obs, &w)?;
    let folds = Folds::blocked(obs, params.folds, params.blocks_per_fold);
    let mut model = ModelState { terms: base };
    let x0 = model.design(n);
    let base_sol = solve(&x0, &obs.values, &w);
    let base_cv = folds.residuals(&x0, &obs.values, &w);
    let base_quality = quality(
        obs,
        &base_sol.residuals,
        &base_cv,
        base_sol.rss_w,
        n - base_sol.rank,
    );
    let base_parameters = parameters(
        &model.terms,
        &base_sol.coef,
        &covariance(obs, &base_sol.cofactor, base_quality.sigma0),
    );
    let structure = structure_tests(
        obs,
        &x0,
        &base_sol.residuals,
        &w,
        base_sol.rss_w,
        n - base_sol.rank,
    );

    let mut pool: Vec<Vec<Term>> = Vec::new();
    let mut source: Vec<usize> = Vec::new(); // the candidate each pool entry came from
    for (k, c) in candidates.iter().enumerate() {
        let v: Vec<Term> = c
            .variants(obs)
            .into_iter()
            .filter(|t| !t.is_invisible() && t.columns.nrows() == n)
            .collect();
        if !v.is_empty() {
            pool.push(v);
            source.push(k);
        }
    }
    let mut used = vec![false; pool.len()];
    let mut times_chosen = vec![0usize; pool.len()];
    let mut scanned: Vec<ScannedTerm> = Vec::new();
    let mut steps = Vec::new();
    let mut findings: Vec<Finding> = Vec::new();
    let mut not_separable: Vec<NotSeparable> = Vec::new();
    let mut current_cv = base_cv.clone();
    let mut current_sol = base_sol.clone();

    for _ in 0..params.max_effects {
        let x = model.design(n);
        let projector = Projector::new(&x, &w);
        let dof = n - current_sol.rank;
        let variants_tested: usize = pool
            .iter()
            .enumerate()
            .filter(|(i, _)| !used[*i])
            .map(|(_, v)| v.len())
            .sum();
        let mut scored: Vec<(usize, usize, f64, f64)> = Vec::new(); // (candidate, variant, p, share)
        for ci in 0..pool.len() {
            if used[ci] {
                continue;
            }
            let variants = &pool[ci];
            let mut best: Option<(usize, crate::fit::Increment)> = None;
            for (vi, t) in variants.iter().enumerate() {
                let inc = projector.increment(&t.columns, &current_sol.residuals);
                if inc.separability < SEPARABILITY_TOLERANCE || inc.new_rank < t.width() {
                    continue;
                }
                if best
                    .as_ref()
                    .is_none_or(|(_, b)| inc.delta_rss > b.delta_rss)
                {
                    best = Some((vi, inc));
                }
            }
            let Some((vi, mut inc)) = best else {
                if steps.is_empty() {
                    record_not_separable(&mut not_separable, &variants[0], &model.terms, &x, &w);
                }
                continue;
            };
            let rss = current_sol.rss_w;
            let residuals = &current_sol.residuals;
            let score = |t: &Term| rss - projector.increment(&t.columns, residuals).delta_rss;
            if let Some(refined) = candidates[source[ci]].refine(vi, &score) {
                inc = projector.increment(&refined.columns, residuals);
                pool[ci][vi] = nth_component(refined, times_chosen[ci]);
            }
            let k = inc.new_rank;
            if dof <= k + 1 {
                continue;
            }
            let rss_new = (current_sol.rss_w - inc.delta_rss).max(1e-300);
            let f = (inc.delta_rss / k as f64) / (rss_new / (dof - k) as f64);
            let p = (stats::f_sf(f, k as f64, (dof - k) as f64) * variants_tested as f64).min(1.0);
            scored.push((ci, vi, p, inc.delta_rss / current_sol.rss_w.max(1e-300)));
        }
        scored.sort_by(|a, b| {
            a.2.partial_cmp(&b.2)
                .unwrap_or(std::cmp::Ordering::Equal)
                .then(b.3.total_cmp(&a.3))
        });
        let cur_cv_rms = rms(&current_cv);
        let mut ranking = Vec::new();
        let mut best: Option<(usize, usize, f64, DVec)> = None; // (candidate, variant, cv rms, cv residuals)
        for &(ci, vi, p, share) in scored.iter().take(params.shortlist) {
            let mut held_out_rms = None;
            if p < params.alpha {
                let t = &pool[ci][vi];
                let xc = hcat(&x, &t.columns);
                let cv = folds.residuals(&xc, &obs.values, &w);
                let r = rms(&cv);
                held_out_rms = Some(r);
                let better = match &best {
                    None => true,
                    Some((bc, bv, br, _)) => {
                        let (b_cost, t_cost) = (complexity(&pool[*bc][*bv]), complexity(t));
                        // Parsimony: within 1 % of the best held-out RMS the simpler cause wins.
                        if (r - br).abs() <= 0.01 * br {
                            t_cost < b_cost || (t_cost == b_cost && r < *br)
                        } else {
                            r < *br
                        }
                    }
                };
                if better {
                    best = Some((ci, vi, r, cv));
                }
            }
            ranking.push(CandidateScore {
                name: pool[ci][vi].name.clone(),
                p_value: p,
                share_of_residual: share,
                held_out_rms,
            });
        }
        let accepted = best.filter(|(_, _, r, _)| *r < cur_cv_rms * (1.0 - params.min_gain));
        let Some((ci, vi, new_rms, cv)) = accepted else {
            steps.push(Step {
                ranking,
                added: None,
                variants_tested,
            });
            break;
        };
        let chosen = pool[ci][vi].clone();
        // Alternatives: shortlisted candidates that explain the same residual direction about as
        // well on held-out data (within 2 %).
        let chosen_perp = projector.residual_part(&chosen.columns);
        let mut alternatives = Vec::new();
        for score in ranking.iter().filter(|c| c.name != chosen.name) {
            let Some(r) = score.held_out_rms else {
                continue;
            };
            if r > new_rms * 1.02 {
                continue;
            }
            let Some(&(cj, vj, _, _)) = scored.iter().find(|s| pool[s.0][s.1].name == score.name)
            else {
                continue;
            };
            let other = projector.residual_part(&pool[cj][vj].columns);
            if max_cosine(&chosen_perp, &other) > 0.99 && !alternatives.contains(&score.name) {
                alternatives.push(score.name.clone());
            }
        }
        let separated_by = separating_hint(&chosen, &alternatives, &pool);
        let p_value = scored
            .iter()
            .find(|s| s.0 == ci)
            .map(|s| s.2)
            .unwrap_or(1.0);
        findings.push(Finding {
            name: chosen.name.clone(),
            label: chosen.label.clone(),
            meaning: chosen.meaning.clone(),
            family: chosen.family.clone(),
            estimates: Vec::new(),
            p_value,
            held_out_rms_before: cur_cv_rms,
            held_out_rms_after: new_rms,
            alternatives,
            separated_by,
            exposed_by: chosen.exposed_by.clone(),
        });
        steps.push(Step {
            ranking,
            added: Some(chosen.name.clone()),
            variants_tested,
        });
        // A drift or a polynomial of the same cause is a different candidate; the chosen one's
        // own alternatives (other degrees of the same slot) are retired with it. A periodic
        // error stays open for another period: a ball screw shows its pitch and a longer wave
        // of the screw, a rotary table its eccentricity and its worm-gear tooth error. The
        // period already in the model is no longer separable, so the next one is another.
        times_chosen[ci] += 1;
        let recurs = matches!(chosen.family, Family::Periodic { .. })
            && times_chosen[ci] < MAX_PERIODIC_COMPONENTS;
        for (cj, variants) in pool.iter().enumerate() {
            if variants[0].name == chosen.name {
                used[cj] = true;
            }
        }
        if recurs {
            used[ci] = false;
            let k = times_chosen[ci];
            for t in &mut pool[ci] {
                *t = nth_component(t.clone(), k);
            }
        }
        model.terms.push(chosen);
        scanned.push(ScannedTerm {
            candidate: source[ci],
            variant: vi,
            component: times_chosen[ci] - 1,
            finding: findings.len() - 1,
        });
        // Hyper-parameters found with the other effects still in the residuals are biased (an
        // undersampled pitch leaks into the long periods of an irregular grid): refine each
        // scanned term again with all the others fitted, so a biased period is corrected rather
        // than patched by a spurious neighbour.
        let changed = refit_scanned(&mut model, &scanned, &mut findings, candidates, obs, &w);
        current_sol = solve(&model.design(n), &obs.values, &w);
        current_cv = if changed {
            folds.residuals(&model.design(n), &obs.values, &w)
        } else {
            cv
        };
    }

    let x = model.design(n);
    let extended = quality(
        obs,
        &current_sol.residuals,
        &current_cv,
        current_sol.rss_w,
        n - current_sol.rank,
    );
    let cov = covariance(obs, &current_sol.cofactor, extended.sigma0);
    let extended_parameters = parameters(&model.terms, &current_sol.coef, &cov);
    let base_count = model.terms.len() - findings.len();
    for (k, f) in findings.iter_mut().enumerate() {
        f.estimates = extended_parameters[base_count + k].estimates.clone();
    }
    let _ = x;
    let residual_series = residual_series(
        obs,
        &findings,
        &structure,
        &base_cv,
        &current_cv,
        params.alpha,
    );
    Ok(Diagnosis {
        observations: n,
        channels: obs.channel_names.clone(),
        setups: obs.setup_names.clone(),
        setup_kind: obs.setup_kind.clone(),
        quantity: obs.quantity,
        stated_noise: obs.sigma.as_ref().map(rms),
        base_parameters,
        base_rms_per_setup: group_rms(&base_sol.residuals, &obs.setup, obs.setup_names.len()),
        base_rms_per_channel: group_rms(&base_sol.residuals, &obs.channel, obs.channel_names.len()),
        base: base_quality,
        structure,
        steps,
        findings,
        not_separable,
        extended,
        extended_parameters,
        residual_series,
        alpha: params.alpha,
    })
}

/// An added term that came from a scanned candidate, so its hyper-parameter can be refined
/// again once later terms are in the model.
struct ScannedTerm {
    candidate: usize,
    variant: usize,
    /// Which component of a recurring cause (0 = first).
    component: usize,
    /// Its finding (and its place after the base terms in the model).
    finding: usize,
}

/// Refines the hyper-parameter of every scanned term with all other terms fitted; keeps a
/// refinement only when it lowers the weighted residual sum of squares. Returns whether any
/// term changed.
fn refit_scanned(
    model: &mut ModelState,
    scanned: &[ScannedTerm],
    findings: &mut [Finding],
    candidates: &[Box<dyn Candidate>],
    obs: &Observations,
    w: &DVec,
) -> bool {
    let n = obs.len();
    let base_count = model.terms.len() - findings.len();
    let mut changed = false;
    for s in scanned {
        let j = base_count + s.finding;
        let rss_with = |t: &Term| {
            let mut terms: Vec<&Term> = model.terms.iter().collect();
            terms[j] = t;
            solve(&design(&terms, n), &obs.values, w).rss_w
        };
        let Some(refined) = candidates[s.candidate].refine(s.variant, &rss_with) else {
            continue;
        };
        if rss_with(&refined) >= rss_with(&model.terms[j]) {
            continue;
        }
        let refined = nth_component(refined, s.component);
        let f = &mut findings[s.finding];
        f.family = refined.family.clone();
        f.meaning = refined.meaning.clone();
        model.terms[j] = refined;
        changed = true;
    }
    changed
}

/// Periodic components one slot may show (pitch, a longer wave of the screw, a harmonic).
const MAX_PERIODIC_COMPONENTS: usize = 3;

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

fn check_identifiable(base: &[Term], obs: &Observations, w: &DVec) -> Result<()> {
    if base.is_empty() {
        return Ok(());
    }
    let mut x = design(&base.iter().collect::<Vec<_>>(), obs.len());
    for (i, wi) in w.iter().enumerate() {
        x.row_mut(i).scale_mut(*wi);
    }
    for j in 0..x.ncols() {
        let nrm = x.column(j).norm();
        if nrm > 0.0 {
            x.column_mut(j).scale_mut(1.0 / nrm);
        }
    }
    let names: Vec<String> = base
        .iter()
        .flat_map(|t| t.coefficients.iter().map(|c| c.0.clone()))
        .collect();
    let report = identifiability(
        &x,
        &names,
        RankTolerance::Relative(crate::fit::RANK_TOLERANCE),
    )
    .map_err(|e| DiagnoseError::InvalidData {
        field: "base model".into(),
        detail: e.to_string(),
    })?;
    if report.is_identifiable() {
        Ok(())
    } else {
        Err(DiagnoseError::NotIdentifiable {
            combinations: report.combination_strings(),
        })
    }
}

fn quality(obs: &Observations, residuals: &DVec, cv: &DVec, rss_w: f64, dof: usize) -> FitQuality {
    let sigma0 = if dof > 0 {
        (rss_w / dof as f64).sqrt()
    } else {
        f64::NAN
    };
    FitQuality {
        rms: rms(residuals),
        max_abs: max_abs(residuals),
        held_out_rms: rms(cv),
        held_out_max_abs: max_abs(cv),
        sigma0,
        dof,
        chi2_p_value: obs
            .sigma
            .as_ref()
            .map(|_| stats::chi2_sf(rss_w, dof as f64)),
    }
}

/// Covariance of the coefficients: the cofactor scaled by σ0² when no noise is stated, and by
/// max(σ0², 1) when it is (a stated noise that the residuals exceed is not trusted blindly).
fn covariance(obs: &Observations, cofactor: &DMat, sigma0: f64) -> DMat {
    let s2 = sigma0 * sigma0;
    let scale = if obs.sigma.is_some() { s2.max(1.0) } else { s2 };
    cofactor * scale
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

fn record_not_separable(out: &mut Vec<NotSeparable>, t: &Term, model: &[Term], x: &DMat, w: &DVec) {
    if matches!(
        t.family,
        Family::Setup | Family::Drift { .. } | Family::Component { .. }
    ) {
        return;
    }
    // Which model terms the candidate is made of: regress it on the model's columns.
    let sol = solve(x, &t.columns.column(0).into_owned(), w);
    let mut contributions: Vec<(String, f64)> = Vec::new();
    let mut c = 0;
    for m in model {
        let k = m.width();
        let mut share = 0.0;
        for j in c..c + k {
            share += (x.column(j) * sol.coef[j]).norm();
        }
        contributions.push((m.name.clone(), share));
        c += k;
    }
    let total: f64 = contributions.iter().map(|c| c.1).sum();
    contributions.sort_by(|a, b| b.1.total_cmp(&a.1));
    let confounded_with = contributions
        .into_iter()
        .filter(|c| c.1 > 0.05 * total)
        .map(|c| c.0)
        .collect();
    out.push(NotSeparable {
        name: t.name.clone(),
        label: t.label.clone(),
        confounded_with,
        separated_by: t.separated_by.clone(),
    });
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

fn residual_series(
    obs: &Observations,
    findings: &[Finding],
    structure: &[StructureTest],
    before: &DVec,
    after: &DVec,
    alpha: f64,
) -> Vec<ResidualSeries> {
    let mut names: Vec<String> = findings
        .iter()
        .filter_map(|f| f.exposed_by.clone())
        .collect();
    if names.is_empty() {
        if let Some(s) = structure
            .iter()
            .filter(|s| s.is_significant(alpha))
            .min_by(|a, b| a.p_value.total_cmp(&b.p_value))
        {
            names.push(s.variable.clone());
        }
    }
    names.dedup();
    let mut out = Vec::new();
    for name in names {
        let x: Vec<f64> = if name == "setup" {
            obs.setup.iter().map(|&s| s as f64).collect()
        } else if let Some(v) = obs.variable(&name) {
            v.values.clone()
        } else {
            continue;
        };
        if out.iter().any(|s: &ResidualSeries| s.variable == name) {
            continue;
        }
        out.push(ResidualSeries {
            variable: name,
            x,
            channel: obs.channel.clone(),
            before: before.as_slice().to_vec(),
            after: after.as_slice().to_vec(),
        });
    }
    out
}
