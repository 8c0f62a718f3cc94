//! Network description (stations, targets, length observations), input checks and the
//! observation model shared with other crates.
//!
//! # Observation model
//!
//! A laser tracker at station `i` (position **Q**ᵢ, dead-path length `dᵢ`) measures the
//! interferometric length to target `j` (position **P**ⱼ):
//!
//! `ℓᵢⱼ = (1 + k)·|Qᵢ − Pⱼ| − dᵢ`   (seed 004: `lᵢ + lᵢⱼ = |Qᵢ − Pⱼ|`),
//!
//! with `k` a dimensionless length-scale error (0 for the adjustment; offered to the
//! diagnosis crate as an extra parameter). Lengths in mm.

use crate::error::{MetrologyError, Result, invalid};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// 3-vector (mm).
pub type Vec3 = Vector3<f64>;

/// Predicted interferometric length `(1 + k)·|Q − P| − d` (mm).
///
/// ```
/// use mte_metrology::network::{predict_length, Vec3};
/// let l = predict_length(&Vec3::new(0.0, 0.0, 0.0), 10.0, &Vec3::new(300.0, 400.0, 0.0), 0.0);
/// assert!((l - 490.0).abs() < 1e-12);
/// ```
pub fn predict_length(station_mm: &Vec3, dead_path_mm: f64, target_mm: &Vec3, scale: f64) -> f64 {
    (1.0 + scale) * (station_mm - target_mm).norm() - dead_path_mm
}

/// Partial derivatives of [`predict_length`] (exact first derivatives).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LengthJacobian {
    /// ∂ℓ/∂P (target coordinates) = −(1 + k)·u, u = (Q − P)/|Q − P|.
    pub d_target: Vec3,
    /// ∂ℓ/∂Q (station coordinates) = (1 + k)·u.
    pub d_station: Vec3,
    /// ∂ℓ/∂d (dead path) = −1.
    pub d_dead_path: f64,
    /// ∂ℓ/∂k (scale) = |Q − P| (mm).
    pub d_scale: f64,
}

/// Length and its Jacobian with respect to target, station, dead path and scale.
///
/// # Errors
/// [`MetrologyError::InvalidInput`] if station and target coincide (direction undefined).
///
/// ```
/// use mte_metrology::network::{length_and_jacobian, Vec3};
/// let (l, j) = length_and_jacobian(&Vec3::zeros(), 0.0, &Vec3::new(0.0, 0.0, 5.0), 0.0).unwrap();
/// assert_eq!(l, 5.0);
/// assert_eq!(j.d_target, Vec3::new(0.0, 0.0, 1.0));
/// ```
pub fn length_and_jacobian(
    station_mm: &Vec3,
    dead_path_mm: f64,
    target_mm: &Vec3,
    scale: f64,
) -> Result<(f64, LengthJacobian)> {
    let d = station_mm - target_mm;
    let r = d.norm();
    if r.is_nan() || r <= 0.0 || !r.is_finite() {
        return Err(invalid(format!(
            "station at {station_mm:?} and target at {target_mm:?} coincide or are not finite"
        )));
    }
    let u = d / r;
    Ok((
        (1.0 + scale) * r - dead_path_mm,
        LengthJacobian {
            d_target: -(1.0 + scale) * u,
            d_station: (1.0 + scale) * u,
            d_dead_path: -1.0,
            d_scale: r,
        },
    ))
}

/// Whether a station's dead-path length is estimated or held fixed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DeadPath {
    /// Estimated (4 unknowns for the station).
    Free,
    /// Held at the given value (3 unknowns for the station), e.g. 0 for plain distances.
    Fixed,
}

/// A tracker station: approximate position and dead path (start values of the adjustment).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Station {
    /// Unique id.
    pub id: String,
    /// Approximate position (mm).
    pub position_mm: Vec3,
    /// Approximate (or fixed) dead-path length (mm).
    pub dead_path_mm: f64,
    /// Free or fixed dead path.
    pub dead_path: DeadPath,
}

/// A target: the commanded (nominal) machine position. The datum is defined on these.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Target {
    /// Unique id.
    pub id: String,
    /// Nominal (commanded) position (mm).
    pub nominal_mm: Vec3,
}

