//! Catalogue counts and names against the papers, squareness sign, redundancy claims.

use approx::assert_relative_eq;
use mte_errors::catalogue::{Catalogue, ParamKind};
use mte_errors::units::Kind;
use mte_errors::{AxisState, ErrorSet, Evaluator};
use mte_kinematics::Machine;

#[test]
fn seed003_has_its_41_errors_in_the_paper_order() {
    // Seed 003 (Zheng et al. 2024) Table 1.
    let m = Machine::library("seed003-ac-table").unwrap();
    let c = Catalogue::seed003(&m).unwrap();
    assert_eq!(c.len(), 41);
    let paper = [
        "δxx", "δyx", "δzx", "εxx", "εyx", "εzx", "δxy", "δyy", "δzy", "εxy", "εyy", "εzy", "δxz",
        "δyz", "δzz", "εxz", "εyz", "εzz", "δxa", "δya", "δza", "εxa", "εya", "εza", "δxc", "δyc",
        "δzc", "εxc", "εyc", "εzc", "Sxy", "Syz", "Sxz", "δxAM", "δyAM", "δzAM", "αAM", "βAM",
        "γAM", "δyCA", "βCA",
    ];
    let iso = [
        "EXX", "EYX", "EZX", "EAX", "EBX", "ECX", "EXY", "EYY", "EZY", "EAY", "EBY", "ECY", "EXZ",
        "EYZ", "EZZ", "EAZ", "EBZ", "ECZ", "EXA", "EYA", "EZA", "EAA", "EBA", "ECA", "EXC", "EYC",
        "EZC", "EAC", "EBC", "ECC", "EC0Y", "EA0Z", "EB0Z", "EX0A", "EY0A", "EZ0A", "EA0A", "EB0A",
        "EC0A", "EY0C", "EB0C",
    ];
    for (i, p) in c.parameters().iter().enumerate() {
        assert_eq!(p.number, Some(i as u32 + 1));
        assert_eq!(p.aliases[0], paper[i], "number {}", i + 1);
        assert_eq!(p.name, iso[i], "number {}", i + 1);
        assert_eq!(c.find(paper[i]).unwrap().number, Some(i as u32 + 1));
    }
    assert_eq!(c.by_kind(ParamKind::Component).len(), 30);
    assert_eq!(c.by_kind(ParamKind::Squareness).len(), 3);
    assert_eq!(c.by_kind(ParamKind::Location).len(), 8);
    assert_eq!(c.by_axis(&m, "C").len(), 8);
}

#[test]
fn seed000_has_its_53_errors() {
    // Seed 000 (Fan et al. 2019) Table 1: 36 motion errors, 9 perpendicularities, q1e…q6e, (θA)e, (θC)e.
    let m = Machine::library("seed000-ca-gantry").unwrap();
    let c = Catalogue::seed000(&m).unwrap();
    assert_eq!(c.len(), 53);
    let names: Vec<&str> = c
        .parameters()
        .iter()
        .map(|p| p.aliases[0].as_str())
        .collect();
    let want_start = [
        "εx(x)", "εy(x)", "εz(x)", "δx(x)", "δy(x)", "δz(x)", "εx(y)",
    ];
    assert_eq!(&names[..7], &want_start);
    assert_eq!(names[18], "εyz(θC)");
    assert_eq!(names[30], "εyz(φ)");
    let tail = [
        "εxy02", "εxz23", "εyz23", "εxz34", "εyz34", "εxy45", "εzx45", "εxz56", "εyz56", "q1e",
        "q2e", "q3e", "q4e", "q5e", "q6e", "(θA)e", "(θC)e",
    ];
    let got_tail: Vec<String> = c.parameters()[36..]
        .iter()
        .map(|p| {
            if p.name.starts_with('q') {
                p.name.clone()
            } else {
                p.aliases[0].clone()
            }
        })
        .collect();
    assert_eq!(got_tail, tail);
    for (i, p) in c.parameters().iter().enumerate() {
        assert_eq!(p.number, Some(i as u32 + 1));
    }
    // The six leading parameters of the paper are all present.
    for n in ["εy(x)", "q6e", "εx(x)", "q5e", "(θC)e", "εzx45"] {
        assert!(c.get(n).is_some(), "{n}");
    }
    // q6e lies along the spindle's position vector q6 = [0, 0, -200]: one slot, weight -1 on dz.
    let q6 = c.find("q6e").unwrap();
    assert_eq!(q6.contributions.len(), 1);
    assert_eq!(q6.contributions[0].weight, -1.0);
    assert_eq!(m.slot_name(q6.contributions[0].slot), "spindle.position.dz");
}

