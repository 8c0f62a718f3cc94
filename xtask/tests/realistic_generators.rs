//! The realistic generators checked against independent facts: a machine without errors gives
//! zero readings and tracker lengths equal to the station–target distances, a pure squareness
//! gives the analytic tip deviation, a B pivot offset gives the ISO 10791-6 BK1 pattern, a
//! reversal separates the two directions by its size, and nothing hidden reaches the files.

// (The diagnosis tests' scratch directories.)
#[path = "../../crates/mte-diagnose/tests/common/mod.rs"]
mod common;

use std::collections::BTreeMap;
use std::path::Path;

use approx::assert_abs_diff_eq;
use xtask::realistic::geom::V3;
use xtask::realistic::rtest::BcMachine;
use xtask::realistic::smooth::{Periodic, Smooth, Waviness};
use xtask::realistic::tracker::TrackerMachine;
use xtask::realistic::{BaseModel, Hidden, Kind, Spec, Truth, write, write_spec};

/// Rows of a CSV file as maps from header to field.
fn read_csv(path: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text
        .lines()
        .filter(|l| !l.is_empty() && !l.starts_with('#'));
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

fn num(row: &BTreeMap<String, String>, key: &str) -> f64 {
    row[key].parse().unwrap()
}

type Row = BTreeMap<String, String>;

/// Every row's `y` is on one sine of its phase `w`, of amplitude `amplitude`: least squares for
/// `y ≈ s·sin(w) + c·cos(w)`, then `s² + c² = amplitude²` and each reading on it.
fn assert_on_sine(rows: &[Row], w: impl Fn(&Row) -> f64, y: impl Fn(&Row) -> f64, amplitude: f64) {
    let (mut ss, mut sc, mut cc, mut sy, mut cy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for r in rows {
        let (w, y) = (w(r), y(r));
        ss += w.sin() * w.sin();
        sc += w.sin() * w.cos();
        cc += w.cos() * w.cos();
        sy += w.sin() * y;
        cy += w.cos() * y;
    }
    let det = ss * cc - sc * sc;
    let (s, c) = ((sy * cc - cy * sc) / det, (cy * ss - sy * sc) / det);
    assert_abs_diff_eq!((s * s + c * c).sqrt(), amplitude, epsilon = 1e-3);
    for r in rows {
        let w = w(r);
        assert_abs_diff_eq!(y(r), s * w.sin() + c * w.cos(), epsilon = 1e-3);
    }
}

fn perfect(kind: Kind, hidden: &[Hidden]) -> Spec {
    let mut s = Spec::new(kind, hidden);
    s.ordinary_scale = 0.0;
    s.noise_scale = 0.0;
    s
}

/// A scratch directory for one dataset, removed when the test is done with it.
fn tmp(name: &str) -> common::Scratch {
    common::scratch(&format!("realistic-{name}"))
}

/// Values are printed with 4 decimals of a µm (R-test, axis) or 7 decimals of a mm (tracker):
/// the tolerances are half a unit of the last printed digit.
const PRINT_UM: f64 = 5e-5;
const PRINT_MM: f64 = 5e-8;

#[test]
fn perfect_bc_trunnion_gives_zero_readings() {
    let dir = tmp("rtest-zero");
    let truth = write_spec(&perfect(Kind::Rtest, &[]), 3, &dir).unwrap();
    let rows = read_csv(&dir.join("rtest.csv"));
    assert_eq!(rows.len() * 3, truth.n_observations);
    for r in &rows {
        for k in ["dx_um", "dy_um", "dz_um"] {
            assert!(num(r, k).abs() <= 1e-9, "{r:?}");
        }
    }
    // And in memory, without printing: readings of a perfect machine vanish to 1e-9 µm.
    let m = BcMachine::perfect(100.0, 150.0);
    let ball = V3::new(120.0, -80.0, 60.0);
    let actual = m.centre_ball(ball, 0.5, 0.0);
    for b in [-1.5, -0.3, 0.0, 0.7, 1.9] {
        for c in [0.0, 1.0, 3.0, 6.0] {
            let r = m.reading(ball, actual, b, c, 10.0);
            assert!(r.norm() <= 1e-9, "{r}");
        }
    }
}

#[test]
fn perfect_head_table_machine_gives_zero_readings_and_a_pivot_offset_its_pattern() {
    let dir = tmp("rtest-head-zero");
    let truth = write_spec(&perfect(Kind::RtestHead, &[]), 3, &dir).unwrap();
    for r in &read_csv(&dir.join("rtest.csv")) {
        for k in ["dx_um", "dy_um", "dz_um"] {
            assert!(num(r, k).abs() <= 1e-9, "{r:?}");
        }
    }
    assert!(truth.n_observations > 0);
    // The B line δ off the tool along X: the tool point swings about (δ, 0, 0) from the pivot
    // instead of the pivot, so it is off by (I − Rot_y(b))·δx̂ = δ·(1 − cos b, 0, sin b) (zero at
    // the centring, B = 0), and the reading (ball − nest) is its negative, whatever C, the ball
    // and the pivot length.
    let mut m = BcMachine::perfect(200.0, 150.0);
    m.head_pivot_mm = Some(260.0);
    let delta = 0.02;
    m.location.ex0b = delta;
    let ball = V3::new(120.0, -80.0, 60.0);
    let actual = m.centre_ball(ball, 0.5, 0.0);
    for b in [-1.5_f64, -0.3, 0.0, 0.7, 1.9] {
        for c in [0.0, 1.0, 3.0] {
            let r = m.reading(ball, actual, b, c, 10.0);
            let want = -delta * 1e3 * V3::new(1.0 - b.cos(), 0.0, b.sin());
            assert!((r - want).norm() <= 1e-9, "b {b}: {r} vs {want}");
        }
    }
}

#[test]
fn b_pivot_offset_gives_the_bk1_pattern() {
    // B turns about a line through (δ, 0, 0) parallel to Y: the ball (centred at B = 0) moves
    // against the nest by (I − Rot_y(−b))·δx̂ = δ·(1 − cos b, 0, −sin b), whatever the ball
    // position (ISO 10791-6 BK1, the pattern of EX0B).
    let delta = 0.012;
    let mut m = BcMachine::perfect(100.0, 150.0);
    m.location.ex0b = delta;
    for ball in [V3::new(0.0, 177.0, 60.0), V3::new(-150.0, 40.0, 120.0)] {
        let actual = m.centre_ball(ball, 0.0, 0.0);
        for b_deg in [-90.0_f64, -45.0, 0.0, 30.0, 90.0] {
            let b = b_deg.to_radians();
            let r = m.reading(ball, actual, b, 0.0, 0.0);
            let expected = V3::new(1.0 - b.cos(), 0.0, -b.sin()) * delta * 1e3;
            assert_abs_diff_eq!(r, expected, epsilon = 1e-9);
        }
    }
}

#[test]
fn a_c_trunnion_s_a_line_offset_gives_its_bk1_pattern() {
    // A perfect A/C trunnion reads zero.
    let dir = tmp("rtest-ac-zero");
    let truth = write_spec(&perfect(Kind::RtestAc, &[]), 3, &dir).unwrap();
    let rows = read_csv(&dir.join("rtest.csv"));
    assert_eq!(rows.len() * 3, truth.n_observations);
    assert!(rows.iter().all(|r| r.contains_key("a_deg")));
    for r in &rows {
        for k in ["dx_um", "dy_um", "dz_um"] {
            assert!(num(r, k).abs() <= 1e-9, "{r:?}");
        }
    }
    assert!(truth.ordinary.iter().any(|e| e.iso_name_hint == "EY0A"));
    // A (sign −1) turns about a line through (0, δ, 0) parallel to X: the ball (centred at
    // A = 0) moves against the nest by (I − Rot_x(−a))·δŷ = δ·(0, 1 − cos a, sin a), whatever
    // the ball position and C (ISO 10791-6 BK1 about A, the pattern of EY0A). The generator
    // holds it as the B/C frame's EX0B = −δ (its module doc).
    let delta = 0.012;
    let mut m = BcMachine::perfect(100.0, 150.0);
    m.ac = true;
    m.location.ex0b = -delta;
    for (ball, c_ref) in [
        (V3::new(0.0, 177.0, 60.0), 0.0),
        (V3::new(-150.0, 40.0, 120.0), 1.2),
    ] {
        let actual = m.centre_ball(ball, c_ref, 0.0);
        for a_deg in [-90.0_f64, -45.0, 0.0, 30.0, 90.0] {
            let a = a_deg.to_radians();
            let r = m.reading(ball, actual, a, c_ref, 0.0);
            let expected = V3::new(0.0, 1.0 - a.cos(), a.sin()) * delta * 1e3;
            assert_abs_diff_eq!(r, expected, epsilon = 1e-9);
        }
    }
}

#[test]
fn perfect_tracker_lengths_are_station_target_distances() {
    let dir = tmp("tracker-zero");
    let truth = write_spec(&perfect(Kind::Tracker, &[]), 4, &dir).unwrap();
    let targets: BTreeMap<String, [f64; 3]> = read_csv(&dir.join("targets.csv"))
        .iter()
        .map(|r| {
            (
                r["id"].clone(),
                [num(r, "x_mm"), num(r, "y_mm"), num(r, "z_mm")],
            )
        })
        .collect();
    let lengths = read_csv(&dir.join("lengths.csv"));
    assert_eq!(lengths.len(), truth.n_observations);
    assert!((4..=6).contains(&truth.stations.len()));
    assert!((60..=150).contains(&targets.len()));
    assert_lengths_reach(&lengths, &truth, &targets, 1.0);
}

#[test]
fn perfect_tracker_tools_lengths_reach_the_reflector_at_its_offset() {
    let dir = tmp("tracker-tools-zero");
    let truth = write_spec(&perfect(Kind::TrackerTools, &[]), 4, &dir).unwrap();
    let rows = read_csv(&dir.join("targets.csv"));
    // Every pose with the reflector at the tool tip and at 2–3 offsets 80–200 mm from it.
    let poses: BTreeMap<String, usize> = rows.iter().fold(BTreeMap::new(), |mut m, r| {
        *m.entry(r["id"].split('T').next().unwrap().to_string())
            .or_default() += 1;
        m
    });
    let per_pose = *poses.values().next().unwrap();
    assert!((3..=4).contains(&per_pose) && poses.values().all(|&n| n == per_pose));
    let targets: BTreeMap<String, [f64; 3]> = rows
        .iter()
        .map(|r| {
            let o = [
                num(r, "tool_x_mm"),
                num(r, "tool_y_mm"),
                num(r, "tool_z_mm"),
            ];
            let reach = o.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!(
                r["id"].ends_with("T1") == (reach == 0.0) && (reach == 0.0 || reach > 80.0),
                "{r:?}"
            );
            (
                r["id"].clone(),
                [
                    num(r, "x_mm") + o[0],
                    num(r, "y_mm") + o[1],
                    num(r, "z_mm") + o[2],
                ],
            )
        })
        .collect();
    let lengths = read_csv(&dir.join("lengths.csv"));
    assert_eq!(lengths.len(), truth.n_observations);
    assert_lengths_reach(&lengths, &truth, &targets, 1.0);
}

#[test]
fn tracker_length_scale_multiplies_the_distances() {
    let dir = tmp("tracker-scale");
    let truth = write_spec(
        &perfect(Kind::Tracker, &[Hidden::TrackerScale { ppm: 7.0 }]),
        5,
        &dir,
    )
    .unwrap();
    let targets: BTreeMap<String, [f64; 3]> = read_csv(&dir.join("targets.csv"))
        .iter()
        .map(|r| {
            (
                r["id"].clone(),
                [num(r, "x_mm"), num(r, "y_mm"), num(r, "z_mm")],
            )
        })
        .collect();
    assert_lengths_reach(
        &read_csv(&dir.join("lengths.csv")),
        &truth,
        &targets,
        1.0 + 7e-6,
    );
}

/// Every tracker length is `scale` times the distance from its station to its target's
/// position less the station's dead path.
fn assert_lengths_reach(
    lengths: &[BTreeMap<String, String>],
    truth: &Truth,
    targets: &BTreeMap<String, [f64; 3]>,
    scale: f64,
) {
    for r in lengths {
        let j: usize = r["station"][1..].parse().unwrap();
        let (st, dead) = truth.stations[j - 1];
        let p = targets[&r["target"]];
        let d = ((st[0] - p[0]).powi(2) + (st[1] - p[1]).powi(2) + (st[2] - p[2]).powi(2)).sqrt();
        assert_abs_diff_eq!(num(r, "length_mm"), scale * d - dead, epsilon = PRINT_MM);
    }
}

#[test]
fn pure_squareness_gives_the_analytic_tip_deviation() {
    // The Y motion along Rot_z(γ)·ŷ = (−sin γ, cos γ, 0): tip deviation y·(−sin γ, cos γ − 1, 0).
    // The Z motion along Rot_x(α)·Rot_y(β)·ẑ: tip deviation z·(Rot_x(α)·Rot_y(β)·ẑ − ẑ).
    let (gamma, alpha, beta) = (40e-6, -25e-6, 15e-6);
    let strokes = [(0.0, 700.0), (-500.0, 0.0), (-600.0, 0.0)];
    let mut m = TrackerMachine::perfect(strokes, 100.0, 50.0, 150.0);
    m.squareness = [gamma, 0.0, 0.0];
    for q in [
        [0.0, -500.0, -300.0],
        [350.0, -120.0, 0.0],
        [700.0, -1.0, -600.0],
    ] {
        let e = m.tip_error(q);
        let y = q[1];
        assert_abs_diff_eq!(
            e,
            V3::new(-y * gamma.sin(), y * (gamma.cos() - 1.0), 0.0),
            epsilon = 1e-12
        );
    }
    m.squareness = [0.0, alpha, beta];
    for q in [[0.0, -500.0, -300.0], [700.0, 0.0, -600.0]] {
        let z = q[2];
        let u = V3::new(
            beta.sin(),
            -alpha.sin() * beta.cos(),
            alpha.cos() * beta.cos(),
        );
        assert_abs_diff_eq!(m.tip_error(q), z * (u - V3::z()), epsilon = 1e-12);
    }
    // A machine without errors puts the tip at (X, Y, Z).
    let m = TrackerMachine::perfect(strokes, 80.0, 30.0, 200.0);
    assert!(m.tip_error([123.0, -321.0, -456.0]).norm() < 1e-12);
}

#[test]
fn reversal_separates_the_directions_by_its_size() {
    let dir = tmp("axis-reversal");
    write_spec(
        &perfect(Kind::Axis, &[Hidden::Reversal { um: 2.5 }]),
        6,
        &dir,
    )
    .unwrap();
    let rows = read_csv(&dir.join("runs.csv"));
    assert!(!rows.is_empty());
    for r in &rows {
        let expected = if r["direction"] == "+" { 1.25 } else { -1.25 };
        assert_abs_diff_eq!(num(r, "deviation_um"), expected, epsilon = PRINT_UM);
    }
    // Perfect and noise-free without hidden effects: all zero.
    let dir = tmp("axis-zero");
    write_spec(&perfect(Kind::Axis, &[]), 6, &dir).unwrap();
    for r in read_csv(&dir.join("runs.csv")) {
        assert!(num(&r, "deviation_um").abs() <= 1e-9);
    }
}

#[test]
fn a_rotary_tables_reversal_separates_the_directions_in_arcsec() {
    // A perfect table with a 10 µrad backlash: the `+` readings 5 µrad (1.031″) above the
    // commanded angle, the `-` ones as far below.
    let dir = tmp("rotary-reversal");
    let truth = write_spec(
        &perfect(Kind::Rotary, &[Hidden::Reversal { um: 10.0 }]),
        8,
        &dir,
    )
    .unwrap();
    assert_abs_diff_eq!(truth.effects[0].value, 10e-6, epsilon = 1e-12);
    let half = 5e-6_f64.to_degrees() * 3600.0;
    let rows = read_csv(&dir.join("runs.csv"));
    assert!(!rows.is_empty());
    for r in &rows {
        let expected = if r["direction"] == "+" { half } else { -half };
        assert_abs_diff_eq!(num(r, "deviation_arcsec"), expected, epsilon = 1e-4);
    }
}

#[test]
fn a_rotary_tables_worm_gear_is_its_harmonic_in_arcsec() {
    // A perfect table with a 5 µrad error at 36 cycles per turn: every deviation (″) is on that
    // sine of the commanded angle, of amplitude 5 µrad = 1.031″.
    let dir = tmp("rotary-worm");
    let truth = write_spec(
        &perfect(
            Kind::Rotary,
            &[Hidden::AngularPositioning {
                rotary: 1,
                harmonic: 36,
                urad: 5.0,
            }],
        ),
        8,
        &dir,
    )
    .unwrap();
    assert_abs_diff_eq!(truth.effects[0].value, 5e-6, epsilon = 1e-12);
    let rows = read_csv(&dir.join("runs.csv"));
    assert_on_sine(
        &rows,
        |r| 36.0 * num(r, "c_deg").to_radians(),
        |r| num(r, "deviation_arcsec"),
        5e-6_f64.to_degrees() * 3600.0,
    );
}

#[test]
fn axis_pitch_is_a_sine_of_the_stated_amplitude_and_period() {
    let dir = tmp("axis-pitch");
    let (a, p) = (2.0, 17.0);
    write_spec(
        &perfect(
            Kind::Axis,
            &[Hidden::Pitch {
                axis: 0,
                amplitude_um: a,
                period_mm: p,
            }],
        ),
        8,
        &dir,
    )
    .unwrap();
    // dev = a·sin(2πx/p + φ): every reading on that sine of the position.
    let rows = read_csv(&dir.join("runs.csv"));
    assert_on_sine(
        &rows,
        |r| std::f64::consts::TAU * num(r, "x_mm") / p,
        |r| num(r, "deviation_um"),
        a,
    );
}

#[test]
fn generators_are_deterministic_and_hide_the_truth() {
    for kind in Kind::ALL {
        let hidden: Vec<Hidden> = match kind {
            Kind::Axis => vec![Hidden::RiseFall { um: 2.0, peak: 0.5 }],
            Kind::Tracker | Kind::TrackerTools => vec![Hidden::Pitch {
                axis: 0,
                amplitude_um: 2.0,
                period_mm: 20.0,
            }],
            Kind::Rotary => vec![Hidden::AngularPositioning {
                rotary: 1,
                harmonic: 36,
                urad: 5.0,
            }],
            Kind::Rtest | Kind::RtestHead | Kind::RtestAc => vec![Hidden::PivotDrift {
                rotary: 0,
                um: 10.0,
                tau_s: 900.0,
            }],
            // Clean datasets only: deterministic for a seed, and no hidden effect accepted.
            Kind::Points | Kind::PointsTargets => {
                let (a, b) = (
                    tmp(&format!("{}-a", kind.name())),
                    tmp(&format!("{}-b", kind.name())),
                );
                write(kind, &[], 11, &a).unwrap();
                write(kind, &[], 11, &b).unwrap();
                for f in ["manifest.json", "points.csv", "machine.json"] {
                    assert_eq!(
                        std::fs::read(a.join(f)).unwrap(),
                        std::fs::read(b.join(f)).unwrap(),
                        "{f}"
                    );
                }
                let pitch = Hidden::Pitch {
                    axis: 0,
                    amplitude_um: 1.0,
                    period_mm: 20.0,
                };
                assert!(write(kind, &[pitch], 11, &tmp(&format!("{}-c", kind.name()))).is_err());
                continue;
            }
        };
        let (a, b, c) = (
            tmp(&format!("{}-a", kind.name())),
            tmp(&format!("{}-b", kind.name())),
            tmp(&format!("{}-c", kind.name())),
        );
        let ta = write(kind, &hidden, 11, &a).unwrap();
        write(kind, &hidden, 11, &b).unwrap();
        write(kind, &[], 11, &c).unwrap();
        assert_eq!(ta.effects.len(), 1);
        let files = |d: &Path| {
            let mut v: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        assert_eq!(files(&a), files(&b));
        assert_eq!(
            files(&a),
            files(&c),
            "same files with and without hidden effects"
        );
        for f in files(&a) {
            assert_eq!(
                std::fs::read(a.join(&f)).unwrap(),
                std::fs::read(b.join(&f)).unwrap(),
                "{f} differs for one seed"
            );
        }
        let manifest: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&ta.manifest).unwrap()).unwrap();
        let clean: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(c.join("manifest.json")).unwrap())
                .unwrap();
        for field in [
            "description",
            "note",
            "instrument",
            "kind",
            "format",
            "base_model",
        ] {
            assert_eq!(manifest.get(field), clean.get(field), "{field}");
        }
        let text = std::fs::read_to_string(&ta.manifest)
            .unwrap()
            .to_lowercase();
        for word in [
            "pitch", "drift", "hidden", "sawtooth", "truth", "rise", "worm", "tooth",
        ] {
            assert!(!text.contains(word), "`{word}` in the manifest");
        }
    }
}

