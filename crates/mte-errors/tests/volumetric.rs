//! Volumetric map of the seed 004 three-axis machine checked by hand, and bad-input handling.

use approx::assert_relative_eq;
use mte_errors::volumetric::{Grid, Method, Point, poses_from_csv, program_from_csv, simulate};
use mte_errors::{Direction, ErrorSet, Evaluator};
use mte_kinematics::Machine;

/// The stated error set: EXX = Legendre P1 of 10 µm over the X stroke [0, 700] mm
/// (δ(x) = 0.010·(2x − 700)/700 mm), EBX = 30 µrad (X pitch), EC0Y = 20 µrad (Y to X
/// squareness), EZZ = 5 µm (Z positioning).
const SET: &str = r#"{
  "format": "mte-errors/1",
  "name": "seed004-hand",
  "parameters": [
    {"name": "EXX", "model": {"type": "legendre", "coefficients_um": [0, 10]}},
    {"name": "EBX", "value_urad": 30},
    {"name": "EC0Y", "value_urad": 20},
    {"name": "EZZ", "value_um": 5}
  ]
}"#;

/// Hand calculation (seed 004 machine: workpiece on Y on X on the bed, table axes with sign −1,
/// the tool on Z; ideal tool tip in the workpiece = (x, y, z)).
/// Workpiece frame W = Trans((δ − x)·x̂) · Rot_y(β) · Trans(−y·ŷ) · Trans(θ·y·x̂)  (X motion error
/// δ, β; Y joint −y·ŷ; squareness slot δx_Y = θ·y), tool tip t = (0, 0, z + ζ). Then
/// p = W⁻¹·t = R_y(−β)·(x − δ, 0, z + ζ) + (−θ·y, y, 0), so the position error is
///   ex = (x − δ)·cos β − (z + ζ)·sin β − θ·y − x
///   ey = 0
///   ez = (x − δ)·sin β + (z + ζ)·cos β − z
/// and the orientation error is (0, −β, 0).
/// Worked with β = 30e-6, θ = 20e-6, ζ = 0.005 mm:
///   (700, −500, −700): δ = 0.010 → ex = 699.99·cosβ + 699.995·sinβ + 0.010 − 700 = 0.020999535 mm,
///                                   ez = 699.99·sinβ − 699.995·cosβ + 700 = 0.026000015 mm
///   (0, 0, 0):         δ = −0.010 → ex = 0.010·cosβ − 0.005·sinβ = 0.0099998500 mm,
///                                   ez = 0.010·sinβ + 0.005·cosβ = 0.0050003000 mm
///   (350, −250, −350): δ = 0     → ex = 350cosβ + 349.995 sinβ + 0.005 − 350 = 0.0154996925 mm,
///                                   ez = 350 sinβ − 349.995 cosβ + 350 = 0.0155001575 mm
///   (0, −500, −700):   δ = −0.010 → ex = 0.040999850 mm, ez = 0.005000615 mm
#[test]
fn seed004_map_matches_hand_calculation() {
    let m = Machine::library("seed004-3axis").unwrap();
    let set = ErrorSet::from_json_str(SET, "seed004-hand.json", None).unwrap();
    let ev = Evaluator::new(&m, &set).unwrap();
    let hand = [
        (
            [700.0, -500.0, -700.0],
            [2.099953500135e-02, 2.600001499468e-02],
        ),
        ([0.0, 0.0, 0.0], [9.999849995500e-03, 5.000299997750e-03]),
        (
            [350.0, -250.0, -350.0],
            [1.549969249839e-02, 1.550015749621e-02],
        ),
        (
            [0.0, -500.0, -700.0],
            [4.099984999235e-02, 5.000614997812e-03],
        ),
    ];
    let pts: Vec<Point> = hand
        .iter()
        .map(|(q, _)| Point {
            q: q.to_vec(),
            time_s: 0.0,
            directions: vec![],
        })
        .collect();
    let r = simulate(&ev, &pts, Method::Exact).unwrap();
    for (k, (_, want)) in hand.iter().enumerate() {
        // 1e-12 mm: the hand values carry 13 significant digits; round-off on 700 mm is ~1e-13.
        assert_relative_eq!(r.position_mm[k][0], want[0], epsilon = 1e-12);
        assert_relative_eq!(r.position_mm[k][1], 0.0, epsilon = 1e-12);
        assert_relative_eq!(r.position_mm[k][2], want[1], epsilon = 1e-12);
        assert_relative_eq!(r.orientation_rad[k][1], -30e-6, epsilon = 1e-15);
    }
    // The first-order model differs by second-order terms only: β²·700/2 ≈ 3e-7 mm here.
    let lin = simulate(&ev, &pts, Method::FirstOrder).unwrap();
    for k in 0..pts.len() {
        for c in 0..3 {
            assert!((lin.position_mm[k][c] - r.position_mm[k][c]).abs() < 1e-6);
        }
    }
    // Summary over a full grid: the worst point is the corner (0, −500, −700) by the formula.
    let grid = Grid::over_strokes(&m, 8).points(&m).unwrap();
    assert_eq!(grid.len(), 512);
    let g = simulate(&ev, &grid, Method::Exact).unwrap();
    let worst = &grid[g.summary.worst_point].q;
    assert_eq!(worst, &vec![0.0, -500.0, -700.0]);
    assert_relative_eq!(
        g.summary.max_position_mm,
        (4.099984999235e-02f64.powi(2) + 5.000614997812e-03f64.powi(2)).sqrt(),
        epsilon = 1e-12
    );
    assert_relative_eq!(g.summary.range_mm[1], 0.0, epsilon = 1e-12);
    // Thread-count independence of the parallel map.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| simulate(&ev, &grid, Method::Exact).unwrap());
    assert_eq!(one, g);
}