#[test]
fn search_by_name_alias_and_suggestions() {
    let m = Machine::library("seed003-ac-table").unwrap();
    let c = Catalogue::for_machine(&m);
    assert_eq!(c.find("exy").unwrap().name, "EXY");
    assert_eq!(c.find("δx(y)").unwrap().name, "EXY");
    assert_eq!(c.find("XOC").unwrap().name, "EX0C");
    assert_eq!(c.find("Z.motion.dz").unwrap().name, "EZZ");
    let e = c.find("EXQ").unwrap_err().to_string();
    assert!(
        e.contains("EXQ") && e.contains("did you mean") && e.contains("EX"),
        "{e}"
    );
    // Every slot is named exactly once among the slot-backed parameters.
    let slot_backed = c
        .parameters()
        .iter()
        .filter(|p| p.kind != ParamKind::Squareness)
        .count();
    assert_eq!(slot_backed, m.n_slots());
    for s in 0..m.n_slots() {
        assert!(!c.by_slot(s).is_empty());
    }
}

/// Squareness sign: EC0Y > 0 gives δx = −EC0Y·y of the tool relative to the workpiece, whether
/// Y moves the table (seed 004, sign −1) or the tool (seed 003, sign +1).
#[test]
fn squareness_sign_is_branch_independent() {
    let theta = 20e-6;
    for (name, q, y) in [
        ("seed004-3axis", vec![300.0, -400.0, -100.0], -400.0),
        ("seed003-ac-table", vec![0.0, 200.0, 0.0, 0.0, 0.0], 200.0),
    ] {
        let m = Machine::library(name).unwrap();
        let set = ErrorSet::new("sq").with_constant("EC0Y", theta, Kind::Angle);
        let ev = Evaluator::new(&m, &set).unwrap();
        let mut e = vec![0.0; ev.n_slots()];
        let pe = ev.pose_error(&AxisState::at(&q), &mut e).unwrap();
        // Exact: the Y path is turned, not rotated, so only δx appears: −θ·y.
        // 1e-12 mm: round-off of differences of ~400 mm coordinates (ε·400 ≈ 1e-13).
        assert_relative_eq!(pe.position.x, -theta * y, epsilon = 1e-12);
        assert_relative_eq!(pe.position.y, 0.0, epsilon = 1e-12);
        assert_relative_eq!(pe.orientation.norm(), 0.0, epsilon = 1e-18);
    }
    // EB0Z > 0 gives δx = +EB0Z·z; EA0Z > 0 gives δy = −EA0Z·z (n × ẑ with n = ŷ, x̂).
    let m = Machine::library("seed004-3axis").unwrap();
    let set = ErrorSet::new("sq")
        .with_constant("EB0Z", theta, Kind::Angle)
        .with_constant("EA0Z", 2.0 * theta, Kind::Angle);
    let ev = Evaluator::new(&m, &set).unwrap();
    let mut e = vec![0.0; ev.n_slots()];
    let pe = ev
        .pose_error(&AxisState::at(&[0.0, 0.0, -600.0]), &mut e)
        .unwrap();
    assert_relative_eq!(pe.position.x, theta * -600.0, epsilon = 1e-12);
    assert_relative_eq!(pe.position.y, -2.0 * theta * -600.0, epsilon = 1e-12);
}

