//! Must-show checks of issue 2: MBS vs POE, the CROSSCHECKS POE value, analytic Jacobian vs
//! finite differences, first-order vs exact, IK∘FK, sign conventions, bad machine files.

use mte_kinematics::{AxisKind, Component, ErrorSlot, KinError, Machine, SlotKind};
use mte_linalg::{Iso3, Vec3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

fn random_q(m: &Machine, rng: &mut ChaCha8Rng) -> Vec<f64> {
    m.axes()
        .iter()
        .map(|a| rng.random_range(a.stroke.0..=a.stroke.1))
        .collect()
}

/// Errors up to 50 µm (translations) and 100 µrad (rotations), uniform.
fn random_e(m: &Machine, rng: &mut ChaCha8Rng, scale: f64) -> Vec<f64> {
    m.error_slots()
        .iter()
        .map(|s| {
            let lim = if s.component.is_translation() {
                0.050
            } else {
                100e-6
            };
            scale * rng.random_range(-lim..=lim)
        })
        .collect()
}

fn rot_gap(a: &Iso3, b: &Iso3) -> f64 {
    (a.rotation * b.rotation.inverse()).angle()
}

fn library() -> Vec<Machine> {
    Machine::library_names()
        .iter()
        .map(|n| Machine::library(n).unwrap())
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Two independent formulations (MBS characteristic matrices vs product of exponentials
    /// with adjoint-transported twists) agree to 1e-9 mm and 1e-12 rad (issue 2).
    #[test]
    fn mbs_and_poe_agree(seed in any::<u64>(), which in 0usize..5) {
        let m = Machine::library(Machine::library_names()[which]).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let q = random_q(&m, &mut rng);
        let e = random_e(&m, &mut rng, 1.0);
        for e in [&e[..], &[][..]] {
            let a = m.tool_in_workpiece(&q, e);
            let b = m.tool_in_workpiece_poe(&q, e);
            prop_assert!((a.translation.vector - b.translation.vector).norm() < 1e-9,
                "{}: {:?} vs {:?}", m.name(), a.translation, b.translation);
            prop_assert!(rot_gap(&a, &b) < 1e-12, "{}: rotation gap {}", m.name(), rot_gap(&a, &b));
        }
        let p1 = m.pose_error(&q, &e);
        let p2 = m.pose_error_poe(&q, &e);
        prop_assert!((p1.position - p2.position).norm() < 1e-9);
        prop_assert!((p1.orientation - p2.orientation).norm() < 1e-12);
    }
}

/// CROSSCHECKS.md (Lynch & Park `modern_robotics` FKinSpace, pytransform3d agrees):
/// exp([S_B]·30°)·exp([S_C]·45°)·M → p = (90.61862179, 35.35533906, −13.75462108) mm.
#[test]
fn crosscheck_poe_value() {
    use mte_linalg::{Vec6, se3};
    let p_ref = Vec3::new(90.61862179, 35.35533906, -13.75462108);
    // (1) directly with se3::exp
    let twist = |w: Vec3, q: Vec3| {
        let v = -w.cross(&q);
        Vec6::new(v.x, v.y, v.z, w.x, w.y, w.z)
    };
    let sb = twist(Vec3::y(), Vec3::new(0.0, 0.0, -100.0));
    let sc = twist(Vec3::z(), Vec3::zeros());
    let t = se3::exp(&(sb * 30f64.to_radians()))
        * se3::exp(&(sc * 45f64.to_radians()))
        * Iso3::translation(50.0, 0.0, 20.0);
    assert!((t.translation.vector - p_ref).norm() < 1e-6);
    // (2) the same chain as a machine file, through both evaluators
    let json = r#"{"format": "mte-machine/1", "name": "crosscheck", "tool": "tool", "workpiece": "bed",
      "bodies": [{"name": "bed"},
        {"name": "B", "parent": "bed", "offset_mm": [0, 0, -100],
         "joint": {"type": "rotary", "axis": "B", "direction": [0, 1, 0], "sign": 1, "stroke_deg": [-180, 180]}},
        {"name": "C", "parent": "B", "offset_mm": [0, 0, 100],
         "joint": {"type": "rotary", "axis": "C", "direction": [0, 0, 1], "sign": 1, "stroke_deg": [-180, 180]}},
        {"name": "tool", "parent": "C", "offset_mm": [50, 0, 20]}]}"#;
    let m = Machine::from_json_str(json).unwrap();
    let q = [30f64.to_radians(), 45f64.to_radians()];
    for g in [
        m.tool_in_workpiece_poe(&q, &[]),
        m.tool_in_workpiece(&q, &[]),
    ] {
        assert!(
            (g.translation.vector - p_ref).norm() < 1e-6,
            "{:?}",
            g.translation
        );
    }
}

/// Analytic Jacobian vs central finite differences of the exact pose error, every library
/// machine, every slot. Steps 1e-3 mm / 1e-4 rad (truncation O(h²) ≈ 1e-9 relative); tolerance
/// 1e-6 relative with an absolute floor of 1e-8 × the largest entry of the column: the
/// round-off of a central difference is ≈ 2e-16 · |p| / h ≈ 1e-8 for |p| ≈ 5 m.
#[test]
fn jacobian_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for m in library() {
        for _ in 0..3 {
            let q = random_q(&m, &mut rng);
            let j = m.jacobian(&q);
            assert_eq!(j.shape(), (6, m.n_slots()));
            let mut e = vec![0.0; m.n_slots()];
            for k in 0..m.n_slots() {
                let h = if m.error_slots()[k].component.is_translation() {
                    1e-3
                } else {
                    1e-4
                };
                e[k] = h;
                let plus = m.pose_error(&q, &e).to_vec6();
                e[k] = -h;
                let minus = m.pose_error(&q, &e).to_vec6();
                e[k] = 0.0;
                let fd = (plus - minus) / (2.0 * h);
                let col = j.column(k);
                let floor = 1e-8 * col.amax().max(fd.amax()).max(1.0);
                for r in 0..6 {
                    let err = (col[r] - fd[r]).abs();
                    assert!(
                        err <= 1e-6 * col[r].abs() + floor,
                        "{} slot {} row {r}: analytic {} vs fd {}",
                        m.name(),
                        m.slot_name(k),
                        col[r],
                        fd[r]
                    );
                }
            }
        }
    }
}

