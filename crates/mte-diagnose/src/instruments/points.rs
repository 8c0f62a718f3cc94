//! 3-D points: an instrument that measures coordinates (a laser tracker in 3-D mode, a CMM,
//! photogrammetry, circle-point analysis of each axis in turn). Each row holds the commanded
//! axes (`<axis>_mm` / `<axis>_deg`), the instrument set-up (`setup`), optional `t_s`, and the
//! measured coordinates of a target in the instrument's frame (`point_x_mm`, `point_y_mm`,
//! `point_z_mm`).
//!
//! The instrument sits on one side of the machine and the target on the other: with
//! `"target": "tool"` (the default) the target is fixed on the tool side and the instrument on
//! the workpiece side (a tracker on the table); with `"target": "workpiece"` the target is on
//! the table and the instrument on the tool side (for a rotary stage with linear stages under
//! it, the bed). The instrument's pose relative to the machine is unknown in each set-up
//! (three translations, three rotations), and so is the target's offset unless the manifest
//! states it (`target_mm`).
//!
//! Several targets may be measured at each position (`target_x_mm`, `target_y_mm`,
//! `target_z_mm` per row: each target's place on a holder, in the frame of the side it is on, from
//! the holder's reference point, which `target_mm` states or the fit finds). Targets apart from one
//! another show the angular errors of the side that carries them apart from its translations, as
//! the reflector offsets of a volumetric calibration do; the holder's orientation (three angles no
//! drawing states to the µrad) is then in the base with the instrument's poses.
//!
//! The nominal machine is fitted first (Gauss–Newton on the poses and the target offset);
//! then every residual is turned into the frame of the machine side that carries the
//! instrument, `v = Rₛᵀ(m − tₛ) − x(q)`, and from there into the bed's, `B(q)·v` with `B(q)`
//! the nominal rotation of that side at the row's axes: the three channels are the bed's
//! directions (a linear axis' error shows as a line against its axis even when the instrument
//! rides on a rotary table) and the noise stays independent and isotropic. A machine error
//! changes x(q) by the first-order kinematics; a pose change adds `δt + ω × x`; a target change
//! `A(q)·δo`; every effect is turned by `B(q)` as the residual is.

use mte_kinematics::Machine;
use mte_linalg::{DMat, DVec, Mat3, Vec3};

use super::machine::{
    axis_variables, load_machine, location_names, read_axes, read_optional_vectors, read_times,
    read_vectors, slot_effects,
};
use crate::Result;
use crate::candidate::{BaseModelSpec, SlotEffect, SlotRole};
use crate::data::{Observations, Variable, VariableKind};
use crate::dataset::{ManifestFile, dataset_manifest};
use crate::model::{DriftOf, Effects, ObservationModel};
use crate::term::{Family, Quantity, Term};

dataset_manifest!(
    /// The manifest of 3-D points (`"kind": "points"`).
    Manifest {
        machine: Option<String>,
        /// `tool` (default) or `workpiece`: the side of the machine the target is fixed to.
        target: Option<String>,
        /// The target's offset from the tool tip (tool frame) or from the workpiece origin
        /// (workpiece frame), mm, when it is calibrated; estimated otherwise. With several
        /// targets per position (per-row `target_x_mm` …), the offset of the holder's reference
        /// point from which those are measured.
        target_mm: Option<[f64; 3]>,
    }
);

/// Where the target sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Tool,
    Workpiece,
}

/// 3-D points linearised at the fitted nominal machine.
pub struct Points {
    machine: Machine,
    side: Side,
    observations: Observations,
    /// Commanded axes per row.
    q: Vec<Vec<f64>>,
    /// The nominal tool frame in the workpiece frame per row (rotation, translation).
    frames: Vec<(Mat3, Vec3)>,
    /// Set-up of each row.
    setup_of: Vec<usize>,
    setup_ids: Vec<String>,
    /// The target's offset (fitted or stated; with several targets, the holder's reference
    /// point) and whether it was fitted.
    offset: Vec3,
    offset_fitted: bool,
    /// Each row's target from the holder's reference point (zeros with one target).
    on_holder: Vec<Vec3>,
    /// Whether the rows' targets differ (the holder's orientation is then in the base).
    several_targets: bool,
    /// Nominal target position per row, in the instrument side's frame.
    x: Vec<Vec3>,
    /// Instrument translation per set-up, turned into the instrument side's frame (`Rₛᵀtₛ`).
    origin: Vec<Vec3>,
    /// Per row, the nominal rotation of the instrument side's frame in the bed's: residuals and
    /// effects are turned by it.
    to_bed: Vec<Mat3>,
    title: String,
}

