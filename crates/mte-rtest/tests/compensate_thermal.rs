//! Compensation (BK4 before/after) and thermal drift tracking.
mod common;
use common::*;
use mte_linalg::Vec3;
use mte_rtest::compensate::{corrected_controller, predict_bk4};
use mte_rtest::thermal::{fit_drift, track};
use mte_rtest::{FitSpec, PlanItem, Program, SetupSpec, SimOptions, identify, simulate};

/// A controller given the true location values makes BK4 read zero (exact IK with the
/// corrected description); with identified values the residual BK4 range shrinks to the order
/// of the identification uncertainty.
#[test]
fn compensation_with_identified_pivots_flattens_bk4() {
    let m = machine();
    let truth = errors(
        &m,
        &[
            ("EX0B", 0.02),
            ("EZ0B", -0.015),
            ("EA0B", 5e-5),
            ("EX0C", -0.012),
            ("EY0C", 0.018),
            ("EB0C", -4e-5),
        ],
    );
    let setup = SetupSpec::new("bk4", Vec3::new(80.0, 100.0, 50.0));
    let before = predict_bk4(&m, &truth[..], &[], &setup).unwrap();
    assert!(before.max_range_um > 30.0, "{before:?}");
    let perfect = predict_bk4(&m, &truth[..], &truth, &setup).unwrap();
    // exact IK with the exact description: only round-off remains
    assert!(perfect.max_range_um < 1e-6, "{perfect:?}");
    let sim = simulate(
        &m,
        &[bk_all(&m, "s", Vec3::new(120.0, 60.0, 50.0), 4.0)],
        &truth[..],
        &SimOptions {
            noise_sd_mm: 0.0005,
            seed: 5,
            ..Default::default()
        },
    )
    .unwrap();
    let fit = identify(&m, &sim.dataset, &FitSpec::pivots(&m).unwrap()).unwrap();
    let ctrl = corrected_controller(&[], m.n_slots(), &fit, None);
    let after = predict_bk4(&m, &truth[..], &ctrl, &setup).unwrap();
    // σ ≈ 0.1 µm / 0.3 µrad per parameter over lever arms ≤ 300 mm: a few tenths of a µm
    assert!(
        after.max_range_um < 1.0,
        "after {after:?} (before {before:?})"
    );
}

/// fit_drift on noise-free exponential data returns the generating τ (grid resolution 3.5 %).
#[test]
fn exponential_drift_model_recovers_tau() {
    let t: Vec<f64> = (0..20).map(|k| k as f64 * 100.0).collect();
    let v: Vec<f64> = t
        .iter()
        .map(|&x| -0.0177 - 0.008 * (1.0 - (-x / 900.0).exp()))
        .collect();
    let (lin, exp) = fit_drift(&t, &v).unwrap();
    let e = exp.unwrap();
    assert!((e.tau_s - 900.0).abs() < 0.04 * 900.0, "tau {}", e.tau_s);
    assert!(e.rms < lin.rms);
    assert!(fit_drift(&t[..1], &v[..1]).is_err());
}

/// Repeated BK1+BK2 cycles with pivots drifting linearly: the tracked series follows the drift
/// and the linear model finds the slope.
#[test]
fn thermal_tracking_recovers_linear_pivot_drift() {
    let m = machine();
    let (sx, sy) = (
        mte_rtest::slot_by_name(&m, "EX0B").unwrap().slot(),
        mte_rtest::slot_by_name(&m, "EY0C").unwrap().slot(),
    );
    let n = m.n_slots();
    let rate = -0.005 / 1800.0; // −5 µm in 30 min (Table 3, XOB)
    let field = move |_q: &[f64], t: f64| {
        let mut e = vec![0.0; n];
        e[sx] = -0.0177 + rate * t;
        e[sy] = -0.0319 + 0.5 * rate * t;
        e
    };
    let mut all: Option<mte_rtest::Dataset> = None;
    for c in 0..7 {
        let item = PlanItem {
            setup: SetupSpec::new(&format!("c{c}"), Vec3::new(100.0, 80.0, 50.0)),
            programs: vec![
                Program::bk1(&m, None).unwrap().with_step(6.0),
                Program::bk2(&m).unwrap().with_step(6.0),
            ],
        };
        let s = simulate(
            &m,
            &[item],
            &field,
            &SimOptions {
                start_t_s: 300.0 * c as f64,
                seed: 40 + c as u64,
                ..Default::default()
            },
        )
        .unwrap();
        match &mut all {
            None => all = Some(s.dataset),
            Some(a) => {
                let off = a.setups.len();
                a.setups.extend(s.dataset.setups);
                a.readings
                    .extend(s.dataset.readings.into_iter().map(|mut r| {
                        r.setup += off;
                        r
                    }));
            }
        }
    }
    let data = all.unwrap();
    let (_fits, series) = track(&m, &data, &FitSpec::pivots(&m).unwrap()).unwrap();
    let xb = series.iter().find(|s| s.label == "EX0B").unwrap();
    // slope within 10 % (per-cycle σ ≈ 0.1 µm over a 9 µm change)
    assert!(
        (xb.linear.a - rate).abs() < 0.1 * rate.abs(),
        "slope {} vs {rate}",
        xb.linear.a
    );
    let yc = series.iter().find(|s| s.label == "EY0C").unwrap();
    assert!(
        (yc.linear.a - 0.5 * rate).abs() < 0.15 * rate.abs(),
        "slope {}",
        yc.linear.a
    );
    assert!((yc.values[0] + 0.0319).abs() < 0.001);
}
