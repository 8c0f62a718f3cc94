//! GUM Supplement 1 Monte Carlo against analytic results (JCGM 101:2008).

use mte_metrology::gum::{
    InputDistribution as D, McParams, Sensitivities, gum_framework, monte_carlo,
    monte_carlo_adaptive, numerical_tolerance, validate,
};
use mte_metrology::stats::{chi2_quantile, normal_quantile};

fn linear(x: &[f64]) -> f64 {
    2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2]
}

fn lin_inputs() -> [D; 3] {
    [
        D::Normal { mean: 1.0, sd: 0.1 },
        D::Normal { mean: 2.0, sd: 0.2 },
        D::Normal { mean: 3.0, sd: 0.4 },
    ]
}

/// Linear Gaussian model: the output is N(y0, u²) with y0 = 2 − 6 + 1.5 = −2.5 and
/// u² = (2·0.1)² + (3·0.2)² + (0.5·0.4)² = 0.44; intervals y0 ± 1.96·u.
#[test]
fn linear_gaussian_matches_analytic() {
    let u = 0.44f64.sqrt();
    let z = normal_quantile(0.975);
    let m = 200_000;
    let r = monte_carlo(
        &linear,
        &lin_inputs(),
        &McParams {
            trials: m,
            coverage: 0.95,
            seed: 11,
        },
    )
    .unwrap();
    // sampling errors: mean u/√M = 0.0015; sd ≈ u/√(2M) = 0.001; quantiles ≈ 0.006u (see test doc)
    assert!((r.estimate + 2.5).abs() < 4.0 * u / (m as f64).sqrt());
    assert!((r.standard_uncertainty - u).abs() < 4.0 * u / (2.0 * m as f64).sqrt());
    for (lo, hi) in [r.symmetric_interval, r.shortest_interval] {
        assert!((lo - (-2.5 - z * u)).abs() < 0.03 * u, "{lo}");
        assert!((hi - (-2.5 + z * u)).abs() < 0.03 * u, "{hi}");
    }
    let guf = gum_framework(&linear, &lin_inputs(), 0.95, Sensitivities::Numerical).unwrap();
    assert!((guf.standard_uncertainty - u).abs() < 1e-9);
    assert!((guf.sensitivities[1] + 3.0).abs() < 1e-9);
    assert!(
        validate(&guf, &r, 1).validated,
        "GUF must validate for a linear Gaussian model"
    );
}

/// Y = X², X ~ N(0, 1): Y ~ χ²₁; shortest 95 % interval starts at 0 and ends at χ²₁(0.95) = 3.841;
/// the symmetric one is [χ²₁(0.025), χ²₁(0.975)] = [0.00098, 5.024]. The GUF (c = 0) fails validation.
#[test]
fn chi_square_output_shortest_vs_symmetric() {
    let f = |x: &[f64]| x[0] * x[0];
    let inp = [D::Normal { mean: 0.0, sd: 1.0 }];
    let r = monte_carlo(
        &f,
        &inp,
        &McParams {
            trials: 200_000,
            coverage: 0.95,
            seed: 5,
        },
    )
    .unwrap();
    assert!(r.shortest_interval.0 < 1e-4);
    assert!((r.shortest_interval.1 - chi2_quantile(0.95, 1.0)).abs() < 0.05);
    assert!((r.symmetric_interval.0 - chi2_quantile(0.025, 1.0)).abs() < 2e-4);
    assert!((r.symmetric_interval.1 - chi2_quantile(0.975, 1.0)).abs() < 0.06);
    assert!((r.standard_uncertainty - 2f64.sqrt()).abs() < 0.02);
    let guf = gum_framework(&f, &inp, 0.95, Sensitivities::Numerical).unwrap();
    assert!(!validate(&guf, &r, 1).validated);
}

/// Rectangular output U(0, 1): symmetric = [0.025, 0.975]; every 95 % interval has width 0.95.
#[test]
fn rectangular_output() {
    let f = |x: &[f64]| x[0];
    let r = monte_carlo(
        &f,
        &[D::Rectangular { a: 0.0, b: 1.0 }],
        &McParams {
            trials: 100_000,
            coverage: 0.95,
            seed: 9,
        },
    )
    .unwrap();
    assert!(
        (r.symmetric_interval.0 - 0.025).abs() < 3e-3
            && (r.symmetric_interval.1 - 0.975).abs() < 3e-3
    );
    assert!((r.shortest_interval.1 - r.shortest_interval.0 - 0.95).abs() < 3e-3);
    assert!((r.standard_uncertainty - 1.0 / 12f64.sqrt()).abs() < 3e-3);
}

