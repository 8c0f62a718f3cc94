//! Morris elementary effects: trajectory design (Morris 1991) with optional Campolongo et al.
//! (2007) optimised trajectories (greedy maximisation of the spread), and the radial design
//! (Campolongo et al. 2011) on a scrambled Sobol' base. μ, μ*, σ per input and output, bootstrap
//! intervals of μ* over trajectories. Effects are computed on the unit (quantile) scale.

use crate::dist::Problem;
use crate::error::{Error, Result};
use crate::model::{Model, eval_checked};
use crate::qmc::SobolSequence;
use crate::stats::{interval, stream};
use rand::Rng;
use rand::seq::SliceRandom;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Morris design.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MorrisDesign {
    /// One-at-a-time trajectories on a p-level grid.
    Trajectory,
    /// Trajectories chosen among `candidates` to maximise their spread (Campolongo 2007, greedy).
    Optimised {
        /// Number of candidate trajectories.
        candidates: usize,
    },
    /// Radial one-at-a-time steps from Sobol' base points (Campolongo 2011).
    Radial,
}

/// Settings of a Morris screening.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MorrisParams {
    /// Number of trajectories r.
    pub r: usize,
    /// Grid levels p (even).
    pub levels: usize,
    /// Design.
    pub design: MorrisDesign,
    /// Seed.
    pub seed: u64,
    /// Bootstrap replicates for μ* intervals.
    pub n_bootstrap: usize,
    /// Confidence level.
    pub confidence: f64,
}

impl Default for MorrisParams {
    fn default() -> Self {
        MorrisParams {
            r: 50,
            levels: 4,
            design: MorrisDesign::Trajectory,
            seed: 0,
            n_bootstrap: 100,
            confidence: 0.95,
        }
    }
}

/// Screening measures of one output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MorrisIndices {
    /// Mean elementary effect μ.
    pub mu: Vec<f64>,
    /// Mean absolute elementary effect μ*.
    pub mu_star: Vec<f64>,
    /// Standard deviation σ of the elementary effects.
    pub sigma: Vec<f64>,
    /// Bootstrap intervals of μ*.
    pub mu_star_ci: Vec<[f64; 2]>,
}

/// Result of [`morris`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MorrisResult {
    /// Input names.
    pub names: Vec<String>,
    /// Model runs r(k + 1).
    pub n_model_runs: usize,
    /// One entry per output.
    pub outputs: Vec<MorrisIndices>,
}

/// A trajectory: k + 1 unit points and, per step, (input changed, Δ in unit scale).
type Traj = (Vec<f64>, Vec<(usize, f64)>);

fn grid_trajectory(k: usize, p: usize, rng: &mut impl Rng) -> Traj {
    let delta = (p / 2) as f64 / p as f64;
    let mut x: Vec<usize> = (0..k).map(|_| rng.random_range(0..p / 2)).collect();
    let mut up: Vec<bool> = (0..k).map(|_| rng.random_bool(0.5)).collect();
    for i in 0..k {
        if !up[i] {
            x[i] += p / 2;
        }
    }
    let lvl = |l: usize| (l as f64 + 0.5) / p as f64;
    let mut order: Vec<usize> = (0..k).collect();
    order.shuffle(rng);
    let mut pts: Vec<f64> = x.iter().map(|&l| lvl(l)).collect();
    let mut steps = Vec::with_capacity(k);
    for &i in &order {
        if up[i] {
            x[i] += p / 2;
        } else {
            x[i] -= p / 2;
        }
        up[i] = !up[i];
        let d = if up[i] { -delta } else { delta };
        let start = pts.len() - k;
        let mut next = pts[start..].to_vec();
        next[i] = lvl(x[i]);
        pts.extend_from_slice(&next);
        steps.push((i, d));
    }
    (pts, steps)
}

fn traj_distance(a: &[f64], b: &[f64], k: usize) -> f64 {
    let mut s = 0.0;
    for pa in a.chunks_exact(k) {
        for pb in b.chunks_exact(k) {
            s += pa
                .iter()
                .zip(pb)
                .map(|(x, y)| (x - y).powi(2))
                .sum::<f64>()
                .sqrt();
        }
    }
    s
}

