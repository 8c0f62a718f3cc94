//! Sparse PCE: exact recovery of polynomial models, indices against analytic values, reported
//! errors against the error on fresh runs.
#![allow(clippy::needless_range_loop)]

use mte_sensitivity::pce::{
    ErrorName, PceParams, PceWarning, READABLE_ERROR, Selection, Validation, build_pce, fit_pce,
    sample_runs,
};
use mte_sensitivity::testfn::{GFunction, Ishigami, Linear};
use mte_sensitivity::{Distribution, Error, MultiOutput, Problem, Sampling};

fn problem8() -> Problem {
    let mut d = vec![
        Distribution::normal(0.0, 1.0).unwrap(),
        Distribution::uniform(-1.0, 1.0).unwrap(),
        Distribution::normal(2.0, 0.5).unwrap(),
    ];
    d.extend(std::iter::repeat_n(
        Distribution::uniform(0.0, 3.0).unwrap(),
        5,
    ));
    Problem::from_dists(&d).unwrap()
}

/// y = 3 + x1 + x1² + x1·x2 + x2³ + 0.2(x3 − 2) in the orthonormal basis (ξ1 = x1, ξ2 = x2,
/// ξ3 = (x3 − 2)/0.5): x1² = 1 + √2 He₂, x1·x2 = ψ₁ψ₁/√3, x2³ = (2/(5√7)) L₃ + (3/(5√3)) L₁,
/// 0.2(x3 − 2) = 0.1 ψ₁(ξ3). Exact coefficients from Hermite / Legendre identities.
#[test]
fn recovers_exact_coefficients_of_a_polynomial() {
    let prob = problem8();
    let f = |x: &[f64]| 3.0 + x[0] + x[0] * x[0] + x[0] * x[1] + x[1].powi(3) + 0.2 * (x[2] - 2.0);
    for selection in [Selection::KFold { folds: 5 }, Selection::CorrectedLoo] {
        let params = PceParams {
            degree: 3,
            n_samples: 200,
            selection,
            seed: 4,
            ..Default::default()
        };
        let r = build_pce(&f, &prob, &params).unwrap();
        let o = &r.outputs[0];
        let expect: Vec<(Vec<(u32, u32)>, f64)> = vec![
            (vec![], 4.0),
            (vec![(0, 1)], 1.0),
            (vec![(0, 2)], 2f64.sqrt()),
            (vec![(0, 1), (1, 1)], 1.0 / 3f64.sqrt()),
            (vec![(1, 3)], 2.0 / (5.0 * 7f64.sqrt())),
            (vec![(1, 1)], 3.0 / (5.0 * 3f64.sqrt())),
            (vec![(2, 1)], 0.1),
        ];
        for (mi, c) in &expect {
            let got = o
                .terms
                .iter()
                .find(|t| &t.0 == mi)
                .map(|t| t.1)
                .unwrap_or(0.0);
            assert!((got - c).abs() < 1e-9, "{selection:?} {mi:?}: {got} vs {c}");
        }
        for (mi, c) in &o.terms {
            if !expect.iter().any(|e| &e.0 == mi) {
                assert!(c.abs() < 1e-9, "{selection:?}: spurious term {mi:?} = {c}");
            }
        }
        assert!(o.train_error < 1e-20, "{}", o.train_error);
        assert_eq!(o.degree, 3);
        let var: f64 = expect[1..].iter().map(|e| e.1 * e.1).sum();
        assert!((o.variance - var).abs() < 1e-9);
        assert!((o.first[2] - 0.01 / var).abs() < 1e-9);
        assert!((o.total[0] - (1.0 + 2.0 + 1.0 / 3.0) / var).abs() < 1e-9);
        assert!(
            o.interactions
                .iter()
                .any(|&(i, j, s)| i == 0 && j == 1 && (s - 1.0 / 3.0 / var).abs() < 1e-9)
        );
    }
}

#[test]
fn linear_model_exactly_with_many_outputs() {
    let prob = problem8();
    let lin = Linear {
        coef: vec![
            vec![1.0, -2.0, 0.5, 0.0, 0.0, 0.0, 0.0, 1.0],
            vec![0.0, 0.0, 0.0, 3.0, 0.0, 0.0, 0.0, 0.0],
        ],
    };
    let r = build_pce(
        &lin,
        &prob,
        &PceParams {
            degree: 2,
            n_samples: 100,
            ..Default::default()
        },
    )
    .unwrap();
    let exact = lin.analytic(&prob);
    for i in 0..8 {
        assert!(
            (r.outputs[0].first[i] - exact[i]).abs() < 1e-10
                && (r.outputs[0].total[i] - exact[i]).abs() < 1e-10
        );
    }
    assert!((r.outputs[1].first[3] - 1.0).abs() < 1e-12);
    assert_eq!(
        r.outputs[0].degree, 1,
        "adaptive degree stops at the exact linear fit"
    );
}