#[test]
fn identical_for_one_and_two_threads() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                monte_carlo(
                    &linear,
                    &lin_inputs(),
                    &McParams {
                        trials: 50_000,
                        coverage: 0.95,
                        seed: 42,
                    },
                )
                .unwrap()
            })
    };
    assert_eq!(run(1), run(2));
    let ad = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                monte_carlo_adaptive(
                    &linear,
                    &lin_inputs(),
                    &McParams {
                        trials: 10_000,
                        coverage: 0.95,
                        seed: 4,
                    },
                    2,
                    10_000_000,
                )
                .unwrap()
            })
    };
    assert_eq!(ad(1), ad(2));
}

/// Adaptive procedure (GUM-S1 7.9): stops with δ from 2 significant digits of u and the result
/// agrees with the analytic u within a few δ.
#[test]
fn adaptive_reaches_tolerance() {
    let r = monte_carlo_adaptive(
        &linear,
        &lin_inputs(),
        &McParams {
            trials: 10_000,
            coverage: 0.95,
            seed: 8,
        },
        2,
        5_000_000,
    )
    .unwrap();
    let u = 0.44f64.sqrt();
    assert_eq!(r.tolerance, numerical_tolerance(u, 2));
    assert!(r.batches >= 2);
    assert!((r.standard_uncertainty - u).abs() < 2.0 * r.tolerance);
    assert!((r.estimate + 2.5).abs() < 2.0 * r.tolerance);
    // 0.6633 → 2 digits: 0.66 → δ = 0.005
    assert!((numerical_tolerance(0.6633, 2) - 0.005).abs() < 1e-15);
    assert!((numerical_tolerance(1.2e-3, 1) - 0.5e-3).abs() < 1e-18);
}

#[test]
fn bad_inputs_are_errors() {
    let f = |x: &[f64]| x[0];
    assert!(
        monte_carlo(
            &f,
            &[D::Normal {
                mean: 0.0,
                sd: -1.0
            }],
            &McParams::default()
        )
        .is_err()
    );
    assert!(
        monte_carlo(
            &f,
            &[D::Rectangular { a: 1.0, b: 0.0 }],
            &McParams::default()
        )
        .is_err()
    );
    assert!(
        monte_carlo(
            &f,
            &[D::Normal { mean: 0.0, sd: 1.0 }],
            &McParams {
                trials: 10,
                coverage: 0.95,
                seed: 1
            }
        )
        .is_err()
    );
    let nan = |_: &[f64]| f64::NAN;
    let e = monte_carlo(
        &nan,
        &[D::Normal { mean: 0.0, sd: 1.0 }],
        &McParams {
            trials: 1000,
            coverage: 0.95,
            seed: 1,
        },
    );
    assert!(e.unwrap_err().to_string().contains("NaN"));
}

/// The linearised tracker measurement function (cached sensitivity) agrees with a full
/// re-adjustment per trial: same seed → same draws → model values within 1 nm.
#[test]
fn linearised_tracker_matches_full_readjustment() {
    use mte_metrology::adjust::{AdjustParams, adjust};
    use mte_metrology::network::{LengthUncertainty, Vec3};
    use mte_metrology::simulate::{SmoothErrorField, StationLayout, cube_edge_targets, simulate};
    use mte_metrology::uncertainty::{FullReadjustment, LinearisedTracker, TrackerQuantity};
    let targets = cube_edge_targets(500.0, 2);
    let field = SmoothErrorField::new(500.0, &targets, 30.0);
    let sim = simulate(
        &StationLayout::FourLow.stations(500.0, true),
        &targets,
        &|p: &Vec3| field.eval(p),
        LengthUncertainty::SEED004,
        3,
    )
    .unwrap();
    let adj = adjust(&sim.network, &AdjustParams::default()).unwrap();
    let inputs = LinearisedTracker::inputs(&adj);
    for q in [
        TrackerQuantity::MaxDeviation,
        TrackerQuantity::TargetComponent(7, 2),
    ] {
        let lin = LinearisedTracker::new(&adj, q).unwrap();
        let full = FullReadjustment {
            network: sim.network.clone(),
            params: AdjustParams::default(),
            quantity: q,
        };
        let p = McParams {
            trials: 1024,
            coverage: 0.95,
            seed: 77,
        };
        let a = monte_carlo(&lin, &inputs, &p).unwrap();
        let b = monte_carlo(&full, &inputs, &p).unwrap();
        assert!(
            (a.estimate - b.estimate).abs() < 1e-6,
            "{} {}",
            a.estimate,
            b.estimate
        );
        assert!((a.standard_uncertainty - b.standard_uncertainty).abs() < 1e-6);
        assert!((a.shortest_interval.1 - b.shortest_interval.1).abs() < 1e-6);
        // and for one component the MC u equals the adjustment's σ (linear Gaussian)
        if let TrackerQuantity::TargetComponent(j, c) = q {
            let s = adj.targets[j].covariance()[(c, c)].sqrt();
            assert!(
                (a.standard_uncertainty / s - 1.0).abs() < 0.1,
                "{} vs {s}",
                a.standard_uncertainty
            );
        }
    }
}
