//! Identification of rotary-axis location errors (and optionally linear-axis squareness) from
//! R-test trajectories: least squares on the full 3-D readings with the model linearised at
//! e = 0, refined by Gauss–Newton (chord) steps on the exact model; σ0-scaled uncertainties,
//! correlations and an SVD identifiability report.

use crate::error::{Result, RtestError};
use crate::model::{Dataset, NuisanceKind, ObservationModel, SetupNuisance};
use crate::names::{NamedSlot, location_errors, slot_by_name, squareness_errors};
use mte_kinematics::Machine;
use mte_linalg::{DMat, DVec, Vec3};
use serde::{Deserialize, Serialize};

/// What to fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitSpec {
    /// Kinematic parameters (constant slot errors).
    pub params: Vec<NamedSlot>,
    /// Nuisance kinds fitted per setup (3 components each).
    pub nuisance: Vec<NuisanceKind>,
    /// Gauss–Newton refinement steps on the exact model after the linear solution.
    pub gauss_newton_iters: usize,
    /// Relative singular value (of the column-scaled design matrix) below which a direction is
    /// treated as unobservable.
    pub rank_rtol: f64,
    /// Relative singular value below which a direction is reported as weakly identifiable.
    pub weak_rtol: f64,
}

impl FitSpec {
    /// The location errors of every rotary axis and a sensor zero per setup.
    ///
    /// # Errors
    /// As [`location_errors`].
    pub fn pivots(m: &Machine) -> Result<FitSpec> {
        Ok(FitSpec {
            params: location_errors(m)?,
            nuisance: vec![NuisanceKind::SensorZero],
            gauss_newton_iters: 2,
            rank_rtol: 1e-7,
            weak_rtol: 1e-3,
        })
    }
    /// Adds the linear-axis squareness errors (EC0Y, EB0Z, EA0Z).
    ///
    /// # Errors
    /// As [`squareness_errors`].
    pub fn with_squareness(mut self, m: &Machine) -> Result<FitSpec> {
        for s in squareness_errors(m)? {
            if !self.params.iter().any(|p| p.slots == s.slots) {
                self.params.push(s);
            }
        }
        Ok(self)
    }
    /// Adds parameters by ISO name (`E<c>0<axis>`).
    ///
    /// # Errors
    /// As [`slot_by_name`].
    pub fn with_names(mut self, m: &Machine, names: &[&str]) -> Result<FitSpec> {
        for n in names {
            let s = slot_by_name(m, n)?;
            if !self.params.iter().any(|p| p.slots == s.slots) {
                self.params.push(s);
            }
        }
        Ok(self)
    }
    /// Restricts the kinematic parameters to the given ISO names (in that order).
    ///
    /// # Errors
    /// As [`slot_by_name`].
    pub fn only(mut self, m: &Machine, names: &[&str]) -> Result<FitSpec> {
        self.params = names
            .iter()
            .map(|n| slot_by_name(m, n))
            .collect::<Result<_>>()?;
        Ok(self)
    }
    /// Replaces the fitted nuisance kinds.
    pub fn with_nuisance(mut self, kinds: &[NuisanceKind]) -> FitSpec {
        self.nuisance = kinds.to_vec();
        self
    }
}

/// What a fitted parameter is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ParamKind {
    /// A kinematic slot error.
    Slot(NamedSlot),
    /// A nuisance component of one setup.
    Nuisance {
        /// Setup index.
        setup: usize,
        /// Kind.
        kind: NuisanceKind,
        /// Component 0..3 (x, y, z).
        component: usize,
    },
}

/// One estimated parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Label ("EX0B", "s.x[ball_y+177]").
    pub label: String,
    /// What it is.
    pub kind: ParamKind,
    /// Estimate, mm or rad.
    pub value: f64,
    /// σ0-scaled standard uncertainty, mm or rad; `None` when the parameter lies in an
    /// unobservable direction.
    pub std_uncertainty: Option<f64>,
}

/// A parameter combination the data cannot (or can hardly) determine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Combination {
    /// Its singular value relative to the largest (column-scaled design matrix).
    pub relative_singular_value: f64,
    /// Parameter labels and weights of the right singular vector (|weight| ≥ 0.1), largest first.
    pub terms: Vec<(String, f64)>,
}

