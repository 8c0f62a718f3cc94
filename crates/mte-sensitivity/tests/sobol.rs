//! Sobol' indices against analytic values (shared/papers/CROSSCHECKS.md, "Analytic sensitivity
//! references"): Ishigami, G-function k = 41, linear model.
#![allow(clippy::needless_range_loop)]

use mte_sensitivity::sobol::{SobolParams, sobol};
use mte_sensitivity::testfn::{GFunction, Ishigami, Linear};
use mte_sensitivity::{Distribution, Error, Problem, Sampling};

fn within(ci: [f64; 2], v: f64, slack: f64) -> bool {
    ci[0] - slack <= v && v <= ci[1] + slack
}

#[test]
fn ishigami_within_bootstrap_intervals_all_designs() {
    let f = Ishigami::default();
    let (s1, st) = f.analytic();
    // CROSSCHECKS.md: S1 = (0.3139, 0.4424, 0), ST = (0.5576, 0.4424, 0.2437)
    assert!((s1[0] - 0.3139).abs() < 1e-4 && (st[2] - 0.2437).abs() < 1e-4);
    for sampling in [
        Sampling::MonteCarlo,
        Sampling::LatinHypercube,
        Sampling::Sobol,
    ] {
        let p = SobolParams {
            n: 1 << 14,
            sampling,
            seed: 2,
            n_bootstrap: 200,
            confidence: 0.99,
            ..Default::default()
        };
        let r = sobol(&f, &Ishigami::problem(), &p).unwrap();
        let o = &r.outputs[0];
        for i in 0..3 {
            // 1e-9 slack only for the exactly-zero S1 of x3 whose interval may touch 0
            assert!(
                within(o.first_ci[i], s1[i], 1e-9),
                "{sampling:?} S1[{i}] = {} ci {:?} analytic {}",
                o.first[i],
                o.first_ci[i],
                s1[i]
            );
            assert!(
                within(o.total_ci[i], st[i], 0.0),
                "{sampling:?} ST[{i}] = {} ci {:?} analytic {}",
                o.total[i],
                o.total_ci[i],
                st[i]
            );
        }
        assert_eq!(r.n_model_runs, 5 * (1 << 14) + 64);
    }
}

/// The intervals are calibrated: over 40 seeds of plain Monte Carlo the 95 % intervals miss the
/// analytic Ishigami values about 2 times per index (binomial(40, 0.05): P(misses > 6) = 0.8 %).
#[test]
fn ishigami_interval_coverage_monte_carlo() {
    let f = Ishigami::default();
    let (s1, st) = f.analytic();
    let mut miss = [0usize; 6];
    for seed in 100..140 {
        let p = SobolParams {
            n: 1 << 12,
            sampling: Sampling::MonteCarlo,
            seed,
            n_bootstrap: 100,
            ..Default::default()
        };
        let o = &sobol(&f, &Ishigami::problem(), &p).unwrap().outputs[0];
        for i in 0..3 {
            miss[i] += usize::from(!within(o.first_ci[i], s1[i], 0.0));
            miss[3 + i] += usize::from(!within(o.total_ci[i], st[i], 0.0));
        }
    }
    assert!(miss.iter().all(|&m| m <= 6), "{miss:?}");
}

#[test]
fn gfunction_41_within_bootstrap_intervals() {
    let g = GFunction::benchmark(41);
    let (s1, st) = g.analytic();
    let p = SobolParams {
        n: 1 << 13,
        seed: 3,
        n_bootstrap: 200,
        confidence: 0.99,
        ..Default::default()
    };
    let r = sobol(&g, &g.problem(), &p).unwrap();
    let o = &r.outputs[0];
    let mut miss = vec![];
    for i in 0..41 {
        if !within(o.first_ci[i], s1[i], 0.0) {
            miss.push(format!(
                "S1[{i}] {} {:?} vs {}",
                o.first[i], o.first_ci[i], s1[i]
            ));
        }
        if !within(o.total_ci[i], st[i], 0.0) {
            miss.push(format!(
                "ST[{i}] {} {:?} vs {}",
                o.total[i], o.total_ci[i], st[i]
            ));
        }
    }
    // 82 intervals at 99 %: allow at most 2 misses (expected 0.8) and check the leading ones exactly
    assert!(miss.len() <= 2, "{miss:?}");
    for i in 0..3 {
        assert!(
            within(o.first_ci[i], s1[i], 0.0) && within(o.total_ci[i], st[i], 0.0),
            "{miss:?}"
        );
    }
}

