//! Hidden effects in laser-tracker multilateration data on the seed 004 three-axis machine.
//!
//! The generator moves the machine with the exact kinematics and injected errors, measures
//! interferometric lengths from four stations (dead paths unknown to the diagnosis, Gaussian
//! length noise) and writes the files; the diagnosis adjusts the network and looks for causes.

mod common;

use mte_diagnose::{BaseModelSpec, DiagnoseParams, Diagnosis, Family, load};
use mte_errors::units::Kind;
use mte_errors::{AxisState, ErrorSet, Evaluator};
use mte_kinematics::Machine;
use mte_linalg::Vec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const NOISE_UM: f64 = 0.2;

struct Hidden {
    /// Periodic positioning error of X: amplitude (mm) and period (mm).
    x_pitch: Option<(f64, f64)>,
    /// A squareness by its ISO name and value (rad), applied as mte-errors' catalogue defines it
    /// (e.g. δx = −EC0Y·y at the tool relative to the workpiece, `docs/conventions.md`).
    squareness: (&'static str, f64),
    /// Relative scale error of every tracker length.
    length_scale: f64,
    /// Angular errors growing linearly through the middle of the travel (rad per mm): the yaw
    /// of X about Z (ECX) and the pitch of Z about X (EAZ).
    angular: (f64, f64),
    /// The reflector's offsets from the tool tip (tool frame, mm) each pose is measured with;
    /// empty: the tool tip only, no offset columns.
    tools: &'static [[f64; 3]],
    /// The manifest's `base_model` (JSON), if any.
    base_model: Option<&'static str>,
}

const NONE: Hidden = Hidden {
    x_pitch: None,
    squareness: ("EC0Y", 0.0),
    length_scale: 0.0,
    angular: (0.0, 0.0),
    tools: &[],
    base_model: None,
};

fn write_dataset(name: &str, hidden: &Hidden, seed: u64) -> common::Dataset {
    let machine = Machine::library("seed004-3axis").unwrap();
    let n_slots = machine.n_slots();
    let dir = common::scratch(&format!("tracker-{name}"));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, NOISE_UM * 1e-3).unwrap();
    let stations = [
        ("S1", Vec3::new(-350.0, 250.0, -800.0), 120.0),
        ("S2", Vec3::new(1050.0, 200.0, -750.0), 95.0),
        ("S3", Vec3::new(350.0, -850.0, -700.0), 140.0),
        ("S4", Vec3::new(300.0, 150.0, 150.0), 110.0),
    ];
    let x_slot = machine.slot_index_by_name("X.motion.dx").unwrap();
    let squareness = Evaluator::new(
        &machine,
        &ErrorSet::new("squareness").with_constant(
            hidden.squareness.0,
            hidden.squareness.1,
            Kind::Angle,
        ),
    )
    .unwrap();
    let ecx = machine.slot_index_by_name("X.motion.ez").unwrap();
    let eaz = machine.slot_index_by_name("Z.motion.ex").unwrap();
    let tools: Vec<[f64; 3]> = match hidden.tools {
        [] => vec![[0.0; 3]],
        t => t.to_vec(),
    };
    let mut targets = String::from(if hidden.tools.is_empty() {
        "id,x_mm,y_mm,z_mm\n"
    } else {
        "id,x_mm,y_mm,z_mm,tool_x_mm,tool_y_mm,tool_z_mm\n"
    });
    let mut lengths = String::from("station,target,length_mm\n");
    let mut k = 0;
    for z in [-600.0, -100.0] {
        for y in [-500.0, -250.0, 0.0] {
            for i in 0..=28 {
                let x = 25.0 * i as f64;
                let mut e = vec![0.0; n_slots];
                if let Some((amp, period)) = hidden.x_pitch {
                    e[x_slot] += amp * (std::f64::consts::TAU * x / period + 0.3).sin();
                }
                let mut square = vec![0.0; n_slots];
                squareness
                    .slot_errors(
                        &AxisState {
                            q: &[x, y, z],
                            time_s: 0.0,
                            directions: &[],
                        },
                        &mut square,
                    )
                    .unwrap();
                e.iter_mut().zip(&square).for_each(|(a, b)| *a += b);
                e[ecx] += hidden.angular.0 * (x - 350.0);
                e[eaz] += hidden.angular.1 * (z + 350.0);
                // The exact pose with these errors; a reflector at `o` in the tool frame.
                let pose = machine.tool_in_workpiece(&[x, y, z], &e);
                for o in &tools {
                    k += 1;
                    let id = format!("P{k}");
                    if hidden.tools.is_empty() {
                        targets.push_str(&format!("{id},{x},{y},{z}\n"));
                    } else {
                        let [ox, oy, oz] = o;
                        targets.push_str(&format!("{id},{x},{y},{z},{ox},{oy},{oz}\n"));
                    }
                    let p = pose.transform_point(&Vec3::from(*o).into()).coords;
                    for (sid, q, dead) in &stations {
                        let l = (1.0 + hidden.length_scale) * (q - p).norm() - dead
                            + noise.sample(&mut rng);
                        lengths.push_str(&format!("{sid},{id},{l:.7}\n"));
                    }
                }
            }
        }
    }
    std::fs::write(dir.join("targets.csv"), targets).unwrap();
    std::fs::write(dir.join("lengths.csv"), lengths).unwrap();
    // Approximate station positions, as a user would read them off a sketch (5 mm off).
    let setups: Vec<String> = stations
        .iter()
        .map(|(id, q, _)| {
            format!(
                r#"{{"id": "{id}", "station_mm": [{}, {}, {}]}}"#,
                q.x + 5.0,
                q.y - 5.0,
                q.z + 5.0
            )
        })
        .collect();
    let base = hidden
        .base_model
        .map_or(String::new(), |b| format!(r#", "base_model": {b}"#));
    let manifest = format!(
        r#"{{"format": "mte-dataset/1", "kind": "tracker", "machine": "seed004-3axis", "noise_um": {NOISE_UM}, "data": "lengths.csv", "targets": "targets.csv", "setups": [{}]{base}}}"#,
        setups.join(", ")
    );
    std::fs::write(dir.join("manifest.json"), manifest).unwrap();
    common::Dataset::new(dir)
}

fn run(path: &std::path::Path) -> Diagnosis {
    let prepared = load(path).expect("dataset loads");
    prepared
        .diagnose(&DiagnoseParams::default())
        .expect("diagnosis runs")
}

fn report(d: &Diagnosis) -> String {
    mte_diagnose::report::markdown(d, "tracker")
}

#[test]
fn clean_tracker_data_yields_no_discovery() {
    let d = run(&write_dataset("clean", &NONE, 31));
    assert!(d.no_discrepancy(), "{}", report(&d));
}

#[test]
fn periodic_pitch_error_of_x_is_found() {
    let d = run(&write_dataset(
        "pitch",
        &Hidden {
            x_pitch: Some((0.003, 160.0)),
            ..NONE
        },
        32,
    ));
    assert_eq!(d.findings.len(), 1, "{}", report(&d));
    let f = &d.findings[0];
    assert_eq!(f.name, "EXX periodic", "{}", report(&d));
    let Family::Periodic { period } = f.family else {
        panic!("{:?}", f.family)
    };
    assert!((period - 160.0).abs() < 2.0, "period {period}");
    let amp = &f.estimates[0];
    assert!(
        (amp.value - 0.003).abs() <= 2.0 * amp.uncertainty,
        "{}",
        amp.text
    );
}

#[test]
fn squareness_of_each_plane_is_found_with_the_catalogues_sign() {
    // Y is a table axis (ISO 841 sign −1), Z a tool-side one: the catalogue's signs hold for
    // either branch, and so must the diagnosis'.
    for (name, other, theta, seed) in [
        ("EC0Y", "EC0X", 40e-6, 33),
        ("EB0Z", "EB0X", -35e-6, 36),
        ("EA0Z", "EA0Y", 30e-6, 37),
    ] {
        let d = run(&write_dataset(
            &format!("square-{name}"),
            &Hidden {
                squareness: (name, theta),
                ..NONE
            },
            seed,
        ));
        assert_eq!(d.findings.len(), 1, "{}", report(&d));
        let f = &d.findings[0];
        assert_eq!(f.family, Family::Squareness, "{}", report(&d));
        // The data see only the angle between the two axes (carried by either): the report
        // names it as ISO 230-1 does, the later axis against the earlier, and lists the other
        // as not separable; its sign is the catalogue's, with which the data were made.
        assert_eq!(f.name, name, "{}", report(&d));
        assert!(f.alternatives.iter().any(|a| a == other), "{}", report(&d));
        // (Within 3 u: three datasets at 2 u would fail one time in seven for an honest u; a
        // wrong sign is off by hundreds of u.)
        let e = &f.estimates[0];
        assert!((e.value - theta).abs() <= 3.0 * e.uncertainty, "{}", e.text);
        // The dataset states no base: the report says so, and that a squareness is an
        // ordinary error the default (stations only) leaves out, with the base that holds it.
        let base = d.base_model.as_ref().expect("the base model is stated");
        assert!(!base.stated && base.spec == BaseModelSpec::default());
        assert!(
            report(&d)
                .contains("Base model (none stated, the instrument's default): no machine errors"),
            "{}",
            report(&d)
        );
        assert!(
            d.notes.iter().any(|n| n
                .contains(&format!("the cause found ({name}) is an ordinary error"))
                && n.contains(r#"`"base_model": {"squareness":true}`"#)),
            "{:?}",
            d.notes
        );
    }
}

#[test]
fn tracker_length_scale_is_found() {
    let scale = 5e-6;
    let d = run(&write_dataset(
        "scale",
        &Hidden {
            length_scale: scale,
            ..NONE
        },
        34,
    ));
    assert_eq!(d.findings.len(), 1, "{}", report(&d));
    let f = &d.findings[0];
    assert_eq!(f.name, "tracker scale", "{}", report(&d));
    let e = &f.estimates[0];
    assert!((e.value - scale).abs() <= 2.0 * e.uncertainty, "{}", e.text);
    // With the stations free, lengths too long in proportion are the machine scaled as a
    // whole: the report names the axes' common scale it cannot tell from it.
    assert_eq!(
        f.alternatives,
        ["EXX scale, EYY scale and EZZ scale together"],
        "{}",
        report(&d)
    );
}

/// A volumetric model (every component error as a cubic, no squareness) on a machine whose X
/// yaws and whose Z pitches along their travel, with an X–Y squareness: through the tool tip
/// alone the yaw of X times its lever arm, with the stations, holds the squareness (the report
/// says so); with the reflector at several offsets from the tool tip the tool's angular errors
/// show apart and the squareness is named and sized.
#[test]
fn tool_offsets_separate_a_squareness_from_the_axes_angular_errors() {
    const BASE: &str = r#"{"components": {"degree": 3}}"#;
    let theta = 30e-6;
    let hidden = Hidden {
        squareness: ("EC0Y", theta),
        angular: (40e-6 / 350.0, 25e-6 / 250.0),
        base_model: Some(BASE),
        ..NONE
    };
    let d = run(&write_dataset("tip-only", &hidden, 35));
    assert!(
        d.findings.iter().all(|f| f.family != Family::Squareness),
        "{}",
        report(&d)
    );
    assert!(
        d.not_separable.iter().any(|n| n.name == "EC0Y"),
        "{}",
        report(&d)
    );
    let d = run(&write_dataset(
        "tools",
        &Hidden {
            tools: &[
                [0.0, 0.0, 0.0],
                [150.0, 5.0, 0.0],
                [-3.0, -140.0, 2.0],
                [4.0, 2.0, -120.0],
            ],
            ..hidden
        },
        35,
    ));
    assert_eq!(d.findings.len(), 1, "{}", report(&d));
    let f = &d.findings[0];
    assert_eq!(f.name, "EC0Y", "{}", report(&d));
    let e = &f.estimates[0];
    assert!((e.value - theta).abs() <= 2.0 * e.uncertainty, "{}", e.text);
}

/// Readings taken with the reflector at several offsets, in a targets table that states the
/// offsets as zeros: the model cannot explain them, and the report points at the dataset (its
/// offsets among what to check) instead of naming a cause.
#[test]
fn offsets_left_out_of_the_table_are_pointed_at() {
    let path = write_dataset(
        "zero-offsets",
        &Hidden {
            tools: &[[0.0, 0.0, 0.0], [150.0, 5.0, 0.0], [-3.0, -140.0, 2.0]],
            ..NONE
        },
        38,
    );
    let targets = path.with_file_name("targets.csv");
    let text = std::fs::read_to_string(&targets).unwrap();
    let zeroed: String = text
        .lines()
        .enumerate()
        .map(|(i, line)| {
            if i == 0 {
                format!("{line}\n")
            } else {
                let fields: Vec<&str> = line.split(',').take(4).collect();
                format!("{},0,0,0\n", fields.join(","))
            }
        })
        .collect();
    std::fs::write(&targets, zeroed).unwrap();
    let d = run(&path);
    let text = report(&d);
    assert_eq!(d.verdict, mte_diagnose::Verdict::Unexplained, "{text}");
    assert!(d.extended.sigma0 > 100.0, "σ0 = {}", d.extended.sigma0);
    assert!(text.contains("check the dataset itself"), "{text}");
}
