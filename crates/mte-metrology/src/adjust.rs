//! Free-network adjustment of multilateration lengths (Gauss–Newton, Schur complement on the
//! target blocks, datum by constraints on the targets).
//!
//! # Model and datum
//!
//! Unknowns: station coordinates **Q**ᵢ (and dead paths dᵢ when free), target coordinates
//! **P**ⱼ. Observation equations `ℓᵢⱼ = |Qᵢ − Pⱼ| − dᵢ` (see [`crate::network`]). Lengths do not
//! see a rigid motion of the whole network, so the normal matrix **N** = **A**ᵀ**WA** has a rank
//! defect of 6; its null space is spanned by **E** (rows `[I | −[X − c]×]` for every station and
//! target coordinate triple, zeros for dead paths).
//!
//! The datum is a set of 6 linear conditions **D**ᵀ(**x** − **x**_ref) = 0 on target coordinates only:
//!
//! * [`Datum::NominalTargets`] (default, seed 004 and GNU Gama's "constrained coordinates"):
//!   **D**ⱼ = **E**ⱼ at the nominal coordinates for every target, i.e. the adjusted targets are as
//!   close as possible (least sum of squared corrections) to the commanded ones;
//! * [`Datum::TargetSubset`]: the same on a chosen subset;
//! * [`Datum::ThreeTwoOne`]: origin target keeps its nominal x, y, z, a second target its y, z,
//!   a third its z.
//!
//! Solve: **N**·δ = **n** together with **D**ᵀδ = c. Targets are eliminated target by target
//! (each is a 3×3 block coupled only to station parameters): **S** = **N**ₛₛ − Σⱼ **N**ₛⱼ**N**ⱼⱼ⁻¹**N**ⱼₛ,
//! solved with a reflexive symmetric generalised inverse **S**⁺ (scaled eigen-decomposition with
//! exactly six null eigenvalues); back-substitution gives a particular solution, and the datum
//! is applied by adding **E**λ with λ = (**D**ᵀ**E**)⁻¹(c − **D**ᵀδ). The cofactor matrix of the
//! constrained solution is **Q** = **S**_D **M** **S**_Dᵀ with **M** the block generalised
//! inverse and **S**_D = **I** − **E**(**D**ᵀ**E**)⁻¹**D**ᵀ (the S-transformation). Cost and
//! memory are linear in the number of targets; per-target 3×3 blocks are computed for all
//! targets, cross blocks on demand ([`Adjustment::covariance_block`]).
//!
//! Weights are 1/σ², so the a-priori σ₀ is 1 and the covariance is the a-priori one
//! (`sigma-act="apriori"` in GNU Gama's terms); multiply by `sigma0_ratio²` for the a-posteriori one.

use crate::error::{MetrologyError, Result, invalid};
use crate::network::{DeadPath, Network, Vec3};
use crate::stats;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, SMatrix, SymmetricEigen, Vector6};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

type Mat36 = SMatrix<f64, 3, 6>;
type Mat63 = SMatrix<f64, 6, 3>;

/// Targets per parallel chunk (fixed, so sums are formed in the same order for any thread count).
const CHUNK: usize = 2048;

/// Datum of the free network (6 conditions on target coordinates).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Datum {
    /// Minimum sum of squared corrections of all targets w.r.t. their nominal coordinates
    /// (inner constraints on translations and rotations, seed 004; Gama "constrained coordinates").
    NominalTargets,
    /// The same minimum on the listed targets (indices into `Network::targets`).
    TargetSubset(Vec<usize>),
    /// 3-2-1: `origin` keeps nominal x, y, z; `x_axis` keeps nominal y, z; `xy_plane` keeps nominal z.
    ThreeTwoOne {
        /// Target fixing the origin.
        origin: usize,
        /// Target fixing the direction of x (keeps its y and z).
        x_axis: usize,
        /// Target fixing the xy plane (keeps its z).
        xy_plane: usize,
    },
}

impl Datum {
    /// Human-readable name of the datum (printed in every report).
    pub fn describe(&self, net: &Network) -> String {
        let id = |j: usize| net.targets.get(j).map(|t| t.id.as_str()).unwrap_or("?");
        match self {
            Datum::NominalTargets => format!(
                "free network, minimum corrections of all {} targets w.r.t. their nominal (commanded) coordinates (inner constraints: 3 translations + 3 rotations)",
                net.targets.len()
            ),
            Datum::TargetSubset(s) => format!(
                "free network, minimum corrections of targets {{{}}} w.r.t. their nominal coordinates",
                s.iter().map(|&j| id(j)).collect::<Vec<_>>().join(", ")
            ),
            Datum::ThreeTwoOne {
                origin,
                x_axis,
                xy_plane,
            } => format!(
                "3-2-1: {} keeps nominal x, y, z; {} keeps nominal y, z; {} keeps nominal z",
                id(*origin),
                id(*x_axis),
                id(*xy_plane)
            ),
        }
    }
}

/// Knobs of [`adjust`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdjustParams {
    /// The datum.
    pub datum: Datum,
    /// Maximum Gauss–Newton iterations.
    pub max_iterations: usize,
    /// Convergence: max |correction| below this (mm).
    pub tolerance_mm: f64,
    /// Significance level of the two-sided χ² test of σ₀ (0.05).
    pub alpha_global: f64,
    /// Significance level of data snooping per observation (Baarda: 0.001 → |w| > 3.29).
    pub alpha_snooping: f64,
}

impl Default for AdjustParams {
    fn default() -> Self {
        Self {
            datum: Datum::NominalTargets,
            max_iterations: 30,
            tolerance_mm: 1e-9,
            alpha_global: 0.05,
            alpha_snooping: 0.001,
        }
    }
}

/// Adjusted station.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdjustedStation {
    /// Id.
    pub id: String,
    /// Adjusted position (mm).
    pub position_mm: Vec3,
    /// Adjusted (or fixed) dead path (mm).
    pub dead_path_mm: f64,
    /// Standard deviations of x, y, z (mm, a priori).
    pub sigma_mm: Vec3,
    /// Standard deviation of the dead path (mm; 0 when fixed).
    pub dead_path_sigma_mm: f64,
}

/// Error ellipsoid of a point (from its 3×3 covariance).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ellipsoid {
    /// 1σ semi-axes (mm), largest first.
    pub semi_axes_mm: [f64; 3],
    /// Unit directions of the semi-axes (columns match `semi_axes_mm`).
    pub axes: [Vec3; 3],
    /// Factor turning 1σ semi-axes into the 95 % ellipsoid: √χ²₃(0.95) = 2.7955.
    pub scale_95: f64,
}

impl Ellipsoid {
    /// From a symmetric positive semi-definite 3×3 covariance (mm²).
    pub fn from_covariance(c: &Matrix3<f64>) -> Self {
        let e = SymmetricEigen::new(*c);
        let mut idx = [0usize, 1, 2];
        idx.sort_by(|&a, &b| e.eigenvalues[b].total_cmp(&e.eigenvalues[a]));
        Ellipsoid {
            semi_axes_mm: idx.map(|i| e.eigenvalues[i].max(0.0).sqrt()),
            axes: idx.map(|i| e.eigenvectors.column(i).into_owned()),
            scale_95: Self::SCALE_95,
        }
    }

