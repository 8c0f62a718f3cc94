#![allow(dead_code, missing_docs)]
use mte_kinematics::Machine;
use mte_linalg::Vec3;
use mte_rtest::{PlanItem, Program, SetupSpec, slot_by_name};

pub fn machine() -> Machine {
    Machine::library("seed002-bc-trunnion").expect("library machine")
}

/// Slot vector with the given ISO-named values (mm, rad).
pub fn errors(m: &Machine, values: &[(&str, f64)]) -> Vec<f64> {
    let mut e = vec![0.0; m.n_slots()];
    for (n, v) in values {
        slot_by_name(m, n).unwrap().add_to(&mut e, *v);
    }
    e
}

/// BK1 + BK2 + BK4 in one setup, sampled every `step` degrees.
pub fn bk_all(m: &Machine, id: &str, ball: Vec3, step: f64) -> PlanItem {
    PlanItem {
        setup: SetupSpec::new(id, ball),
        programs: vec![
            Program::bk1(m, None).unwrap().with_step(step),
            Program::bk2(m).unwrap().with_step(step),
            Program::bk4(m, None).unwrap().with_step(step),
        ],
    }
}
