//! Committed artefacts are regenerated in memory and compared byte for byte: the bundled R-test
//! dataset (the seed-002 reproduction page is checked in xtask, with its generator). Run with
//! `MTE_REGENERATE=1` to rewrite.
mod common;
use common::*;
use mte_linalg::Vec3;
use mte_rtest::io::{dataset_to_strings, read_dataset};
use mte_rtest::{
    FitSpec, PlanItem, Program, SetupSpec, SimOptions, identify, setup_consistency, simulate,
};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn check_or_write(path: &PathBuf, text: &str) {
    if std::env::var("MTE_REGENERATE").is_ok() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    let on_disk = std::fs::read_to_string(path).unwrap_or_default();
    assert!(
        on_disk == text,
        "{} is stale: run `MTE_REGENERATE=1 cargo test -p mte-rtest --test artefacts`",
        path.display()
    );
}

const ALPHA: f64 = 5.25e-5;

/// The bundled dataset: one ball at table (0, 177, 60) mm measured at C = 0 (BK1, BK2, BK4) and
/// at C = 180° (BK1); the machine has B/C pivot errors and a Y straightness δz(y) = −α·y.
fn bundled() -> (String, String) {
    let m = machine();
    let base = errors(
        &m,
        &[
            ("EX0B", 0.0041),
            ("EZ0B", -0.0096),
            ("EA0B", 0.0004f64.to_radians()),
            ("EX0C", 0.0152),
            ("EY0C", -0.0118),
            ("EA0C", 0.0003f64.to_radians()),
            ("EB0C", -0.0002f64.to_radians()),
        ],
    );
    let yi = m.axis_index("Y").unwrap();
    let sz = m.slot_index_by_name("Y.motion.dz").unwrap();
    let field = move |q: &[f64], _t: f64| {
        let mut e = base.clone();
        e[sz] -= ALPHA * q[yi];
        e
    };
    let ball = Vec3::new(0.0, 177.0, 60.0);
    let plan = [
        PlanItem {
            setup: SetupSpec::new("Y+177", ball),
            programs: vec![
                Program::bk1(&m, None).unwrap(),
                Program::bk2(&m).unwrap(),
                Program::bk4(&m, None).unwrap(),
            ],
        },
        PlanItem {
            setup: SetupSpec::new("Y-177", ball).centred_at("C", 180.0),
            programs: vec![Program::bk1(&m, None).unwrap().with_hold("C", 180.0)],
        },
    ];
    let mut sim = simulate(
        &m,
        &plan,
        &field,
        &SimOptions {
            noise_sd_mm: 0.0005,
            sensor_zero_sd_mm: 0.003,
            seed: 20021,
            ..Default::default()
        },
    )
    .unwrap();
    sim.dataset.note = "SIMULATED, not measured: exact kinematics of seed002-bc-trunnion with EX0B 4.1 µm, EZ0B -9.6 µm, EA0B 0.0004°, EX0C 15.2 µm, EY0C -11.8 µm, EA0C 0.0003°, EB0C -0.0002°, a Y straightness dz(y) = -52.5 µrad·y, sensor noise 0.5 µm per component, sensor zero offsets 3 µm, seed 20021".into();
    let rot = |a: &str| a == "B" || a == "C";
    dataset_to_strings(
        &sim.dataset,
        "seed002-two-positions.csv",
        "R-test, 3-D sensor nest + precision ball",
        &rot,
    )
}

#[test]
fn bundled_dataset_is_fresh_and_shows_the_two_position_effect() {
    let (man, csv) = bundled();
    let dir = root().join("fixtures/rtest");
    check_or_write(&dir.join("seed002-two-positions.json"), &man);
    check_or_write(&dir.join("seed002-two-positions.csv"), &csv);
    let m = machine();
    let ds = read_dataset(&dir.join("seed002-two-positions.json"), &|a: &str| {
        a == "B" || a == "C"
    })
    .unwrap();
    assert!(ds.note.starts_with("SIMULATED"));
    let spec = FitSpec::pivots(&m)
        .unwrap()
        .only(&m, &["EX0B", "EZ0B", "EA0B", "EC0B"])
        .unwrap();
    let bk1: Vec<usize> = ds.select(Some("BK1"), None);
    let sub = ds.subset(&bk1);
    assert!(
        setup_consistency(&m, &sub, &spec)
            .unwrap()
            .inconsistent(5.0)
            .contains(&"EZ0B")
    );
    let joint = identify(&m, &sub, &spec).unwrap();
    let ea = joint.get("EA0B").unwrap().value;
    // the generator's EA0B (0.0004° = 7 µrad) plus the relative B/Y squareness +α
    assert!(
        (ea - (0.0004f64.to_radians() + ALPHA)).abs() < 3e-6,
        "EA0B {ea}"
    );
}

#[test]
fn csv_errors_name_line_and_column() {
    let man = r#"{"format":"mte-rtest/1","machine":"seed002-bc-trunnion","csv":"r.csv","axes":["X","Y","Z","B","C"],
      "setups":[{"id":"s","ball_mm":[0,0,0],"centring":{"X":0,"Y":0,"Z":0,"B":0,"C":0}}]}"#;
    let rot = |a: &str| a == "B" || a == "C";
    let csv = "setup,test,t_s,x_mm,y_mm,z_mm,b_deg,c_deg,dx_um,dy_um,dz_um\ns,BK1,0,0,0,0,0,0,1,2,3\ns,BK1,1,0,0,0,zz,0,1,2,3\n";
    let e = mte_rtest::io::dataset_from_str("m.json", man, "r.csv", csv, &rot)
        .unwrap_err()
        .to_string();
    assert!(e.contains("r.csv line 3") && e.contains("b_deg"), "{e}");
    let csv = "setup,test,t_s,x_mm,y_mm,z_mm,b_deg,dx_um,dy_um,dz_um\n";
    let e = mte_rtest::io::dataset_from_str("m.json", man, "r.csv", csv, &rot)
        .unwrap_err()
        .to_string();
    assert!(e.contains("c_deg"), "{e}");
    let csv =
        "setup,test,t_s,x_mm,y_mm,z_mm,b_deg,c_deg,dx_um,dy_um,dz_um\nq,BK1,0,0,0,0,0,0,1,2,3\n";
    let e = mte_rtest::io::dataset_from_str("m.json", man, "r.csv", csv, &rot)
        .unwrap_err()
        .to_string();
    assert!(e.contains("setup `q`"), "{e}");
    let e = mte_rtest::io::dataset_from_str(
        "m.json",
        &man.replace("mte-rtest/1", "v0"),
        "r.csv",
        csv,
        &rot,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("format"), "{e}");
}