    /// √χ²₃(0.95), the 1σ → 95 % factor of a 3-D normal. A constant because a network of 10⁵
    /// targets would otherwise invert the χ² distribution 10⁵ times (half the adjustment time);
    /// `scale_95_is_the_chi2_quantile` checks it against [`stats::chi2_quantile`].
    pub const SCALE_95: f64 = 2.795_483_482_915_107_4;
}

/// Adjusted target: the spatial error of the machine at this commanded point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdjustedTarget {
    /// Id.
    pub id: String,
    /// Nominal (commanded) position (mm).
    pub nominal_mm: Vec3,
    /// Adjusted (measured) position in the datum (mm).
    pub position_mm: Vec3,
    /// Error = adjusted − nominal (mm), machine coordinates.
    pub deviation_mm: Vec3,
    /// 3×3 covariance (mm², a priori), row-major.
    pub covariance_mm2: [[f64; 3]; 3],
    /// Error ellipsoid.
    pub ellipsoid: Ellipsoid,
}

impl AdjustedTarget {
    /// Covariance as a matrix.
    pub fn covariance(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|r, c| self.covariance_mm2[r][c])
    }
    /// 3-D standard uncertainty √(tr C) (mm).
    pub fn sigma_3d_mm(&self) -> f64 {
        self.covariance().trace().max(0.0).sqrt()
    }
}

/// Statistics of one observation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObservationStats {
    /// Station id.
    pub station: String,
    /// Target id.
    pub target: String,
    /// Observed length (mm).
    pub observed_mm: f64,
    /// Adjusted length (mm).
    pub adjusted_mm: f64,
    /// Residual v = adjusted − observed (mm).
    pub residual_mm: f64,
    /// A-priori standard deviation (mm).
    pub sigma_mm: f64,
    /// Redundancy number rᵢ = 1 − pᵢ·aᵢQaᵢᵀ (0 … 1, sum = degrees of freedom).
    pub redundancy: f64,
    /// Standardised residual wᵢ = vᵢ / (σᵢ·√rᵢ) (Baarda's w-test statistic; NaN-free: 0 if rᵢ ≈ 0).
    pub standardised_residual: f64,
    /// Flagged by data snooping (|w| > critical value).
    pub suspect: bool,
}

/// Global test of the variance factor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GlobalTest {
    /// Weighted sum of squared residuals \[pvv\] = Σ (vᵢ/σᵢ)².
    pub pvv: f64,
    /// Degrees of freedom.
    pub degrees_of_freedom: usize,
    /// σ₀' / σ₀ = √(\[pvv\]/f).
    pub sigma0_ratio: f64,
    /// Two-sided acceptance interval of σ₀'/σ₀ at 1 − α.
    pub interval: (f64, f64),
    /// Whether the ratio lies in the interval.
    pub passed: bool,
    /// Data-snooping critical value (two-sided normal quantile at α_snooping).
    pub snooping_critical: f64,
}

/// Result of [`adjust`].
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Adjustment {
    /// The datum, in words.
    pub datum_description: String,
    /// The datum.
    pub datum: Datum,
    /// Gauss–Newton iterations used.
    pub iterations: usize,
    /// Stations.
    pub stations: Vec<AdjustedStation>,
    /// Targets.
    pub targets: Vec<AdjustedTarget>,
    /// Per observation, in input order.
    pub observations: Vec<ObservationStats>,
    /// χ² test of σ₀.
    pub global: GlobalTest,
    /// Warnings from the checks.
    pub warnings: Vec<String>,
    /// The parameters used.
    pub params: AdjustParams,
    #[serde(skip)]
    pub(crate) model: Option<CovModel>,
}

/// Everything needed to form covariance blocks after the solve.
#[derive(Clone, Debug)]
pub(crate) struct CovModel {
    pub(crate) net: Network,
    pub(crate) layout: Layout,
    pub(crate) q: Vec<Vec3>,
    pub(crate) p: Vec<Vec3>,
    pub(crate) center: Vec3,
    pub(crate) s_pinv: DMatrix<f64>,
    pub(crate) ninv: Vec<Matrix3<f64>>,
    pub(crate) u: Vec<Vec3>,
    pub(crate) w: Vec<f64>,
    pub(crate) dat: DatumMats,
}

#[derive(Clone, Debug)]
pub(crate) struct DatumMats {
    rows: Vec<(usize, Mat36)>,
    h: Matrix6<f64>,
    wmat: DMatrix<f64>, // 6 × ns
    g: Matrix6<f64>,
    in_datum: Vec<Option<usize>>, // target → index into rows
}

#[derive(Clone, Debug)]
pub(crate) struct Layout {
    pub(crate) st_off: Vec<usize>,
    pub(crate) st_np: Vec<usize>,
    pub(crate) ns: usize,
    pub(crate) t_off: Vec<usize>,
    pub(crate) t_obs: Vec<usize>,
}

impl Layout {
    fn new(net: &Network) -> Self {
        let mut st_off = Vec::new();
        let mut st_np = Vec::new();
        let mut ns = 0;
        for s in &net.stations {
            let np = if s.dead_path == DeadPath::Free { 4 } else { 3 };
            st_off.push(ns);
            st_np.push(np);
            ns += np;
        }
        let n = net.targets.len();
        let mut cnt = vec![0usize; n + 1];
        for o in &net.observations {
            cnt[o.target + 1] += 1;
        }
        for j in 0..n {
            cnt[j + 1] += cnt[j];
        }
        let mut fill = cnt.clone();
        let mut t_obs = vec![0usize; net.observations.len()];
        for (k, o) in net.observations.iter().enumerate() {
            t_obs[fill[o.target]] = k;
            fill[o.target] += 1;
        }
        Layout {
            st_off,
            st_np,
            ns,
            t_off: cnt,
            t_obs,
        }
    }
    fn obs_of(&self, j: usize) -> &[usize] {
        &self.t_obs[self.t_off[j]..self.t_off[j + 1]]
    }
}

fn e_rows(x: &Vec3, c: &Vec3) -> Mat36 {
    let d = x - c;
    let mut m = Mat36::zeros();
    m.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&Matrix3::identity());
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-skew(&d)));
    m
}

fn skew(v: &Vec3) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// a_s of observation k as a 4-vector (4th entry used only with a free dead path).
#[inline]
fn a_s(u: &Vec3) -> [f64; 4] {
    [u.x, u.y, u.z, -1.0]
}