#[test]
fn linear_model_indices_and_convergence() {
    let prob = Problem::from_dists(&[
        Distribution::normal(0.0, 1.0).unwrap(),
        Distribution::normal(5.0, 2.0).unwrap(),
        Distribution::uniform(-1.0, 1.0).unwrap(),
    ])
    .unwrap();
    let lin = Linear::new(vec![1.0, 0.5, 3.0]);
    let exact = lin.analytic(&prob);
    let p = SobolParams {
        n: 1 << 14,
        seed: 5,
        n_bootstrap: 200,
        confidence: 0.99,
        checkpoints: vec![1024, 4096],
        ..Default::default()
    };
    let r = sobol(&lin, &prob, &p).unwrap();
    let o = &r.outputs[0];
    for i in 0..3 {
        assert!(
            within(o.first_ci[i], exact[i], 0.0) && within(o.total_ci[i], exact[i], 0.0),
            "{i}: {o:?} vs {exact:?}"
        );
    }
    // Jansen's total estimator is exact term by term for an additive model: (f(A) − f(A_B^i))² only
    // involves input i, so the indices sum to one up to the variance estimate.
    assert_eq!(r.convergence.len(), 2);
    assert_eq!(r.convergence[0].n, 1024);
    assert!((o.mean - 2.5).abs() < 0.05, "{}", o.mean);
}

#[test]
fn second_order_of_ishigami() {
    // S13 = V13/V = b²π⁸(1/18 − 1/50)/V (Ishigami), the only non-zero pair.
    let f = Ishigami::default();
    let (_, st) = f.analytic();
    let s13 = st[2];
    let p = SobolParams {
        n: 1 << 14,
        seed: 2,
        n_bootstrap: 0,
        second_order: true,
        ..Default::default()
    };
    let r = sobol(&f, &Ishigami::problem(), &p).unwrap();
    let s2 = r.outputs[0].second.as_ref().unwrap();
    assert!((s2[0][2] - s13).abs() < 0.03, "{s2:?} vs {s13}");
    assert!(s2[0][1].abs() < 0.03 && s2[1][2].abs() < 0.03, "{s2:?}");
}

#[test]
fn identical_across_thread_counts() {
    let g = GFunction::benchmark(8);
    for sampling in [
        Sampling::MonteCarlo,
        Sampling::LatinHypercube,
        Sampling::Sobol,
    ] {
        let p = SobolParams {
            n: 5000,
            sampling,
            seed: 9,
            n_bootstrap: 50,
            ..Default::default()
        };
        let run = |t: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
                .install(|| sobol(&g, &g.problem(), &p).unwrap())
        };
        assert_eq!(run(1), run(2), "{sampling:?}");
    }
}

#[test]
fn bad_input_gives_clear_errors() {
    let g = GFunction::benchmark(3);
    let e = sobol(
        &g,
        &g.problem(),
        &SobolParams {
            n: 10,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, Error::SampleSize { n: 10, .. }), "{e}");
    let nan = |x: &[f64]| if x[1] > 0.9 { f64::NAN } else { x[0] };
    let e = sobol(
        &nan,
        &g.problem(),
        &SobolParams {
            n: 1024,
            n_bootstrap: 0,
            ..Default::default()
        },
    )
    .unwrap_err();
    match e {
        Error::ModelOutput {
            output: 0,
            value,
            x,
        } => assert!(value.is_nan() && x[1] > 0.9),
        other => panic!("{other}"),
    }
    let constant = |_: &[f64]| 1.0;
    let e = sobol(
        &constant,
        &g.problem(),
        &SobolParams {
            n: 1024,
            n_bootstrap: 0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, Error::Degenerate { output: 0, .. }), "{e}");
}
