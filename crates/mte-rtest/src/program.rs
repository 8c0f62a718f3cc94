//! R-test programs (ISO 10791-6 BK1, BK2, BK4 and user-defined) and the controller's
//! inverse kinematics with the rotary angles given.

use crate::error::{Result, RtestError};
use crate::kin;
use mte_kinematics::Machine;
use mte_linalg::{Mat3, Vec3};
use serde::{Deserialize, Serialize};

/// A rotary-axis program: piecewise-linear waypoints of the moved rotary axes, run at a constant
/// speed of the leading axis; the linear axes follow so that the nominal ball centre stays at the
/// nominal nest centre.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Program {
    /// Test name ("BK1", "BK2", "BK4" or a user name).
    pub name: String,
    /// The rotary axes the waypoints move, by name.
    pub axes: Vec<String>,
    /// Waypoints, one value per entry of `axes`, degrees.
    pub waypoints_deg: Vec<Vec<f64>>,
    /// Rotary axes held at a fixed angle during the program (others not listed: 0°).
    pub hold_deg: Vec<(String, f64)>,
    /// Speed of the axis with the largest travel in a segment, deg/s.
    pub speed_deg_s: f64,
    /// Sampling step of that axis, degrees.
    pub step_deg: f64,
}

/// One sample of a program: time from the program start and the rotary angles.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramSample {
    /// Time since the program start, s.
    pub t_s: f64,
    /// Commanded axes in machine order with the rotary axes set (linear axes 0 until commanded).
    pub q: Vec<f64>,
}

/// The rotary axis a BK1 test tilts (A or B) and the one BK2 turns (C).
fn find_rotary(m: &Machine, names: &[&str], what: &str) -> Result<usize> {
    let axes = kin::axes(m);
    for n in names {
        if let Some(i) = axes.iter().position(|a| a.name == *n && a.rotary) {
            return Ok(i);
        }
    }
    Err(kin::unknown_axis(
        m,
        &names.join("|"),
        &format!("{what} needs a rotary axis named {}", names.join(" or ")),
    ))
}

impl Program {
    /// BK1: the tilt axis (A or B) 0 → +range → −range → 0 with the other rotary axes held;
    /// `range_deg` defaults to 90° and is clipped to the axis stroke.
    ///
    /// # Errors
    /// [`RtestError::UnknownAxis`] when the machine has no rotary A or B axis.
    pub fn bk1(m: &Machine, range_deg: Option<f64>) -> Result<Program> {
        let i = find_rotary(m, &["B", "A"], "BK1")?;
        let a = &kin::axes(m)[i];
        let r = range_deg.unwrap_or(90.0).abs();
        let hi = r.min(a.stroke.1.to_degrees());
        let lo = (-r).max(a.stroke.0.to_degrees());
        Ok(Program {
            name: "BK1".into(),
            axes: vec![a.name.clone()],
            waypoints_deg: vec![
                vec![0.0_f64.clamp(lo, hi)],
                vec![hi],
                vec![lo],
                vec![0.0_f64.clamp(lo, hi)],
            ],
            hold_deg: vec![],
            speed_deg_s: 12.0,
            step_deg: 2.0,
        })
    }

    /// BK2: the C axis one full turn one way and back (0 → 360° → 0).
    ///
    /// # Errors
    /// [`RtestError::UnknownAxis`] when the machine has no rotary C axis.
    pub fn bk2(m: &Machine) -> Result<Program> {
        let i = find_rotary(m, &["C"], "BK2")?;
        Ok(Program {
            name: "BK2".into(),
            axes: vec![kin::axes(m)[i].name.clone()],
            waypoints_deg: vec![vec![0.0], vec![360.0], vec![0.0]],
            hold_deg: vec![],
            speed_deg_s: 24.0,
            step_deg: 2.0,
        })
    }

    /// BK4: the tilt axis over its range (clipped ±`range_deg`, default 90°) and back while C
    /// turns at twice its speed (C = 2·(tilt − lowest tilt)); all linear axes follow.
    ///
    /// # Errors
    /// [`RtestError::UnknownAxis`] when the machine lacks a tilt (A/B) or a C axis.
    pub fn bk4(m: &Machine, range_deg: Option<f64>) -> Result<Program> {
        let it = find_rotary(m, &["B", "A"], "BK4")?;
        let ic = find_rotary(m, &["C"], "BK4")?;
        let axes = kin::axes(m);
        let r = range_deg.unwrap_or(90.0).abs();
        let hi = r.min(axes[it].stroke.1.to_degrees());
        let lo = (-r).max(axes[it].stroke.0.to_degrees());
        Ok(Program {
            name: "BK4".into(),
            axes: vec![axes[it].name.clone(), axes[ic].name.clone()],
            waypoints_deg: vec![vec![lo, 0.0], vec![hi, 2.0 * (hi - lo)], vec![lo, 0.0]],
            hold_deg: vec![],
            speed_deg_s: 24.0,
            step_deg: 2.0,
        })
    }