fn datum_rows(datum: &Datum, net: &Network, center: &Vec3) -> Result<Vec<(usize, Mat36)>> {
    let n = net.targets.len();
    let chk = |j: usize| -> Result<()> {
        if j >= n {
            Err(MetrologyError::InvalidDatum {
                what: format!("target index {j} out of range ({n} targets)"),
            })
        } else {
            Ok(())
        }
    };
    Ok(match datum {
        Datum::NominalTargets => (0..n)
            .map(|j| (j, e_rows(&net.targets[j].nominal_mm, center)))
            .collect(),
        Datum::TargetSubset(s) => {
            let mut v = Vec::new();
            let mut seen = std::collections::HashSet::new();
            for &j in s {
                chk(j)?;
                if !seen.insert(j) {
                    return Err(MetrologyError::InvalidDatum {
                        what: format!("target `{}` listed twice", net.targets[j].id),
                    });
                }
                v.push((j, e_rows(&net.targets[j].nominal_mm, center)));
            }
            if v.len() < 3 {
                return Err(MetrologyError::InvalidDatum {
                    what: format!(
                        "{} datum targets; at least 3 non-collinear targets are needed",
                        v.len()
                    ),
                });
            }
            v
        }
        Datum::ThreeTwoOne {
            origin,
            x_axis,
            xy_plane,
        } => {
            for &j in [origin, x_axis, xy_plane] {
                chk(j)?;
            }
            if origin == x_axis || origin == xy_plane || x_axis == xy_plane {
                return Err(MetrologyError::InvalidDatum {
                    what: "3-2-1 needs three different targets".into(),
                });
            }
            let mut a = Mat36::zeros();
            a[(0, 0)] = 1.0;
            a[(1, 1)] = 1.0;
            a[(2, 2)] = 1.0;
            let mut b = Mat36::zeros();
            b[(1, 3)] = 1.0;
            b[(2, 4)] = 1.0;
            let mut c = Mat36::zeros();
            c[(2, 5)] = 1.0;
            vec![(*origin, a), (*x_axis, b), (*xy_plane, c)]
        }
    })
}

struct Lin {
    u: Vec<Vec3>,
    f: Vec<f64>,
    w: Vec<f64>,
}

fn linearise(net: &Network, q: &[Vec3], d: &[f64], p: &[Vec3]) -> Result<Lin> {
    let r: Vec<Result<(Vec3, f64)>> = net
        .observations
        .par_iter()
        .map(|o| {
            let diff = q[o.station] - p[o.target];
            let r = diff.norm();
            if !(r > 0.0 && r.is_finite()) {
                return Err(invalid(format!(
                    "station `{}` and target `{}` coincide (or diverged)",
                    net.stations[o.station].id, net.targets[o.target].id
                )));
            }
            Ok((diff / r, o.length_mm - (r - d[o.station])))
        })
        .collect();
    let mut u = Vec::with_capacity(r.len());
    let mut f = Vec::with_capacity(r.len());
    for x in r {
        let (a, b) = x?;
        u.push(a);
        f.push(b);
    }
    let w = net
        .observations
        .iter()
        .map(|o| 1.0 / (o.sigma_mm * o.sigma_mm))
        .collect();
    Ok(Lin { u, f, w })
}

struct Reduced {
    s: DMatrix<f64>,
    rs: DVector<f64>,
    ninv: Vec<Matrix3<f64>>,
    g: Vec<Vec3>,
}

/// Form the reduced station system (parallel over fixed target chunks, ordered reduction).
fn reduce(net: &Network, lay: &Layout, lin: &Lin) -> Result<Reduced> {
    let n = net.targets.len();
    let ns = lay.ns;
    let chunks: Vec<Result<(DMatrix<f64>, DVector<f64>, Vec<Matrix3<f64>>, Vec<Vec3>)>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut s = DMatrix::<f64>::zeros(ns, ns);
            let mut rs = DVector::<f64>::zeros(ns);
            let (j0, j1) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
            let mut ninvs = Vec::with_capacity(j1 - j0);
            let mut gs = Vec::with_capacity(j1 - j0);
            for j in j0..j1 {
                let obs = lay.obs_of(j);
                let mut ntt = Matrix3::<f64>::zeros();
                let mut nt = Vec3::zeros();
                for &k in obs {
                    let (u, w, f) = (&lin.u[k], lin.w[k], lin.f[k]);
                    ntt += w * u * u.transpose();
                    nt -= w * f * u;
                    // station diagonal block and rhs
                    let st = net.observations[k].station;
                    let (o, np) = (lay.st_off[st], lay.st_np[st]);
                    let a = a_s(u);
                    for r in 0..np {
                        rs[o + r] += w * a[r] * f;
                        for cc in 0..np {
                            s[(o + r, o + cc)] += w * a[r] * a[cc];
                        }
                    }
                }
                let tr = ntt.trace();
                let det = ntt.determinant();
                let ninv = match ntt.try_inverse() {
                    Some(m) if det > 1e-12 * (tr / 3.0).powi(3) => m,
                    _ => {
                        return Err(MetrologyError::RankDefect {
                            what: format!(
                                "target `{}`: its lines of sight span less than 3 directions (stations seeing it are collinear with it)",
                                net.targets[j].id
                            ),
                        });
                    }
                };
                let g = ninv * nt;
                // Schur update
                for &k in obs {
                    let (uk, wk) = (&lin.u[k], lin.w[k]);
                    let sk = net.observations[k].station;
                    let (ok, npk) = (lay.st_off[sk], lay.st_np[sk]);
                    let ak = a_s(uk);
                    let nu = ninv * uk;
                    let ug = uk.dot(&g);
                    for r in 0..npk {
                        rs[ok + r] += wk * ak[r] * ug;
                    }
                    for &l in obs {
                        let (ul, wl) = (&lin.u[l], lin.w[l]);
                        let sl = net.observations[l].station;
                        let (ol, npl) = (lay.st_off[sl], lay.st_np[sl]);
                        let al = a_s(ul);
                        let cc = wk * wl * nu.dot(ul);
                        for r in 0..npk {
                            let t = cc * ak[r];
                            for q in 0..npl {
                                s[(ok + r, ol + q)] -= t * al[q];
                            }
                        }
                    }
                }
                ninvs.push(ninv);
                gs.push(g);
            }
            Ok((s, rs, ninvs, gs))
        })
        .collect();
    let mut s = DMatrix::<f64>::zeros(ns, ns);
    let mut rs = DVector::<f64>::zeros(ns);
    let mut ninv = Vec::with_capacity(n);
    let mut g = Vec::with_capacity(n);
    for c in chunks {
        let (a, b, ni, gi) = c?;
        s += a;
        rs += b;
        ninv.extend(ni);
        g.extend(gi);
    }
    // symmetrise
    let st = s.transpose();
    s = (s + st) * 0.5;
    Ok(Reduced { s, rs, ninv, g })
}

fn param_name(net: &Network, lay: &Layout, idx: usize) -> String {
    for (i, s) in net.stations.iter().enumerate() {
        if idx >= lay.st_off[i] && idx < lay.st_off[i] + lay.st_np[i] {
            return format!(
                "station {} {}",
                s.id,
                ["x", "y", "z", "dead path"][idx - lay.st_off[i]]
            );
        }
    }
    format!("parameter {idx}")
}

