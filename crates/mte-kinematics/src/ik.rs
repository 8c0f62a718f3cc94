//! Inverse kinematics: tool tip and tool axis in the workpiece frame → axis commands,
//! every solution branch within the strokes.
//!
//! The rotary axes are solved first from the tool axis alone: the tool orientation in the
//! workpiece frame is `R = R_Wᵀ · R_T`, a product of rotations about the home directions of
//! the rotary axes (workpiece-side ones reversed with negated angle, then tool-side ones in
//! chain order), applied to the home tool axis z₀ = +z. With two rotary axes this is
//! Paden–Kahan subproblem 2 (`Rot(u₁, φ₁)·Rot(u₂, φ₂)·z₀ = k`, zero, one or two
//! solutions), with one it is subproblem 1, with none the axis must already match.
//! Each rotary angle is then repeated by ±2π while it stays within its stroke. For each
//! rotary solution the tip position is affine in the linear axes, solved as a 3 × 3 system.

use crate::error::{KinError, Result};
use crate::machine::{AxisKind, Branch, Machine};
use mte_linalg::{Mat3, Vec3};
use std::f64::consts::PI;

/// Tool axis closer than this (sin of the angle) to the first rotary axis is singular.
const SINGULAR_SIN: f64 = 1e-9;
/// Tolerance for the tool axis being producible (dot-product residual).
const REACH_TOL: f64 = 1e-10;
/// Stroke tolerance: rad for rotary, mm for linear axes.
const STROKE_TOL: f64 = 1e-9;

/// Angle φ with `Rot(u, φ)·x = y` (Paden–Kahan subproblem 1; u unit, u·x = u·y assumed).
fn subproblem1(u: &Vec3, x: &Vec3, y: &Vec3) -> f64 {
    let xp = x - u * u.dot(x);
    let yp = y - u * u.dot(y);
    u.dot(&xp.cross(&yp)).atan2(xp.dot(&yp))
}

fn rot(u: &Vec3, a: f64) -> Mat3 {
    mte_linalg::so3::exp(&(u * a))
}

struct RotaryStep {
    axis: usize,
    u: Vec3,
    /// q = factor · φ (factor = sign for tool side, −sign for workpiece side; ±1)
    factor: f64,
}

