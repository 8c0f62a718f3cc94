//! Space-filling designs on the unit hypercube: plain Monte Carlo, Latin hypercube and scrambled
//! Sobol'. Rows are generated in blocks; a block's content depends only on (seed, block index),
//! so designs are identical whatever the number of threads.

use crate::error::{Error, Result};
use crate::qmc::SobolSequence;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Rows per random-number stream for Monte Carlo and LHS jitter.
pub const ROW_BLOCK: usize = 64;

/// How points are placed in the unit hypercube.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Independent uniform points (ChaCha8 streams).
    #[serde(alias = "mc")]
    MonteCarlo,
    /// Latin hypercube: one point per 1/n stratum in each dimension, random pairing and jitter.
    #[serde(alias = "lhs")]
    LatinHypercube,
    /// Scrambled Sobol' sequence (linear matrix scramble + digital shift). Best with n = 2^m.
    #[default]
    #[serde(alias = "qmc")]
    Sobol,
}

impl Sampling {
    /// Parses `"mc"`, `"monte_carlo"`, `"lhs"`, `"latin_hypercube"`, `"sobol"`, `"qmc"`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for other names.
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "mc" | "monte_carlo" => Ok(Sampling::MonteCarlo),
            "lhs" | "latin_hypercube" => Ok(Sampling::LatinHypercube),
            "sobol" | "qmc" => Ok(Sampling::Sobol),
            o => Err(Error::InvalidParameter {
                name: "sampling",
                message: format!("unknown sampling `{o}`; expected mc, lhs or sobol"),
            }),
        }
    }
}

/// An n × dim design on (0, 1)^dim.
#[derive(Debug, Clone)]
pub struct UnitDesign {
    kind: Sampling,
    dim: usize,
    n: usize,
    seed: u64,
    perms: Vec<u32>,
    sobol: Option<SobolSequence>,
}

fn stream(seed: u64, id: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(id);
    r
}

impl UnitDesign {
    /// A design of `n` points in `dim` dimensions.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for `dim` = 0 or too many Sobol' dimensions.
    pub fn new(kind: Sampling, dim: usize, n: usize, seed: u64) -> Result<Self> {
        if dim == 0 {
            return Err(Error::InvalidParameter {
                name: "dim",
                message: "design needs at least one dimension".into(),
            });
        }
        let mut d = UnitDesign {
            kind,
            dim,
            n,
            seed,
            perms: vec![],
            sobol: None,
        };
        match kind {
            Sampling::MonteCarlo => {}
            Sampling::LatinHypercube => {
                d.perms = vec![0u32; dim * n];
                for j in 0..dim {
                    let p = &mut d.perms[j * n..(j + 1) * n];
                    for (i, v) in p.iter_mut().enumerate() {
                        *v = i as u32;
                    }
                    let mut rng = stream(seed, (1u64 << 40) + j as u64);
                    for i in (1..n).rev() {
                        let t = rng.random_range(0..=i);
                        p.swap(i, t);
                    }
                }
            }
            Sampling::Sobol => d.sobol = Some(SobolSequence::scrambled(dim, seed)?),
        }
        Ok(d)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the design is empty.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Writes rows `first … first + n_rows − 1` row-major into `out`.
    ///
    /// # Panics
    /// If `first` is not a multiple of [`ROW_BLOCK`], rows exceed `len()`, or `out` has the wrong size.
    pub fn fill(&self, first: usize, n_rows: usize, out: &mut [f64]) {
        assert_eq!(
            first % ROW_BLOCK,
            0,
            "first row must be a multiple of ROW_BLOCK"
        );
        assert!(first + n_rows <= self.n, "rows beyond the design");
        assert_eq!(out.len(), n_rows * self.dim);
        let dim = self.dim;
        match self.kind {
            Sampling::Sobol => self
                .sobol
                .as_ref()
                .expect("sobol")
                .fill(first as u64, n_rows, out),
            Sampling::MonteCarlo | Sampling::LatinHypercube => {
                for (b, chunk) in out.chunks_mut(ROW_BLOCK * dim).enumerate() {
                    let block = (first / ROW_BLOCK + b) as u64;
                    let mut rng = stream(self.seed, block);
                    for v in chunk.iter_mut() {
                        // (0, 1) open: 53 random bits plus half an ulp of the grid
                        *v = ((rng.random::<u64>() >> 11) as f64 + 0.5)
                            * (1.0 / 9_007_199_254_740_992.0);
                    }
                    if self.kind == Sampling::LatinHypercube {
                        let rows = chunk.len() / dim;
                        for r in 0..rows {
                            let row = first + b * ROW_BLOCK + r;
                            for j in 0..dim {
                                let p = self.perms[j * self.n + row] as f64;
                                chunk[r * dim + j] = (p + chunk[r * dim + j]) / self.n as f64;
                            }
                        }
                    }
                }
            }
        }
    }

    /// The whole design as a row-major n × dim vector.
    pub fn to_vec(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.n * self.dim];
        self.fill(0, self.n, &mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lhs_has_one_point_per_stratum() {
        let n = 200;
        let d = UnitDesign::new(Sampling::LatinHypercube, 3, n, 5)
            .unwrap()
            .to_vec();
        for j in 0..3 {
            let mut seen = vec![false; n];
            for r in 0..n {
                let c = (d[r * 3 + j] * n as f64) as usize;
                assert!(!seen[c]);
                seen[c] = true;
            }
        }
    }

    #[test]
    fn mc_blocks_are_reproducible_and_in_open_cube() {
        let a = UnitDesign::new(Sampling::MonteCarlo, 4, 300, 9).unwrap();
        let all = a.to_vec();
        let mut part = vec![0.0; 100 * 4];
        a.fill(128, 100, &mut part);
        assert_eq!(&all[128 * 4..228 * 4], &part[..]);
        assert!(all.iter().all(|&v| v > 0.0 && v < 1.0));
        let mean = all.iter().sum::<f64>() / all.len() as f64;
        assert!((mean - 0.5).abs() < 0.03, "{mean}"); // 1200 U(0,1): sd of mean 0.0083
    }
}