/// Reflexive symmetric generalised inverse of the reduced station matrix, with exactly 6 null
/// eigenvalues expected; more → rank defect naming the weak combination.
fn pinv_station(net: &Network, lay: &Layout, s: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let ns = lay.ns;
    let dsc = DVector::from_iterator(ns, (0..ns).map(|i| 1.0 / s[(i, i)].max(1e-300).sqrt()));
    let st = DMatrix::from_fn(ns, ns, |r, c| s[(r, c)] * dsc[r] * dsc[c]);
    let eig = SymmetricEigen::new(st);
    let mut idx: Vec<usize> = (0..ns).collect();
    idx.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let lmax = eig.eigenvalues[idx[ns - 1]].max(1e-300);
    if ns > 6 {
        let l7 = eig.eigenvalues[idx[6]];
        if l7 < 1e-11 * lmax {
            let v = eig.eigenvectors.column(idx[6]);
            let mut comp: Vec<(usize, f64)> = (0..ns).map(|i| (i, v[i] * dsc[i])).collect();
            let vmax = comp.iter().map(|c| c.1.abs()).fold(0.0, f64::max);
            comp.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            let names: Vec<String> = comp
                .iter()
                .take_while(|c| c.1.abs() > 0.2 * vmax)
                .take(8)
                .map(|c| format!("{:+.3}·({})", c.1 / vmax, param_name(net, lay, c.0)))
                .collect();
            return Err(MetrologyError::RankDefect {
                what: format!(
                    "the station parameters have more than the 6 datum defects (7th eigenvalue {:.2e} of the scaled reduced normal matrix); undetermined combination: {} — typical causes: coplanar stations with free dead paths, too few targets, targets on a line or plane",
                    l7 / lmax,
                    names.join(" ")
                ),
            });
        }
    }
    let mut inv = DMatrix::<f64>::zeros(ns, ns);
    for &i in idx.iter().skip(6) {
        let v = eig.eigenvectors.column(i);
        inv += (v * v.transpose()) / eig.eigenvalues[i];
    }
    Ok(DMatrix::from_fn(ns, ns, |r, c| {
        inv[(r, c)] * dsc[r] * dsc[c]
    }))
}

/// Rigid-motion basis rows for station i (np × 6).
fn e_station(q: &Vec3, np: usize, c: &Vec3) -> DMatrix<f64> {
    let e = e_rows(q, c);
    DMatrix::from_fn(np, 6, |r, k| if r < 3 { e[(r, k)] } else { 0.0 })
}

/// Y_j = B_j S⁺ (3 × ns), B_j = N_jj⁻¹ N_js.
fn y_of(
    net: &Network,
    lay: &Layout,
    lin_u: &[Vec3],
    w: &[f64],
    ninv: &Matrix3<f64>,
    j: usize,
    s_pinv: &DMatrix<f64>,
) -> DMatrix<f64> {
    let ns = lay.ns;
    let mut y = DMatrix::<f64>::zeros(3, ns);
    for &k in lay.obs_of(j) {
        let st = net.observations[k].station;
        let (o, np) = (lay.st_off[st], lay.st_np[st]);
        let ck = -w[k] * (ninv * lin_u[k]);
        let a = a_s(&lin_u[k]);
        // row vector a^T S⁺[o..o+np, :]
        for col in 0..ns {
            let mut t = 0.0;
            for r in 0..np {
                t += a[r] * s_pinv[(o + r, col)];
            }
            for r in 0..3 {
                y[(r, col)] += ck[r] * t;
            }
        }
    }
    y
}

/// M_jj = N_jj⁻¹ + Y_j B_jᵀ.
fn m_jj(
    net: &Network,
    lay: &Layout,
    u: &[Vec3],
    w: &[f64],
    ninv: &Matrix3<f64>,
    j: usize,
    y: &DMatrix<f64>,
) -> Matrix3<f64> {
    let mut m = *ninv;
    for &k in lay.obs_of(j) {
        let st = net.observations[k].station;
        let (o, np) = (lay.st_off[st], lay.st_np[st]);
        let ck = -w[k] * (ninv * u[k]);
        let a = a_s(&u[k]);
        let mut ya = Vec3::zeros();
        for r in 0..3 {
            for q in 0..np {
                ya[r] += y[(r, o + q)] * a[q];
            }
        }
        m += ya * ck.transpose();
    }
    m
}

impl CovModel {
    fn e_target(&self, j: usize) -> Mat36 {
        e_rows(&self.p[j], &self.center)
    }

    fn build_datum(&mut self, datum: &Datum) -> Result<()> {
        let rows = datum_rows(datum, &self.net, &self.center)?;
        self.dat = self.datum_mats(rows)?;
        Ok(())
    }

    fn datum_mats(&self, rows: Vec<(usize, Mat36)>) -> Result<DatumMats> {
        let ns = self.layout.ns;
        let mut dte = Matrix6::<f64>::zeros();
        let mut in_datum = vec![None; self.net.targets.len()];
        for (r, (j, dj)) in rows.iter().enumerate() {
            dte += dj.transpose() * self.e_target(*j);
            in_datum[*j] = Some(r);
        }
        let h = check_dte(&dte)?;
        let mut wmat = DMatrix::<f64>::zeros(6, ns);
        let mut ys = Vec::with_capacity(rows.len());
        for (j, dj) in &rows {
            let y = y_of(
                &self.net,
                &self.layout,
                &self.u,
                &self.w,
                &self.ninv[*j],
                *j,
                &self.s_pinv,
            );
            // B_j = Ninv_j N_js; W += D_jᵀ B_j
            for &k in self.layout.obs_of(*j) {
                let st = self.net.observations[k].station;
                let (o, np) = (self.layout.st_off[st], self.layout.st_np[st]);
                let ck = -self.w[k] * (self.ninv[*j] * self.u[k]);
                let dc = dj.transpose() * ck; // 6
                let a = a_s(&self.u[k]);
                for r in 0..6 {
                    for q in 0..np {
                        wmat[(r, o + q)] += dc[r] * a[q];
                    }
                }
            }
            ys.push(y);
        }
        let mut g = Matrix6::<f64>::zeros();
        for ((j, dj), y) in rows.iter().zip(&ys) {
            let kj = dj.transpose() * self.ninv[*j] + mat_6x3(&(&wmat * y.transpose()));
            g += kj * dj;
        }
        Ok(DatumMats {
            rows,
            h,
            wmat,
            g,
            in_datum,
        })
    }

    /// K_j = (DᵀM)_{:,t_j}.
    fn k_target(&self, j: usize, y: &DMatrix<f64>) -> Mat63 {
        let mut k = mat_6x3(&(&self.dat.wmat * y.transpose()));
        if let Some(r) = self.dat.in_datum[j] {
            k += self.dat.rows[r].1.transpose() * self.ninv[j];
        }
        k
    }

