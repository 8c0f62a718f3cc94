//! 3-D points of a rotary stage with linear stages (circle-point analysis): a C rotary table on
//! the bed carries the instrument (a tracker or camera bar set on the table, in an unknown
//! pose); X, Y, Z carry a target on the spindle side. The C axis line is off its nominal place
//! and tilted (its four location errors EX0C, EY0C, EA0C, EB0C), X has a scale error (its
//! positioning error growing linearly with X), and every coordinate carries white noise.
//! Transforms are written out here ([`super::geom`]), sharing no code with `mte-kinematics`.

use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::geom::{Iso, V3, rot, rot_z, trans};
use super::smooth::signed;

/// What the points generator put in (kept in memory, never written).
#[derive(Debug, Clone)]
pub struct PointsTruth {
    /// The manifest to load.
    pub manifest: PathBuf,
    /// EX0C, EY0C (mm), EA0C, EB0C (rad): the C axis line's place and direction.
    pub location: [(String, f64); 4],
    /// The scale error of X (ratio).
    pub x_scale: f64,
    /// The target's offset from the tool tip, mm.
    pub target_mm: V3,
    /// Noise, µm.
    pub noise_um: f64,
    /// Rows written.
    pub rows: usize,
}

/// Tool length (tool tip below the Z carriage's reference), mm.
const TOOL_MM: f64 = 120.0;

/// Writes `machine.json`, `points.csv` and `manifest.json` into `dir`. With `state_offset`,
/// the manifest states the target's offset (a calibrated holder); otherwise it is left to the
/// fit. `base_model` goes into the manifest as it is.
///
/// # Errors
/// Writing the files.
pub fn write_points(
    seed: u64,
    dir: &Path,
    state_offset: bool,
    base_model: Option<serde_json::Value>,
) -> std::io::Result<PointsTruth> {
    std::fs::create_dir_all(dir)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let location = [
        ("EX0C".to_string(), signed(&mut rng, 10.0, 40.0) * 1e-3),
        ("EY0C".to_string(), signed(&mut rng, 10.0, 40.0) * 1e-3),
        ("EA0C".to_string(), signed(&mut rng, 20.0, 80.0) * 1e-6),
        ("EB0C".to_string(), signed(&mut rng, 20.0, 80.0) * 1e-6),
    ];
    let x_scale = signed(&mut rng, 10.0, 40.0) * 1e-6;
    let noise_um = rng.random_range(0.5..2.0);
    let target_mm = V3::new(
        rng.random_range(-30.0..30.0),
        rng.random_range(-30.0..30.0),
        rng.random_range(-60.0..-20.0),
    );
    // The C table: its line displaced by (dx, dy) and tilted by (a, b) about X and Y of the bed,
    // then the table turned by −C (ISO 841 sign of a table axis).
    let [(_, dx), (_, dy), (_, a), (_, b)] = &location;
    let table = |c_deg: f64| -> Iso {
        trans(V3::new(*dx, *dy, 0.0)) * rot(V3::new(*a, *b, 0.0)) * rot_z(-c_deg.to_radians())
    };
    // Target in the bed frame: X with its scale error, Y and Z exact, then the target offset.
    let target = |x: f64, y: f64, z: f64| V3::new(x * (1.0 + x_scale), y, z) + target_mm;
    let noise = Normal::new(0.0, noise_um * 1e-3).unwrap_or_else(|_| unreachable!());
    let grid = [&[-150.0, 0.0, 150.0][..], &[-120.0, 120.0], &[-150.0, 0.0]];
    let (csv, rows) = programme(&mut rng, grid, false, Some(&noise), &|x, y, z, c| {
        table(c)
            .inverse_transform_point(&target(x, y, z).into())
            .coords
    });
    std::fs::write(dir.join("points.csv"), csv)?;
    std::fs::write(
        dir.join("machine.json"),
        serde_json::to_string_pretty(&machine_json())?,
    )?;
    let mut manifest = serde_json::json!({
        "format": "mte-dataset/1",
        "kind": "points",
        "description": "3-D points of a target on the spindle side, measured from the C table (simulated)",
        "machine": "machine.json",
        "data": "points.csv",
        "noise_um": noise_um,
        "target": "tool",
    });
    if state_offset {
        manifest["target_mm"] = serde_json::json!([target_mm.x, target_mm.y, target_mm.z]);
    }
    if let Some(b) = base_model {
        manifest["base_model"] = b;
    }
    let path = dir.join("manifest.json");
    std::fs::write(&path, serde_json::to_string_pretty(&manifest)?)?;
    Ok(PointsTruth {
        manifest: path,
        location,
        x_scale,
        target_mm,
        noise_um,
        rows,
    })
}