/// One interferometric length from a station to a target.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LengthObservation {
    /// Index into [`Network::stations`].
    pub station: usize,
    /// Index into [`Network::targets`].
    pub target: usize,
    /// Observed length (mm).
    pub length_mm: f64,
    /// Standard deviation (mm).
    pub sigma_mm: f64,
}

/// Length uncertainty U(L) = a + b·L at coverage factor k (seed 004: 0.2 µm + 0.3 µm/m·L, k = 2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LengthUncertainty {
    /// Constant term (µm).
    pub a_um: f64,
    /// Length-proportional term (µm per m).
    pub b_um_per_m: f64,
    /// Coverage factor of a + b·L.
    pub k: f64,
}

impl LengthUncertainty {
    /// Seed 004's tracker: U = 0.2 µm + 0.3 µm/m·L at k = 2.
    pub const SEED004: Self = Self {
        a_um: 0.2,
        b_um_per_m: 0.3,
        k: 2.0,
    };

    /// Standard uncertainty (mm) for a length in mm: (a + b·L)/k.
    ///
    /// ```
    /// let s = mte_metrology::network::LengthUncertainty::SEED004.sigma_mm(1000.0);
    /// assert!((s - 0.25e-3).abs() < 1e-15);
    /// ```
    pub fn sigma_mm(&self, length_mm: f64) -> f64 {
        (self.a_um + self.b_um_per_m * length_mm.abs() * 1e-3) / self.k * 1e-3
    }
}

/// The whole measurement: stations, targets and lengths.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Network {
    /// Stations (approximate values).
    pub stations: Vec<Station>,
    /// Targets (nominal values).
    pub targets: Vec<Target>,
    /// Observations.
    pub observations: Vec<LengthObservation>,
}

/// Non-fatal findings of [`Network::check`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CheckReport {
    /// Number of observations.
    pub n_observations: usize,
    /// Number of unknowns (station coordinates, free dead paths, target coordinates).
    pub n_unknowns: usize,
    /// Redundancy n_obs − (n_unknowns − 6).
    pub degrees_of_freedom: usize,
    /// Warnings (weak geometry etc.).
    pub warnings: Vec<String>,
}

impl Network {
    /// Look up a station index by id.
    pub fn station_index(&self, id: &str) -> Option<usize> {
        self.stations.iter().position(|s| s.id == id)
    }

    /// Look up a target index by id.
    pub fn target_index(&self, id: &str) -> Option<usize> {
        self.targets.iter().position(|t| t.id == id)
    }

    /// Number of free dead paths.
    pub fn n_free_dead_paths(&self) -> usize {
        self.stations
            .iter()
            .filter(|s| s.dead_path == DeadPath::Free)
            .count()
    }