    fn target_cov(&self, j: usize) -> Matrix3<f64> {
        let y = y_of(
            &self.net,
            &self.layout,
            &self.u,
            &self.w,
            &self.ninv[j],
            j,
            &self.s_pinv,
        );
        let m = m_jj(
            &self.net,
            &self.layout,
            &self.u,
            &self.w,
            &self.ninv[j],
            j,
            &y,
        );
        let kj = self.k_target(j, &y);
        let ej = self.e_target(j);
        let ehk = ej * self.dat.h * kj;
        let c = m - ehk - ehk.transpose()
            + ej * self.dat.h * self.dat.g * self.dat.h.transpose() * ej.transpose();
        (c + c.transpose()) * 0.5
    }

    /// Full parameter count.
    fn n_params(&self) -> usize {
        self.layout.ns + 3 * self.net.targets.len()
    }

    /// Dense M (block generalised inverse) — small networks only.
    fn dense_m(&self) -> DMatrix<f64> {
        let ns = self.layout.ns;
        let n = self.net.targets.len();
        let u = self.n_params();
        let mut m = DMatrix::<f64>::zeros(u, u);
        m.view_mut((0, 0), (ns, ns)).copy_from(&self.s_pinv);
        let ys: Vec<DMatrix<f64>> = (0..n)
            .map(|j| {
                y_of(
                    &self.net,
                    &self.layout,
                    &self.u,
                    &self.w,
                    &self.ninv[j],
                    j,
                    &self.s_pinv,
                )
            })
            .collect();
        // B_j dense
        let bs: Vec<DMatrix<f64>> = (0..n)
            .map(|j| {
                let mut b = DMatrix::<f64>::zeros(3, ns);
                for &k in self.layout.obs_of(j) {
                    let st = self.net.observations[k].station;
                    let (o, np) = (self.layout.st_off[st], self.layout.st_np[st]);
                    let ck = -self.w[k] * (self.ninv[j] * self.u[k]);
                    let a = a_s(&self.u[k]);
                    for r in 0..3 {
                        for q in 0..np {
                            b[(r, o + q)] += ck[r] * a[q];
                        }
                    }
                }
                b
            })
            .collect();
        for j in 0..n {
            let yt = -ys[j].transpose();
            m.view_mut((0, ns + 3 * j), (ns, 3)).copy_from(&yt);
            m.view_mut((ns + 3 * j, 0), (3, ns))
                .copy_from(&yt.transpose());
            for k in 0..n {
                let mut blk = &ys[j] * bs[k].transpose();
                if j == k {
                    blk += DMatrix::from_fn(3, 3, |r, c| self.ninv[j][(r, c)]);
                }
                m.view_mut((ns + 3 * j, ns + 3 * k), (3, 3)).copy_from(&blk);
            }
        }
        m
    }

    fn dense_e(&self) -> DMatrix<f64> {
        let ns = self.layout.ns;
        let mut e = DMatrix::<f64>::zeros(self.n_params(), 6);
        for (i, q) in self.q.iter().enumerate() {
            let es = e_station(q, self.layout.st_np[i], &self.center);
            e.view_mut((self.layout.st_off[i], 0), (self.layout.st_np[i], 6))
                .copy_from(&es);
        }
        for j in 0..self.net.targets.len() {
            let ej = self.e_target(j);
            e.view_mut((ns + 3 * j, 0), (3, 6)).copy_from(&ej);
        }
        e
    }

    fn dense_d(&self) -> DMatrix<f64> {
        let ns = self.layout.ns;
        let mut d = DMatrix::<f64>::zeros(self.n_params(), 6);
        for (j, dj) in &self.dat.rows {
            d.view_mut((ns + 3 * j, 0), (3, 6)).copy_from(dj);
        }
        d
    }

    /// Dense covariance in the current datum: S_D M S_Dᵀ.
    fn dense_cov(&self) -> DMatrix<f64> {
        let e = self.dense_e();
        let d = self.dense_d();
        let h = DMatrix::from_fn(6, 6, |r, c| self.dat.h[(r, c)]);
        let sd =
            DMatrix::<f64>::identity(self.n_params(), self.n_params()) - &e * h * d.transpose();
        let q = &sd * self.dense_m() * sd.transpose();
        (&q + q.transpose()) * 0.5
    }
}

fn mat_6x3(m: &DMatrix<f64>) -> Mat63 {
    Mat63::from_fn(|r, c| m[(r, c)])
}

fn check_dte(dte: &Matrix6<f64>) -> Result<Matrix6<f64>> {
    let sv = dte.singular_values();
    let (mx, mn) = (sv.max(), sv.min());
    if mn.is_nan() || mn <= 1e-10 * mx {
        return Err(MetrologyError::InvalidDatum {
            what: format!(
                "the datum conditions do not fix all 6 rigid-motion parameters (condition {:.1e}); use non-collinear datum targets, and for 3-2-1 a second target apart from the origin in x and a third apart in y",
                mx / mn.max(1e-300)
            ),
        });
    }
    dte.try_inverse()
        .ok_or_else(|| MetrologyError::InvalidDatum {
            what: "DᵀE singular".into(),
        })
}

