//! Benches against the peers' figures in shared/bench/peers/results (see the crate README).
#![allow(missing_docs)]
//!
//! cargo bench -p mte-sensitivity --bench sensitivity

use criterion::{Criterion, criterion_group, criterion_main};
use mte_sensitivity::pce::{PceParams, Selection, build_pce};
use mte_sensitivity::sobol::{SobolParams, sobol};
use mte_sensitivity::testfn::GFunction;
use mte_sensitivity::{Distribution, MultiOutput, Problem, Sampling};
use std::hint::black_box;

/// The peers' "machine-tool-like" 41-input model (common.py mt_model_nonpoly), rebuilt with our
/// own permutation: 20 position errors σ = 5 µm, 21 angle errors σ = 10/3″; linear contributions
/// 4·0.85^i µm, 4 quadratic and 5 bilinear terms (~1.3 % of variance), plus 1 µm·sin(2x/σ) on 3
/// inputs (a degree-3 PCE cannot represent it).
struct MtModel {
    a: Vec<f64>,
    q: Vec<(usize, f64)>,
    pairs: Vec<(usize, usize, f64)>,
    sins: Vec<(usize, f64)>,
}

fn mt_model(variant: u64) -> (MtModel, Problem) {
    let arcsec = std::f64::consts::PI / (180.0 * 3600.0);
    let sigma: Vec<f64> = (0..41)
        .map(|i| if i < 20 { 5.0 } else { 10.0 / 3.0 * arcsec })
        .collect();
    let mut perm: Vec<usize> = (0..41).collect();
    let mut s = 0x1234_5678u64 ^ variant.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    for i in (1..41).rev() {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        perm.swap(i, (s >> 33) as usize % (i + 1));
    }
    let mut a = vec![0.0; 41];
    for (rank, &i) in perm.iter().enumerate() {
        let sign = if (rank * 7 + variant as usize) % 3 == 0 {
            -1.0
        } else {
            1.0
        };
        a[i] = sign * 4.0 * 0.85f64.powi(rank as i32) / sigma[i];
    }
    let q = [(0, 0.45), (2, 0.30), (5, 0.20), (9, 0.15)]
        .iter()
        .map(|&(r, sd)| (perm[r], sd / (2f64.sqrt() * sigma[perm[r]].powi(2))))
        .collect();
    let pairs = [
        (0, 1, 0.40),
        (1, 3, 0.30),
        (2, 7, 0.25),
        (4, 11, 0.20),
        (6, 20, 0.15),
    ]
    .iter()
    .map(|&(i, j, sd)| (perm[i], perm[j], sd / (sigma[perm[i]] * sigma[perm[j]])))
    .collect();
    let sins = [3, 6, 12]
        .iter()
        .map(|&r| (perm[r], 2.0 / sigma[perm[r]]))
        .collect();
    let prob = Problem::from_dists(
        &sigma
            .iter()
            .map(|&s| Distribution::normal(0.0, s).unwrap())
            .collect::<Vec<_>>(),
    )
    .unwrap();
    (MtModel { a, q, pairs, sins }, prob)
}

impl MtModel {
    fn eval(&self, x: &[f64]) -> f64 {
        let mut y: f64 = self.a.iter().zip(x).map(|(a, b)| a * b).sum();
        y += self.q.iter().map(|&(i, c)| c * x[i] * x[i]).sum::<f64>();
        y += self
            .pairs
            .iter()
            .map(|&(i, j, b)| b * x[i] * x[j])
            .sum::<f64>();
        y + self
            .sins
            .iter()
            .map(|&(i, w)| (w * x[i]).sin())
            .sum::<f64>()
    }
}

fn benches(c: &mut Criterion) {
    let mut g = c.benchmark_group("sensitivity");
    g.sample_size(10);
    let gf = GFunction::benchmark(41);
    let prob = gf.problem();
    for (name, nb) in [("sobol_gfun41_n1e5", 0), ("sobol_gfun41_n1e5_boot100", 100)] {
        let p = SobolParams {
            n: 100_000,
            sampling: Sampling::Sobol,
            seed: 1,
            n_bootstrap: nb,
            ..Default::default()
        };
        g.bench_function(name, |b| {
            b.iter(|| black_box(sobol(&gf, &prob, &p).unwrap()))
        });
    }
    let (m, prob) = mt_model(0);
    let f = |x: &[f64]| m.eval(x);
    let p = PceParams {
        degree: 3,
        adaptive_degree: false,
        n_samples: 1000,
        ..Default::default()
    };
    g.bench_function("pce_deg3_k41_n1000_kfold", |b| {
        b.iter(|| black_box(build_pce(&f, &prob, &p).unwrap()))
    });
    // The peers' setting (numpy OMP + corrected LOO). The full-data path alone chooses the
    // model; the 5 fold paths beside it repeat the search for the selection-aware error.
    let pl = PceParams {
        selection: Selection::CorrectedLoo,
        ..p.clone()
    };
    g.bench_function("pce_deg3_k41_n1000_corrected_loo", |b| {
        b.iter(|| black_box(build_pce(&f, &prob, &pl).unwrap()))
    });
    let pa = PceParams {
        adaptive_degree: true,
        ..p.clone()
    };
    g.bench_function("pce_deg1to3_k41_n1000_kfold_adaptive", |b| {
        b.iter(|| black_box(build_pce(&f, &prob, &pa).unwrap()))
    });
    let models: Vec<MtModel> = (0..120).map(|v| mt_model(v).0).collect();
    let many = MultiOutput::new(120, |x: &[f64], y: &mut [f64]| {
        for (yo, m) in y.iter_mut().zip(&models) {
            *yo = m.eval(x);
        }
    });
    g.bench_function("pce_deg3_k41_n1000_120_outputs", |b| {
        b.iter(|| black_box(build_pce(&many, &prob, &p).unwrap()))
    });
    g.finish();
}

criterion_group!(b, benches);
criterion_main!(b);