    /// A user-defined program.
    ///
    /// # Errors
    /// [`RtestError::UnknownAxis`] for an axis that is not a rotary axis of the machine,
    /// [`RtestError::TooShort`] for fewer than 2 waypoints, [`RtestError::Invalid`] for a
    /// waypoint of the wrong length, a non-finite value or a non-positive speed.
    pub fn custom(
        m: &Machine,
        name: &str,
        axes: &[&str],
        waypoints_deg: Vec<Vec<f64>>,
        speed_deg_s: f64,
    ) -> Result<Program> {
        let p = Program {
            name: name.into(),
            axes: axes.iter().map(|s| s.to_string()).collect(),
            waypoints_deg,
            hold_deg: vec![],
            speed_deg_s,
            step_deg: 2.0,
        };
        p.check(m)?;
        Ok(p)
    }

    /// The same program with a rotary axis held at `deg` (e.g. BK1 with C at 180°).
    pub fn with_hold(mut self, axis: &str, deg: f64) -> Program {
        self.hold_deg.retain(|(a, _)| a != axis);
        self.hold_deg.push((axis.into(), deg));
        self
    }

    /// The same program with another sampling step (degrees of the leading axis).
    pub fn with_step(mut self, step_deg: f64) -> Program {
        self.step_deg = step_deg;
        self
    }

    fn check(&self, m: &Machine) -> Result<()> {
        let axes = kin::axes(m);
        for a in self.axes.iter().chain(self.hold_deg.iter().map(|(a, _)| a)) {
            match axes.iter().find(|x| &x.name == a) {
                None => {
                    return Err(kin::unknown_axis(
                        m,
                        a,
                        &format!("program `{}`: not an axis of the machine", self.name),
                    ));
                }
                Some(x) if !x.rotary => {
                    return Err(kin::unknown_axis(
                        m,
                        a,
                        &format!(
                            "program `{}`: a linear axis; programs move rotary axes",
                            self.name
                        ),
                    ));
                }
                _ => {}
            }
        }
        if self.axes.is_empty() {
            return Err(RtestError::Invalid {
                field: format!("program `{}`.axes", self.name),
                message: "no axis to move".into(),
            });
        }
        if self.waypoints_deg.len() < 2 {
            return Err(RtestError::TooShort {
                what: format!("program `{}`", self.name),
                found: self.waypoints_deg.len(),
                needed: 2,
                unit: "waypoints".into(),
            });
        }
        for (k, w) in self.waypoints_deg.iter().enumerate() {
            if w.len() != self.axes.len() || w.iter().any(|v| !v.is_finite()) {
                return Err(RtestError::Invalid {
                    field: format!("program `{}`.waypoints_deg[{k}]", self.name),
                    message: format!(
                        "expected {} finite values (one per axis {:?})",
                        self.axes.len(),
                        self.axes
                    ),
                });
            }
        }
        if !(self.speed_deg_s > 0.0
            && self.speed_deg_s.is_finite()
            && self.step_deg > 0.0
            && self.step_deg.is_finite())
        {
            return Err(RtestError::Invalid {
                field: format!("program `{}`.speed_deg_s/step_deg", self.name),
                message: format!(
                    "must be positive and finite, found {} and {}",
                    self.speed_deg_s, self.step_deg
                ),
            });
        }
        Ok(())
    }

    /// Samples the program: rotary angles at every `step_deg` of the leading axis, with time.
    /// Linear axes are left at 0 (see [`command_linear_axes`]).
    ///
    /// # Errors
    /// As [`Program::custom`].
    pub fn sample(&self, m: &Machine) -> Result<Vec<ProgramSample>> {
        self.check(m)?;
        let axes = kin::axes(m);
        let idx: Vec<usize> = self
            .axes
            .iter()
            .map(|a| axes.iter().position(|x| &x.name == a).unwrap_or(0))
            .collect();
        let mut base = vec![0.0; axes.len()];
        for (a, v) in &self.hold_deg {
            if let Some(i) = axes.iter().position(|x| &x.name == a) {
                base[i] = v.to_radians();
            }
        }
        let mut out = Vec::new();
        let mut t0 = 0.0;
        for (k, pair) in self.waypoints_deg.windows(2).enumerate() {
            let (a, b) = (&pair[0], &pair[1]);
            let travel = a
                .iter()
                .zip(b)
                .map(|(x, y)| (y - x).abs())
                .fold(0.0, f64::max);
            let n = ((travel / self.step_deg).ceil() as usize).max(1);
            let dur = travel / self.speed_deg_s;
            let first = if k == 0 { 0 } else { 1 };
            for s in first..=n {
                let f = s as f64 / n as f64;
                let mut q = base.clone();
                for (j, &i) in idx.iter().enumerate() {
                    q[i] = (a[j] + f * (b[j] - a[j])).to_radians();
                }
                out.push(ProgramSample {
                    t_s: t0 + f * dur,
                    q,
                });
            }
            t0 += dur;
        }
        Ok(out)
    }
}