/// Adjust the network: Gauss–Newton to convergence, datum per `params.datum`, statistics and
/// per-target covariance.
///
/// # Errors
/// Input checks of [`Network::check`], extra rank defects (named), an invalid datum, or
/// [`MetrologyError::NoConvergence`].
///
/// ```
/// use mte_metrology::simulate::{cube_edge_targets, StationLayout, simulate};
/// use mte_metrology::network::LengthUncertainty;
/// use mte_metrology::adjust::{adjust, AdjustParams};
/// let targets = cube_edge_targets(500.0, 2);
/// let stations = StationLayout::FourLow.stations(500.0, true);
/// let sim = simulate(&stations, &targets, &|_p| mte_metrology::network::Vec3::zeros(),
///                    LengthUncertainty::SEED004, 7).unwrap();
/// let adj = adjust(&sim.network, &AdjustParams::default()).unwrap();
/// assert_eq!(adj.global.degrees_of_freedom, 96 - (16 + 72 - 6));
/// assert!(adj.max_deviation().1 < 0.01); // mm: pure noise recovers a few µm at most
/// ```
pub fn adjust(net: &Network, params: &AdjustParams) -> Result<Adjustment> {
    let check = net.check()?;
    let lay = Layout::new(net);
    let n = net.targets.len();
    let center: Vec3 = net.targets.iter().map(|t| t.nominal_mm).sum::<Vec3>() / n as f64;
    let rows = datum_rows(&params.datum, net, &center)?;
    let (mut q, mut d): (Vec<Vec3>, Vec<f64>) = (0..net.stations.len())
        .map(|i| start_values(net, i))
        .unzip();
    let mut p: Vec<Vec3> = net.targets.iter().map(|t| t.nominal_mm).collect();
    let mut iterations = 0;
    let mut last = f64::INFINITY;
    let mut converged = false;
    while iterations < params.max_iterations {
        iterations += 1;
        let lin = linearise(net, &q, &d, &p)?;
        let red = reduce(net, &lay, &lin)?;
        let s_pinv = pinv_station(net, &lay, &red.s)?;
        let xs = &s_pinv * &red.rs;
        // back-substitute targets
        let xt: Vec<Vec3> = (0..n)
            .into_par_iter()
            .map(|j| {
                let mut x = red.g[j];
                for &k in lay.obs_of(j) {
                    let st = net.observations[k].station;
                    let (o, np) = (lay.st_off[st], lay.st_np[st]);
                    let a = a_s(&lin.u[k]);
                    let mut ax = 0.0;
                    for r in 0..np {
                        ax += a[r] * xs[o + r];
                    }
                    x += lin.w[k] * (red.ninv[j] * lin.u[k]) * ax;
                }
                x
            })
            .collect();
        // datum: λ = (DᵀE)⁻¹ (c − Dᵀδ), c = −Dᵀ(x − x_ref)
        let mut dte = Matrix6::<f64>::zeros();
        let mut rhs = Vector6::<f64>::zeros();
        for (j, dj) in &rows {
            dte += dj.transpose() * e_rows(&p[*j], &center);
            rhs -= dj.transpose() * (p[*j] - net.targets[*j].nominal_mm + xt[*j]);
        }
        let h = check_dte(&dte)?;
        let lambda = h * rhs;
        let mut step: f64 = 0.0;
        for (i, qi) in q.iter_mut().enumerate() {
            let e = e_rows(qi, &center);
            let dx = xs.rows(lay.st_off[i], 3).into_owned() + e * lambda;
            *qi += Vec3::new(dx[0], dx[1], dx[2]);
            step = step.max(dx.amax());
            if lay.st_np[i] == 4 {
                let dd = xs[lay.st_off[i] + 3];
                d[i] += dd;
                step = step.max(dd.abs());
            }
        }
        for j in 0..n {
            let dx = xt[j] + e_rows(&p[j], &center) * lambda;
            p[j] += dx;
            step = step.max(dx.amax());
        }
        if !step.is_finite() {
            return Err(MetrologyError::NoConvergence {
                iterations,
                last_step_mm: step,
            });
        }
        last = step;
        if step < params.tolerance_mm {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(MetrologyError::NoConvergence {
            iterations,
            last_step_mm: last,
        });
    }
    finish(
        net,
        params,
        check.warnings,
        lay,
        center,
        q,
        d,
        p,
        iterations,
    )
}

/// Start values of station `i`: its stated position and dead path, or those its lengths give in
/// closed form with the targets at their nominal places ([`closed_form_station`]), whichever
/// fits its lengths better. A station placed roughly (half a metre off) would otherwise start
/// Gauss–Newton where the linearised geometry is wrong enough to diverge.
fn start_values(net: &Network, i: usize) -> (Vec3, f64) {
    let station = &net.stations[i];
    let stated = (station.position_mm, station.dead_path_mm);
    let misfit = |(q, d): (Vec3, f64)| -> f64 {
        net.observations
            .iter()
            .filter(|o| o.station == i)
            .map(|o| {
                let r = o.length_mm - ((q - net.targets[o.target].nominal_mm).norm() - d);
                (r / o.sigma_mm).powi(2)
            })
            .sum()
    };
    match closed_form_station(net, i) {
        Some(closed) if misfit(closed) < misfit(stated) => closed,
        _ => stated,
    }
}

/// Station `i`'s position and dead path from its lengths alone, the targets at their nominal
/// positions P_j: squaring |Q − P_j| = ℓ_j + d gives, with w = |Q|² − d², equations linear in
/// (Q, d, w), −2 P_j·Q − 2 ℓ_j d + w = ℓ_j² − |P_j|² (with a fixed dead path d is known and w =
/// |Q|²), solved by least squares about the targets' centroid. `None` where the targets cannot
/// place the station: too few, or in a plane (the station's mirror image fits as well).
fn closed_form_station(net: &Network, i: usize) -> Option<(Vec3, f64)> {
    let free = net.stations[i].dead_path == DeadPath::Free;
    let obs: Vec<_> = net.observations.iter().filter(|o| o.station == i).collect();
    let unknowns = if free { 5 } else { 4 };
    if obs.len() < unknowns + 1 {
        return None;
    }
    let c = obs
        .iter()
        .map(|o| net.targets[o.target].nominal_mm)
        .sum::<Vec3>()
        / obs.len() as f64;
    // Lengths and positions in units of the targets' spread, for a well-scaled system.
    let spread = (obs
        .iter()
        .map(|o| (net.targets[o.target].nominal_mm - c).norm_squared())
        .sum::<f64>()
        / obs.len() as f64)
        .sqrt();
    if spread.is_nan() || spread <= 0.0 {
        return None;
    }
    let d0 = net.stations[i].dead_path_mm / spread;
    let mut a = DMatrix::<f64>::zeros(obs.len(), unknowns);
    let mut b = DVector::<f64>::zeros(obs.len());
    for (r, o) in obs.iter().enumerate() {
        let pj = (net.targets[o.target].nominal_mm - c) / spread;
        let l = o.length_mm / spread;
        for k in 0..3 {
            a[(r, k)] = -2.0 * pj[k];
        }
        a[(r, 3)] = 1.0;
        if free {
            a[(r, 4)] = -2.0 * l;
            b[r] = l * l - pj.norm_squared();
        } else {
            b[r] = (l + d0).powi(2) - pj.norm_squared();
        }
    }
    let svd = a.svd(true, true);
    let largest = svd.singular_values.max();
    if svd.singular_values.min() < 1e-9 * largest {
        return None;
    }
    let x = svd.solve(&b, 0.0).ok()?;
    let q = Vec3::new(x[0], x[1], x[2]) * spread + c;
    let d = if free {
        x[4] * spread
    } else {
        net.stations[i].dead_path_mm
    };
    (q.iter().all(|v| v.is_finite()) && d.is_finite()).then_some((q, d))
}

#[allow(clippy::too_many_arguments)]
fn finish(
    net: &Network,
    params: &AdjustParams,
    warnings: Vec<String>,
    lay: Layout,
    center: Vec3,
    q: Vec<Vec3>,
    d: Vec<f64>,
    p: Vec<Vec3>,
    iterations: usize,
) -> Result<Adjustment> {
    let lin = linearise(net, &q, &d, &p)?;
    let red = reduce(net, &lay, &lin)?;
    let s_pinv = pinv_station(net, &lay, &red.s)?;
    let mut model = CovModel {
        net: net.clone(),
        layout: lay,
        q,
        p,
        center,
        s_pinv,
        ninv: red.ninv,
        u: lin.u.clone(),
        w: lin.w.clone(),
        dat: DatumMats {
            rows: vec![],
            h: Matrix6::identity(),
            wmat: DMatrix::zeros(6, 0),
            g: Matrix6::zeros(),
            in_datum: vec![],
        },
    };
    model.build_datum(&params.datum)?;
    let n_unknowns = model.n_params();
    let dof = net.observations.len() + 6 - n_unknowns;
    // redundancy numbers: r_k = 1 − w_k a_k M a_kᵀ (a_k ⟂ null space, any g-inverse)
    let lay = &model.layout;
    let n = net.targets.len();
    let per_target: Vec<(Vec<(usize, f64)>, Matrix3<f64>)> = (0..n)
        .into_par_iter()
        .map(|j| {
            let y = y_of(
                net,
                lay,
                &model.u,
                &model.w,
                &model.ninv[j],
                j,
                &model.s_pinv,
            );
            let mjj = m_jj(net, lay, &model.u, &model.w, &model.ninv[j], j, &y);
            let mut red_k = Vec::new();
            for &k in lay.obs_of(j) {
                let st = net.observations[k].station;
                let (o, np) = (lay.st_off[st], lay.st_np[st]);
                let a = a_s(&model.u[k]);
                let at = -model.u[k];
                // a_s S⁺ a_sᵀ
                let mut qss = 0.0;
                for r in 0..np {
                    for c in 0..np {
                        qss += a[r] * model.s_pinv[(o + r, o + c)] * a[c];
                    }
                }
                // 2 a_s M_{s,t} a_tᵀ, M_{s,t} = −Yᵀ
                let mut qst = 0.0;
                for r in 0..np {
                    for c in 0..3 {
                        qst -= a[r] * y[(c, o + r)] * at[c];
                    }
                }
                let qtt = at.dot(&(mjj * at));
                let qa = qss + 2.0 * qst + qtt;
                red_k.push((k, 1.0 - model.w[k] * qa));
            }
            let cov = {
                let kj = model.k_target(j, &y);
                let ej = model.e_target(j);
                let ehk = ej * model.dat.h * kj;
                let c = mjj - ehk - ehk.transpose()
                    + ej * model.dat.h * model.dat.g * model.dat.h.transpose() * ej.transpose();
                (c + c.transpose()) * 0.5
            };
            (red_k, cov)
        })
        .collect();
    let mut redundancy = vec![0.0; net.observations.len()];
    let mut covs = Vec::with_capacity(n);
    for (rk, c) in per_target {
        for (k, r) in rk {
            redundancy[k] = r;
        }
        covs.push(c);
    }
    let crit = stats::normal_quantile(1.0 - params.alpha_snooping / 2.0);
    // [pvv] summed serially, in observation order, so it does not depend on the thread count.
    let pvv: f64 = lin.f.iter().zip(&lin.w).map(|(f, w)| f * f * w).sum();
    let observations: Vec<ObservationStats> = net
        .observations
        .par_iter()
        .enumerate()
        .map(|(k, o)| {
            let v = -lin.f[k];
            let r = redundancy[k].clamp(0.0, 1.0);
            let wstat = if r > 1e-9 {
                v / (o.sigma_mm * r.sqrt())
            } else {
                0.0
            };
            ObservationStats {
                station: net.stations[o.station].id.clone(),
                target: net.targets[o.target].id.clone(),
                observed_mm: o.length_mm,
                adjusted_mm: o.length_mm + v,
                residual_mm: v,
                sigma_mm: o.sigma_mm,
                redundancy: r,
                standardised_residual: wstat,
                suspect: wstat.abs() > crit,
            }
        })
        .collect();
    let f = dof as f64;
    let (ratio, interval, passed) = if dof > 0 {
        let ratio = (pvv / f).sqrt();
        let lo = (stats::chi2_quantile(params.alpha_global / 2.0, f) / f).sqrt();
        let hi = (stats::chi2_quantile(1.0 - params.alpha_global / 2.0, f) / f).sqrt();
        (ratio, (lo, hi), ratio >= lo && ratio <= hi)
    } else {
        (f64::NAN, (f64::NAN, f64::NAN), true)
    };
    let ratio = if ratio.is_nan() { 0.0 } else { ratio };
    let interval = if interval.0.is_nan() {
        (0.0, f64::INFINITY)
    } else {
        interval
    };
    let stations = net
        .stations
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let np = model.layout.st_np[i];
            let c = model.station_cov(i);
            AdjustedStation {
                id: s.id.clone(),
                position_mm: model.q[i],
                dead_path_mm: if np == 4 { d[i] } else { s.dead_path_mm },
                sigma_mm: Vec3::new(
                    c[(0, 0)].max(0.0).sqrt(),
                    c[(1, 1)].max(0.0).sqrt(),
                    c[(2, 2)].max(0.0).sqrt(),
                ),
                dead_path_sigma_mm: if np == 4 {
                    c[(3, 3)].max(0.0).sqrt()
                } else {
                    0.0
                },
            }
        })
        .collect();
    let targets = net
        .targets
        .par_iter()
        .enumerate()
        .map(|(j, t)| AdjustedTarget {
            id: t.id.clone(),
            nominal_mm: t.nominal_mm,
            position_mm: model.p[j],
            deviation_mm: model.p[j] - t.nominal_mm,
            covariance_mm2: [0, 1, 2].map(|r| [0, 1, 2].map(|c| covs[j][(r, c)])),
            ellipsoid: Ellipsoid::from_covariance(&covs[j]),
        })
        .collect();
    Ok(Adjustment {
        datum_description: params.datum.describe(net),
        datum: params.datum.clone(),
        iterations,
        stations,
        targets,
        observations,
        global: GlobalTest {
            pvv,
            degrees_of_freedom: dof,
            sigma0_ratio: ratio,
            interval,
            passed,
            snooping_critical: crit,
        },
        warnings,
        params: params.clone(),
        model: Some(model),
    })
}