/// `Jacobian::apply` (unrolled, allocation-free) equals the dense product J·e.
#[test]
fn jacobian_apply_is_the_matrix_product() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for m in library() {
        let q = random_q(&m, &mut rng);
        let e = random_e(&m, &mut rng, 1.0);
        let j = m.jacobian(&q);
        let dense = &j.matrix * mte_linalg::nalgebra::DVector::from_column_slice(&e);
        let gap =
            (j.apply(&e).to_vec6() - mte_linalg::Vec6::from_column_slice(dense.as_slice())).norm();
        assert!(gap <= 1e-12 * dense.norm(), "{}: {gap}", m.name());
    }
}

/// The first-order model J·e differs from the exact pose error by a second-order term:
/// halving every error divides the gap by 4 (within 2 %).
#[test]
fn first_order_gap_is_second_order() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for m in library() {
        for _ in 0..3 {
            let q = random_q(&m, &mut rng);
            let e = random_e(&m, &mut rng, 1.0);
            let j = m.jacobian(&q);
            let gap = |s: f64| {
                let es: Vec<f64> = e.iter().map(|x| x * s).collect();
                (m.pose_error(&q, &es).to_vec6() - j.apply(&es).to_vec6()).norm()
            };
            let (g1, g2) = (gap(1.0), gap(0.5));
            assert!(g1 > 1e-9, "{}: gap {g1} too small to measure", m.name());
            let ratio = g1 / g2;
            assert!((ratio - 4.0).abs() < 0.08, "{}: ratio {ratio}", m.name());
        }
    }
}