impl Combination {
    /// "EY0C (+0.71), EA0C (−0.71)".
    pub fn describe(&self) -> String {
        self.terms
            .iter()
            .map(|(n, w)| format!("{n} ({w:+.2})"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// SVD identifiability report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Identifiability {
    /// Number of parameters.
    pub n_params: usize,
    /// Numerical rank.
    pub rank: usize,
    /// Singular values relative to the largest, descending (column-scaled design matrix).
    pub relative_singular_values: Vec<f64>,
    /// Directions below `rank_rtol`: the data carry no information on these combinations.
    pub unobservable: Vec<Combination>,
    /// Directions between `rank_rtol` and `weak_rtol`: poorly determined.
    pub weak: Vec<Combination>,
}

/// The result of [`identify`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fit {
    /// All estimates: kinematic parameters first (spec order), then nuisance per setup.
    pub estimates: Vec<Estimate>,
    /// Correlation matrix of the estimates (rows/cols as `estimates`; 0 for unobservable ones).
    pub correlation: DMat,
    /// Full slot vector with the estimated kinematic parameters (other slots 0).
    pub slot_values: Vec<f64>,
    /// Estimated nuisance per setup.
    pub nuisance: Vec<SetupNuisance>,
    /// a-posteriori standard deviation of a reading component, mm.
    pub sigma0_mm: f64,
    /// Degrees of freedom (3·readings − rank).
    pub dof: usize,
    /// Residuals (measured − exact model at the estimate), per reading, mm.
    pub residuals: Vec<Vec3>,
    /// Identifiability report.
    pub identifiability: Identifiability,
    /// Human-readable warnings (unobservable / weak combinations).
    pub warnings: Vec<String>,
}

impl Fit {
    /// The estimate with this label.
    pub fn get(&self, label: &str) -> Option<&Estimate> {
        self.estimates.iter().find(|e| e.label == label)
    }
    /// The kinematic estimates only.
    pub fn kinematic(&self) -> impl Iterator<Item = &Estimate> {
        self.estimates
            .iter()
            .filter(|e| matches!(e.kind, ParamKind::Slot(_)))
    }
    /// Largest absolute residual component, mm.
    pub fn max_abs_residual_mm(&self) -> f64 {
        self.residuals
            .iter()
            .flat_map(|r| r.iter().copied())
            .fold(0.0, |a, b| a.max(b.abs()))
    }
}

/// Design matrix (3·readings × parameters) of a spec on a dataset, with the parameter kinds and
/// labels, from the sensitivity at e = 0 (constant slot errors).
///
/// # Errors
/// As [`ObservationModel::new`].
pub fn design_matrix(
    m: &Machine,
    data: &Dataset,
    spec: &FitSpec,
) -> Result<(DMat, Vec<ParamKind>, Vec<String>)> {
    let model = ObservationModel::new(m, data)?;
    let sens = model.sensitivity();
    let mut kinds: Vec<ParamKind> = spec.params.iter().cloned().map(ParamKind::Slot).collect();
    let mut labels: Vec<String> = spec.params.iter().map(|p| p.iso.clone()).collect();
    for (si, s) in data.setups.iter().enumerate() {
        for &k in &spec.nuisance {
            for c in 0..3 {
                kinds.push(ParamKind::Nuisance {
                    setup: si,
                    kind: k,
                    component: c,
                });
                labels.push(format!("{}.{}[{}]", k.label(), ["x", "y", "z"][c], s.id));
            }
        }
    }
    let p = kinds.len();
    let mut a = DMat::zeros(3 * data.readings.len(), p);
    for (i, (r, s)) in data.readings.iter().zip(&sens).enumerate() {
        let cst = s.constant();
        for (j, kind) in kinds.iter().enumerate() {
            for row in 0..3 {
                a[(3 * i + row, j)] = match kind {
                    ParamKind::Slot(ns) => ns.derivative(|slot| cst[(row, slot)]),
                    ParamKind::Nuisance {
                        setup,
                        kind,
                        component,
                    } => {
                        if *setup == r.setup {
                            s.nuisance(*kind)[(row, *component)]
                        } else {
                            0.0
                        }
                    }
                };
            }
        }
    }
    Ok((a, kinds, labels))
}

fn unpack(
    m: &Machine,
    n_setups: usize,
    kinds: &[ParamKind],
    theta: &DVec,
) -> (Vec<f64>, Vec<SetupNuisance>) {
    let mut e = vec![0.0; m.n_slots()];
    let mut nu = vec![SetupNuisance::default(); n_setups];
    for (k, kind) in kinds.iter().enumerate() {
        match kind {
            ParamKind::Slot(ns) => ns.add_to(&mut e, theta[k]),
            ParamKind::Nuisance {
                setup,
                kind,
                component,
            } => nu[*setup].get_mut(*kind)[*component] = theta[k],
        }
    }
    (e, nu)
}

/// Least-squares identification (see the module docs).
///
/// Unobservable combinations do not make this fail: the minimum-norm solution is returned, the
/// affected parameters get `std_uncertainty: None`, and `warnings` / `identifiability` say which
/// parameters cannot be told apart.
///
/// # Errors
/// [`RtestError::TooShort`] with fewer reading components than parameters + 1,
/// [`RtestError::Invalid`] / [`RtestError::UnknownAxis`] for an inconsistent dataset.
pub fn identify(m: &Machine, data: &Dataset, spec: &FitSpec) -> Result<Fit> {
    let (a, kinds, labels) = design_matrix(m, data, spec)?;
    let (nr, p) = a.shape();
    if p == 0 {
        return Err(RtestError::Fit("no parameter to fit".into()));
    }
    if nr <= p {
        return Err(RtestError::TooShort {
            what: format!("dataset for {p} parameters"),
            found: nr,
            needed: p + 1,
            unit: "reading components (3 per reading)".into(),
        });
    }
    let model = ObservationModel::new(m, data)?;
    let y = DVec::from_iterator(
        nr,
        data.readings.iter().flat_map(|r| r.d_mm.iter().copied()),
    );
    // column scaling
    // columns at round-off level (a parameter the readings do not depend on at all, e.g. a C
    // location error when C never moves) are zeroed so that scaling cannot inflate them
    let raw: Vec<f64> = (0..p).map(|j| a.column(j).norm()).collect();
    let big = raw.iter().copied().fold(0.0, f64::max);
    let scale: Vec<f64> = raw
        .iter()
        .map(|&r| if r > 1e-9 * big { r } else { 0.0 })
        .collect();
    let mut a_s = a.clone();
    for (j, &sc) in scale.iter().enumerate() {
        if sc > 0.0 {
            a_s.column_mut(j).scale_mut(1.0 / sc);
        } else {
            a_s.column_mut(j).fill(0.0);
        }
    }
    // shared SVD (faer): singular values in non-increasing order, full V; nr > p was checked
    let svd = mte_linalg::lstsq::Svd::new(&a_s)
        .map_err(|e| RtestError::Fit(format!("SVD of the design matrix: {e}")))?;
    let sv = &svd.singular_values;
    let smax = sv[0];
    if smax.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(RtestError::Fit(
            "the readings do not depend on any fitted parameter".into(),
        ));
    }
    let rel: Vec<f64> = sv.iter().map(|&s| s / smax).collect();
    let rank = rel.iter().filter(|&&r| r > spec.rank_rtol).count();
    let combo = |k: usize| -> Combination {
        let row = svd.v.column(k);
        let mut terms: Vec<(String, f64)> = (0..p)
            .filter(|&j| row[j].abs() >= 0.1)
            .map(|j| (labels[j].clone(), row[j]))
            .collect();
        terms.sort_by(|x, y| y.1.abs().total_cmp(&x.1.abs()));
        Combination {
            relative_singular_value: rel[k],
            terms,
        }
    };
    // null space in reduced row-echelon form: each combination leads with its own parameter,
    // so a k-dimensional null space reads as k separate trade-offs (basis-independent)
    let unobservable: Vec<Combination> = {
        let k = p - rank;
        let mut nmat = DMat::from_fn(k, p, |r, j| svd.v[(j, rank + r)]);
        let mut used = vec![false; p];
        for r in 0..k {
            let (mut best, mut bj) = (0.0, 0);
            for j in 0..p {
                if !used[j] && nmat[(r, j)].abs() > best {
                    best = nmat[(r, j)].abs();
                    bj = j;
                }
            }
            if best == 0.0 {
                continue;
            }
            used[bj] = true;
            let piv = nmat[(r, bj)];
            for j in 0..p {
                nmat[(r, j)] /= piv;
            }
            for rr in 0..k {
                if rr != r {
                    let f = nmat[(rr, bj)];
                    for j in 0..p {
                        let v = nmat[(r, j)];
                        nmat[(rr, j)] -= f * v;
                    }
                }
            }
        }
        (0..k)
            .map(|r| {
                let row = nmat.row(r).into_owned();
                let nrm = row.norm().max(1e-300);
                let mut terms: Vec<(String, f64)> = (0..p)
                    .filter(|&j| (row[j] / nrm).abs() >= 0.1)
                    .map(|j| (labels[j].clone(), row[j] / nrm))
                    .collect();
                terms.sort_by(|x, y| y.1.abs().total_cmp(&x.1.abs()));
                Combination {
                    relative_singular_value: rel[rank + r],
                    terms,
                }
            })
            .collect()
    };
    let weak: Vec<Combination> = (0..rank)
        .filter(|&k| rel[k] < spec.weak_rtol)
        .map(combo)
        .collect();
    // pseudo-inverse on the retained subspace (scaled coordinates)
    let mut pinv_s = DMat::zeros(p, p); // V S^-2 V^T
    let mut vs_inv = DMat::zeros(p, p); // V S^-1 (columns)
    for (k, &s) in sv.iter().enumerate().take(rank) {
        let v = svd.v.column(k).into_owned();
        pinv_s += &v * v.transpose() / (s * s);
        vs_inv.set_column(k, &(v / s));
    }
    let solve = |rhs: &DVec| -> DVec {
        // θ_s = V S^-1 U^T rhs = V S^-2 V^T A_s^T rhs
        let g = a_s.transpose() * rhs;
        let ts = &pinv_s * g;
        DVec::from_iterator(
            p,
            (0..p).map(|j| ts[j] / if scale[j] > 0.0 { scale[j] } else { 1.0 }),
        )
    };
    let n_set = data.setups.len();
    let mut theta = DVec::zeros(p);
    let mut resid_vec = y.clone();
    for it in 0..=spec.gauss_newton_iters {
        if it > 0 {
            let (e, nu) = unpack(m, n_set, &kinds, &theta);
            let pred = model.predict(&e[..], &nu)?;
            resid_vec = DVec::from_iterator(
                nr,
                data.readings
                    .iter()
                    .zip(&pred)
                    .flat_map(|(r, q)| (r.d_mm - q).iter().copied().collect::<Vec<_>>()),
            );
        }
        theta += solve(&resid_vec);
    }
    let (e, nu) = unpack(m, n_set, &kinds, &theta);
    let pred = model.predict(&e[..], &nu)?;
    let residuals: Vec<Vec3> = data
        .readings
        .iter()
        .zip(&pred)
        .map(|(r, q)| r.d_mm - q)
        .collect();
    let ssr: f64 = residuals.iter().map(|r| r.norm_squared()).sum();
    let dof = nr - rank;
    let sigma0 = (ssr / dof as f64).sqrt();
    // covariance (unscaled) and which parameters touch the null space
    let mut cov = pinv_s * (sigma0 * sigma0);
    for i in 0..p {
        for j in 0..p {
            let si = if scale[i] > 0.0 { scale[i] } else { 1.0 };
            let sj = if scale[j] > 0.0 { scale[j] } else { 1.0 };
            cov[(i, j)] /= si * sj;
        }
    }
    let in_null: Vec<bool> = (0..p)
        .map(|j| {
            unobservable
                .iter()
                .any(|c| c.terms.iter().any(|(l, _)| *l == labels[j]))
                || scale[j] == 0.0
        })
        .collect();
    let estimates: Vec<Estimate> = (0..p)
        .map(|j| Estimate {
            label: labels[j].clone(),
            kind: kinds[j].clone(),
            value: theta[j],
            std_uncertainty: (!in_null[j]).then(|| cov[(j, j)].max(0.0).sqrt()),
        })
        .collect();
    let correlation = DMat::from_fn(p, p, |i, j| {
        if in_null[i] || in_null[j] {
            return if i == j { 1.0 } else { 0.0 };
        }
        let d = (cov[(i, i)] * cov[(j, j)]).sqrt();
        if d > 0.0 { cov[(i, j)] / d } else { 0.0 }
    });
    let mut warnings = Vec::new();
    for c in &unobservable {
        warnings.push(format!("unobservable with these data: {} (only this combination's orthogonal complement is determined)", c.describe()));
    }
    for c in &weak {
        warnings.push(format!(
            "weakly identifiable (relative singular value {:.1e}): {}",
            c.relative_singular_value,
            c.describe()
        ));
    }
    // A location error beyond these is not a machine's: the design cannot separate it from
    // the others even when the rank test passed (e.g. one test of one setup).
    let implausible: Vec<String> = estimates
        .iter()
        .filter_map(|e| {
            let ParamKind::Slot(s) = &e.kind else {
                return None;
            };
            let (limit, unit) = if s.angular {
                (PLAUSIBLE_ANGLE_RAD, "rad")
            } else {
                (PLAUSIBLE_LENGTH_MM, "mm")
            };
            let u = e.std_uncertainty.unwrap_or(0.0);
            (!(e.value.abs() <= limit && u <= limit))
                .then(|| format!("{} = {:.3e} ± {:.3e} {unit}", e.label, e.value, u))
        })
        .collect();
    if !implausible.is_empty() {
        warnings.push(format!(
            "the design cannot separate these parameters: {} (beyond any machine's location error, |angle| ≤ {PLAUSIBLE_ANGLE_RAD} rad, |offset| ≤ {PLAUSIBLE_LENGTH_MM} mm); these data ({} readings, {} setup(s)) do not determine them: measure more tests or setups, or fit fewer parameters",
            implausible.join(", "),
            data.readings.len(),
            n_set
        ));
    }
    let _ = vs_inv;
    Ok(Fit {
        estimates,
        correlation,
        slot_values: e,
        nuisance: nu,
        sigma0_mm: sigma0,
        dof,
        residuals,
        identifiability: Identifiability {
            n_params: p,
            rank,
            relative_singular_values: rel,
            unobservable,
            weak,
        },
        warnings,
    })
}

/// Largest plausible rotary-axis location angle error (or its uncertainty), rad: 0.01 rad ≈
/// 0.57°, far beyond any machine's misalignment. Larger estimates are reported as a design
/// that cannot separate the parameters.
pub const PLAUSIBLE_ANGLE_RAD: f64 = 0.01;
/// Largest plausible location offset error (or its uncertainty), mm.
pub const PLAUSIBLE_LENGTH_MM: f64 = 10.0;

/// A value and its standard uncertainty (None when unobservable).
pub type ValueU = (f64, Option<f64>);

/// One fit per setup, the same spec, and the spread of each kinematic parameter across setups:
/// the check that exposed the B-axis/Y squareness in seed 002 (Table 2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Consistency {
    /// Setup ids, in dataset order.
    pub setups: Vec<String>,
    /// Per parameter label: value per setup (mm/rad) and its standard uncertainty.
    pub values: Vec<(String, Vec<ValueU>)>,
    /// Per parameter label: max − min across setups and the largest |difference| / combined
    /// uncertainty (z-score; above 3 the setups disagree beyond noise).
    pub spread: Vec<(String, f64, f64)>,
}