impl CovModel {
    /// Station covariance block (np × np) in the current datum.
    fn station_cov(&self, i: usize) -> DMatrix<f64> {
        let (o, np) = (self.layout.st_off[i], self.layout.st_np[i]);
        let m = self.s_pinv.view((o, o), (np, np)).into_owned();
        let es = e_station(&self.q[i], np, &self.center);
        let ks = -(&self.dat.wmat * &self.s_pinv).columns(o, np).into_owned(); // 6 × np
        let h = DMatrix::from_fn(6, 6, |r, c| self.dat.h[(r, c)]);
        let g = DMatrix::from_fn(6, 6, |r, c| self.dat.g[(r, c)]);
        let ehk = &es * &h * &ks;
        let c = m - &ehk - ehk.transpose() + &es * &h * g * h.transpose() * es.transpose();
        (&c + c.transpose()) * 0.5
    }
}

/// Exact rotation exp(ω̂) (Rodrigues).
fn so3_exp(w: &Vec3) -> Matrix3<f64> {
    let th = w.norm();
    let k = skew(w);
    if th < 1e-8 {
        Matrix3::identity() + k + 0.5 * k * k
    } else {
        Matrix3::identity() + (th.sin() / th) * k + ((1.0 - th.cos()) / (th * th)) * k * k
    }
}