/// IK∘FK = identity: random poses within strokes of every library machine; the original
/// axis values are among the solutions and every returned branch reproduces tip and axis.
#[test]
fn inverse_of_forward_is_identity() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for m in library() {
        let mut checked = 0;
        let mut branches = 0;
        while checked < 40 {
            let q = random_q(&m, &mut rng);
            let g = m.tool_in_workpiece(&q, &[]);
            let axis = g.rotation * Vec3::z();
            let sols = match m.inverse(&g.translation.vector, &axis) {
                Ok(s) => s,
                Err(KinError::Singular { .. }) => continue,
                Err(e) => panic!("{}: {e} at {q:?}", m.name()),
            };
            assert!(
                sols.iter()
                    .any(|s| s.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-7)),
                "{}: {q:?} not among {sols:?}",
                m.name()
            );
            for s in &sols {
                let h = m.tool_in_workpiece(s, &[]);
                assert!((h.translation.vector - g.translation.vector).norm() < 1e-8);
                assert!((h.rotation * Vec3::z() - axis).norm() < 1e-10);
                for (a, v) in m.axes().iter().zip(s) {
                    assert!(
                        *v >= a.stroke.0 && *v <= a.stroke.1,
                        "{} out of stroke",
                        a.name
                    );
                }
            }
            branches += sols.len();
            checked += 1;
        }
        let rotaries = m
            .axes()
            .iter()
            .filter(|a| a.kind == AxisKind::Rotary)
            .count();
        if rotaries == 2 {
            // two Paden–Kahan branches, often with ±2π copies: more than one per pose on average
            assert!(
                branches > 40,
                "{}: only {branches} solutions for 40 poses",
                m.name()
            );
        }
    }
}

/// The second Paden–Kahan branch: on the AC table, (A, C) and (−A, C ± π) give the same
/// tool axis; with linear axes in stroke both are returned.
#[test]
fn ac_table_returns_both_branches() {
    let m = Machine::library("seed003-ac-table").unwrap();
    let q = [10.0, 20.0, 30.0, 0.5, 1.0];
    let g = m.tool_in_workpiece(&q, &[]);
    let sols = m
        .inverse(&g.translation.vector, &(g.rotation * Vec3::z()))
        .unwrap();
    assert!(
        sols.iter()
            .any(|s| (s[3] - 0.5).abs() < 1e-9 && (s[4] - 1.0).abs() < 1e-9)
    );
    assert!(
        sols.iter()
            .any(|s| (s[3] + 0.5).abs() < 1e-9 && (s[4] - (1.0 + PI)).abs() < 1e-9)
    );
}

/// Head–table structure (B head on the tool side, C table) — not in the library, built here.
#[test]
fn head_table_inverse() {
    let json = r#"{"format": "mte-machine/1", "name": "head-table", "tool": "tool", "workpiece": "wp",
      "bodies": [{"name": "bed"},
        {"name": "X", "parent": "bed", "offset_mm": [0, 0, 0], "joint": {"type": "linear", "axis": "X", "direction": [1, 0, 0], "sign": 1, "stroke_mm": [-500, 500]}},
        {"name": "Y", "parent": "X", "offset_mm": [0, 0, 0], "joint": {"type": "linear", "axis": "Y", "direction": [0, 1, 0], "sign": 1, "stroke_mm": [-500, 500]}},
        {"name": "Z", "parent": "Y", "offset_mm": [0, 0, 400], "joint": {"type": "linear", "axis": "Z", "direction": [0, 0, 1], "sign": 1, "stroke_mm": [-500, 500]}},
        {"name": "B", "parent": "Z", "offset_mm": [0, 0, 0], "joint": {"type": "rotary", "axis": "B", "direction": [0, 1, 0], "sign": 1, "stroke_deg": [-100, 100]}},
        {"name": "tool", "parent": "B", "offset_mm": [0, 0, -250]},
        {"name": "C", "parent": "bed", "offset_mm": [20, 30, 0], "joint": {"type": "rotary", "axis": "C", "direction": [0, 0, 1], "sign": -1, "stroke_deg": [-360, 360]}},
        {"name": "wp", "parent": "C", "offset_mm": [0, 0, 50]}]}"#;
    let m = Machine::from_json_str(json).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..50 {
        let q = random_q(&m, &mut rng);
        let g = m.tool_in_workpiece(&q, &[]);
        let sols = m
            .inverse(&g.translation.vector, &(g.rotation * Vec3::z()))
            .unwrap();
        assert!(
            sols.iter()
                .any(|s| s.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-7))
        );
    }
}