/// The largest Gauss–Newton steps of the nominal fit.
const NOMINAL_ITERATIONS: usize = 50;

impl Points {
    /// Reads the points a manifest names and fits the nominal machine to them.
    pub(crate) fn read(
        file: &ManifestFile,
        noise_um: Option<f64>,
    ) -> Result<(Self, Option<serde_json::Value>)> {
        let manifest: Manifest = file.parse()?;
        let noise_um = manifest.noise_um.or(noise_um);
        file.check_noise("noise_um", noise_um)?;
        let side = match manifest.target.as_deref() {
            None | Some("tool") => Side::Tool,
            Some("workpiece") => Side::Workpiece,
            Some(other) => {
                return Err(file.error(format!(
                    "field `target`: `{other}`, expected `tool` or `workpiece`"
                )));
            }
        };
        if let Some(o) = manifest.target_mm {
            if o.iter().any(|v| !v.is_finite() || v.abs() > 1e4) {
                return Err(file.error(format!(
                    "field `target_mm`: {o:?}, expected a finite offset within 10 m"
                )));
            }
        }
        let machine = load_machine(file, manifest.machine.as_deref())?;
        let table = file.table(&manifest.data)?;
        if table.is_empty() {
            return Err(crate::DiagnoseError::Dataset {
                path: table.source_name.clone(),
                detail: "no observations".into(),
            });
        }
        let axes = read_axes(&machine, &table)?;
        let rows = table.len();
        let q: Vec<Vec<f64>> = (0..rows)
            .map(|r| axes.iter().map(|a| a[r]).collect())
            .collect();
        let m = read_vectors(
            &table,
            ["point_x_mm", "point_y_mm", "point_z_mm"],
            1e6,
            "a coordinate of 1 km or more is not a measured point",
        )?;
        let on_holder = read_optional_vectors(
            &table,
            ["target_x_mm", "target_y_mm", "target_z_mm"],
            1e4,
            "a target 10 m or more from its holder's reference is not on the machine",
        )?
        .unwrap_or_else(|| vec![Vec3::zeros(); rows]);
        let several_targets = on_holder.iter().any(|o| o != &on_holder[0]);
        let (setup_ids, setup_of) = table.groups(table.require("setup")?);
        for (k, id) in setup_ids.iter().enumerate() {
            let count = setup_of.iter().filter(|&&s| s == k).count();
            if count < 3 {
                return Err(crate::DiagnoseError::Dataset {
                    path: table.source_name.clone(),
                    detail: format!(
                        "set-up `{id}` has {count} point(s); the instrument's pose needs at least 3 points that do not lie on a line"
                    ),
                });
            }
        }
        // Per row, the nominal tool frame in the workpiece frame and the rotation of the
        // instrument side's frame in the bed's (residuals and effects are turned by it), from one
        // forward kinematics.
        let (frames, to_bed): (Vec<(Mat3, Vec3)>, Vec<Mat3>) = q
            .iter()
            .map(|qr| {
                let poses = machine.branch_poses(qr, &[]);
                let g = poses.tool_in_workpiece();
                let instrument_side = match side {
                    Side::Tool => poses.workpiece_in_base,
                    Side::Workpiece => poses.tool_in_base,
                };
                (
                    (
                        *g.rotation.to_rotation_matrix().matrix(),
                        g.translation.vector,
                    ),
                    *instrument_side.rotation.to_rotation_matrix().matrix(),
                )
            })
            .unzip();
        let fit = fit_nominal(
            &frames,
            &on_holder,
            side,
            &m,
            &setup_of,
            setup_ids.len(),
            manifest.target_mm.map(Vec3::from),
        )
        .map_err(|detail| file.error(detail))?;
        let n = 3 * rows;
        let residual: Vec<Vec3> = (0..rows)
            .map(|r| {
                let (rot, t) = &fit.poses[setup_of[r]];
                to_bed[r] * (rot.transpose() * (m[r] - t) - fit.x[r])
            })
            .collect();
        let per_obs = |v: &[f64]| -> Vec<f64> { (0..n).map(|i| v[i / 3]).collect() };
        let mut variables = axis_variables(
            &machine,
            &axes.iter().map(|a| per_obs(a)).collect::<Vec<_>>(),
        );
        if let Some(t) = read_times(&table)? {
            variables.push(Variable {
                name: "t".into(),
                kind: VariableKind::Time,
                values: per_obs(&t),
            });
        }
        let observations = Observations {
            values: DVec::from_fn(n, |i, _| residual[i / 3][i % 3]),
            sigma: noise_um.map(|u| DVec::from_element(n, u * 1e-3)),
            variables,
            setup: (0..n).map(|i| setup_of[i / 3]).collect(),
            setup_names: setup_ids.clone(),
            channel: (0..n).map(|i| i % 3).collect(),
            channel_names: vec!["dx".into(), "dy".into(), "dz".into()],
            setup_kind: "instrument set-up".into(),
            quantity: Quantity::Length,
        };
        let title = manifest.description.clone().unwrap_or_else(|| {
            format!(
                "3-D points of a target on the {} side of {}",
                match side {
                    Side::Tool => "tool",
                    Side::Workpiece => "workpiece",
                },
                machine.name()
            )
        });
        Ok((
            Points {
                origin: fit.poses.iter().map(|(r, t)| r.transpose() * t).collect(),
                to_bed,
                x: fit.x,
                offset: fit.offset,
                offset_fitted: manifest.target_mm.is_none(),
                on_holder,
                several_targets,
                machine,
                side,
                observations,
                q,
                frames,
                setup_of,
                setup_ids,
                title,
            },
            manifest.base_model,
        ))
    }
}