#[test]
fn program_csv_directions_time_and_errors() {
    let m = Machine::library("seed004-3axis").unwrap();
    let prog = "# program\nx_mm,y_mm,z_mm,t_s\n0,0,0,0\n100,0,0,1\n100,-10,0,2\n50,-10,0,3\n";
    let pts = program_from_csv(prog, "p.csv", &m).unwrap();
    assert_eq!(pts[0].directions, vec![Direction::Unknown; 3]);
    assert_eq!(pts[1].directions[0], Direction::Positive);
    assert_eq!(pts[2].directions[0], Direction::Positive); // X did not move: direction kept
    assert_eq!(pts[2].directions[1], Direction::Negative);
    assert_eq!(pts[3].directions[0], Direction::Negative);
    assert_eq!(pts[3].time_s, 3.0);
    // Reversal of X (span 4 µm) shows up with the direction: ±2 µm.
    let set = ErrorSet::from_json_str(
        r#"{"format": "mte-errors/1", "parameters": [{"name": "EXX", "model": {"type": "reversal", "span_um": 4}}]}"#,
        "r.json",
        None,
    )
    .unwrap();
    let ev = Evaluator::new(&m, &set).unwrap();
    let r = simulate(&ev, &pts, Method::Exact).unwrap();
    // X is a table axis (sign −1): +2 µm of the X body shows as −2 µm at the tool.
    assert_relative_eq!(r.position_mm[1][0], -0.002, epsilon = 1e-12);
    assert_relative_eq!(r.position_mm[3][0], 0.002, epsilon = 1e-12);
    assert_relative_eq!(r.position_mm[0][0], 0.0, epsilon = 1e-12);

    for (bad, line, what) in [
        ("x_mm,y_mm\n0,0\n", 1, "z_<unit>"),
        ("x_mm,y_mm,z_mm\n0,0,0\n1,NaN,0\n", 3, "y_mm"),
        ("x_mm,y_mm,z_deg\n0,0,0\n", 1, "z_deg"),
        ("x_mm,y_mm,z_mm,t_s\n0,0,0,5\n0,0,0,4\n", 3, "backwards"),
        ("x_mm,y_mm,z_mm,dir_x\n0,0,0,2\n", 2, "dir_x"),
        ("x_mm,y_mm,z_mm\n0,0\n", 2, "fields"),
    ] {
        let e = program_from_csv(bad, "bad.csv", &m)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.csv") && e.contains(&format!("line {line}")) && e.contains(what),
            "{e}"
        );
    }
    let e = poses_from_csv("x_mm,y_mm\n1,2\n", "poses.csv", &m)
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 1") && e.contains("z_<unit>"), "{e}");
}

#[test]
fn tabulated_model_outside_range_is_an_error_naming_the_point() {
    let m = Machine::library("seed004-3axis").unwrap();
    let set = ErrorSet::from_json_str(
        r#"{"format": "mte-errors/1", "parameters": [{"name": "EXX", "model": {"type": "table", "positions_mm": [0, 300], "values_um": [0, 3]}}]}"#,
        "t.json",
        None,
    )
    .unwrap();
    let ev = Evaluator::new(&m, &set).unwrap();
    let pts = vec![
        Point {
            q: vec![100.0, 0.0, 0.0],
            time_s: 0.0,
            directions: vec![],
        },
        Point {
            q: vec![400.0, 0.0, 0.0],
            time_s: 0.0,
            directions: vec![],
        },
    ];
    let e = simulate(&ev, &pts, Method::Exact).unwrap_err().to_string();
    assert!(
        e.contains("EXX") && e.contains("point 1") && e.contains("400"),
        "{e}"
    );
}

/// The bundled error sets load, bind to their library machines and simulate.
#[test]
fn bundled_fixtures_bind_and_simulate() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/errors");
    for (file, machine) in [
        ("seed004-demo.json", "seed004-3axis"),
        ("seed003-demo.json", "seed003-ac-table"),
    ] {
        let m = Machine::library(machine).unwrap();
        let set = ErrorSet::from_file(&dir.join(file)).unwrap();
        assert_eq!(set.machine.as_deref(), Some(machine));
        let ev = Evaluator::new(&m, &set).unwrap();
        let pts = Grid::over_strokes(&m, 4).points(&m).unwrap();
        let r = simulate(&ev, &pts, Method::Exact).unwrap();
        // Demonstration magnitudes: tens of µm, as an uncompensated machine (seed 004: 20–50 µm).
        assert!(
            r.summary.max_position_mm > 0.005 && r.summary.max_position_mm < 0.2,
            "{file}: {}",
            r.summary.max_position_mm
        );
    }
    let prog = std::fs::read_to_string(dir.join("seed004-program.csv")).unwrap();
    let m = Machine::library("seed004-3axis").unwrap();
    let pts = program_from_csv(&prog, "seed004-program.csv", &m).unwrap();
    assert_eq!(pts.len(), 7);
    // The seed 003 set names its errors with the paper's aliases; four carry distributions.
    let set = ErrorSet::from_file(&dir.join("seed003-demo.json")).unwrap();
    assert_eq!(set.random_entries().len(), 4);
}
