//! Machine description: bodies, joints, axes, error slots, and its versioned JSON form
//! (`"format": "mte-machine/1"`, documented in `docs/formats.md` and `docs/conventions.md`).

use crate::error::{KinError, Result};
use mte_linalg::Vec3;
use mte_linalg::json::{self, Tagged};
use serde::Deserialize;
use std::collections::HashMap;
use std::path::Path;

/// The format tag every machine file carries.
pub const FORMAT: &str = "mte-machine/1";

/// Kind of a machine axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AxisKind {
    /// Translation along the axis direction (command in mm).
    Linear,
    /// Rotation about the axis line (command in rad).
    Rotary,
}

/// Which kinematic branch a body belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Branch {
    /// The bed, and any body both branches pass through.
    Shared,
    /// Between the bed and the tool (the tool included).
    Tool,
    /// Between the bed and the workpiece (the workpiece included).
    Workpiece,
    /// On neither branch (has no effect on the tool pose).
    Neither,
}

/// A commanded machine axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Axis name as commanded ("X", "Y", "Z", "A", "B", "C", "W", …).
    pub name: String,
    /// Linear or rotary.
    pub kind: AxisKind,
    /// Index of the body this axis moves (its joint is between the body and its parent).
    pub body: usize,
    /// Stroke (min, max): mm for linear axes, rad for rotary axes.
    pub stroke: (f64, f64),
    /// Unit direction of motion / rotation axis in the parent frame at home
    /// (at home every body frame is parallel to the bed frame).
    pub direction: Vec3,
    /// +1 or −1: the body moves by `sign · q` along `direction` (linear) or turns by
    /// `sign · q` about `direction`, right-hand rule (rotary). ISO 841 makes table axes −1
    /// so that +q moves the tool relative to the workpiece in the + sense.
    pub sign: f64,
    /// Branch the axis sits on.
    pub branch: Branch,
}

/// Joint between a body and its parent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Joint {
    /// Rigidly attached (tool, workpiece, spindle housing, bed).
    Fixed,
    /// Moved by axis `axis` (index into [`Machine::axes`]); linear or rotary as the axis says.
    Axis(usize),
}

/// A rigid body of the machine. Body 0 is the bed (the machine reference frame).
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Name ("bed", "X", "C", "spindle", "tool", "workpiece", …). Axis bodies carry the axis name.
    pub name: String,
    /// Parent body (None only for the bed).
    pub parent: Option<usize>,
    /// Origin of this body's frame in the parent frame at home (q = 0), mm. For a rotary
    /// body this point lies on the rotation axis (the pivot).
    pub offset_mm: Vec3,
    /// The joint to the parent.
    pub joint: Joint,
    /// Whether the body has 6 motion-error slots (every moving body; optionally a
    /// fixed body such as a spindle, for its error motions).
    pub motion_errors: bool,
    /// Branch of the body.
    pub branch: Branch,
}

/// Kind of an error slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SlotKind {
    /// Constant, between the parent and the joint: location / assembly / squareness /
    /// setup errors. T = P·**ΔP**·S·ΔS.
    Position,
    /// After the joint motion, in the moved body frame: component errors, functions of
    /// the axis coordinate (evaluated by the caller at q). T = P·ΔP·S·**ΔS**.
    Motion,
}

/// Component of a 6-vector error: translations δ (mm) then rotations ε (rad).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Component {
    /// δx, mm.
    Dx,
    /// δy, mm.
    Dy,
    /// δz, mm.
    Dz,
    /// εx (about x), rad.
    Ex,
    /// εy (about y), rad.
    Ey,
    /// εz (about z), rad.
    Ez,
}

impl Component {
    /// All six in vector order.
    pub const ALL: [Component; 6] = [
        Component::Dx,
        Component::Dy,
        Component::Dz,
        Component::Ex,
        Component::Ey,
        Component::Ez,
    ];
    /// Index 0..6 in the (δ ; ε) 6-vector.
    pub fn index(self) -> usize {
        self as usize
    }
    /// Short name: "dx", "dy", "dz", "ex", "ey", "ez".
    pub fn name(self) -> &'static str {
        ["dx", "dy", "dz", "ex", "ey", "ez"][self as usize]
    }
    /// True for δ (mm), false for ε (rad).
    pub fn is_translation(self) -> bool {
        (self as usize) < 3
    }
}