/// Singular and unreachable requests are errors, not NaN.
#[test]
fn singular_and_unreachable_are_errors() {
    let m = Machine::library("seed000-ca-gantry").unwrap();
    // CA head with A = 0: tool axis parallel to C, C undetermined
    let r = m.inverse(&Vec3::new(0.0, 0.0, 0.0), &Vec3::z());
    assert!(
        matches!(r, Err(KinError::Singular { ref axis, .. }) if axis == "C"),
        "{r:?}"
    );
    let m3 = Machine::library("seed004-3axis").unwrap();
    assert!(matches!(
        m3.inverse(&Vec3::new(1.0, -1.0, -1.0), &Vec3::x()),
        Err(KinError::Unreachable { .. })
    ));
    assert!(matches!(
        m3.inverse(&Vec3::new(f64::NAN, 0.0, 0.0), &Vec3::z()),
        Err(KinError::Unreachable { .. })
    ));
    assert!(matches!(
        m3.inverse(&Vec3::new(5000.0, -1.0, -1.0), &Vec3::z()),
        Err(KinError::OutOfStroke { .. })
    ));
    // AC table: A is limited to ±130°, so a tool axis pointing down is beyond reach of A alone
    // only if it needs |A| > 130°: (0, 0, −1) needs A = ±180°.
    let mac = Machine::library("seed003-ac-table").unwrap();
    let r = mac.inverse(&Vec3::zeros(), &Vec3::new(0.0, 0.0, -1.0));
    assert!(
        matches!(
            r,
            Err(KinError::Singular { .. }) | Err(KinError::OutOfStroke { .. })
        ),
        "{r:?}"
    );
    let r = mac.inverse(&Vec3::zeros(), &Vec3::new(0.0, 0.5, -1.0));
    assert!(matches!(r, Err(KinError::OutOfStroke { .. })), "{r:?}");
}

fn slot(m: &Machine, body: &str, kind: SlotKind, c: Component) -> usize {
    m.slot_index(ErrorSlot {
        body: m.body_index(body).unwrap(),
        kind,
        component: c,
    })
    .unwrap()
}

/// docs/conventions.md §Signs, each pinned here.
mod signs {
    use super::*;

    /// +10 µm of the C axis' X location error (C.position.dx) moves the C pivot, and with it
    /// the table and workpiece, +10 µm in X of the bed frame; measured quantity: tool tip
    /// relative to the workpiece, so the pose error is −10 µm in X (at A = C = 0).
    #[test]
    fn c_location_error_moves_pivot_plus_x() {
        let m = Machine::library("seed003-ac-table").unwrap();
        let mut e = vec![0.0; m.n_slots()];
        e[slot(&m, "C", SlotKind::Position, Component::Dx)] = 0.010;
        let q = [50.0, 20.0, -30.0, 0.0, 0.0];
        let b = m.branch_poses(&q, &e);
        let b0 = m.branch_poses(&q, &[]);
        let pivot_shift =
            b.workpiece_in_base.translation.vector - b0.workpiece_in_base.translation.vector;
        assert!((pivot_shift - Vec3::new(0.010, 0.0, 0.0)).norm() < 1e-12);
        let pe = m.pose_error(&q, &e);
        assert!((pe.position - Vec3::new(-0.010, 0.0, 0.0)).norm() < 1e-12);
    }

    /// Tool-side positioning error: +10 µm of Z.motion.dz → tool tip +10 µm in Z.
    #[test]
    fn tool_side_error_enters_positive() {
        let m = Machine::library("seed004-3axis").unwrap();
        let mut e = vec![0.0; m.n_slots()];
        e[slot(&m, "Z", SlotKind::Motion, Component::Dz)] = 0.010;
        let pe = m.pose_error(&[300.0, -200.0, -400.0], &e);
        assert!((pe.position - Vec3::new(0.0, 0.0, 0.010)).norm() < 1e-12);
    }