    /// Checks before solving: finite values, positive lengths and sigmas, unique ids, at
    /// least 4 stations, each target seen from ≥ 3 stations, m·n ≥ 4m + 3n − 6 (3m with fixed
    /// dead paths), non-coplanar stations when dead paths are free.
    ///
    /// # Errors
    /// A [`MetrologyError`] naming the offending item.
    pub fn check(&self) -> Result<CheckReport> {
        let mut ids = HashMap::new();
        for s in &self.stations {
            if ids.insert(s.id.as_str(), ()).is_some() {
                return Err(MetrologyError::DuplicateId {
                    kind: "station",
                    id: s.id.clone(),
                });
            }
            if !s.position_mm.iter().all(|v| v.is_finite()) || !s.dead_path_mm.is_finite() {
                return Err(invalid(format!(
                    "station `{}`: coordinates or dead path not finite",
                    s.id
                )));
            }
        }
        let mut tids = HashMap::new();
        for t in &self.targets {
            if tids.insert(t.id.as_str(), ()).is_some() {
                return Err(MetrologyError::DuplicateId {
                    kind: "target",
                    id: t.id.clone(),
                });
            }
            if !t.nominal_mm.iter().all(|v| v.is_finite()) {
                return Err(invalid(format!(
                    "target `{}`: nominal coordinates not finite",
                    t.id
                )));
            }
        }
        let m = self.stations.len();
        let n = self.targets.len();
        if m < 4 {
            return Err(MetrologyError::TooFewData {
                what: format!(
                    "{m} stations; multilateration needs at least 4 non-coplanar stations"
                ),
            });
        }
        let mut seen = vec![0usize; n];
        let mut pair = HashMap::new();
        for (k, o) in self.observations.iter().enumerate() {
            if o.station >= m || o.target >= n {
                return Err(invalid(format!(
                    "observation #{k}: station index {} / target index {} out of range ({m} stations, {n} targets)",
                    o.station, o.target
                )));
            }
            let name = || {
                format!(
                    "observation #{k} ({} → {})",
                    self.stations[o.station].id, self.targets[o.target].id
                )
            };
            if !o.length_mm.is_finite() {
                return Err(invalid(format!("{}: length is {}", name(), o.length_mm)));
            }
            if o.length_mm < 0.0 {
                return Err(invalid(format!(
                    "{}: negative length {} mm",
                    name(),
                    o.length_mm
                )));
            }
            if o.sigma_mm.is_nan() || o.sigma_mm <= 0.0 || !o.sigma_mm.is_finite() {
                return Err(invalid(format!(
                    "{}: standard deviation must be > 0, got {} mm",
                    name(),
                    o.sigma_mm
                )));
            }
            if pair.insert((o.station, o.target), k).is_some() {
                return Err(invalid(format!(
                    "{}: repeated station–target pair (average repeats first)",
                    name()
                )));
            }
            seen[o.target] += 1;
        }
        for (j, c) in seen.iter().enumerate() {
            if *c < 3 {
                return Err(MetrologyError::TooFewData {
                    what: format!(
                        "target `{}` is seen from {c} station(s); at least 3 are needed",
                        self.targets[j].id
                    ),
                });
            }
        }
        let n_dp = self.n_free_dead_paths();
        let n_unknowns = 3 * m + n_dp + 3 * n;
        let n_obs = self.observations.len();
        if n_obs + 6 < n_unknowns {
            return Err(MetrologyError::TooFewData {
                what: format!(
                    "{n_obs} lengths for {n_unknowns} unknowns minus 6 datum parameters ({m} stations, {n} targets, {n_dp} free dead paths): need m·n ≥ {}m + 3n − 6",
                    if n_dp > 0 { 4 } else { 3 }
                ),
            });
        }
        let mut warnings = Vec::new();
        // coplanarity of the stations
        let c: Vec3 = self.stations.iter().map(|s| s.position_mm).sum::<Vec3>() / m as f64;
        let mut cov = nalgebra::Matrix3::<f64>::zeros();
        for s in &self.stations {
            let d = s.position_mm - c;
            cov += d * d.transpose();
        }
        let eig = nalgebra::SymmetricEigen::new(cov / m as f64);
        let mut ev: Vec<f64> = eig.eigenvalues.iter().map(|v| v.max(0.0).sqrt()).collect();
        ev.sort_by(|a, b| a.total_cmp(b));
        let spread = ev[2].max(1e-300);
        if ev[0] < 1e-6 * spread {
            let msg = format!(
                "stations {} are coplanar (rms distance from their best-fit plane {:.3e} mm, in-plane spread {:.1} mm)",
                self.stations
                    .iter()
                    .map(|s| s.id.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                ev[0],
                spread
            );
            if n_dp > 0 {
                return Err(MetrologyError::RankDefect {
                    what: format!(
                        "{msg}; with free dead paths this adds a rank defect — raise or lower at least one station"
                    ),
                });
            }
            warnings.push(format!(
                "{msg}; targets on both sides of the plane are ambiguous by reflection"
            ));
        } else if ev[0] < 0.02 * spread {
            warnings.push(format!(
                "stations are nearly coplanar (out-of-plane rms {:.1} mm vs spread {:.1} mm): weak geometry, expect large uncertainties",
                ev[0], spread
            ));
        }
        Ok(CheckReport {
            n_observations: n_obs,
            n_unknowns,
            degrees_of_freedom: n_obs + 6 - n_unknowns,
            warnings,
        })
    }
}
