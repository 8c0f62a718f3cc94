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

use super::geom::{Iso, LinearErrors, V3, rot, rot_z, trans};
use super::smooth::{Periodic, signed};

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
    let (csv, rows) = programme(
        &mut rng,
        grid,
        &[(V3::zeros(), target_mm)],
        false,
        Some(&noise),
        &|x, y, z, c, _| {
            table(c)
                .inverse_transform_point(&target(x, y, z).into())
                .coords
        },
    );
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
/// decimals the file prints when `round_c`), and at each angle every (x, y, z) of `grid` and
/// every target of `targets` (its place as the file states it, its offset from the tool tip):
/// the target in the table frame (`in_table(x, y, z, c_deg, offset)`) seen from the instrument,
/// with `noise` on each coordinate. With several targets each row states its place. Returns the
/// CSV text and its number of rows.
fn programme(
    rng: &mut ChaCha8Rng,
    grid: [&[f64]; 3],
    targets: &[(V3, V3)],
    round_c: bool,
    noise: Option<&Normal<f64>>,
    in_table: &dyn Fn(f64, f64, f64, f64, V3) -> V3,
) -> (String, usize) {
    let several = targets.len() > 1;
    let mut csv = String::from(if several {
        "setup,x_mm,y_mm,z_mm,c_deg,target_x_mm,target_y_mm,target_z_mm,point_x_mm,point_y_mm,point_z_mm\n"
    } else {
        "setup,x_mm,y_mm,z_mm,c_deg,point_x_mm,point_y_mm,point_z_mm\n"
    });
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
                        for (place, offset) in targets {
                            let mut v = pose
                                .inverse_transform_point(&in_table(x, y, z, c, *offset).into())
                                .coords;
                            if let Some(noise) = noise {
                                v += V3::from_fn(|_, _| noise.sample(rng));
                            }
                            let place = if several {
                                format!("{:.1},{:.1},{:.1},", place.x, place.y, place.z)
                            } else {
                                String::new()
                            };
                            csv.push_str(&format!(
                                "{setup},{x:.3},{y:.3},{z:.3},{c:.4},{place}{:.5},{:.5},{:.5}\n",
                                v.x, v.y, v.z
                            ));
                            rows += 1;
                        }
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

/// The realistic points machine (the C table with X, Y, Z stages the dataset's `machine.json`
/// describes) with its true errors: every component error of X, Y, Z, three squareness errors
/// between them, the C line's four location errors and C's six error motions, and the hidden
/// effects.
#[derive(Debug, Clone)]
pub struct PointsMachine {
    /// Strokes of X, Y, Z, mm.
    pub strokes: [(f64, f64); 3],
    /// Component errors of X, Y, Z.
    pub components: [LinearErrors; 3],
    /// Squareness, rad: X's motion turned about Z against Y's (`[0]`), Z's about X and Y
    /// against X's (`[1]`, `[2]`).
    pub squareness: [f64; 3],
    /// The C line's place (mm) and tilt about X and Y of the bed (rad): EX0C, EY0C, EA0C, EB0C.
    pub location: [f64; 4],
    /// C's error motions: translations (mm) and rotations (rad) as functions over a turn.
    pub motion_d: [Periodic; 3],
    /// See [`PointsMachine::motion_d`].
    pub motion_e: [Periodic; 3],
    /// C's hidden angular positioning error `amplitude · sin(k·θ + φ)`: (rad, k, φ).
    pub angular: Option<(f64, f64, f64)>,
    /// Open world: a Y positioning error growing from mid-Y at a rate that changes along X.
    pub two_axis: Option<super::TwoAxis>,
}

impl PointsMachine {
    /// A machine without errors.
    pub fn perfect() -> Self {
        Self {
            strokes: STROKES,
            components: [0; 3].map(|_| LinearErrors::zero()),
            squareness: [0.0; 3],
            location: [0.0; 4],
            motion_d: [0; 3].map(|_| Periodic::zero()),
            motion_e: [0; 3].map(|_| Periodic::zero()),
            angular: None,
            two_axis: None,
        }
    }

    /// The tool frame in the bed frame: bed → Y → (squareness) → X → (squareness) → Z → tool,
    /// each carriage moved by its nominal translation, then its error transform.
    fn tool(&self, x: f64, y: f64, z: f64) -> Iso {
        let [ex, ey, ez] = &self.components;
        trans(V3::new(0.0, y, 0.0))
            * ey.at(y)
            * rot(V3::new(0.0, 0.0, self.squareness[0]))
            * trans(V3::new(x, 0.0, 0.0))
            * ex.at(x)
            * rot(V3::new(self.squareness[1], self.squareness[2], 0.0))
            * trans(V3::new(0.0, 0.0, z + TOOL_MM))
            * ez.at(z)
            * trans(V3::new(0.0, 0.0, -TOOL_MM))
    }

    /// The table frame in the bed frame: the C line displaced and tilted, the table turned by
    /// −C (ISO 841 sign of a table axis), then C's error motions.
    fn table(&self, c_deg: f64) -> Iso {
        let c = c_deg.to_radians();
        let [dx, dy, a, b] = self.location;
        let d = V3::from_fn(|k, _| self.motion_d[k].at(c));
        let extra = self
            .angular
            .map_or(0.0, |(amp, k, phase)| amp * (k * c + phase).sin());
        let e = V3::new(
            self.motion_e[0].at(c),
            self.motion_e[1].at(c),
            self.motion_e[2].at(c) + extra,
        );
        trans(V3::new(dx, dy, 0.0)) * rot(V3::new(a, b, 0.0)) * rot_z(-c) * trans(d) * rot(e)
    }

    /// A target at `offset` from the tool tip (tool frame, mm) in the table frame, at commanded
    /// X, Y, Z (mm) and C (°).
    pub fn target(&self, x: f64, y: f64, z: f64, c_deg: f64, offset: V3) -> V3 {
        let mut p = self.tool(x, y, z).transform_point(&offset.into());
        if let Some(e) = &self.two_axis {
            p.y += e.at(x, y, self.strokes[1]);
        }
        self.table(c_deg).inverse_transform_point(&p).coords
    }

    /// The XY squareness as ISO 230-1 defines it, the angle between the axes' least-squares
    /// reference lines through what the measured positions `x`, `y` (each once) show (rad, sign
    /// of `squareness[0]`): besides X's turned direction of motion, the slope of each
    /// straightness across the other axis, and the mean yaw of the Y carriage, which turns X
    /// (riding on it) against Y.
    pub fn xy_squareness(&self, x: &[f64], y: &[f64]) -> f64 {
        let [ex, ey, _] = &self.components;
        self.squareness[0] + ey.e[2].mean(y) + ex.d[1].slope(x) + ey.d[0].slope(y)
    }
}

/// The positions of X, Y, Z the realistic programme measures, mm.
const GRID: [&[f64]; 3] = [
    &[-250.0, -120.0, 0.0, 130.0, 250.0],
    &[-240.0, -80.0, 90.0, 250.0],
    &[-260.0, -110.0, 60.0],
];

/// Strokes of X, Y, Z of the realistic machine, mm.
const STROKES: [(f64, f64); 3] = [(-300.0, 300.0), (-300.0, 300.0), (-300.0, 100.0)];

/// The places of 3–4 targets on a holder (tool frame, mm, from its reference point): one on the
/// reference, one across in X, one across in Y and (with four) one further down the tool, each
/// 80–200 mm out with a few mm to the sides, to 0.1 mm as a calibrated holder states them.
fn draw_holder(rng: &mut ChaCha8Rng) -> Vec<V3> {
    let round = |v: f64| (v * 10.0).round() / 10.0;
    let n = rng.random_range(3..=4);
    let mut places = vec![V3::zeros()];
    for k in (0..3).take(n - 1) {
        let mut o = V3::from_fn(|_, _| round(rng.random_range(-10.0..=10.0)));
        let reach = round(rng.random_range(80.0..=200.0));
        o[k] = if k == 2 || rng.random_bool(0.5) {
            -reach
        } else {
            reach
        };
        places.push(o);
    }
    places
}

/// A realistic points dataset of the same machine: every ordinary error at once — the six
/// component errors of each of X, Y and Z as random smooth functions, the three squareness
/// errors between them, the C line's four location errors and C's six error motions (periodic
/// over a turn) — measured on a richer programme (12 angles of C, 5 × 4 × 3 positions of X, Y,
/// Z, two instrument set-ups) with a calibrated target or, for `points-targets`, 3–4 targets on
/// a holder turned by up to 0.5 mrad about each axis (the file states their places as drawn);
/// on top, the hidden effects of `spec`: a squareness beyond the ordinary one, an angular
/// positioning error of C at one harmonic of a turn (on top of C's ordinary error motion about
/// Z), or (open world) a Y positioning error growing from mid-Y at a rate that changes along X.
/// Their random parts are drawn after every ordinary error: a clean dataset is the same with or
/// without this option.
pub(crate) fn write(
    spec: &super::Spec,
    rng: &mut ChaCha8Rng,
    dir: &Path,
) -> std::io::Result<super::Truth> {
    use super::Hidden;
    use super::geom::REALISTIC;
    let s = spec.ordinary_scale;
    let mut m = PointsMachine::perfect();
    m.components =
        [0, 1, 2].map(|k| LinearErrors::draw(rng, k, STROKES[k], REALISTIC, s, spec.waviness));
    m.squareness = [0; 3].map(|_| signed(rng, 5.0, 60.0) * 1e-6 * s);
    let (dx, dy) = (
        signed(rng, 10.0, 40.0) * 1e-3 * s,
        signed(rng, 10.0, 40.0) * 1e-3 * s,
    );
    let (a, b) = (
        signed(rng, 20.0, 80.0) * 1e-6 * s,
        signed(rng, 20.0, 80.0) * 1e-6 * s,
    );
    m.location = [dx, dy, a, b];
    m.motion_d = [0; 3].map(|_| {
        let size = rng.random_range(1.0..5.0) * 1e-3 * s;
        Periodic::draw(rng, size, spec.waviness)
    });
    m.motion_e = [0; 3].map(|_| {
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
    for h in &spec.hidden {
        match *h {
            Hidden::Squareness { pair: 0, urad } => {
                m.squareness[0] += urad * 1e-6;
                effects.push(super::squareness_truth(
                    0,
                    urad,
                    m.xy_squareness(GRID[0], GRID[1]),
                ));
            }
            Hidden::AngularPositioning {
                rotary: 1,
                harmonic,
                urad,
            } => {
                let (drawn, truth) =
                    super::angular_positioning(rng, &m.motion_e[2], 1, harmonic, urad);
                m.angular = Some(drawn);
                effects.push(truth);
            }
            Hidden::TwoAxis { um } => {
                let (e, truth) = super::two_axis(rng, um, STROKES[0]);
                m.two_axis = Some(e);
                effects.push(truth);
            }
            _ => return Err(super::unsupported(spec.kind, h)),
        }
    }
    // The targets: one at the stated offset, or several on a holder whose reference point is
    // there, turned a little (the holder's orientation is no drawing's).
    let (places, holder) = if spec.kind == super::Kind::PointsTargets {
        let places = draw_holder(rng);
        let turn = V3::from_fn(|_, _| rng.random_range(-0.5..=0.5) * 1e-3);
        (places, rot(turn))
    } else {
        (vec![V3::zeros()], Iso::identity())
    };
    let targets: Vec<(V3, V3)> = places
        .iter()
        .map(|o| (*o, target_mm + holder.transform_vector(o)))
        .collect();
    // The noise's stream, from here on ([`Spec::noise_seed`]).
    let mut own = spec.noise_rng();
    let rng = own.as_mut().unwrap_or(rng);
    let noise = Normal::new(0.0, (noise_um * 1e-3).max(1e-300)).expect("finite σ");
    // Angles rounded as printed: the readings are computed at the angle the file states.
    let (csv, rows) = programme(
        rng,
        GRID,
        &targets,
        true,
        (noise_um > 0.0).then_some(&noise),
        &|x, y, z, c, o| m.target(x, y, z, c, o),
    );
    std::fs::write(dir.join("points.csv"), csv)?;
    std::fs::write(
        dir.join("machine.json"),
        serde_json::to_string_pretty(&machine_json())?,
    )?;
    let description = if targets.len() > 1 {
        "3-D points of targets on a holder on the spindle side, measured from the C table (simulated realistic machine)"
    } else {
        "3-D points of a target on the spindle side, measured from the C table (simulated realistic machine)"
    };
    let manifest = serde_json::json!({
        "format": "mte-dataset/1",
        "kind": "points",
        "description": description,
        "machine": "machine.json",
        "data": "points.csv",
        "noise_um": super::axis::stated_noise(noise_um.max(0.05)),
        "target": "tool",
        "target_mm": [target_mm.x, target_mm.y, target_mm.z],
    });
    let path = super::write_manifest(dir, manifest, &spec.base_model)?;
    Ok(super::Truth {
        kind: spec.kind,
        manifest: path,
        effects,
        ordinary: Vec::new(),
        noise_um,
        stations: Vec::new(),
        n_observations: 3 * rows,
    })
}