/// The nominal fit: instrument pose per set-up, target offset, nominal target positions.
struct NominalFit {
    poses: Vec<(Mat3, Vec3)>,
    offset: Vec3,
    x: Vec<Vec3>,
}

/// d x / d offset: the tool's rotation in the workpiece frame (target on the tool), or its
/// inverse (target on the workpiece).
fn offset_jacobian(frame: &(Mat3, Vec3), side: Side) -> Mat3 {
    match side {
        Side::Tool => frame.0,
        Side::Workpiece => frame.0.transpose(),
    }
}

/// The target's nominal position in the instrument side's frame, with the tool frame
/// `(rotation, translation)` in the workpiece frame.
fn target_position(frame: &(Mat3, Vec3), side: Side, offset: &Vec3) -> Vec3 {
    let (r, p) = frame;
    match side {
        Side::Tool => p + r * offset,
        Side::Workpiece => r.transpose() * (offset - p),
    }
}

/// Fits the instrument's poses (and the target offset unless `known`) to the measured points
/// by Gauss–Newton from a closed-form start (Kabsch with the offset at zero); row `r`'s target
/// is at `on_holder[r]` from the offset.
fn fit_nominal(
    frames: &[(Mat3, Vec3)],
    on_holder: &[Vec3],
    side: Side,
    m: &[Vec3],
    setup_of: &[usize],
    n_setups: usize,
    known: Option<Vec3>,
) -> std::result::Result<NominalFit, String> {
    let mut offset = known.unwrap_or_else(Vec3::zeros);
    let positions = |offset: &Vec3| -> Vec<Vec3> {
        frames
            .iter()
            .zip(on_holder)
            .map(|(f, o)| target_position(f, side, &(offset + o)))
            .collect()
    };
    let mut x = positions(&offset);
    let mut poses: Vec<(Mat3, Vec3)> = (0..n_setups)
        .map(|s| {
            let idx: Vec<usize> = (0..m.len()).filter(|&r| setup_of[r] == s).collect();
            kabsch(
                &idx.iter().map(|&r| x[r]).collect::<Vec<_>>(),
                &idx.iter().map(|&r| m[r]).collect::<Vec<_>>(),
            )
        })
        .collect();
    let n_par = 6 * n_setups + if known.is_none() { 3 } else { 0 };
    for _ in 0..NOMINAL_ITERATIONS {
        let mut jac = DMat::zeros(3 * m.len(), n_par);
        let mut res = DVec::zeros(3 * m.len());
        for (r, (mr, xr)) in m.iter().zip(&x).enumerate() {
            let s = setup_of[r];
            let (rot, t) = &poses[s];
            let world = rot * xr;
            let e = mr - (world + t);
            for k in 0..3 {
                res[3 * r + k] = e[k];
                jac[(3 * r + k, 6 * s + k)] = 1.0;
            }
            // ω × (R x) = −[R x]× ω
            let skew = mte_linalg::skew(&world);
            for a in 0..3 {
                for b in 0..3 {
                    jac[(3 * r + a, 6 * s + 3 + b)] = -skew[(a, b)];
                }
            }
            if known.is_none() {
                let a = rot * offset_jacobian(&frames[r], side);
                for i in 0..3 {
                    for j in 0..3 {
                        jac[(3 * r + i, 6 * n_setups + j)] = a[(i, j)];
                    }
                }
            }
        }
        let fail = || "the instrument's pose could not be fitted (degenerate or absurd points)";
        let svd = jac
            .clone()
            .try_svd(true, true, f64::EPSILON, 500)
            .ok_or_else(fail)?;
        let tol = svd.singular_values.max() * 1e-10;
        let step = svd.solve(&res, tol).map_err(|_| fail())?;
        for (s, pose) in poses.iter_mut().enumerate() {
            let dt = Vec3::new(step[6 * s], step[6 * s + 1], step[6 * s + 2]);
            let w = Vec3::new(step[6 * s + 3], step[6 * s + 4], step[6 * s + 5]);
            pose.0 = mte_linalg::so3::exp(&w) * pose.0;
            pose.1 += dt;
        }
        if known.is_none() {
            offset += Vec3::new(
                step[6 * n_setups],
                step[6 * n_setups + 1],
                step[6 * n_setups + 2],
            );
        }
        x = positions(&offset);
        if step.amax() < 1e-12 {
            break;
        }
    }
    if !finite_poses(&poses) {
        return Err("the instrument's pose could not be fitted (the points are degenerate)".into());
    }
    Ok(NominalFit { poses, offset, x })
}