impl Machine {
    /// Every axis solution (in [`Machine::axes`] order, mm and rad) that puts the tool tip at
    /// `tip_mm` with tool axis `tool_axis` (both in the workpiece frame, ideal machine).
    /// Rotary axes: every branch of the orientation solution and every equivalent angle
    /// (±2π) within the stroke. Solutions are sorted lexicographically.
    ///
    /// Supported structures: 3 linear axes plus 0, 1 or 2 rotary axes on either branch
    /// (3-axis, 4-axis, table–table, head–head, head–table).
    ///
    /// # Errors
    /// - [`KinError::Singular`] when an axis is not determined (tool axis parallel to the
    ///   first rotary axis in the product above, e.g. A = 0 on an AC table or a CA head;
    ///   or a rotary axis parallel to the tool axis at home);
    /// - [`KinError::Unreachable`] when the tool axis cannot be produced (non-finite or zero
    ///   input, a 3-axis machine asked for another axis, …);
    /// - [`KinError::OutOfStroke`] when solutions exist but none is within the strokes;
    /// - [`KinError::UnsupportedStructure`] for other structures.
    ///
    /// ```
    /// use mte_kinematics::{Machine, KinError};
    /// use mte_linalg::Vec3;
    /// let m = Machine::library("seed003-ac-table").unwrap();
    /// // vertical tool: A = 0 and C is free — a singular configuration, reported as such
    /// let r = m.inverse(&Vec3::new(10.0, 20.0, 30.0), &Vec3::z());
    /// assert!(matches!(r, Err(KinError::Singular { .. })));
    /// ```
    pub fn inverse(&self, tip_mm: &Vec3, tool_axis: &Vec3) -> Result<Vec<Vec<f64>>> {
        if !tip_mm.iter().chain(tool_axis.iter()).all(|x| x.is_finite()) {
            return Err(KinError::Unreachable {
                reason: format!("non-finite input: tip {tip_mm:?}, axis {tool_axis:?}"),
            });
        }
        let n = tool_axis.norm();
        if n < 1e-12 {
            return Err(KinError::Unreachable {
                reason: "tool axis has zero length".into(),
            });
        }
        let k = tool_axis / n;
        let unsupported = |reason: String| KinError::UnsupportedStructure {
            machine: self.name.clone(),
            reason,
        };
        for a in &self.axes {
            if matches!(a.branch, Branch::Shared | Branch::Neither) {
                return Err(unsupported(format!(
                    "axis {} moves both branches or neither, so it does not change the tool pose",
                    a.name
                )));
            }
        }
        let linear: Vec<usize> = (0..self.axes.len())
            .filter(|&i| self.axes[i].kind == AxisKind::Linear)
            .collect();
        if linear.len() != 3 {
            return Err(unsupported(format!(
                "{} linear axes (inverse kinematics needs exactly 3)",
                linear.len()
            )));
        }
        // rotation sequence: workpiece-side rotaries reversed (negated), then tool side
        let mut steps: Vec<RotaryStep> = Vec::new();
        for &j in self.wp_chain.iter().rev() {
            if let Some((AxisKind::Rotary, _, a)) = self.consts[j].joint {
                let ax = &self.axes[a];
                steps.push(RotaryStep {
                    axis: a,
                    u: ax.direction,
                    factor: -ax.sign,
                });
            }
        }
        for &j in &self.tool_chain {
            if let Some((AxisKind::Rotary, _, a)) = self.consts[j].joint {
                let ax = &self.axes[a];
                steps.push(RotaryStep {
                    axis: a,
                    u: ax.direction,
                    factor: ax.sign,
                });
            }
        }
        let z0 = Vec3::z();
        // angle sets φ (one per step)
        let phis: Vec<Vec<f64>> = match steps.len() {
            0 => {
                if (k - z0).norm() > REACH_TOL {
                    return Err(KinError::Unreachable {
                        reason: format!(
                            "machine {} has no rotary axis; its tool axis is always (0, 0, 1), asked for {:?}",
                            self.name,
                            [k.x, k.y, k.z]
                        ),
                    });
                }
                vec![vec![]]
            }
            1 => {
                let u = steps[0].u;
                if u.cross(&z0).norm() < SINGULAR_SIN {
                    return Err(KinError::Singular {
                        axis: self.axes[steps[0].axis].name.clone(),
                        reason: "the rotary axis is parallel to the tool axis".into(),
                    });
                }
                if (u.dot(&k) - u.dot(&z0)).abs() > REACH_TOL {
                    return Err(KinError::Unreachable {
                        reason: format!(
                            "axis {} keeps the tool axis at {:.6}° from its own direction; asked for {:.6}°",
                            self.axes[steps[0].axis].name,
                            u.dot(&z0).clamp(-1.0, 1.0).acos().to_degrees(),
                            u.dot(&k).clamp(-1.0, 1.0).acos().to_degrees()
                        ),
                    });
                }
                vec![vec![subproblem1(&u, &z0, &k)]]
            }
            2 => self.subproblem2(&steps, &k, &z0)?,
            m => {
                return Err(unsupported(format!(
                    "{m} rotary axes (supported: 0, 1 or 2)"
                )));
            }
        };

        let mut sols: Vec<Vec<f64>> = Vec::new();
        let mut rejected: Vec<String> = Vec::new();
        for phi in &phis {
            // every equivalent rotary command within the stroke
            let mut partial: Vec<Vec<f64>> = vec![vec![0.0; self.axes.len()]];
            for (st, &p) in steps.iter().zip(phi) {
                let ax = &self.axes[st.axis];
                let base = st.factor * p;
                let (lo, hi) = ax.stroke;
                let m0 = ((lo - base) / (2.0 * PI)).ceil() as i64 - 1;
                let m1 = ((hi - base) / (2.0 * PI)).floor() as i64 + 1;
                let cands: Vec<f64> = (m0..=m1)
                    .map(|m| base + 2.0 * PI * m as f64)
                    .filter(|v| *v >= lo - STROKE_TOL && *v <= hi + STROKE_TOL)
                    .map(|v| v.clamp(lo, hi))
                    .collect();
                if cands.is_empty() {
                    rejected.push(format!(
                        "{} = {:.6}° (mod 360°) outside [{:.3}°, {:.3}°]",
                        ax.name,
                        base.to_degrees(),
                        lo.to_degrees(),
                        hi.to_degrees()
                    ));
                }
                partial = partial
                    .into_iter()
                    .flat_map(|s| {
                        cands.iter().map(move |&v| {
                            let mut s = s.clone();
                            s[st.axis] = v;
                            s
                        })
                    })
                    .collect();
            }
            for mut s in partial {
                // tip position is affine in the linear axes
                for &i in &linear {
                    s[i] = 0.0;
                }
                let p0 = self.tool_in_workpiece(&s, &[]).translation.vector;
                let mut a = Mat3::zeros();
                const STEP: f64 = 100.0;
                for (c, &i) in linear.iter().enumerate() {
                    s[i] = STEP;
                    let p = self.tool_in_workpiece(&s, &[]).translation.vector;
                    a.set_column(c, &((p - p0) / STEP));
                    s[i] = 0.0;
                }
                let Some(ainv) = a.try_inverse().filter(|_| a.determinant().abs() > 1e-9) else {
                    return Err(unsupported(
                        "the linear axes do not span 3-D space at this rotary position".into(),
                    ));
                };
                let x = ainv * (tip_mm - p0);
                let mut ok = true;
                for (c, &i) in linear.iter().enumerate() {
                    let (lo, hi) = self.axes[i].stroke;
                    let tol = STROKE_TOL * (1.0 + lo.abs().max(hi.abs()));
                    if x[c] < lo - tol || x[c] > hi + tol {
                        ok = false;
                        rejected.push(format!(
                            "{} = {:.6} mm outside [{}, {}] (with {})",
                            self.axes[i].name,
                            x[c],
                            lo,
                            hi,
                            self.describe_rotaries(&s)
                        ));
                    }
                    s[i] = x[c].clamp(lo, hi);
                }
                if ok {
                    sols.push(s);
                }
            }
        }
        if sols.is_empty() {
            return Err(KinError::OutOfStroke {
                reason: rejected.join("; "),
            });
        }
        sols.sort_by(|a, b| {
            a.iter()
                .zip(b)
                .map(|(x, y)| x.total_cmp(y))
                .find(|o| o.is_ne())
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        sols.dedup_by(|a, b| a.iter().zip(b.iter()).all(|(x, y)| (x - y).abs() < 1e-12));
        Ok(sols)
    }

    fn describe_rotaries(&self, s: &[f64]) -> String {
        let v: Vec<String> = self
            .axes
            .iter()
            .zip(s)
            .filter(|(a, _)| a.kind == AxisKind::Rotary)
            .map(|(a, v)| format!("{} = {:.6}°", a.name, v.to_degrees()))
            .collect();
        if v.is_empty() {
            "no rotary axes".into()
        } else {
            v.join(", ")
        }
    }

    /// Paden–Kahan subproblem 2 on directions: `Rot(u1, φ1)·Rot(u2, φ2)·z0 = k`.
    fn subproblem2(&self, steps: &[RotaryStep], k: &Vec3, z0: &Vec3) -> Result<Vec<Vec<f64>>> {
        let (u1, u2) = (steps[0].u, steps[1].u);
        let (n1, n2) = (
            &self.axes[steps[0].axis].name,
            &self.axes[steps[1].axis].name,
        );
        let cr = u1.cross(&u2);
        let s2 = cr.norm_squared();
        if s2 < 1e-18 {
            return Err(KinError::UnsupportedStructure {
                machine: self.name.clone(),
                reason: format!("rotary axes {n1} and {n2} are parallel"),
            });
        }
        if u2.cross(z0).norm() < SINGULAR_SIN {
            return Err(KinError::Singular {
                axis: n2.clone(),
                reason: format!("axis {n2} is parallel to the tool axis at home"),
            });
        }
        if u1.cross(k).norm() < SINGULAR_SIN {
            return Err(KinError::Singular {
                axis: n1.clone(),
                reason: format!(
                    "tool axis {:?} is parallel to the rotary axis {n1}",
                    [k.x, k.y, k.z]
                ),
            });
        }
        // c = Rot(u2, φ2) z0 = Rot(u1, −φ1) k: u1·c = u1·k, u2·c = u2·z0, |c| = 1
        let d = u1.dot(&u2);
        let (a1, a2) = (u1.dot(k), u2.dot(z0));
        let den = 1.0 - d * d;
        let alpha = (a1 - d * a2) / den;
        let beta = (a2 - d * a1) / den;
        let g2 = (1.0 - alpha * alpha - beta * beta - 2.0 * alpha * beta * d) / s2;
        if g2 < -REACH_TOL {
            return Err(KinError::Unreachable {
                reason: format!(
                    "tool axis {:?} is beyond the tilt range of axes {n1}/{n2}",
                    [k.x, k.y, k.z]
                ),
            });
        }
        let gammas: Vec<f64> = if g2 <= REACH_TOL {
            vec![0.0]
        } else {
            let g = g2.sqrt();
            vec![g, -g]
        };
        let mut out = Vec::new();
        for g in gammas {
            let c = u1 * alpha + u2 * beta + cr * g;
            let phi2 = subproblem1(&u2, z0, &c);
            let phi1 = subproblem1(&u1, &c, k);
            // guard against round-off on the way back
            let back = rot(&u1, phi1) * rot(&u2, phi2) * z0;
            if (back - k).norm() < 1e-8 {
                out.push(vec![phi1, phi2]);
            }
        }
        if out.is_empty() {
            return Err(KinError::Unreachable {
                reason: format!("no rotation of axes {n1}/{n2} produces tool axis {k:?}"),
            });
        }
        Ok(out)
    }
}
