//! Synthetic tracker measurements for seed 004 style studies: cube-edge targets, station
//! layouts, smooth machine error fields, noisy lengths, and the truth expressed in the
//! free-network datum.

use crate::error::Result;
use crate::network::{
    DeadPath, LengthObservation, LengthUncertainty, Network, Station, Target, Vec3, predict_length,
};
use nalgebra::Matrix3;
use rand::SeedableRng;
use rand_chacha::ChaCha20Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Targets on the 12 edges of the cube [0, L]³, `per_edge` equally spaced interior points per
/// edge (at k/(per_edge+1)); `per_edge = 2` gives the 24 targets of seed 004 / the Gama network.
/// Ids `P1`, `P2`, … in the order of the Gama network for `per_edge = 2`.
pub fn cube_edge_targets(edge_mm: f64, per_edge: usize) -> Vec<Target> {
    let l = edge_mm;
    let f: Vec<f64> = (1..=per_edge)
        .map(|k| k as f64 / (per_edge + 1) as f64 * l)
        .collect();
    let mut pts = Vec::new();
    // edges in the order (x, y fixed; z varies), (x, z; y), (y, z; x) for the 4 corner pairs
    let corners2 = [(0.0, 0.0), (0.0, l), (l, 0.0), (l, l)];
    let mut by_edge: Vec<Vec<Vec3>> = Vec::new();
    for &(a, b) in &corners2 {
        by_edge.push(f.iter().map(|&t| Vec3::new(a, b, t)).collect()); // along z
        by_edge.push(f.iter().map(|&t| Vec3::new(a, t, b)).collect()); // along y
        by_edge.push(f.iter().map(|&t| Vec3::new(t, a, b)).collect()); // along x
    }
    // Gama order: x=0,y=0 (z); x=0,z=0 (y); y=0,z=0 (x); x=0,z=L (y); y=0,z=L (x); x=0,y=L (z);
    // y=L,z=0 (x); y=L,z=L (x); x=L,y=0 (z); x=L,z=0 (y); x=L,z=L (y); x=L,y=L (z)
    let order = [0usize, 1, 2, 4, 8, 3, 5, 11, 6, 7, 10, 9];
    for e in order {
        pts.extend(by_edge[e].iter().copied());
    }
    pts.into_iter()
        .enumerate()
        .map(|(i, p)| Target {
            id: format!("P{}", i + 1),
            nominal_mm: p,
        })
        .collect()
}

/// Station layouts studied in the seed 004 reproduction (cube [0, L]³ on the table).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum StationLayout {
    /// 4 stations below the cube, outside its corners, at heights −0.3L, −0.2L, −0.3L, −0.1L
    /// (the Gama network's layout scaled to L; not coplanar).
    FourLow,
    /// 2 low (−0.3L) and 2 high (+1.3L) at the 4 outer corners, diagonally alternating.
    TwoHighTwoLow,
    /// `FourLow` plus 2 high stations (+1.3L) outside the middle of the y = 0 and y = L faces.
    Six,
}

impl StationLayout {
    /// All layouts.
    pub const ALL: [StationLayout; 3] = [
        StationLayout::FourLow,
        StationLayout::TwoHighTwoLow,
        StationLayout::Six,
    ];

    /// Name for reports.
    pub fn name(&self) -> &'static str {
        match self {
            StationLayout::FourLow => "4 low",
            StationLayout::TwoHighTwoLow => "2 high + 2 low",
            StationLayout::Six => "6 stations (4 low + 2 high)",
        }
    }

    /// Station positions for a cube of edge `edge_mm`; dead paths 0 and free or fixed.
    pub fn stations(&self, edge_mm: f64, free_dead_path: bool) -> Vec<Station> {
        let l = edge_mm;
        let rel: Vec<[f64; 3]> = match self {
            StationLayout::FourLow => vec![
                [-0.15, -0.15, -0.3],
                [1.15, -0.15, -0.2],
                [1.15, 1.15, -0.3],
                [-0.15, 1.15, -0.1],
            ],
            StationLayout::TwoHighTwoLow => vec![
                [-0.15, -0.15, -0.3],
                [1.15, -0.15, 1.3],
                [1.15, 1.15, -0.3],
                [-0.15, 1.15, 1.3],
            ],
            StationLayout::Six => vec![
                [-0.15, -0.15, -0.3],
                [1.15, -0.15, -0.2],
                [1.15, 1.15, -0.3],
                [-0.15, 1.15, -0.1],
                [0.5, -0.3, 1.3],
                [0.5, 1.3, 1.3],
            ],
        };
        rel.iter()
            .enumerate()
            .map(|(i, r)| Station {
                id: format!("S{}", i + 1),
                position_mm: Vec3::new(r[0] * l, r[1] * l, r[2] * l),
                dead_path_mm: 0.0,
                dead_path: if free_dead_path {
                    DeadPath::Free
                } else {
                    DeadPath::Fixed
                },
            })
            .collect()
    }
}

/// A smooth geometric error field of a 3-axis machine over the cube [0, L]³: scale errors,
/// squareness, a straightness bow and a small periodic term, scaled so that the largest error
/// over `targets` is `max_um`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SmoothErrorField {
    /// Cube edge (mm).
    pub edge_mm: f64,
    /// Scale of the unit field (mm).
    pub scale_mm: f64,
}