/// Ishigami by PCE: a smooth non-polynomial model; degree chosen adaptively up to 10.
/// Analytic indices from CROSSCHECKS.md; tolerance 0.01 (truncation of sin at degree ≤ 10).
#[test]
fn ishigami_indices_and_intervals() {
    let f = Ishigami::default();
    let (s1, st) = f.analytic();
    let params = PceParams {
        degree: 10,
        n_samples: 800,
        n_bootstrap: 100,
        seed: 1,
        ..Default::default()
    };
    let r = build_pce(&f, &Ishigami::problem(), &params).unwrap();
    let o = &r.outputs[0];
    for i in 0..3 {
        assert!(
            (o.first[i] - s1[i]).abs() < 0.01 && (o.total[i] - st[i]).abs() < 0.01,
            "{i}: {:?} {:?}",
            o.first,
            o.total
        );
        assert!(
            o.total_ci[i][0] - 0.01 <= st[i] && st[i] <= o.total_ci[i][1] + 0.01,
            "{i}: {:?}",
            o.total_ci
        );
    }
    assert!(o.cv_error < 1e-3, "{}", o.cv_error);
    // independent validation set
    let (xv, yv) = sample_runs(&f, &Ishigami::problem(), Sampling::MonteCarlo, 2000, 77).unwrap();
    let ve = r.validation_error(&Ishigami::problem(), 0, &xv, &yv);
    assert!(
        ve < 3.0 * o.cv_error + 1e-4,
        "validation {ve} vs cv {}",
        o.cv_error
    );
}

/// Under K-fold CV the full-data path is sized by the folds: it stops at the chosen size, neither
/// beyond it (as long as a fold still runs) nor short of it (by its own corrected-LOO patience).
#[test]
fn kfold_full_path_stops_at_the_chosen_size() {
    let f = Ishigami::default();
    for seed in 0..3 {
        let params = PceParams {
            degree: 8,
            adaptive_degree: false,
            n_samples: 200,
            seed,
            ..Default::default()
        };
        let r = build_pce(&f, &Ishigami::problem(), &params).unwrap();
        let o = &r.outputs[0];
        assert!(o.terms.len() > 5, "seed {seed}: {} terms", o.terms.len());
        assert_eq!(o.omp_steps, o.terms.len(), "seed {seed}");
    }
}

#[test]
fn identical_across_thread_counts() {
    let f = MultiOutput::new(2, |x: &[f64], y: &mut [f64]| {
        y[0] = x[0].sin() + x[1] * x[2];
        y[1] = (x[3] * x[0]).cos();
    });
    let prob = Problem::from_dists(&[Distribution::normal(0.0, 1.0).unwrap(); 6]).unwrap();
    let params = PceParams {
        degree: 4,
        n_samples: 300,
        n_bootstrap: 20,
        ..Default::default()
    };
    let run = |t: usize, params: &PceParams| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(|| build_pce(&f, &prob, params).unwrap())
    };
    assert_eq!(run(1, &params), run(2, &params));
    // corrected LOO with its fold searches, and a validation on fresh runs
    let loo = PceParams {
        selection: Selection::CorrectedLoo,
        validation: Some(Validation {
            n: 1000,
            seed: None,
        }),
        ..params
    };
    let (one, two) = (run(1, &loo), run(2, &loo));
    assert!(one.outputs[1].validation_error.is_some());
    // cv_error is NaN under corrected LOO (NaN ≠ NaN): compared through Debug, which prints
    // every value in full (shortest round-trip form)
    assert_eq!(format!("{one:?}"), format!("{two:?}"));
}

#[test]
fn bad_input_gives_clear_errors() {
    let prob = problem8();
    let x = vec![0.5; 8 * 5];
    let e = fit_pce(
        &prob,
        &x,
        &[1.0, 2.0, 3.0, 4.0, 5.0],
        1,
        &PceParams::default(),
    )
    .unwrap_err();
    assert!(matches!(e, Error::SampleSize { n: 5, .. }), "{e}");
    let f = |x: &[f64]| if x[0] > 2.0 { f64::NAN } else { x[0] };
    let e = build_pce(
        &f,
        &prob,
        &PceParams {
            n_samples: 2000,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, Error::ModelOutput { output: 0, .. }), "{e}");
    let e = fit_pce(&prob, &x[..39], &[1.0; 5], 1, &PceParams::default()).unwrap_err();
    assert!(matches!(e, Error::Dimension { .. }), "{e}");
}