/// One scalar entry of the error vector.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ErrorSlot {
    /// The body whose transform the error perturbs.
    pub body: usize,
    /// Position (before the joint) or motion (after the joint).
    pub kind: SlotKind,
    /// Which component.
    pub component: Component,
}

/// Per-body constants used by the evaluators.
#[derive(Debug, Clone)]
pub(crate) struct BodyConst {
    /// Home position of the body origin in the bed frame (C_j of the POE form).
    pub home: Vec3,
    /// First position slot index (6 consecutive), if any.
    pub pos_slot: Option<usize>,
    /// First motion slot index (6 consecutive), if any.
    pub mot_slot: Option<usize>,
    /// Signed unit direction `sign · direction` and kind, for moving bodies.
    pub joint: Option<(AxisKind, Vec3, usize)>,
}

/// A machine: bodies, axes, error slots and precomputed chains. Immutable once built;
/// cheap to share across threads (`Sync`).
#[derive(Debug, Clone)]
pub struct Machine {
    pub(crate) name: String,
    pub(crate) description: String,
    pub(crate) bodies: Vec<Body>,
    pub(crate) axes: Vec<Axis>,
    pub(crate) slots: Vec<ErrorSlot>,
    pub(crate) slot_names: Vec<String>,
    pub(crate) tool: usize,
    pub(crate) workpiece: usize,
    pub(crate) consts: Vec<BodyConst>,
    /// Bodies from the bed (excluded) to the tool (included), outward.
    pub(crate) tool_chain: Vec<usize>,
    /// Bodies from the bed (excluded) to the workpiece (included), outward.
    pub(crate) wp_chain: Vec<usize>,
    pub(crate) json: String,
}

/// The file as written; [`Machine::parse`] checks what serde cannot (names, topology, ranges).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MachineJson {
    #[serde(rename = "format")]
    _format: String,
    name: String,
    description: Option<String>,
    #[serde(rename = "source")]
    _source: Option<String>,
    bodies: Vec<BodyJson>,
    tool: String,
    workpiece: String,
    axis_order: Option<Vec<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BodyJson {
    name: String,
    parent: Option<String>,
    offset_mm: Option<[f64; 3]>,
    joint: Option<Tagged<JointJson>>,
    motion_errors: Option<bool>,
    #[serde(rename = "note")]
    _note: Option<String>,
}

#[derive(Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
enum JointJson {
    Fixed {},
    Linear {
        axis: String,
        direction: [f64; 3],
        sign: f64,
        stroke_mm: [f64; 2],
    },
    Rotary {
        axis: String,
        direction: [f64; 3],
        sign: f64,
        stroke_deg: [f64; 2],
    },
}

/// Largest length in a machine file, mm (10 km: beyond it a number is a typo, not a machine).
const MAX_LENGTH_MM: f64 = 1e7;
/// Largest rotary stroke end, degrees (about 2 800 turns).
const MAX_ANGLE_DEG: f64 = 1e6;

impl Machine {
    /// Parse and validate a machine description (`"format": "mte-machine/1"`).
    ///
    /// # Errors
    /// [`KinError::Json`] for malformed JSON; [`KinError::Field`] naming the field for a
    /// missing or unknown field, wrong type, a number beyond a machine's size, zero-length
    /// direction, unknown body or axis name, duplicate names, or a cycle in the topology.
    ///
    /// ```
    /// use mte_kinematics::Machine;
    /// let bad = r#"{"format": "mte-machine/1", "name": "m", "tool": "t", "workpiece": "bed",
    ///   "bodies": [{"name": "bed"}, {"name": "t", "parent": "bed", "offset_mm": [0, 0, 0],
    ///   "joint": {"type": "linear", "axis": "Z", "direction": [0, 0, 0], "sign": 1, "stroke_mm": [0, 1]}}]}"#;
    /// let err = Machine::from_json_str(bad).unwrap_err().to_string();
    /// assert!(err.contains("bodies[1].joint.direction"), "{err}");
    /// ```
    pub fn from_json_str(s: &str) -> Result<Machine> {
        Self::parse(s, "<string>")
    }