impl SmoothErrorField {
    /// Field scaled so that its largest error over `targets`, after removing the rigid motion
    /// that the free network cannot see ([`align_to_nominal`]), is `max_um`.
    pub fn new(edge_mm: f64, targets: &[Target], max_um: f64) -> Self {
        let unit = SmoothErrorField {
            edge_mm,
            scale_mm: 1.0,
        };
        let nominal: Vec<Vec3> = targets.iter().map(|t| t.nominal_mm).collect();
        let actual: Vec<Vec3> = nominal.iter().map(|p| p + unit.eval(p) * 1e-3).collect();
        let aligned = align_to_nominal(&actual, &nominal);
        let m = aligned
            .iter()
            .zip(&nominal)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max)
            * 1e3;
        SmoothErrorField {
            edge_mm,
            scale_mm: if m > 0.0 { max_um * 1e-3 / m } else { 0.0 },
        }
    }

    /// Error vector (mm) at a nominal position.
    pub fn eval(&self, p: &Vec3) -> Vec3 {
        let s = p / self.edge_mm;
        let (x, y, z) = (s.x, s.y, s.z);
        let tau = std::f64::consts::TAU;
        let dx = 0.8 * x + 0.5 * y - 0.3 * z * y + 0.15 * (tau * x).sin();
        let dy = -0.6 * y + 0.4 * x * x + 0.3 * z + 0.1 * (tau * y).cos();
        let dz = 0.5 * z - 0.4 * x * (1.0 - x) + 0.35 * y * z;
        Vec3::new(dx, dy, dz) * self.scale_mm
    }
}

/// A simulated measurement and its truth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Simulation {
    /// The network as a user would have it: approximate stations (true + (1, −2, 0.5) mm,
    /// dead path start 0), nominal targets, noisy lengths with σ(L).
    pub network: Network,
    /// True station positions (mm).
    pub true_stations: Vec<Vec3>,
    /// True dead paths (mm).
    pub true_dead_paths: Vec<f64>,
    /// True target positions (mm) = nominal + field.
    pub true_targets: Vec<Vec3>,
}

/// Simulate all station–target lengths with Gaussian noise σ(L) from `u`, seeded (ChaCha20).
/// True dead paths are 40 + 5·i mm for free dead paths (0 for fixed ones).
///
/// # Errors
/// None in practice (kept for future checks).
pub fn simulate(
    stations: &[Station],
    targets: &[Target],
    field: &dyn Fn(&Vec3) -> Vec3,
    u: LengthUncertainty,
    seed: u64,
) -> Result<Simulation> {
    let mut rng = ChaCha20Rng::seed_from_u64(seed);
    let true_targets: Vec<Vec3> = targets
        .iter()
        .map(|t| t.nominal_mm + field(&t.nominal_mm))
        .collect();
    let true_stations: Vec<Vec3> = stations.iter().map(|s| s.position_mm).collect();
    let true_dead_paths: Vec<f64> = stations
        .iter()
        .enumerate()
        .map(|(i, s)| {
            if s.dead_path == DeadPath::Free {
                40.0 + 5.0 * i as f64
            } else {
                s.dead_path_mm
            }
        })
        .collect();
    let mut obs = Vec::new();
    for (i, s) in stations.iter().enumerate() {
        for (j, t) in true_targets.iter().enumerate() {
            let l = predict_length(&true_stations[i], true_dead_paths[i], t, 0.0);
            let sigma = u.sigma_mm(l + true_dead_paths[i]);
            let e: f64 = StandardNormal.sample(&mut rng);
            let _ = s;
            obs.push(LengthObservation {
                station: i,
                target: j,
                length_mm: l + sigma * e,
                sigma_mm: sigma,
            });
        }
    }
    let approx: Vec<Station> = stations
        .iter()
        .map(|s| Station {
            position_mm: s.position_mm + Vec3::new(1.0, -2.0, 0.5),
            dead_path_mm: if s.dead_path == DeadPath::Free {
                0.0
            } else {
                s.dead_path_mm
            },
            ..s.clone()
        })
        .collect();
    Ok(Simulation {
        network: Network {
            stations: approx,
            targets: targets.to_vec(),
            observations: obs,
        },
        true_stations,
        true_dead_paths,
        true_targets,
    })
}

/// Express true points in the minimum-correction datum: the rigid motion (R, t) minimising
/// Σ|R·pⱼ + t − nominalⱼ|² (Kabsch/Procrustes), applied to the points. Its optimality
/// conditions are exactly the [`crate::adjust::Datum::NominalTargets`] conditions.
pub fn align_to_nominal(points: &[Vec3], nominal: &[Vec3]) -> Vec<Vec3> {
    let n = points.len() as f64;
    let cp: Vec3 = points.iter().sum::<Vec3>() / n;
    let cn: Vec3 = nominal.iter().sum::<Vec3>() / n;
    let mut h = Matrix3::<f64>::zeros();
    for (p, q) in points.iter().zip(nominal) {
        h += (p - cp) * (q - cn).transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let mut d = Matrix3::<f64>::identity();
    if (vt.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = vt.transpose() * d * u.transpose();
    points.iter().map(|p| r * (p - cp) + cn).collect()
}