    /// Workpiece-side angular error: +100 µrad yaw (X.motion.ez) of the X table turns the
    /// workpiece +100 µrad about z; the tool relative to the workpiece turns −100 µrad.
    #[test]
    fn table_yaw_enters_negative() {
        let m = Machine::library("seed004-3axis").unwrap();
        let mut e = vec![0.0; m.n_slots()];
        e[slot(&m, "X", SlotKind::Motion, Component::Ez)] = 100e-6;
        let pe = m.pose_error(&[300.0, -200.0, -400.0], &e);
        assert!((pe.orientation - Vec3::new(0.0, 0.0, -100e-6)).norm() < 1e-15);
    }

    /// ISO 841 linear table axes: +X (sign −1, the table moves −X) moves the tool +X
    /// relative to the workpiece: the ideal tool tip in the workpiece frame is (X, Y, Z).
    #[test]
    fn iso841_linear_table_axes() {
        let m = Machine::library("seed004-3axis").unwrap();
        let g = m.tool_in_workpiece(&[123.0, -45.0, -67.0], &[]);
        assert!((g.translation.vector - Vec3::new(123.0, -45.0, -67.0)).norm() < 1e-12);
    }

    /// ISO 841 rotary table: +C = +90° turns the tool +90° about Z relative to the workpiece:
    /// a tool at X = 100 sits at (0, 100, 0) in the workpiece frame.
    #[test]
    fn iso841_rotary_table_axes() {
        let m = Machine::library("seed003-ac-table").unwrap();
        let g = m.tool_in_workpiece(&[100.0, 0.0, 0.0, 0.0, PI / 2.0], &[]);
        assert!((g.translation.vector - Vec3::new(0.0, 100.0, 0.0)).norm() < 1e-12);
        // +A = +90°: the tool axis (0, 0, 1) turns about +X to (0, −1, 0) in the workpiece frame
        let g = m.tool_in_workpiece(&[0.0, 0.0, 0.0, PI / 2.0, 0.0], &[]);
        assert!((g.rotation * Vec3::z() - Vec3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
    }

    /// Head axes (sign +1): +A = +90° on the CA head turns the tool axis about +X to (0, −1, 0)
    /// in the bed (and workpiece) frame.
    #[test]
    fn head_rotary_axes() {
        let m = Machine::library("seed000-ca-gantry").unwrap();
        let g = m.tool_in_workpiece(&[1000.0, -1000.0, 1000.0, 0.0, PI / 2.0], &[]);
        assert!((g.rotation * Vec3::z() - Vec3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
    }

    /// A position error's rotation acts at the joint frame origin: εy = +100 µrad at the A
    /// pivot of the CA head moves the tool tip, 350 mm below it, by ε × r = (−0.035, 0, 0) mm
    /// to first order (the exact value adds +ε²·350/2 = 1.75e-6 mm in z).
    #[test]
    fn rotation_errors_act_at_the_body_origin() {
        let m = Machine::library("seed000-ca-gantry").unwrap();
        let mut e = vec![0.0; m.n_slots()];
        e[slot(&m, "A", SlotKind::Position, Component::Ey)] = 100e-6;
        let pe = m.pose_error(&[1000.0, -1000.0, 1000.0, 0.0, 0.0], &e);
        // tip is 200 + 150 = 350 mm below the A body origin: ε ŷ × (0, 0, −350) = (−0.035, 0, 0)
        assert!(
            (pe.position - Vec3::new(-0.035, 0.0, 1.75e-6)).norm() < 1e-9,
            "{:?}",
            pe.position
        );
        assert!((pe.orientation - Vec3::new(0.0, 100e-6, 0.0)).norm() < 1e-15);
    }
}

/// Seed 001: lower-order body array rows of the paper (1-based there, 0-based here).
#[test]
fn seed001_lower_order_array() {
    let m = Machine::library("seed001-4axis").unwrap();
    let l = m.lower_order_array();
    // paper: L(2)=1, L(3)=2, L(4)=3, L(5)=4, L(6)=5, L(7)=1, L(8)=7
    let paper = [(2, 1), (3, 2), (4, 3), (5, 4), (6, 5), (7, 1), (8, 7)];
    for (j, p) in paper {
        assert_eq!(l[1][j - 1] + 1, p, "L({j})");
    }
    assert_eq!(l[0], (0..8).collect::<Vec<_>>());
    assert!(l.last().unwrap().iter().all(|&j| j == 0));
}

/// Seed 000 Table 3: body home positions are the running sums of q1..q6, qw.
#[test]
fn seed000_table3_geometry() {
    let m = Machine::library("seed000-ca-gantry").unwrap();
    let home = |n: &str| m.body_home_mm(m.body_index(n).unwrap());
    assert_eq!(home("workpiece"), Vec3::new(3000.0, 1940.0, 250.0));
    assert_eq!(home("Z"), Vec3::new(200.0, 4440.0, 5950.0));
    assert_eq!(home("spindle"), Vec3::new(30.0, 4250.0, -1650.0));
    // 6 bodies × 6 position + 5 axes × 6 motion + spindle 6 motion + tool 6 position
    assert_eq!(m.n_slots(), 8 * 6 + 6 * 6);
    assert_eq!(
        m.slot_name(slot(&m, "X", SlotKind::Motion, Component::Dx)),
        "X.motion.dx"
    );
    let k = m.slot_index_by_name("C.position.ey").unwrap();
    assert_eq!(m.slot_axis(k).unwrap().name, "C");
}

/// Bad machine files: the error names the field; nothing panics.
mod bad_files {
    use super::*;

    fn base() -> serde_json::Value {
        serde_json::from_str(Machine::library_json("seed003-ac-table").unwrap()).unwrap()
    }

    fn field_of(v: &serde_json::Value) -> String {
        match Machine::from_json_str(&v.to_string()) {
            Err(KinError::Field { field, .. }) => field,
            other => panic!("expected a field error, got {other:?}"),
        }
    }

    #[test]
    fn unknown_axis() {
        let mut v = base();
        v["axis_order"][3] = "Q".into();
        assert_eq!(field_of(&v), "axis_order[3]");
        let msg = Machine::from_json_str(&v.to_string())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("unknown axis \"Q\""), "{msg}");
    }

    #[test]
    fn zero_length_direction() {
        let mut v = base();
        v["bodies"][5]["joint"]["direction"] = serde_json::json!([0, 0, 0]);
        assert_eq!(field_of(&v), "bodies[5].joint.direction");
    }

    #[test]
    fn cycle_in_topology() {
        let mut v = base();
        v["bodies"][5]["parent"] = "C".into(); // A ← C ← A
        let f = field_of(&v);
        assert!(f == "bodies[5].parent" || f == "bodies[6].parent", "{f}");
        let msg = Machine::from_json_str(&v.to_string())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("cycle"), "{msg}");
    }

    #[test]
    fn missing_field() {
        let mut v = base();
        v["bodies"][2].as_object_mut().unwrap().remove("offset_mm");
        assert_eq!(field_of(&v), "bodies[2].offset_mm");
        let mut v = base();
        v["bodies"][3]["joint"]
            .as_object_mut()
            .unwrap()
            .remove("sign");
        assert_eq!(field_of(&v), "bodies[3].joint.sign");
        let mut v = base();
        v.as_object_mut().unwrap().remove("tool");
        assert_eq!(field_of(&v), "tool");
    }

    #[test]
    fn nan_and_non_finite() {
        let mut v = base();
        v["bodies"][2]["offset_mm"][1] = "NaN".into();
        assert_eq!(field_of(&v), "bodies[2].offset_mm[1]");
        // a literal NaN is not JSON: reported with line and column
        let text = Machine::library_json("seed004-3axis").unwrap().replacen(
            "[0, 0, 150]",
            "[0, NaN, 150]",
            1,
        );
        match Machine::from_json_str(&text) {
            Err(KinError::Json { line, .. }) => assert!(line > 1),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn other_mistakes() {
        let mut v = base();
        v["format"] = "mte-machine/9".into();
        assert_eq!(field_of(&v), "format");
        let mut v = base();
        v["bodies"][1]["joint"]["dirction"] = serde_json::json!([1, 0, 0]);
        assert_eq!(field_of(&v), "bodies[1].joint.dirction");
        let mut v = base();
        v["bodies"][1]["parent"] = "nowhere".into();
        assert_eq!(field_of(&v), "bodies[1].parent");
        let mut v = base();
        v["bodies"][1]["joint"]["sign"] = 2.into();
        assert_eq!(field_of(&v), "bodies[1].joint.sign");
        let mut v = base();
        v["bodies"][2]["name"] = "X".into();
        assert_eq!(field_of(&v), "bodies[2].name");
        let err = Machine::from_file(std::path::Path::new("/nonexistent/m.json")).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/m.json"));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Deleting any span of a valid file never panics: it loads or returns an error.
        #[test]
        fn truncated_files_never_panic(a in 0usize..3000, len in 1usize..40) {
            let text = Machine::library_json("seed002-bc-trunnion").unwrap();
            let a = a.min(text.len());
            let b = (a + len).min(text.len());
            if text.is_char_boundary(a) && text.is_char_boundary(b) {
                let t = format!("{}{}", &text[..a], &text[b..]);
                let _ = Machine::from_json_str(&t);
            }
        }
    }
}

/// The input contract of machine files (issue #20): a BOM, unknown fields, magnitudes, duplicates.
mod input_contract {
    use super::*;

    fn base() -> serde_json::Value {
        serde_json::from_str(Machine::library_json("seed003-ac-table").unwrap()).unwrap()
    }

    fn msg(v: &serde_json::Value) -> String {
        Machine::from_json_str(&v.to_string())
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn bom_is_accepted_in_files_and_strings() {
        let text = Machine::library_json("seed004-3axis").unwrap();
        let dir = std::env::temp_dir().join(format!("mte-kin-bom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.json");
        std::fs::write(&path, format!("\u{feff}{text}")).unwrap();
        assert_eq!(Machine::from_file(&path).unwrap().name(), "seed004-3axis");
        assert!(Machine::from_json_str(&format!("\u{feff}{text}")).is_ok());
        // a directory is not a machine file
        let err = Machine::from_file(&dir).unwrap_err().to_string();
        assert!(err.contains("not a regular file"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn unknown_fields_are_rejected_with_the_closest_name() {
        let mut v = base();
        v["bodies"][2]["ofset_mm"] = serde_json::json!([0, 0, 0]);
        let m = msg(&v);
        assert!(
            m.contains("<string>: field `bodies[2].ofset_mm`")
                && m.contains("unknown field")
                && m.contains("did you mean `offset_mm`?"),
            "{m}"
        );
        let mut v = base();
        v["bodies"][1]["joint"]["type"] = "lineer".into();
        let m = msg(&v);
        assert!(
            m.contains("`bodies[1].joint.type`") && m.contains("did you mean `linear`?"),
            "{m}"
        );
        let mut v = base();
        v["bodies"][1]["parent"] = "bd".into();
        let m = msg(&v);
        assert!(m.contains("did you mean `bed`?"), "{m}");
        // a fixed joint has no other fields
        let mut v = base();
        v["bodies"][7]["joint"] = serde_json::json!({"type": "fixed", "axis": "Q"});
        let m = msg(&v);
        assert!(
            m.contains("`bodies[7].joint.axis`") && m.contains("unknown field"),
            "{m}"
        );
    }

    #[test]
    fn huge_direction_is_normalised_safely() {
        let mut v = base();
        v["bodies"][1]["joint"]["direction"] = serde_json::json!([1e300, 1e300, 0]);
        let m = Machine::from_json_str(&v.to_string()).unwrap();
        let d = m.axes()[m.axis_index("X").unwrap()].direction;
        approx::assert_relative_eq!(d, Vec3::new(1.0, 1.0, 0.0).normalize(), epsilon = 1e-15);
    }

    #[test]
    fn impossible_magnitudes_are_rejected() {
        let mut v = base();
        v["bodies"][2]["offset_mm"][0] = 2e7.into();
        let m = msg(&v);
        assert!(
            m.contains("`bodies[2].offset_mm[0]`") && m.contains("20000000 mm is beyond"),
            "{m}"
        );
        let mut v = base();
        v["bodies"][1]["joint"]["stroke_mm"] = serde_json::json!([-1e9, 100]);
        let m = msg(&v);
        assert!(
            m.contains("`bodies[1].joint.stroke_mm`") && m.contains("-1000000000"),
            "{m}"
        );
    }

    #[test]
    fn duplicates_name_both_occurrences() {
        let mut v = base();
        let axis = v["bodies"][1]["joint"]["axis"].clone();
        v["bodies"][2]["joint"]["axis"] = axis;
        let m = msg(&v);
        assert!(
            m.contains("`bodies[2].joint.axis`")
                && m.contains("duplicate axis name")
                && m.contains("also bodies[1].joint.axis"),
            "{m}"
        );
        let mut v = base();
        v["bodies"][3]["name"] = v["bodies"][1]["name"].clone();
        let m = msg(&v);
        assert!(
            m.contains("`bodies[3].name`") && m.contains("also bodies[1]"),
            "{m}"
        );
        let mut v = base();
        v["axis_order"][2] = v["axis_order"][0].clone();
        let m = msg(&v);
        assert!(
            m.contains("`axis_order[2]`") && m.contains("listed twice (also axis_order[0])"),
            "{m}"
        );
    }
}

/// A swivel head's line translation (`position_error_slots`: the head body's slot, the
/// carried spindle's at −1) is the pivot moved against the tool: the same tool pose as the
/// nominal geometry with the head body's offset moved by δ and the spindle's by −δ. The slot
/// alone moves the tool with the head. The outer head axis, which carries another axis, has
/// no carried body and keeps its own slot.
#[test]
fn a_head_line_translation_is_the_pivot_moved_against_the_tool() {
    let m = Machine::library("seed000-ca-gantry").unwrap();
    let body = |name: &str| m.body_index(name).unwrap();
    let (a, c, spindle) = (body("A"), body("C"), body("spindle"));
    assert_eq!(m.head_carries(a), Some(spindle));
    assert_eq!(m.head_carries(c), None);
    // A tilt of the line is its own slot.
    assert_eq!(m.position_error_slots(a, Component::Ex).unwrap().len(), 1);
    let delta = 0.02;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (component, direction) in [
        (Component::Dy, Vec3::new(0.0, 1.0, 0.0)),
        (Component::Dz, Vec3::new(0.0, 0.0, 1.0)),
    ] {
        let slots = m.position_error_slots(a, component).unwrap();
        assert_eq!(slots.len(), 2);
        let mut e = vec![0.0; m.n_slots()];
        for &(s, f) in &slots {
            e[s] += f * delta;
        }
        let moved = m
            .with_body_offset(a, m.bodies()[a].offset_mm + direction * delta)
            .with_body_offset(spindle, m.bodies()[spindle].offset_mm - direction * delta);
        let mut rigid = vec![0.0; m.n_slots()];
        rigid[slots[0].0] = delta;
        let mut rigid_differs = false;
        for _ in 0..20 {
            let q = random_q(&m, &mut rng);
            let by_slots = m.tool_in_workpiece(&q, &e);
            let by_geometry = moved.tool_in_workpiece(&q, &[]);
            let gap = (by_slots.translation.vector - by_geometry.translation.vector).norm();
            assert!(gap < 1e-9, "{component:?}: {gap} mm");
            assert!(rot_gap(&by_slots, &by_geometry) < 1e-12);
            let shifted = m.tool_in_workpiece(&q, &rigid).translation.vector;
            rigid_differs |= (shifted - by_slots.translation.vector).norm() > 1e-3 * delta;
        }
        assert!(
            rigid_differs,
            "{component:?}: the slot alone is the same motion"
        );
    }
    let outer = m.position_error_slots(c, Component::Dx).unwrap();
    assert_eq!(outer.len(), 1);
}