/// Morris screening of every output of `model`.
///
/// # Errors
/// [`Error::SampleSize`] for r < 2, [`Error::InvalidParameter`] for odd or too few levels,
/// [`Error::ModelOutput`] for non-finite model values.
pub fn morris<M: Model + ?Sized>(
    model: &M,
    problem: &Problem,
    params: &MorrisParams,
) -> Result<MorrisResult> {
    let k = problem.dim();
    let m = model.n_outputs();
    let r = params.r;
    if r < 2 {
        return Err(Error::SampleSize {
            estimator: "Morris (trajectories r)",
            n: r,
            min: 2,
        });
    }
    if params.levels < 2 || params.levels % 2 != 0 {
        return Err(Error::InvalidParameter {
            name: "levels",
            message: format!("must be even and ≥ 2, got {}", params.levels),
        });
    }
    let trajs: Vec<Traj> = match params.design {
        MorrisDesign::Trajectory => (0..r)
            .map(|t| grid_trajectory(k, params.levels, &mut stream(params.seed, t as u64)))
            .collect(),
        MorrisDesign::Optimised { candidates } => {
            if candidates < r {
                return Err(Error::InvalidParameter {
                    name: "candidates",
                    message: format!("need at least r = {r} candidates, got {candidates}"),
                });
            }
            let cands: Vec<Traj> = (0..candidates)
                .map(|t| grid_trajectory(k, params.levels, &mut stream(params.seed, t as u64)))
                .collect();
            // Greedy: start with the candidate farthest from all others, then add the one whose
            // summed distance to the chosen set is largest.
            let mut chosen = vec![];
            let mut score = vec![0.0; candidates];
            let mut used = vec![false; candidates];
            let first = (0..candidates)
                .into_par_iter()
                .map(|i| {
                    (0..candidates.min(64))
                        .map(|j| traj_distance(&cands[i].0, &cands[j].0, k))
                        .sum::<f64>()
                })
                .collect::<Vec<f64>>();
            let mut next = (0..candidates)
                .max_by(|&a, &b| first[a].total_cmp(&first[b]))
                .expect("candidates");
            while chosen.len() < r {
                used[next] = true;
                chosen.push(next);
                let d: Vec<f64> = (0..candidates)
                    .into_par_iter()
                    .map(|i| {
                        if used[i] {
                            0.0
                        } else {
                            traj_distance(&cands[i].0, &cands[next].0, k)
                        }
                    })
                    .collect();
                for i in 0..candidates {
                    score[i] += d[i];
                }
                if let Some(b) = (0..candidates)
                    .filter(|&i| !used[i])
                    .max_by(|&a, &b| score[a].total_cmp(&score[b]))
                {
                    next = b;
                }
            }
            chosen.into_iter().map(|i| cands[i].clone()).collect()
        }
        MorrisDesign::Radial => {
            let seq = SobolSequence::scrambled(2 * k, params.seed)?;
            let mut ab = vec![0.0; r * 2 * k];
            seq.fill(0, r, &mut ab);
            (0..r)
                .map(|t| {
                    let a = &ab[t * 2 * k..t * 2 * k + k];
                    let b = &ab[t * 2 * k + k..(t + 1) * 2 * k];
                    let mut pts = a.to_vec();
                    let mut steps = vec![];
                    for i in 0..k {
                        let mut x = a.to_vec();
                        x[i] = b[i];
                        pts.extend_from_slice(&x);
                        steps.push((i, b[i] - a[i]));
                    }
                    (pts, steps)
                })
                .collect()
        }
    };
    let radial = params.design == MorrisDesign::Radial;
    // elementary effects ee[t][i][o]
    let ees: Vec<Vec<f64>> = trajs
        .par_iter()
        .map(|(pts, steps)| -> Result<Vec<f64>> {
            let mut x = pts.clone();
            for row in x.chunks_exact_mut(k) {
                problem.transform_unit(row);
            }
            let mut y = vec![0.0; (k + 1) * m];
            eval_checked(model, k + 1, k, &x, &mut y)?;
            let mut ee = vec![0.0; k * m];
            for (s, &(i, d)) in steps.iter().enumerate() {
                let (p0, p1) = if radial { (0, s + 1) } else { (s, s + 1) };
                for o in 0..m {
                    ee[i * m + o] = if d.abs() > 1e-12 {
                        (y[p1 * m + o] - y[p0 * m + o]) / d
                    } else {
                        0.0
                    };
                }
            }
            Ok(ee)
        })
        .collect::<Result<_>>()?;
    let stats = |sel: &[usize], i: usize, o: usize| {
        let n = sel.len() as f64;
        let v: Vec<f64> = sel.iter().map(|&t| ees[t][i * m + o]).collect();
        let mu = v.iter().sum::<f64>() / n;
        let mus = v.iter().map(|e| e.abs()).sum::<f64>() / n;
        let sd = (v.iter().map(|e| (e - mu).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        (mu, mus, sd)
    };
    let all: Vec<usize> = (0..r).collect();
    let boots: Vec<Vec<usize>> = (0..params.n_bootstrap)
        .map(|b| {
            let mut rng = stream(params.seed ^ 0x3033_1155, b as u64);
            (0..r).map(|_| rng.random_range(0..r)).collect()
        })
        .collect();
    let outputs = (0..m)
        .map(|o| {
            let mut out = MorrisIndices {
                mu: vec![],
                mu_star: vec![],
                sigma: vec![],
                mu_star_ci: vec![],
            };
            for i in 0..k {
                let (mu, mus, sd) = stats(&all, i, o);
                out.mu.push(mu);
                out.mu_star.push(mus);
                out.sigma.push(sd);
                if !boots.is_empty() {
                    out.mu_star_ci.push(
                        interval(
                            boots.iter().map(|s| stats(s, i, o).1).collect(),
                            params.confidence,
                        )
                        .0,
                    );
                }
            }
            out
        })
        .collect();
    Ok(MorrisResult {
        names: problem.names(),
        n_model_runs: r * (k + 1),
        outputs,
    })
}