/// The redundancy notes are true: the effect columns of EC0C and ECC (and EZ0C, EZC) are equal
/// at random poses of the AC table (independent check through the kinematic Jacobian).
#[test]
fn redundancy_claims_hold_numerically() {
    let m = Machine::library("seed003-ac-table").unwrap();
    let c = Catalogue::for_machine(&m);
    assert!(
        c.find("EC0C")
            .unwrap()
            .redundant_with
            .contains(&"ECC".to_string())
    );
    assert!(
        c.find("ECC")
            .unwrap()
            .redundant_with
            .contains(&"EC0C".to_string())
    );
    assert!(
        c.find("EZ0C")
            .unwrap()
            .redundant_with
            .contains(&"EZC".to_string())
    );
    let (i1, i2) = (c.index_of("EC0C").unwrap(), c.index_of("ECC").unwrap());
    let (i3, i4) = (c.index_of("EZ0C").unwrap(), c.index_of("EZC").unwrap());
    let (i5, i6) = (c.index_of("EX0C").unwrap(), c.index_of("EXC").unwrap());
    let mut differ = 0.0f64;
    for k in 0..7 {
        let t = k as f64;
        let q = [
            100.0 * t.sin(),
            -50.0 + 20.0 * t,
            30.0 * t.cos(),
            0.3 * t - 1.0,
            0.9 * t,
        ];
        let j = c.effect_matrix(&m, &q).unwrap();
        for r in 0..6 {
            assert_relative_eq!(j[(r, i1)], j[(r, i2)], epsilon = 1e-9);
            assert_relative_eq!(j[(r, i3)], j[(r, i4)], epsilon = 1e-9);
            differ = differ.max((j[(r, i5)] - j[(r, i6)]).abs());
        }
    }
    // EX0C (radial offset of the C line) is NOT the same as EXC (it turns with C).
    assert!(differ > 0.1, "{differ}");
}

#[test]
fn unknown_names_and_unit_mismatch_are_errors() {
    let m = Machine::library("seed004-3axis").unwrap();
    let json = r#"{"format": "mte-errors/1", "parameters": [{"name": "EXQ", "value_um": 1}]}"#;
    let set = ErrorSet::from_json_str(json, "s.json", None).unwrap();
    let e = Evaluator::new(&m, &set).unwrap_err().to_string();
    assert!(e.contains("EXQ") && e.contains("did you mean"), "{e}");
    let json = r#"{"format": "mte-errors/1", "parameters": [{"name": "EBX", "value_um": 1}]}"#;
    let set = ErrorSet::from_json_str(json, "s.json", None).unwrap();
    let e = Evaluator::new(&m, &set).unwrap_err().to_string();
    assert!(
        e.contains("EBX") && e.contains("value_um") && e.contains("angle"),
        "{e}"
    );
    let json = r#"{"format": "mte-errors/1", "parameters": [{"name": "EXY", "value_um": 1}, {"name": "δx(y)", "value_um": 1}]}"#;
    let set = ErrorSet::from_json_str(json, "s.json", None).unwrap();
    let e = Evaluator::new(&m, &set).unwrap_err().to_string();
    assert!(e.contains("same parameter"), "{e}");
}

/// Two entries of one slot (an ISO name and an alias) name both places.
#[test]
fn two_entries_of_one_parameter_name_both() {
    let m = Machine::library("seed004-3axis").unwrap();
    let json = r#"{"format": "mte-errors/1", "parameters": [{"name": "EXY", "value_um": 1}, {"name": "δx(y)", "value_um": 1}]}"#;
    let set = ErrorSet::from_json_str(json, "s.json", None).unwrap();
    let e = Evaluator::new(&m, &set).unwrap_err().to_string();
    assert!(
        e.contains("parameters[1] (δx(y))") && e.contains("also parameters[0] (EXY)"),
        "{e}"
    );
}