    /// Read and parse a machine file (a regular file; a UTF-8 byte-order mark is dropped);
    /// errors name the file.
    ///
    /// # Errors
    /// [`KinError::Io`] if the file cannot be read, otherwise as [`Machine::from_json_str`].
    pub fn from_file(p: &Path) -> Result<Machine> {
        let text = mte_linalg::text::read_text(p).map_err(|e| KinError::Io {
            path: p.display().to_string(),
            message: e.to_string(),
        })?;
        Self::parse(&text, &p.display().to_string())
    }

    pub(crate) fn parse(s: &str, src: &str) -> Result<Machine> {
        let err = |field: &str, message: String| KinError::Field {
            source_name: src.to_string(),
            field: if field.is_empty() { "(root)" } else { field }.to_string(),
            message,
        };
        let root = json::parse(s).map_err(|e| KinError::Json {
            source_name: src.to_string(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })?;
        let file: MachineJson = json::check_format(&root, FORMAT)
            .and_then(|()| json::from_value(&root))
            .map_err(|e| err(&e.path, e.message))?;
        let raw = &file.bodies;
        if raw.len() < 2 {
            return Err(err(
                "bodies",
                "expected at least the bed and one more body".into(),
            ));
        }
        let name_ok =
            |n: &str| !(n.is_empty() || n.contains(char::is_whitespace) || n.contains('.'));
        let mut index: HashMap<&str, usize> = HashMap::new();
        let mut axes: Vec<Axis> = Vec::new();
        let mut axis_of_body = vec![None; raw.len()];
        for (i, b) in raw.iter().enumerate() {
            let path = format!("bodies[{i}]");
            if !name_ok(&b.name) {
                return Err(err(
                    &format!("{path}.name"),
                    format!(
                        "body name {:?} must be non-empty, without spaces or dots",
                        b.name
                    ),
                ));
            }
            if let Some(prev) = index.insert(b.name.as_str(), i) {
                return Err(err(
                    &format!("{path}.name"),
                    format!("duplicate body name {:?} (also bodies[{prev}])", b.name),
                ));
            }
            match (i, &b.parent, &b.offset_mm, &b.joint) {
                (0, Some(_), _, _) => {
                    return Err(err(
                        &format!("{path}.parent"),
                        "the first body is the bed and has no parent (expected null or no field)"
                            .into(),
                    ));
                }
                (0, _, Some(o), _) if *o != [0.0; 3] => {
                    return Err(err(
                        &format!("{path}.offset_mm"),
                        "the bed defines the machine frame; its offset must be [0, 0, 0]".into(),
                    ));
                }
                (0, _, _, Some(Tagged(JointJson::Linear { .. } | JointJson::Rotary { .. }))) => {
                    return Err(err(
                        &format!("{path}.joint"),
                        "the bed cannot have a moving joint".into(),
                    ));
                }
                (1.., None, _, _) => {
                    return Err(err(
                        &format!("{path}.parent"),
                        "missing field (expected the name of the parent body; only bodies[0], the bed, has none)".into(),
                    ));
                }
                (1.., _, None, _) => {
                    return Err(err(
                        &format!("{path}.offset_mm"),
                        "missing field (expected an array of 3 numbers)".into(),
                    ));
                }
                _ => {}
            }
            for (k, x) in b.offset_mm.unwrap_or_default().iter().enumerate() {
                if x.abs() > MAX_LENGTH_MM {
                    return Err(err(
                        &format!("{path}.offset_mm[{k}]"),
                        format!("{x} mm is beyond any machine (at most {MAX_LENGTH_MM:e} mm)"),
                    ));
                }
            }
            let (kind, axis, direction, sign, stroke, key, max) = match &b.joint {
                None | Some(Tagged(JointJson::Fixed {})) => continue,
                Some(Tagged(JointJson::Linear {
                    axis,
                    direction,
                    sign,
                    stroke_mm,
                })) => (
                    AxisKind::Linear,
                    axis,
                    direction,
                    *sign,
                    *stroke_mm,
                    "stroke_mm",
                    MAX_LENGTH_MM,
                ),
                Some(Tagged(JointJson::Rotary {
                    axis,
                    direction,
                    sign,
                    stroke_deg,
                })) => (
                    AxisKind::Rotary,
                    axis,
                    direction,
                    *sign,
                    *stroke_deg,
                    "stroke_deg",
                    MAX_ANGLE_DEG,
                ),
            };
            let path = format!("{path}.joint");
            if !name_ok(axis) {
                return Err(err(
                    &format!("{path}.axis"),
                    format!("axis name {axis:?} must be non-empty, without spaces or dots"),
                ));
            }
            if let Some(k) = axes.iter().position(|a| a.name == *axis) {
                return Err(err(
                    &format!("{path}.axis"),
                    format!(
                        "duplicate axis name {axis:?} (also bodies[{}].joint.axis)",
                        axes[k].body
                    ),
                ));
            }
            // scaled by the largest component first: [1e300, 1e300, 0] is a direction too
            let d = Vec3::from(*direction);
            let scale = d.amax();
            if scale < 1e-9 {
                return Err(err(
                    &format!("{path}.direction"),
                    format!("zero-length direction {direction:?} (expected a non-zero 3-vector)"),
                ));
            }
            if sign != 1.0 && sign != -1.0 {
                return Err(err(
                    &format!("{path}.sign"),
                    format!("expected 1 or -1, found {sign}"),
                ));
            }
            if stroke[0] > stroke[1] || stroke.iter().any(|x| x.abs() > max) {
                return Err(err(
                    &format!("{path}.{key}"),
                    format!(
                        "expected [min, max] with min <= max, each within ±{max:e}, found [{}, {}]",
                        stroke[0], stroke[1]
                    ),
                ));
            }
            axis_of_body[i] = Some(axes.len());
            axes.push(Axis {
                name: axis.clone(),
                kind,
                body: i,
                stroke: match kind {
                    AxisKind::Linear => (stroke[0], stroke[1]),
                    AxisKind::Rotary => (stroke[0].to_radians(), stroke[1].to_radians()),
                },
                direction: (d / scale).normalize(),
                sign,
                branch: Branch::Neither,
            });
        }
        let known_bodies = || {
            raw.iter()
                .map(|b| b.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let body_ref = |field: &str, name: &str| -> Result<usize> {
            index.get(name).copied().ok_or_else(|| {
                err(
                    field,
                    format!(
                        "unknown body {name:?} (bodies: {}){}",
                        known_bodies(),
                        json::did_you_mean(name, raw.iter().map(|b| &b.name))
                    ),
                )
            })
        };
        let mut parents = vec![None; raw.len()];
        for (i, b) in raw.iter().enumerate().skip(1) {
            let pi = body_ref(
                &format!("bodies[{i}].parent"),
                b.parent.as_deref().unwrap_or(""),
            )?;
            if pi == i {
                return Err(err(
                    &format!("bodies[{i}].parent"),
                    format!("cycle in the topology: body {:?} is its own parent", b.name),
                ));
            }
            parents[i] = Some(pi);
        }
        // cycle detection: every body must reach the bed within len steps
        for i in 0..raw.len() {
            let mut j = i;
            let mut path = vec![raw[i].name.as_str()];
            while let Some(p) = parents[j] {
                j = p;
                path.push(&raw[j].name);
                if path.len() > raw.len() + 1 {
                    path.pop();
                    return Err(err(
                        &format!("bodies[{i}].parent"),
                        format!(
                            "cycle in the topology: {} … never reaches the bed {:?}",
                            path.join(" → "),
                            raw[0].name
                        ),
                    ));
                }
            }
        }
        let tool = body_ref("tool", &file.tool)?;
        let workpiece = body_ref("workpiece", &file.workpiece)?;
        if tool == workpiece {
            return Err(err(
                "tool",
                "tool and workpiece must be different bodies".into(),
            ));
        }

        // axes in body order, then reordered by axis_order
        let mut order: Vec<usize> = (0..axes.len()).collect();
        if let Some(names) = &file.axis_order {
            let known = axes.iter().map(|a| a.name.as_str()).collect::<Vec<_>>();
            order.clear();
            for (k, nm) in names.iter().enumerate() {
                let pos = axes.iter().position(|a| a.name == *nm).ok_or_else(|| {
                    err(
                        &format!("axis_order[{k}]"),
                        format!(
                            "unknown axis {nm:?} (machine axes: {}){}",
                            known.join(", "),
                            json::did_you_mean(nm, &known)
                        ),
                    )
                })?;
                if let Some(prev) = order.iter().position(|&p| p == pos) {
                    return Err(err(
                        &format!("axis_order[{k}]"),
                        format!("axis {nm:?} listed twice (also axis_order[{prev}])"),
                    ));
                }
                order.push(pos);
            }
            if order.len() != axes.len() {
                let missing: Vec<_> = (0..axes.len())
                    .filter(|p| !order.contains(p))
                    .map(|p| axes[p].name.as_str())
                    .collect();
                return Err(err(
                    "axis_order",
                    format!("axes missing from axis_order: {}", missing.join(", ")),
                ));
            }
        }
        let bodies = raw
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let joint = match axis_of_body[i] {
                    None => Joint::Fixed,
                    Some(a) => Joint::Axis(order.iter().position(|&p| p == a).expect("ordered")),
                };
                if joint != Joint::Fixed && b.motion_errors == Some(false) {
                    return Err(err(
                        &format!("bodies[{i}].motion_errors"),
                        "a moving body always has motion-error slots (expected true or no field)"
                            .into(),
                    ));
                }
                Ok(Body {
                    name: b.name.clone(),
                    parent: parents[i],
                    offset_mm: Vec3::from(b.offset_mm.unwrap_or_default()),
                    joint,
                    motion_errors: b.motion_errors.unwrap_or(joint != Joint::Fixed),
                    branch: Branch::Neither,
                })
            })
            .collect::<Result<Vec<Body>>>()?;
        let axes = order.iter().map(|&p| axes[p].clone()).collect();
        Ok(Machine::build(
            file.name,
            file.description.unwrap_or_default(),
            bodies,
            axes,
            tool,
            workpiece,
            s.to_string(),
        ))
    }

    /// Assemble the derived data (branches, chains, slots, home positions).
    pub(crate) fn build(
        name: String,
        description: String,
        mut bodies: Vec<Body>,
        mut axes: Vec<Axis>,
        tool: usize,
        workpiece: usize,
        json: String,
    ) -> Machine {
        let chain_to = |end: usize, bodies: &[Body]| {
            let mut c = vec![];
            let mut j = end;
            while let Some(p) = bodies[j].parent {
                c.push(j);
                j = p;
            }
            c.reverse();
            c
        };
        let tool_chain = chain_to(tool, &bodies);
        let wp_chain = chain_to(workpiece, &bodies);
        for (i, b) in bodies.iter_mut().enumerate() {
            let on_t = i == 0 || tool_chain.contains(&i);
            let on_w = i == 0 || wp_chain.contains(&i);
            b.branch = match (on_t, on_w) {
                (true, true) => Branch::Shared,
                (true, false) => Branch::Tool,
                (false, true) => Branch::Workpiece,
                (false, false) => Branch::Neither,
            };
        }
        for a in &mut axes {
            a.branch = bodies[a.body].branch;
        }
        let mut slots = Vec::new();
        let mut slot_names = Vec::new();
        let mut consts = Vec::with_capacity(bodies.len());
        for (i, b) in bodies.iter().enumerate() {
            let mut home = b.offset_mm;
            let mut j = i;
            while let Some(p) = bodies[j].parent {
                home += bodies[p].offset_mm;
                j = p;
            }
            let mut c = BodyConst {
                home,
                pos_slot: None,
                mot_slot: None,
                joint: match b.joint {
                    Joint::Fixed => None,
                    Joint::Axis(k) => Some((axes[k].kind, axes[k].direction * axes[k].sign, k)),
                },
            };
            if i == 0 {
                consts.push(c);
                continue;
            }
            for (kind, label) in [
                (SlotKind::Position, "position"),
                (SlotKind::Motion, "motion"),
            ] {
                if kind == SlotKind::Motion && !b.motion_errors {
                    continue;
                }
                let start = slots.len();
                for comp in Component::ALL {
                    slots.push(ErrorSlot {
                        body: i,
                        kind,
                        component: comp,
                    });
                    slot_names.push(format!("{}.{label}.{}", b.name, comp.name()));
                }
                match kind {
                    SlotKind::Position => c.pos_slot = Some(start),
                    SlotKind::Motion => c.mot_slot = Some(start),
                }
            }
            consts.push(c);
        }
        Machine {
            name,
            description,
            bodies,
            axes,
            slots,
            slot_names,
            tool,
            workpiece,
            consts,
            tool_chain,
            wp_chain,
            json,
        }
    }

    /// Machine name (e.g. "seed003-ac-table").
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Free-text description from the file (geometry choices, sources).
    pub fn description(&self) -> &str {
        &self.description
    }
    /// The JSON text the machine was read from.
    pub fn json(&self) -> &str {
        &self.json
    }
    /// Moving axes in command order (the order of `q`).
    pub fn axes(&self) -> &[Axis] {
        &self.axes
    }
    /// Index of the axis with this name in [`Machine::axes`].
    pub fn axis_index(&self, name: &str) -> Option<usize> {
        self.axes.iter().position(|a| a.name == name)
    }
    /// All bodies; 0 is the bed.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }
    /// Index of the body with this name.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }
    /// The workpiece body.
    pub fn workpiece_body(&self) -> usize {
        self.workpiece
    }
    /// The tool body (its frame origin is the tool tip; tool axis = +z of its frame).
    pub fn tool_body(&self) -> usize {
        self.tool
    }
    /// Bodies from the bed (excluded) out to the tool (included).
    pub fn tool_chain(&self) -> &[usize] {
        &self.tool_chain
    }
    /// Bodies from the bed (excluded) out to the workpiece (included).
    pub fn workpiece_chain(&self) -> &[usize] {
        &self.wp_chain
    }
    /// Error slots in canonical order: bodies in index order, per body 6 position slots
    /// (dx, dy, dz, ex, ey, ez) then, if it has them, 6 motion slots.
    pub fn error_slots(&self) -> &[ErrorSlot] {
        &self.slots
    }
    /// Number of error slots (the length of `e`).
    pub fn n_slots(&self) -> usize {
        self.slots.len()
    }
    /// Index of a slot in the error vector.
    pub fn slot_index(&self, slot: ErrorSlot) -> Option<usize> {
        let c = self.consts.get(slot.body)?;
        let start = match slot.kind {
            SlotKind::Position => c.pos_slot?,
            SlotKind::Motion => c.mot_slot?,
        };
        Some(start + slot.component.index())
    }
    /// Index of the slot with this name ("X.motion.dx", "C.position.ey", "tool.position.dz").
    pub fn slot_index_by_name(&self, name: &str) -> Option<usize> {
        self.slot_names.iter().position(|s| s == name)
    }
    /// Machine-level name of slot `i`: `"{body}.{position|motion}.{dx|dy|dz|ex|ey|ez}"`.
    ///
    /// # Panics
    /// If `i >= n_slots()`.
    pub fn slot_name(&self, i: usize) -> &str {
        &self.slot_names[i]
    }
    /// All slot names in slot order.
    pub fn slot_names(&self) -> &[String] {
        &self.slot_names
    }
    /// The axis whose body slot `i` belongs to (None for tool, workpiece, spindle, …).
    ///
    /// # Panics
    /// If `i >= n_slots()`.
    pub fn slot_axis(&self, i: usize) -> Option<&Axis> {
        match self.bodies[self.slots[i].body].joint {
            Joint::Axis(k) => Some(&self.axes[k]),
            Joint::Fixed => None,
        }
    }
    /// The body after `body` on its kinematic branch, and whether that branch is the tool's.
    pub fn next_on_branch(&self, body: usize) -> Option<(usize, bool)> {
        [(&self.tool_chain, true), (&self.wp_chain, false)]
            .into_iter()
            .find_map(|(chain, tool)| {
                let k = chain.iter().position(|&b| b == body)?;
                chain.get(k + 1).map(|&next| (next, tool))
            })
    }

    /// The axis that moves `body`, if one does.
    pub fn axis_moving(&self, body: usize) -> Option<&Axis> {
        self.axes.iter().find(|a| a.body == body)
    }

    /// The body a swivel head carries directly: when a rotary axis moves `body` on the tool
    /// branch and no axis moves the next body there (the tool, or a spindle carrying it), that
    /// next body.
    pub fn head_carries(&self, body: usize) -> Option<usize> {
        let (next, tool) = self.next_on_branch(body)?;
        (tool
            && self.axis_moving(body)?.kind == AxisKind::Rotary
            && self.axis_moving(next).is_none())
        .then_some(next)
    }

    /// The slots, with their factors, of the position error `component` of `body` (a location
    /// error such as `EX0B`, a squareness such as `EC0Y`): the body's position slot; for a
    /// translation of a swivel head's line ([`Machine::head_carries`]) with the carried body's
    /// same slot at −1, so that the line moves against the tool, which keeps its place (a pivot
    /// offset, as head calibration identifies it; the slot alone would shift the head rigidly,
    /// tool included, which no measurement of the tool against the table can see). `None` for
    /// a body without position slots.
    pub fn position_error_slots(
        &self,
        body: usize,
        component: Component,
    ) -> Option<Vec<(usize, f64)>> {
        let slot = |body: usize| {
            self.slot_index(ErrorSlot {
                body,
                kind: SlotKind::Position,
                component,
            })
        };
        let mut out = vec![(slot(body)?, 1.0)];
        if let Some(carried) = self
            .head_carries(body)
            .filter(|_| component.is_translation())
        {
            out.push((slot(carried)?, -1.0));
        }
        Some(out)
    }

    /// Home position (q = 0) of a body's frame origin in the bed frame, mm.
    ///
    /// # Panics
    /// If `body` is out of range.
    pub fn body_home_mm(&self, body: usize) -> Vec3 {
        self.consts[body].home
    }

    /// Lower-order body array of seed 001: row `n` holds L^n(j) for every body j
    /// (L^0(j) = j, L^1(j) = parent, L^n = L(L^{n−1}); the bed maps to itself).
    /// Rows run until every entry is the bed.
    ///
    /// ```
    /// let m = mte_kinematics::Machine::library("seed001-4axis").unwrap();
    /// let l = m.lower_order_array();
    /// assert_eq!(l[1][2], 1); // L(3) = 2 in the paper's 1-based numbering
    /// ```
    pub fn lower_order_array(&self) -> Vec<Vec<usize>> {
        let nb = self.bodies.len();
        let mut rows = vec![(0..nb).collect::<Vec<_>>()];
        while rows.last().is_some_and(|r| r.iter().any(|&j| j != 0)) {
            let last = rows.last().expect("non-empty");
            let next = last
                .iter()
                .map(|&j| self.bodies[j].parent.unwrap_or(0))
                .collect();
            rows.push(next);
        }
        rows
    }

    /// A copy of this machine with another tool offset (tool tip relative to its parent at
    /// home, mm), e.g. a different tool length or an R-test sensor nest.
    pub fn with_tool_offset(&self, offset_mm: Vec3) -> Machine {
        self.with_body_offset(self.tool, offset_mm)
    }

    /// A copy of this machine with another workpiece offset (workpiece frame origin relative
    /// to its parent at home, mm), e.g. another R-test ball position.
    pub fn with_workpiece_offset(&self, offset_mm: Vec3) -> Machine {
        self.with_body_offset(self.workpiece, offset_mm)
    }

    /// A copy of this machine with another offset of body `body` (relative to its parent at
    /// home, mm). [`Machine::json`] still returns the original text.
    ///
    /// # Panics
    /// If `body` is out of range.
    pub fn with_body_offset(&self, body: usize, offset_mm: Vec3) -> Machine {
        let mut bodies = self.bodies.clone();
        bodies[body].offset_mm = offset_mm;
        Machine::build(
            self.name.clone(),
            self.description.clone(),
            bodies,
            self.axes.clone(),
            self.tool,
            self.workpiece,
            self.json.clone(),
        )
    }
}