fn finite_poses(poses: &[(Mat3, Vec3)]) -> bool {
    poses
        .iter()
        .all(|(r, t)| r.iter().all(|v| v.is_finite()) && t.iter().all(|v| v.is_finite()))
}

/// The rotation and translation that carry the points `a` onto `b` best (least squares).
fn kabsch(a: &[Vec3], b: &[Vec3]) -> (Mat3, Vec3) {
    let n = a.len().max(1) as f64;
    let ca = a.iter().fold(Vec3::zeros(), |s, p| s + p) / n;
    let cb = b.iter().fold(Vec3::zeros(), |s, p| s + p) / n;
    let h = a.iter().zip(b).fold(Mat3::zeros(), |h, (p, q)| {
        h + (p - ca) * (q - cb).transpose()
    });
    let Some(svd) = h.try_svd(true, true, f64::EPSILON, 500) else {
        return (Mat3::identity(), cb - ca);
    };
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return (Mat3::identity(), cb - ca);
    };
    let mut d = Mat3::identity();
    if (v_t.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = v_t.transpose() * d * u.transpose();
    (r, cb - r * ca)
}

impl ObservationModel for Points {
    fn observations(&self) -> &Observations {
        &self.observations
    }

    /// The machine's errors through the first-order kinematics at the target; the instrument's
    /// pose in every set-up, the target's offset (unless stated) and, with several targets, their
    /// holder's orientation as instrument parameters;
    /// the instrument's scale as a candidate. Default base: the location errors of every rotary
    /// axis, as for the R-test.
    fn effects(&self) -> Effects {
        let machine = &self.machine;
        let rows = self.q.len();
        let n = 3 * rows;
        let mut s = DMat::zeros(n, machine.n_slots());
        let mut jac = DMat::zeros(6, machine.n_slots());
        for r in 0..rows {
            machine.jacobian_into(&self.q[r], &mut jac);
            let (rot, tip) = &self.frames[r];
            for j in 0..machine.n_slots() {
                let dp = Vec3::new(jac[(0, j)], jac[(1, j)], jac[(2, j)]);
                let dtheta = Vec3::new(jac[(3, j)], jac[(4, j)], jac[(5, j)]);
                let offset = self.offset + self.on_holder[r];
                let dx = match self.side {
                    Side::Tool => dp + dtheta.cross(&(*rot * offset)),
                    Side::Workpiece => -(rot.transpose() * (dp + dtheta.cross(&(offset - tip)))),
                };
                let dx = self.to_bed[r] * dx;
                for k in 0..3 {
                    s[(3 * r + k, j)] = dx[k];
                }
            }
        }
        let mut errors = slot_effects(machine, &s, &self.observations, None, &|_| None);
        // The tool's and the workpiece's set-up offsets are the target's offset and the
        // instrument's pose.
        errors.retain(|e| {
            !matches!(
                e.role,
                SlotRole::Constant {
                    family: Family::Setup
                }
            )
        });
        errors.push(SlotEffect {
            name: "instrument scale".into(),
            label: "scale error of the instrument's coordinates".into(),
            meaning: "every measured coordinate is too large or too small in proportion about the instrument's origin (its length standard, air-refraction compensation, temperature)".into(),
            quantity: Quantity::Ratio,
            role: SlotRole::Constant { family: Family::Instrument },
            column: DVec::from_fn(n, |i, _| {
                let r = i / 3;
                (self.to_bed[r] * (self.x[r] + self.origin[self.setup_of[r]]))[i % 3]
            }),
            separated_by: Some("a calibrated reference length measured by the instrument".into()),
            reference: None,
        });
        let mut instrument = Vec::new();
        for (k, id) in self.setup_ids.iter().enumerate() {
            let on = |i: usize| self.setup_of[i / 3] == k;
            for (a, letter) in ['x', 'y', 'z'].into_iter().enumerate() {
                instrument.push(Term::single(
                    format!("{id} position {letter}"),
                    format!("instrument position in {letter} (set-up {id})"),
                    "where the instrument stands relative to the machine",
                    Family::Base,
                    DVec::from_fn(n, |i, _| {
                        if on(i) {
                            self.to_bed[i / 3][(i % 3, a)]
                        } else {
                            0.0
                        }
                    }),
                    Quantity::Length,
                ));
            }
            for (a, letter) in ['x', 'y', 'z'].into_iter().enumerate() {
                let axis = Vec3::ith(a, 1.0);
                instrument.push(Term::single(
                    format!("{id} rotation {letter}"),
                    format!("instrument orientation about {letter} (set-up {id})"),
                    "how the instrument's frame is turned relative to the machine",
                    Family::Base,
                    DVec::from_fn(n, |i, _| {
                        if on(i) {
                            (self.to_bed[i / 3] * axis.cross(&self.x[i / 3]))[i % 3]
                        } else {
                            0.0
                        }
                    }),
                    Quantity::Angle,
                ));
            }
        }
        let a: Vec<Mat3> = self
            .frames
            .iter()
            .zip(&self.to_bed)
            .map(|(f, b)| b * offset_jacobian(f, self.side))
            .collect();
        if self.offset_fitted {
            for (k, letter) in ['x', 'y', 'z'].into_iter().enumerate() {
                instrument.push(Term::single(
                    format!("target offset {letter}"),
                    format!("target offset in {letter}"),
                    "where the target sits on its side of the machine",
                    Family::Base,
                    DVec::from_fn(n, |i, _| a[i / 3][(i % 3, k)]),
                    Quantity::Length,
                ));
            }
        }
        // The holder's orientation, which no drawing states to the µrad: turned by δφ (in the
        // frame of its side) it moves each target by δφ × o, o the target's place on it.
        if self.several_targets {
            for (k, letter) in ['x', 'y', 'z'].into_iter().enumerate() {
                let axis = Vec3::ith(k, 1.0);
                instrument.push(Term::single(
                    format!("target holder orientation {letter}"),
                    format!("the target holder's orientation about {letter}"),
                    "how the targets' holder sits on its side of the machine: its turn moves each target in proportion to its place on the holder",
                    Family::Base,
                    DVec::from_fn(n, |i, _| {
                        let r = i / 3;
                        (a[r] * axis.cross(&self.on_holder[r]))[i % 3]
                    }),
                    Quantity::Angle,
                ));
            }
        }
        Effects {
            errors,
            instrument,
            location: location_names(machine),
            default_base: BaseModelSpec {
                location: true,
                ..Default::default()
            },
            drift: DriftOf::WholeBase,
            ..Effects::default()
        }
    }

    fn title(&self) -> String {
        self.title.clone()
    }
}