/// The three linear axes the controller uses to follow the ball: X, Y, Z by name, else the first
/// three linear axes.
pub(crate) fn follow_axes(m: &Machine) -> Result<[usize; 3]> {
    let axes = kin::axes(m);
    let by_name: Vec<usize> = ["X", "Y", "Z"]
        .iter()
        .filter_map(|n| axes.iter().position(|a| a.name == *n && !a.rotary))
        .collect();
    let lin: Vec<usize> = if by_name.len() == 3 {
        by_name
    } else {
        (0..axes.len())
            .filter(|&i| !axes[i].rotary)
            .take(3)
            .collect()
    };
    if lin.len() < 3 {
        return Err(RtestError::Inverse(format!(
            "machine `{}` has {} linear axes; the R-test needs three to follow the ball",
            m.name(),
            lin.len()
        )));
    }
    Ok([lin[0], lin[1], lin[2]])
}

/// Inverse kinematics with the rotary angles given: sets the three following linear axes of
/// `q` so that the nest centre `nest_mm` (tool frame) coincides with `ball_mm` (table frame) in
/// the controller's model with slot values `ctrl_e` (empty = nominal). With constant slot errors
/// the tool position is affine in the linear axes, so one solve is exact; a second pass guards
/// against round-off.
///
/// # Errors
/// [`RtestError::Inverse`] when the linear axis directions are (nearly) dependent.
pub fn command_linear_axes(
    m: &Machine,
    ctrl_e: &[f64],
    ball_mm: &Vec3,
    nest_mm: &Vec3,
    q: &mut [f64],
) -> Result<()> {
    let lin = follow_axes(m)?;
    let pos = |q: &[f64]| -> Vec3 {
        let (w, t) = kin::poses(m, q, ctrl_e);
        kin::apply(&w.inverse(), &kin::apply(&t, nest_mm))
    };
    for _ in 0..2 {
        let p0 = pos(q);
        let mut j = Mat3::zeros();
        for (c, &i) in lin.iter().enumerate() {
            let mut qq = q.to_vec();
            qq[i] += 1.0;
            j.set_column(c, &(pos(&qq) - p0));
        }
        let f = ball_mm - p0;
        let Some(inv) = j.try_inverse().filter(|_| j.determinant().abs() > 1e-9) else {
            return Err(RtestError::Inverse(format!(
                "linear axes cannot move the nest in all directions at q = {q:?}"
            )));
        };
        let dq = inv * f;
        for (c, &i) in lin.iter().enumerate() {
            q[i] += dq[c];
        }
    }
    Ok(())
}

/// Commanded axes for every sample of a program with the ball at `ball_mm`, checking strokes.
///
/// # Errors
/// [`RtestError::OutOfStroke`] when an axis leaves its stroke, errors of [`Program::sample`] and
/// [`command_linear_axes`].
pub fn command_program(
    m: &Machine,
    program: &Program,
    ctrl_e: &[f64],
    ball_mm: &Vec3,
    nest_mm: &Vec3,
) -> Result<Vec<ProgramSample>> {
    let mut samples = program.sample(m)?;
    let axes = kin::axes(m);
    for (k, s) in samples.iter_mut().enumerate() {
        command_linear_axes(m, ctrl_e, ball_mm, nest_mm, &mut s.q)?;
        for (i, a) in axes.iter().enumerate() {
            let v = s.q[i];
            let tol = 1e-9;
            if v < a.stroke.0 - tol || v > a.stroke.1 + tol {
                let (f, unit) = if a.rotary {
                    (180.0 / std::f64::consts::PI, "deg")
                } else {
                    (1.0, "mm")
                };
                return Err(RtestError::OutOfStroke {
                    program: program.name.clone(),
                    axis: a.name.clone(),
                    value: v * f,
                    lo: a.stroke.0 * f,
                    hi: a.stroke.1 * f,
                    unit: unit.into(),
                    sample: k,
                });
            }
        }
    }
    Ok(samples)
}