/// The measurement programme: two set-ups, each with the instrument on the table in a pose
/// nobody measured; in each, 12 angles of C (30° apart, jittered by ±5°, rounded to the 4
/// decimals the file prints when `round_c`), and at each angle every (x, y, z) of `grid`: the
/// target in the table frame (`in_table(x, y, z, c_deg)`) seen from the instrument, with
/// `noise` on each coordinate. Returns the CSV text and its number of rows.
fn programme(
    rng: &mut ChaCha8Rng,
    grid: [&[f64]; 3],
    round_c: bool,
    noise: Option<&Normal<f64>>,
    in_table: &dyn Fn(f64, f64, f64, f64) -> V3,
) -> (String, usize) {
    let mut csv = String::from("setup,x_mm,y_mm,z_mm,c_deg,point_x_mm,point_y_mm,point_z_mm\n");
    let mut rows = 0;
    for setup in ["S1", "S2"] {
        let pose = trans(V3::new(
            rng.random_range(-300.0..300.0),
            rng.random_range(-300.0..300.0),
            rng.random_range(-100.0..100.0),
        )) * rot(V3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-3.0..3.0),
        ));
        for k in 0..12 {
            let mut c = 30.0 * k as f64 + rng.random_range(-5.0..5.0);
            if round_c {
                c = (c * 1e4).round() / 1e4;
            }
            for &x in grid[0] {
                for &y in grid[1] {
                    for &z in grid[2] {
                        let mut v = pose
                            .inverse_transform_point(&in_table(x, y, z, c).into())
                            .coords;
                        if let Some(noise) = noise {
                            v += V3::from_fn(|_, _| noise.sample(rng));
                        }
                        csv.push_str(&format!(
                            "{setup},{x:.3},{y:.3},{z:.3},{c:.4},{:.5},{:.5},{:.5}\n",
                            v.x, v.y, v.z
                        ));
                        rows += 1;
                    }
                }
            }
        }
    }
    (csv, rows)
}

/// The `mte-machine/1` description: C table on the bed; Y, X, Z on the tool side.
fn machine_json() -> serde_json::Value {
    serde_json::json!({
        "format": "mte-machine/1",
        "name": "c-stage-xyz",
        "description": "A C rotary table on the bed with X, Y, Z linear stages carrying the spindle (bed-Y-X-Z-tool); table axis with sign -1.",
        "tool": "tool",
        "workpiece": "workpiece",
        "axis_order": ["X", "Y", "Z", "C"],
        "bodies": [
            {"name": "bed"},
            {"name": "Y", "parent": "bed", "offset_mm": [0, 0, 0],
             "joint": {"type": "linear", "axis": "Y", "direction": [0, 1, 0], "sign": 1, "stroke_mm": [-300, 300]}},
            {"name": "X", "parent": "Y", "offset_mm": [0, 0, 0],
             "joint": {"type": "linear", "axis": "X", "direction": [1, 0, 0], "sign": 1, "stroke_mm": [-300, 300]}},
            {"name": "Z", "parent": "X", "offset_mm": [0.0, 0.0, TOOL_MM],
             "joint": {"type": "linear", "axis": "Z", "direction": [0, 0, 1], "sign": 1, "stroke_mm": [-300, 100]}},
            {"name": "tool", "parent": "Z", "offset_mm": [0.0, 0.0, -TOOL_MM]},
            {"name": "C", "parent": "bed", "offset_mm": [0, 0, 0],
             "joint": {"type": "rotary", "axis": "C", "direction": [0, 0, 1], "sign": -1, "stroke_deg": [0, 360]}},
            {"name": "workpiece", "parent": "C", "offset_mm": [0, 0, 0]}
        ]
    })
}