impl Adjustment {
    fn model(&self) -> Result<&CovModel> {
        self.model.as_ref().ok_or_else(|| {
            invalid("this adjustment was deserialised; covariance data are not kept in JSON")
        })
    }

    /// The largest spatial error: (target index, |adjusted − nominal| in mm).
    pub fn max_deviation(&self) -> (usize, f64) {
        self.targets
            .iter()
            .enumerate()
            .map(|(j, t)| (j, t.deviation_mm.norm()))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a })
    }

    /// Order of the parameters in [`Adjustment::dense_covariance`]: names like `S1.x`, `S1.d`, `P3.z`.
    pub fn parameter_names(&self) -> Vec<String> {
        let mut v = Vec::new();
        if let Some(m) = &self.model {
            for (i, s) in m.net.stations.iter().enumerate() {
                for c in ["x", "y", "z", "d"].iter().take(m.layout.st_np[i]) {
                    v.push(format!("{}.{c}", s.id));
                }
            }
            for t in &m.net.targets {
                for c in ["x", "y", "z"] {
                    v.push(format!("{}.{c}", t.id));
                }
            }
        }
        v
    }

    /// Covariance (mm², a priori) between target `a` and target `b` (3×3), in the current datum.
    ///
    /// # Errors
    /// Index out of range, or an adjustment read back from JSON (no model kept).
    pub fn covariance_block(&self, a: usize, b: usize) -> Result<Matrix3<f64>> {
        let m = self.model()?;
        let n = m.net.targets.len();
        if a >= n || b >= n {
            return Err(invalid(format!(
                "target index {a} or {b} out of range ({n} targets)"
            )));
        }
        if a == b {
            return Ok(m.target_cov(a));
        }
        let ya = y_of(&m.net, &m.layout, &m.u, &m.w, &m.ninv[a], a, &m.s_pinv);
        let yb = y_of(&m.net, &m.layout, &m.u, &m.w, &m.ninv[b], b, &m.s_pinv);
        // M_ab = B_a S⁺ B_bᵀ = Y_a B_bᵀ; compute via B_b's sparse form
        let mut mab = Matrix3::<f64>::zeros();
        for &k in m.layout.obs_of(b) {
            let st = m.net.observations[k].station;
            let (o, np) = (m.layout.st_off[st], m.layout.st_np[st]);
            let ck = -m.w[k] * (m.ninv[b] * m.u[k]);
            let aa = a_s(&m.u[k]);
            let mut ya_a = Vec3::zeros();
            for r in 0..3 {
                for q in 0..np {
                    ya_a[r] += ya[(r, o + q)] * aa[q];
                }
            }
            mab += ya_a * ck.transpose();
        }
        let ka = m.k_target(a, &ya);
        let kb = m.k_target(b, &yb);
        let (ea, eb) = (m.e_target(a), m.e_target(b));
        let h = m.dat.h;
        Ok(
            mab - ea * h * kb - ka.transpose() * h.transpose() * eb.transpose()
                + ea * h * m.dat.g * h.transpose() * eb.transpose(),
        )
    }

    /// Full covariance (mm², a priori) of all parameters in the order of
    /// [`Adjustment::parameter_names`] (stations first, then targets). Dense: for small networks.
    ///
    /// # Errors
    /// More than 6000 parameters, or no model kept.
    pub fn dense_covariance(&self) -> Result<DMatrix<f64>> {
        let m = self.model()?;
        if m.n_params() > 6000 {
            return Err(invalid(format!(
                "{} parameters: use covariance_block for large networks",
                m.n_params()
            )));
        }
        Ok(m.dense_cov())
    }

    /// Distance between two adjusted targets (mm) — datum invariant.
    pub fn target_distance_mm(&self, a: usize, b: usize) -> f64 {
        (self.targets[a].position_mm - self.targets[b].position_mm).norm()
    }

    /// S-transformation to another datum: the adjusted network is moved by the rigid motion
    /// that satisfies the new datum conditions exactly (iterated, exact rotation), and all
    /// covariance blocks are re-expressed in the new datum (**Q**' = **S**_D' **Q** **S**_D'ᵀ).
    /// Residuals, σ₀, redundancy numbers and distances are unchanged.
    ///
    /// # Errors
    /// An invalid datum, or no model kept.
    pub fn s_transform(&self, datum: Datum) -> Result<Adjustment> {
        let m = self.model()?;
        let net = &m.net;
        let rows = datum_rows(&datum, net, &m.center)?;
        let mut q = m.q.clone();
        let mut p = m.p.clone();
        for _ in 0..10 {
            let mut dte = Matrix6::<f64>::zeros();
            let mut rhs = Vector6::<f64>::zeros();
            for (j, dj) in &rows {
                dte += dj.transpose() * e_rows(&p[*j], &m.center);
                rhs -= dj.transpose() * (p[*j] - net.targets[*j].nominal_mm);
            }
            let lam = check_dte(&dte)? * rhs;
            let t = Vec3::new(lam[0], lam[1], lam[2]);
            let r = so3_exp(&Vec3::new(lam[3], lam[4], lam[5]));
            for x in q.iter_mut().chain(p.iter_mut()) {
                *x = m.center + t + r * (*x - m.center);
            }
            if lam.amax() < 1e-15 {
                break;
            }
        }
        let d: Vec<f64> = self.stations.iter().map(|s| s.dead_path_mm).collect();
        let params = AdjustParams {
            datum,
            ..self.params.clone()
        };
        finish(
            net,
            &params,
            self.warnings.clone(),
            m.layout.clone(),
            m.center,
            q,
            d,
            p,
            self.iterations,
        )
    }

    /// Target rows of the linear map from observed lengths to adjusted target coordinates in
    /// the current datum: δp = T·δℓ (3n × n_obs, dense; T = S_D M Aᵀ W restricted to targets).
    /// Valid while length perturbations are small against the geometry (linearisation error
    /// ~ δℓ²/L, i.e. < 1e-9 mm for µm noise over 100 mm).
    ///
    /// # Errors
    /// More than 6000 parameters, or no model kept.
    pub fn target_sensitivity(&self) -> Result<DMatrix<f64>> {
        let m = self.model()?;
        let q = self.dense_covariance()?;
        let ns = m.layout.ns;
        let n = m.net.targets.len();
        let nobs = m.net.observations.len();
        let mut t = DMatrix::<f64>::zeros(3 * n, nobs);
        for (k, o) in m.net.observations.iter().enumerate() {
            let (so, np) = (m.layout.st_off[o.station], m.layout.st_np[o.station]);
            let a = a_s(&m.u[k]);
            let at = -m.u[k];
            for r in 0..3 * n {
                let mut v = 0.0;
                for c in 0..np {
                    v += q[(ns + r, so + c)] * a[c];
                }
                for c in 0..3 {
                    v += q[(ns + r, ns + 3 * o.target + c)] * at[c];
                }
                t[(r, k)] = v * m.w[k];
            }
        }
        Ok(t)
    }
}