#[test]
fn base_model_default_is_the_standard_user_model() {
    let standard = BaseModel::standard();
    assert_eq!(BaseModel::Default.resolve(), Some(standard.clone()));
    assert_eq!(BaseModel::Omit.resolve(), None);
    assert_eq!(standard["components"]["degree"], 3);
}

#[test]
fn smooth_functions_have_their_size_and_rotary_ones_close_over_a_turn() {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    for k in 0..40 {
        let waviness = if k % 2 == 0 {
            Waviness::Gentle
        } else {
            Waviness::Wavy
        };
        let f = Smooth::draw(&mut rng, -300.0, 500.0, 0.007, waviness);
        let v: Vec<f64> = (0..=800).map(|i| f.at(-300.0 + i as f64)).collect();
        let pv =
            v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min);
        // Sampled every 1 mm here, every 4 mm when scaled: the peak-to-valley agrees to 1 %.
        assert_abs_diff_eq!(pv, 0.007, epsilon = 7e-5);
        assert_abs_diff_eq!(f.at(-300.0), 0.0, epsilon = 1e-15);
        let g = Periodic::draw(&mut rng, 5e-6, waviness);
        for t in [0.0, 1.0, 2.5, 4.0] {
            assert_abs_diff_eq!(g.at(t), g.at(t + std::f64::consts::TAU), epsilon = 1e-15);
        }
    }
}

