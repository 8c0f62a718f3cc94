//! The thin adapter between this crate and `mte-kinematics`: every call into the kinematics
//! goes through here, so the rest of the crate sees one small, stable surface.

use crate::error::RtestError;
use mte_kinematics::{AxisKind, Machine};
use mte_linalg::{DMat, Iso3, Mat3, Vec3};

/// What the R-test needs to know about one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisInfo {
    /// Axis name ("X", "B", …).
    pub name: String,
    /// Rotary (true) or linear (false).
    pub rotary: bool,
    /// Stroke (mm or rad).
    pub stroke: (f64, f64),
    /// Body moved by the axis.
    pub body: usize,
}

pub(crate) fn axes(m: &Machine) -> Vec<AxisInfo> {
    m.axes()
        .iter()
        .map(|a| AxisInfo {
            name: a.name.clone(),
            rotary: matches!(a.kind, AxisKind::Rotary),
            stroke: a.stroke,
            body: a.body,
        })
        .collect()
}

pub(crate) fn axis_names(m: &Machine) -> Vec<String> {
    m.axes().iter().map(|a| a.name.clone()).collect()
}

pub(crate) fn unknown_axis(m: &Machine, name: &str, message: &str) -> RtestError {
    RtestError::UnknownAxis {
        name: name.to_string(),
        message: message.to_string(),
        machine: m.name().to_string(),
        known: axis_names(m).join(", "),
    }
}

/// (workpiece in base, tool in base), exact, with slot errors `e` (empty = ideal).
pub(crate) fn poses(m: &Machine, q: &[f64], e: &[f64]) -> (Iso3, Iso3) {
    let b = m.branch_poses(q, e);
    (b.workpiece_in_base, b.tool_in_base)
}

pub(crate) fn rot(g: &Iso3) -> Mat3 {
    g.rotation.to_rotation_matrix().into_inner()
}

pub(crate) fn apply(g: &Iso3, p: &Vec3) -> Vec3 {
    g.transform_point(&(*p).into()).coords
}

/// 6 × n_slots Jacobian of the pose error (rows px, py, pz, ox, oy, oz; workpiece frame) at e = 0.
pub(crate) fn jacobian(m: &Machine, q: &[f64]) -> DMat {
    m.jacobian(q).matrix
}
