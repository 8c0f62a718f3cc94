//! Morris screening and local indices.
#![allow(clippy::needless_range_loop)]

use mte_sensitivity::local::{gradient_spread, motion_increment, unit_increment};
use mte_sensitivity::morris::{MorrisDesign, MorrisParams, morris};
use mte_sensitivity::stats::spearman;
use mte_sensitivity::testfn::{GFunction, Linear};
use mte_sensitivity::{Distribution, Problem};

/// μ* ranks the G-function inputs like the analytic total index (aᵢ = (i − 1)/2 decreasing
/// importance). SALib plain Morris reaches Spearman 0.97 at r = 50 (shared/bench/peers/results/morris.json).
#[test]
fn morris_ranks_gfunction_inputs() {
    let g = GFunction::benchmark(41);
    let (_, st) = g.analytic();
    for design in [
        MorrisDesign::Trajectory,
        MorrisDesign::Optimised { candidates: 100 },
        MorrisDesign::Radial,
    ] {
        let r = morris(
            &g,
            &g.problem(),
            &MorrisParams {
                r: 50,
                design,
                seed: 1,
                ..Default::default()
            },
        )
        .unwrap();
        let mus = &r.outputs[0].mu_star;
        let rho = spearman(mus, &st);
        assert!(rho > 0.9, "{design:?}: Spearman {rho}");
        let mut idx: Vec<usize> = (0..41).collect();
        idx.sort_by(|&a, &b| mus[b].total_cmp(&mus[a]));
        assert!(
            idx[..3].contains(&0) && idx[..3].contains(&1),
            "{design:?}: top {:?}",
            &idx[..5]
        );
        assert!(r.outputs[0].mu_star_ci[0][0] <= mus[0] && mus[0] <= r.outputs[0].mu_star_ci[0][1]);
    }
}

#[test]
fn morris_linear_is_exact_and_thread_independent() {
    let p = Problem::from_dists(&[
        Distribution::uniform(0.0, 2.0).unwrap(),
        Distribution::uniform(0.0, 1.0).unwrap(),
    ])
    .unwrap();
    let lin = Linear::new(vec![3.0, -1.0]);
    let run = |t: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(|| {
                morris(
                    &lin,
                    &p,
                    &MorrisParams {
                        r: 10,
                        ..Default::default()
                    },
                )
                .unwrap()
            })
    };
    let a = run(1);
    assert_eq!(a, run(2));
    // unit-scale effects: ∂y/∂u = a·(hi − lo)
    assert!((a.outputs[0].mu[0] - 6.0).abs() < 1e-12 && (a.outputs[0].mu[1] + 1.0).abs() < 1e-12);
    assert!(a.outputs[0].sigma[0] < 1e-12);
}

#[test]
fn local_methods() {
    let p = Problem::from_dists(&[
        Distribution::normal(1.0, 0.5).unwrap(),
        Distribution::tolerance(0.015, 3.0).unwrap(),
    ])
    .unwrap();
    let r = gradient_spread(&|x: &[f64]| 2.0 * x[0] + 100.0 * x[1], &p, 1e-3).unwrap();
    // effects 2·0.5 = 1 and 100·0.005 = 0.5
    assert!((r[0].effect[0] - 1.0).abs() < 1e-9 && (r[0].effect[1] - 0.5).abs() < 1e-9);
    // Motion increment: a constant-rate error (rigid shift) has zero range, a varying one does not.
    let sens = vec![vec![1.0, 1.0, 1.0], vec![0.5, 1.0, 1.5]];
    let rate = vec![vec![0.0, 0.0, 0.0], vec![1.0, 1.0, 1.0]];
    let ds = vec![vec![1.0; 3], vec![2.0; 3]];
    let mi = motion_increment(&sens, &rate, &ds).unwrap();
    assert_eq!(mi.share, vec![0.0, 1.0]);
    let ui = unit_increment(&sens, &[1.0, 1.0]).unwrap();
    assert_eq!(ui.share, vec![0.0, 1.0]);
    assert!(motion_increment(&sens, &rate[..1], &ds).is_err());
}