/// The case, the Sobol' G-function with 41 inputs at degree 3 (13244 candidates) and 1000
/// Latin-hypercube runs, where no expansion fits well: for both rules the selection-aware error
/// lies within a factor 1.5 of the error on 20000 fresh Monte Carlo runs (the validation, here
/// through `PceParams::validation`). Under corrected LOO the rule's own score is optimistic by
/// orders of magnitude (4e-3 against 0.84 measured) and must come with its warnings.
#[test]
fn gfunction_41_selection_aware_error_matches_fresh_runs() {
    let g = GFunction::benchmark(41);
    let base = PceParams {
        degree: 3,
        n_samples: 1000,
        seed: 0,
        validation: Some(Validation {
            n: 20_000,
            seed: Some(12_345),
        }),
        ..Default::default()
    };
    for selection in [Selection::KFold { folds: 5 }, Selection::CorrectedLoo] {
        let params = PceParams {
            selection,
            ..base.clone()
        };
        let o = build_pce(&g, &g.problem(), &params)
            .unwrap()
            .outputs
            .remove(0);
        let fresh = o.validation_error.unwrap();
        let ratio = o.selection_aware_error / fresh;
        assert!(
            (1.0 / 1.5..=1.5).contains(&ratio),
            "{selection:?}: selection-aware {} vs fresh {fresh}",
            o.selection_aware_error
        );
        // no expansion from 1000 runs reads this function: both say so
        assert!(
            o.warnings
                .iter()
                .any(|w| matches!(w, PceWarning::LargeError { .. }))
        );
        match selection {
            Selection::CorrectedLoo => {
                assert!(o.loo_error < 0.1 * fresh, "{} vs {fresh}", o.loo_error);
                assert!(
                    o.warnings.contains(&PceWarning::Disagree {
                        low: ErrorName::CorrectedLoo,
                        low_value: o.loo_error,
                        high: ErrorName::SelectionAware,
                        high_value: o.selection_aware_error,
                    }),
                    "{:?}",
                    o.warnings
                );
            }
            Selection::KFold { .. } => {
                assert_eq!(o.selection_aware_error, o.cv_error);
                assert!(
                    !o.warnings
                        .iter()
                        .any(|w| matches!(w, PceWarning::Disagree { .. })),
                    "{:?}",
                    o.warnings
                );
            }
        }
    }
}

/// Ishigami, where the expansion is good: for both rules at 800 runs (relative error about 2e-6),
/// and under K-fold at 150 runs (about 2e-2), the selection-aware error lies within a factor 1.5
/// of the error on 20000 fresh runs, and nothing warns of a large error. Measured over seeds 0–9
/// (`cargo run -p mte-sensitivity --example pce_errors`): 0.83–1.33 for K-fold at 150, 300 and
/// 800 runs, 0.92–1.26 for corrected LOO at 800 runs. Corrected LOO at 150 runs is not tested:
/// its fold searches on 120 runs differ from the search on all runs more (ratios 0.89–1.92,
/// two seeds of ten above 1.5; 0.46–1.39 at 300 runs), which a `validation` then shows.
#[test]
fn ishigami_selection_aware_error_matches_fresh_runs() {
    let f = Ishigami::default();
    let prob = Ishigami::problem();
    let (xv, yv) = sample_runs(&f, &prob, Sampling::MonteCarlo, 20_000, 77).unwrap();
    let cases = [
        (800, 10, Selection::KFold { folds: 5 }),
        (800, 10, Selection::CorrectedLoo),
        (150, 6, Selection::KFold { folds: 5 }),
    ];
    for (n, degree, selection) in cases {
        let params = PceParams {
            degree,
            n_samples: n,
            selection,
            seed: 1,
            ..Default::default()
        };
        let r = build_pce(&f, &prob, &params).unwrap();
        let o = &r.outputs[0];
        let fresh = r.validation_error(&prob, 0, &xv, &yv);
        let ratio = o.selection_aware_error / fresh;
        assert!(
            (1.0 / 1.5..=1.5).contains(&ratio),
            "n {n} {selection:?}: selection-aware {} vs fresh {fresh} (loo {})",
            o.selection_aware_error,
            o.loo_error
        );
        assert!(fresh < READABLE_ERROR, "n {n}: {fresh}");
        assert!(
            !o.warnings
                .iter()
                .any(|w| matches!(w, PceWarning::LargeError { .. })),
            "{:?}",
            o.warnings
        );
    }
}

/// A validation of fewer than 2 runs is an error, and validation changes no fitted value.
#[test]
fn validation_is_checked_and_changes_no_fit() {
    let f = Ishigami::default();
    let prob = Ishigami::problem();
    let params = PceParams {
        degree: 5,
        n_samples: 100,
        ..Default::default()
    };
    let bad = PceParams {
        validation: Some(Validation { n: 1, seed: None }),
        ..params.clone()
    };
    let e = build_pce(&f, &prob, &bad).unwrap_err();
    assert!(matches!(e, Error::SampleSize { n: 1, min: 2, .. }), "{e}");
    let plain = build_pce(&f, &prob, &params).unwrap().outputs.remove(0);
    let checked = build_pce(
        &f,
        &prob,
        &PceParams {
            validation: Some(Validation { n: 500, seed: None }),
            ..params
        },
    )
    .unwrap()
    .outputs
    .remove(0);
    assert_eq!(plain.terms, checked.terms);
    assert_eq!(plain.selection_aware_error, checked.selection_aware_error);
    assert!(plain.validation_error.is_none());
    assert!(checked.validation_error.unwrap() > 0.0);
}