/// A realistic points dataset of the same machine: every ordinary error at once — the six
/// component errors of each of X, Y and Z as random smooth functions, the three squareness
/// errors between them, the C line's four location errors and C's six error motions (periodic
/// over a turn) — measured on a richer programme (12 angles of C, 5 × 4 × 3 positions of X, Y,
/// Z, two instrument set-ups) with a calibrated target; on top, the hidden effects of
/// `spec`: a squareness beyond the ordinary one, an angular positioning error of C at one
/// harmonic of a turn (on top of C's ordinary error motion about Z), or (open world) a Y
/// positioning error growing from mid-Y at a rate that changes along X. Their random parts are
/// drawn after every ordinary error: a clean dataset is the same with or without this option.
pub(crate) fn write(
    spec: &super::Spec,
    rng: &mut ChaCha8Rng,
    dir: &Path,
) -> std::io::Result<super::Truth> {
    use super::Hidden;
    use super::geom::{LinearErrors, REALISTIC};
    use super::smooth::Periodic;
    let s = spec.ordinary_scale;
    let strokes = [(-300.0, 300.0), (-300.0, 300.0), (-300.0, 100.0)];
    let [ex, ey, ez] =
        [0, 1, 2].map(|k| LinearErrors::draw(rng, k, strokes[k], REALISTIC, s, spec.waviness));
    let mut squareness = [0; 3].map(|_| signed(rng, 5.0, 60.0) * 1e-6 * s);
    let (dx, dy) = (
        signed(rng, 10.0, 40.0) * 1e-3 * s,
        signed(rng, 10.0, 40.0) * 1e-3 * s,
    );
    let (a, b) = (
        signed(rng, 20.0, 80.0) * 1e-6 * s,
        signed(rng, 20.0, 80.0) * 1e-6 * s,
    );
    let motion_d = [0; 3].map(|_| {
        let size = rng.random_range(1.0..5.0) * 1e-3 * s;
        Periodic::draw(rng, size, spec.waviness)
    });
    let motion_e = [0; 3].map(|_| {
        let size = rng.random_range(2.0..20.0) * 1e-6 * s;
        Periodic::draw(rng, size, spec.waviness)
    });
    let noise_um = rng.random_range(0.5..2.0) * spec.noise_scale;
    let target_mm = V3::new(
        rng.random_range(-30.0..30.0),
        rng.random_range(-30.0..30.0),
        rng.random_range(-60.0..-20.0),
    );
    let mut effects = Vec::new();
    // C's angular positioning error beyond its ordinary error motion about Z: (rad, k, phase).
    let mut angular: Option<(f64, f64, f64)> = None;
    let mut two_axis: Option<super::TwoAxis> = None;
    for h in &spec.hidden {
        match *h {
            Hidden::Squareness { pair, urad } if pair < 3 => {
                squareness[pair] += urad * 1e-6;
                effects.push(super::squareness_truth(pair, urad, squareness[pair]));
            }
            Hidden::AngularPositioning {
                rotary: 1,
                harmonic,
                urad,
            } => {
                let (drawn, truth) =
                    super::angular_positioning(rng, &motion_e[2], 1, harmonic, urad);
                angular = Some(drawn);
                effects.push(truth);
            }
            Hidden::TwoAxis { um } => {
                let (e, truth) = super::two_axis(rng, um, strokes[0]);
                two_axis = Some(e);
                effects.push(truth);
            }
            _ => return Err(super::unsupported(super::Kind::Points, h)),
        }
    }
    // Tool side: bed → Y → (squareness) → X → (squareness) → Z → tool, each carriage moved by
    // its nominal translation, then its error transform.
    let tool = |x: f64, y: f64, z: f64| -> Iso {
        trans(V3::new(0.0, y, 0.0))
            * ey.at(y)
            * rot(V3::new(0.0, 0.0, squareness[0]))
            * trans(V3::new(x, 0.0, 0.0))
            * ex.at(x)
            * rot(V3::new(squareness[1], squareness[2], 0.0))
            * trans(V3::new(0.0, 0.0, z + TOOL_MM))
            * ez.at(z)
            * trans(V3::new(0.0, 0.0, -TOOL_MM))
    };
    // Workpiece side: the C line displaced and tilted, the table turned by −C, then C's error
    // motions.
    let table = |c_deg: f64| -> Iso {
        let c = c_deg.to_radians();
        let d = V3::new(motion_d[0].at(c), motion_d[1].at(c), motion_d[2].at(c));
        let extra = angular.map_or(0.0, |(amp, k, phase)| amp * (k * c + phase).sin());
        let e = V3::new(
            motion_e[0].at(c),
            motion_e[1].at(c),
            motion_e[2].at(c) + extra,
        );
        trans(V3::new(dx, dy, 0.0)) * rot(V3::new(a, b, 0.0)) * rot_z(-c) * trans(d) * rot(e)
    };
    let noise = Normal::new(0.0, (noise_um * 1e-3).max(1e-300)).expect("finite σ");
    let grid = [
        &[-250.0, -120.0, 0.0, 130.0, 250.0][..],
        &[-240.0, -80.0, 90.0, 250.0],
        &[-260.0, -110.0, 60.0],
    ];
    // Angles rounded as printed: the readings are computed at the angle the file states.
    let (csv, rows) = programme(
        rng,
        grid,
        true,
        (noise_um > 0.0).then_some(&noise),
        &|x, y, z, c| {
            let mut p = tool(x, y, z).transform_point(&target_mm.into());
            if let Some(e) = &two_axis {
                p.y += e.at(x, y, strokes[1]);
            }
            table(c).inverse_transform_point(&p).coords
        },
    );
    std::fs::write(dir.join("points.csv"), csv)?;
    std::fs::write(
        dir.join("machine.json"),
        serde_json::to_string_pretty(&machine_json())?,
    )?;
    let manifest = serde_json::json!({
        "format": "mte-dataset/1",
        "kind": "points",
        "description": "3-D points of a target on the spindle side, measured from the C table (simulated realistic machine)",
        "machine": "machine.json",
        "data": "points.csv",
        "noise_um": super::axis::stated_noise(noise_um.max(0.05)),
        "target": "tool",
        "target_mm": [target_mm.x, target_mm.y, target_mm.z],
    });
    let path = super::write_manifest(dir, manifest, &spec.base_model)?;
    Ok(super::Truth {
        kind: super::Kind::Points,
        manifest: path,
        effects,
        ordinary: Vec::new(),
        noise_um,
        stations: Vec::new(),
        n_observations: 3 * rows,
    })
}