#[test]
fn unsupported_effects_are_refused() {
    let err = write(
        Kind::Axis,
        &[Hidden::BTilt { urad: 10.0 }],
        1,
        &tmp("refuse"),
    )
    .unwrap_err();
    assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
}

#[test]
fn another_noise_seed_draws_the_same_machine_with_other_noise() {
    // An axis of 3–20 µm positioning error and a 2 µm reversal, read with σ of 0.1–0.6 µm:
    // the dataset's own draw and two of the noise's own stream. The same machine and
    // programme give the same positions, times and truth; the readings differ by two
    // independent draws of the noise alone, √2 σ rms (a machine drawn anew would differ by
    // micrometres).
    let hidden = [Hidden::Reversal { um: 2.0 }];
    let draws: Vec<(common::Scratch, Truth)> = [None, Some(1), Some(2)]
        .into_iter()
        .map(|noise_seed| {
            let dir = tmp(&format!("noise-seed-{noise_seed:?}"));
            let mut spec = Spec::new(Kind::Axis, &hidden);
            spec.noise_seed = noise_seed;
            let truth = write_spec(&spec, 3, &dir).unwrap();
            (dir, truth)
        })
        .collect();
    let rows: Vec<Vec<Row>> = draws
        .iter()
        .map(|(dir, _)| read_csv(&dir.join("runs.csv")))
        .collect();
    let sigma = draws[0].1.noise_um;
    for (k, (_, truth)) in draws.iter().enumerate().skip(1) {
        assert_eq!(truth.effects, draws[0].1.effects);
        assert_eq!(truth.noise_um, sigma);
        assert_eq!(rows[k].len(), rows[0].len());
        let mut sum_sq = 0.0;
        for (a, b) in rows[0].iter().zip(&rows[k]) {
            for key in ["run", "direction", "x_mm", "t_s"] {
                assert_eq!(a[key], b[key]);
            }
            sum_sq += (num(a, "deviation_um") - num(b, "deviation_um")).powi(2);
        }
        let rms = (sum_sq / rows[0].len() as f64).sqrt();
        // Over 100+ readings the rms of a difference of draws is within a fifth of √2 σ.
        assert!(
            (rms / (std::f64::consts::SQRT_2 * sigma) - 1.0).abs() < 0.2,
            "rms difference {rms} µm against σ {sigma} µm"
        );
    }
}
