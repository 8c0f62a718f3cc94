//! The observation model: zero readings on an ideal machine, the analytic BK1 trajectory of a
//! shifted B line, and the first-order sensitivity against finite differences of the exact model.
mod common;
use approx::assert_abs_diff_eq;
use common::*;
use mte_linalg::{Mat3, Vec3};
use mte_rtest::{
    ObservationModel, PlanItem, Program, SetupNuisance, SetupSpec, SimOptions, command_plan,
    simulate,
};

#[test]
fn error_free_machine_reads_zero() {
    let m = machine();
    let plan = [bk_all(&m, "s1", Vec3::new(120.0, 80.0, 50.0), 4.0)];
    let opts = SimOptions {
        noise_sd_mm: 0.0,
        ..Default::default()
    };
    let sim = simulate(&m, &plan, &vec![0.0; m.n_slots()][..], &opts).unwrap();
    assert!(sim.dataset.readings.len() > 100);
    let worst = sim
        .dataset
        .readings
        .iter()
        .map(|r| r.d_mm.norm())
        .fold(0.0, f64::max);
    // round-off of a few kinematic evaluations at ~300 mm: 1e-9 mm is far below 1 nm
    assert!(worst < 1e-9, "ideal machine read {worst} mm");
}

/// A B line shifted by c = (EX0B, 0, EZ0B) and nothing else: the ball turns about the true line
/// while the nest turns about the nominal one, so d = (I − R_rel)·c exactly, with
/// R_rel = R_W(q)·R_W(q_ref)ᵀ (derivation in the crate README).
#[test]
fn bk1_shifted_b_line_matches_the_analytic_trajectory() {
    let m = machine();
    let c = Vec3::new(0.020, 0.0, -0.015);
    let e = errors(&m, &[("EX0B", c.x), ("EZ0B", c.z)]);
    let plan = [PlanItem {
        setup: SetupSpec::new("s", Vec3::new(0.0, 100.0, 40.0)),
        programs: vec![Program::bk1(&m, None).unwrap()],
    }];
    let ds = command_plan(&m, &plan, &SimOptions::default()).unwrap();
    let model = ObservationModel::new(&m, &ds).unwrap();
    let pred = model.predict_constant(&e, &[]).unwrap();
    let q_ref = &ds.setups[0].centring_q;
    let rw = |q: &[f64]| -> Mat3 {
        m.branch_poses(q, &[])
            .workpiece_in_base
            .rotation
            .to_rotation_matrix()
            .into_inner()
    };
    let mut biggest: f64 = 0.0;
    for (r, d) in ds.readings.iter().zip(&pred) {
        let rel = rw(&r.q) * rw(q_ref).transpose();
        let expect = (Mat3::identity() - rel) * c;
        biggest = biggest.max(expect.norm());
        // exact identity; 1e-10 mm covers round-off
        assert_abs_diff_eq!(*d, expect, epsilon = 1e-10);
    }
    assert!(biggest > 0.02, "the test must move the ball noticeably");
}

/// ∂d/∂e (at_row + at_centring) and the nuisance blocks against central differences of the exact
/// predictor, for every location slot of both rotary axes and for a tool-side slot.
#[test]
fn sensitivity_matches_finite_differences() {
    let m = machine();
    let mut item = bk_all(&m, "s", Vec3::new(60.0, -90.0, 30.0), 15.0);
    item.setup.nest_mm = Vec3::new(0.0, 0.0, 5.0);
    let ds = command_plan(&m, &[item], &SimOptions::default()).unwrap();
    let model = ObservationModel::new(&m, &ds).unwrap();
    let sens = model.sensitivity();
    let h = 1e-6;
    let mut names: Vec<String> = mte_rtest::location_errors(&m)
        .unwrap()
        .into_iter()
        .map(|s| s.iso)
        .collect();
    names.extend(["EA0Y", "EC0Y", "EB0Z", "EX0X"].map(String::from));
    for n in names {
        let slot = mte_rtest::slot_by_name(&m, &n).unwrap().slot();
        let mut ep = vec![0.0; m.n_slots()];
        ep[slot] = h;
        let mut em = ep.clone();
        em[slot] = -h;
        let p = model.predict_constant(&ep, &[]).unwrap();
        let q = model.predict_constant(&em, &[]).unwrap();
        for (k, s) in sens.iter().enumerate() {
            let fd = (p[k] - q[k]) / (2.0 * h);
            let an = s.constant().column(slot).into_owned();
            // central difference error O(h²·second derivative) ≈ 1e-12·1e5 — 1e-5 relative to
            // a column of size up to ~300 mm/rad is ample
            for r in 0..3 {
                assert!(
                    (fd[r] - an[r]).abs() < 1e-5 * (1.0 + an[r].abs()),
                    "{n} row {k} comp {r}: fd {} vs {}",
                    fd[r],
                    an[r]
                );
            }
        }
    }
    for kind in [
        mte_rtest::NuisanceKind::SensorZero,
        mte_rtest::NuisanceKind::NestOffset,
        mte_rtest::NuisanceKind::BallOffset,
    ] {
        for c in 0..3 {
            let mut np = SetupNuisance::default();
            np.get_mut(kind)[c] = 1e-3;
            let mut nm = SetupNuisance::default();
            nm.get_mut(kind)[c] = -1e-3;
            let p = model.predict_constant(&[], &[np]).unwrap();
            let q = model.predict_constant(&[], &[nm]).unwrap();
            for (k, s) in sens.iter().enumerate() {
                let fd = (p[k] - q[k]) / 2e-3;
                let an = s.nuisance(kind).column(c).into_owned();
                assert_abs_diff_eq!(fd, an, epsilon = 1e-9);
            }
        }
    }
}