impl Consistency {
    /// Parameters whose setups disagree beyond `z` standard uncertainties.
    pub fn inconsistent(&self, z: f64) -> Vec<&str> {
        self.spread
            .iter()
            .filter(|s| s.2 > z)
            .map(|s| s.0.as_str())
            .collect()
    }
}

/// Fits every setup on its own with `spec` and compares the kinematic parameters.
///
/// # Errors
/// As [`identify`] for any setup.
pub fn setup_consistency(m: &Machine, data: &Dataset, spec: &FitSpec) -> Result<Consistency> {
    let mut fits = Vec::new();
    for si in 0..data.setups.len() {
        let rows = data.select(None, Some(si));
        let mut sub = data.subset(&rows);
        sub.setups = vec![data.setups[si].clone()];
        for r in &mut sub.readings {
            r.setup = 0;
        }
        fits.push(identify(m, &sub, spec)?);
    }
    let mut values = Vec::new();
    let mut spread = Vec::new();
    for p in &spec.params {
        let v: Vec<(f64, Option<f64>)> = fits
            .iter()
            .map(|f| {
                f.get(&p.iso)
                    .map(|e| (e.value, e.std_uncertainty))
                    .unwrap_or((0.0, None))
            })
            .collect();
        // spread over the setups where the parameter is observable (0 when fewer than two)
        let seen: Vec<f64> = v.iter().filter(|x| x.1.is_some()).map(|x| x.0).collect();
        let mx = seen.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mn = seen.iter().copied().fold(f64::INFINITY, f64::min);
        let (mx, mn) = if seen.len() < 2 { (0.0, 0.0) } else { (mx, mn) };
        let mut z: f64 = 0.0;
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                if let (Some(a), Some(b)) = (v[i].1, v[j].1) {
                    let u = (a * a + b * b).sqrt();
                    if u > 0.0 {
                        z = z.max((v[i].0 - v[j].0).abs() / u);
                    }
                }
            }
        }
        spread.push((p.iso.clone(), mx - mn, z));
        values.push((p.iso.clone(), v));
    }
    Ok(Consistency {
        setups: data.setups.iter().map(|s| s.id.clone()).collect(),
        values,
        spread,
    })
}
