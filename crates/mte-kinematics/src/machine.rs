//! Machine description: bodies, joints, axes, error slots, and its versioned JSON form
//! (`"format": "mte-machine/1"`, documented in `docs/formats.md` and `docs/conventions.md`).

use crate::error::{KinError, Result};
use mte_linalg::Vec3;
use serde_json::{Map, Value};
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

struct Names {
    /// "machine.json" or "<string>" or "library:NAME".
    src: String,
}

impl Names {
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> KinError {
        KinError::Field {
            source_name: self.src.clone(),
            field: field.into(),
            message: message.into(),
        }
    }
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

fn check_keys(n: &Names, path: &str, obj: &Map<String, Value>, allowed: &[&str]) -> Result<()> {
    for k in obj.keys() {
        if !allowed.contains(&k.as_str()) {
            return Err(n.err(
                format!("{path}.{k}"),
                format!("unknown field (expected one of: {})", allowed.join(", ")),
            ));
        }
    }
    Ok(())
}

fn get_str<'a>(n: &Names, path: &str, obj: &'a Map<String, Value>, key: &str) -> Result<&'a str> {
    match obj.get(key) {
        None => Err(n.err(format!("{path}.{key}"), "missing field (expected a string)")),
        Some(Value::String(s)) => Ok(s),
        Some(v) => Err(n.err(
            format!("{path}.{key}"),
            format!("expected a string, found {}", type_name(v)),
        )),
    }
}

fn get_opt_str<'a>(
    n: &Names,
    path: &str,
    obj: &'a Map<String, Value>,
    key: &str,
) -> Result<Option<&'a str>> {
    match obj.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(_) => get_str(n, path, obj, key).map(Some),
    }
}

fn number(n: &Names, field: &str, v: &Value) -> Result<f64> {
    match v {
        Value::Number(x) => {
            let x = x
                .as_f64()
                .ok_or_else(|| n.err(field, "number out of f64 range"))?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(n.err(field, format!("expected a finite number, found {x}")))
            }
        }
        // JSON has no NaN literal; a string "NaN"/"inf" is the usual way it sneaks in.
        Value::String(s) => Err(n.err(
            field,
            format!("expected a finite number, found the string {s:?}"),
        )),
        other => Err(n.err(
            field,
            format!("expected a finite number, found {}", type_name(other)),
        )),
    }
}

fn get_vec<const N: usize>(
    n: &Names,
    path: &str,
    obj: &Map<String, Value>,
    key: &str,
) -> Result<[f64; N]> {
    let field = format!("{path}.{key}");
    let arr = match obj.get(key) {
        None => {
            return Err(n.err(
                field,
                format!("missing field (expected an array of {N} numbers)"),
            ));
        }
        Some(Value::Array(a)) => a,
        Some(v) => {
            return Err(n.err(
                field,
                format!("expected an array of {N} numbers, found {}", type_name(v)),
            ));
        }
    };
    if arr.len() != N {
        return Err(n.err(field, format!("expected {N} numbers, found {}", arr.len())));
    }
    let mut out = [0.0; N];
    for (i, v) in arr.iter().enumerate() {
        out[i] = number(n, &format!("{field}[{i}]"), v)?;
    }
    Ok(out)
}

struct RawJoint {
    kind: AxisKind,
    axis: String,
    direction: Vec3,
    sign: f64,
    stroke: (f64, f64),
}

struct RawBody {
    name: String,
    parent: Option<String>,
    offset: Vec3,
    joint: Option<RawJoint>,
    motion_errors: Option<bool>,
}

fn parse_joint(n: &Names, path: &str, v: &Value) -> Result<Option<RawJoint>> {
    let obj = v
        .as_object()
        .ok_or_else(|| n.err(path, format!("expected an object, found {}", type_name(v))))?;
    let ty = get_str(n, path, obj, "type")?;
    let kind = match ty {
        "fixed" => {
            check_keys(n, path, obj, &["type"])?;
            return Ok(None);
        }
        "linear" => AxisKind::Linear,
        "rotary" => AxisKind::Rotary,
        other => {
            return Err(n.err(
                format!("{path}.type"),
                format!(
                    "unknown joint type {other:?} (expected \"fixed\", \"linear\" or \"rotary\")"
                ),
            ));
        }
    };
    let stroke_key = if kind == AxisKind::Linear {
        "stroke_mm"
    } else {
        "stroke_deg"
    };
    check_keys(
        n,
        path,
        obj,
        &["type", "axis", "direction", "sign", stroke_key],
    )?;
    let axis = get_str(n, path, obj, "axis")?.to_string();
    if axis.is_empty() || axis.contains(char::is_whitespace) || axis.contains('.') {
        return Err(n.err(
            format!("{path}.axis"),
            format!("axis name {axis:?} must be non-empty, without spaces or dots"),
        ));
    }
    let d = get_vec::<3>(n, path, obj, "direction")?;
    let d = Vec3::new(d[0], d[1], d[2]);
    let norm = d.norm();
    if norm < 1e-9 {
        return Err(n.err(
            format!("{path}.direction"),
            format!(
                "zero-length direction {:?} (expected a non-zero 3-vector)",
                [d.x, d.y, d.z]
            ),
        ));
    }
    let sign = match obj.get("sign") {
        None => {
            return Err(n.err(
                format!("{path}.sign"),
                "missing field (expected 1 or -1: the body moves by sign·q along/about direction)",
            ));
        }
        Some(v) => number(n, &format!("{path}.sign"), v)?,
    };
    if sign != 1.0 && sign != -1.0 {
        return Err(n.err(
            format!("{path}.sign"),
            format!("expected 1 or -1, found {sign}"),
        ));
    }
    let s = get_vec::<2>(n, path, obj, stroke_key)?;
    if s[0] > s[1] {
        return Err(n.err(
            format!("{path}.{stroke_key}"),
            format!(
                "expected [min, max] with min <= max, found [{}, {}]",
                s[0], s[1]
            ),
        ));
    }
    let stroke = if kind == AxisKind::Rotary {
        (s[0].to_radians(), s[1].to_radians())
    } else {
        (s[0], s[1])
    };
    Ok(Some(RawJoint {
        kind,
        axis,
        direction: d / norm,
        sign,
        stroke,
    }))
}

fn parse_body(n: &Names, i: usize, v: &Value) -> Result<RawBody> {
    let path = format!("bodies[{i}]");
    let obj = v
        .as_object()
        .ok_or_else(|| n.err(&path, format!("expected an object, found {}", type_name(v))))?;
    check_keys(
        n,
        &path,
        obj,
        &[
            "name",
            "parent",
            "offset_mm",
            "joint",
            "motion_errors",
            "note",
        ],
    )?;
    let name = get_str(n, &path, obj, "name")?.to_string();
    if name.is_empty() || name.contains(char::is_whitespace) || name.contains('.') {
        return Err(n.err(
            format!("{path}.name"),
            format!("body name {name:?} must be non-empty, without spaces or dots"),
        ));
    }
    let parent = if i == 0 {
        match obj.get("parent") {
            None | Some(Value::Null) => None,
            Some(_) => {
                return Err(n.err(
                    format!("{path}.parent"),
                    "the first body is the bed and has no parent (expected null or no field)",
                ));
            }
        }
    } else {
        match obj.get("parent") {
            None | Some(Value::Null) => {
                return Err(n.err(
                    format!("{path}.parent"),
                    "missing field (expected the name of the parent body; only bodies[0], the bed, has none)",
                ));
            }
            Some(_) => Some(get_str(n, &path, obj, "parent")?.to_string()),
        }
    };
    let offset = if i == 0 && !obj.contains_key("offset_mm") {
        Vec3::zeros()
    } else {
        let o = get_vec::<3>(n, &path, obj, "offset_mm")?;
        Vec3::new(o[0], o[1], o[2])
    };
    if i == 0 && offset != Vec3::zeros() {
        return Err(n.err(
            format!("{path}.offset_mm"),
            "the bed defines the machine frame; its offset must be [0, 0, 0]",
        ));
    }
    let joint = match obj.get("joint") {
        None | Some(Value::Null) => None,
        Some(j) => parse_joint(n, &format!("{path}.joint"), j)?,
    };
    if i == 0 && joint.is_some() {
        return Err(n.err(
            format!("{path}.joint"),
            "the bed cannot have a moving joint",
        ));
    }
    if let Some(note) = obj.get("note") {
        if !note.is_string() {
            return Err(n.err(format!("{path}.note"), "expected a string"));
        }
    }
    let motion_errors = match obj.get("motion_errors") {
        None | Some(Value::Null) => None,
        Some(Value::Bool(b)) => Some(*b),
        Some(v) => {
            return Err(n.err(
                format!("{path}.motion_errors"),
                format!("expected a boolean, found {}", type_name(v)),
            ));
        }
    };
    Ok(RawBody {
        name,
        parent,
        offset,
        joint,
        motion_errors,
    })
}

impl Machine {
    /// Parse and validate a machine description (`"format": "mte-machine/1"`).
    ///
    /// # Errors
    /// [`KinError::Json`] for malformed JSON; [`KinError::Field`] naming the field for a
    /// missing field, wrong type, NaN/non-finite number, zero-length direction, unknown
    /// body or axis name, duplicate names, or a cycle in the topology.
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

    /// Read and parse a machine file; errors name the file.
    ///
    /// # Errors
    /// [`KinError::Io`] if the file cannot be read, otherwise as [`Machine::from_json_str`].
    pub fn from_file(p: &Path) -> Result<Machine> {
        let text = std::fs::read_to_string(p).map_err(|e| KinError::Io {
            path: p.display().to_string(),
            message: e.to_string(),
        })?;
        Self::parse(&text, &p.display().to_string())
    }

    pub(crate) fn parse(s: &str, src: &str) -> Result<Machine> {
        let n = Names {
            src: src.to_string(),
        };
        let root: Value = serde_json::from_str(s).map_err(|e| KinError::Json {
            source_name: src.to_string(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })?;
        let obj = root.as_object().ok_or_else(|| {
            n.err(
                "(root)",
                format!("expected an object, found {}", type_name(&root)),
            )
        })?;
        check_keys(
            &n,
            "(root)",
            obj,
            &[
                "format",
                "name",
                "description",
                "source",
                "bodies",
                "tool",
                "workpiece",
                "axis_order",
            ],
        )
        .map_err(|e| match e {
            KinError::Field {
                source_name,
                field,
                message,
            } => KinError::Field {
                source_name,
                field: field.trim_start_matches("(root).").to_string(),
                message,
            },
            e => e,
        })?;
        let format = get_str(&n, "", obj, "format").map_err(|_| {
            n.err(
                "format",
                format!("missing or not a string (expected \"{FORMAT}\")"),
            )
        })?;
        if format != FORMAT {
            return Err(n.err(
                "format",
                format!("unsupported format {format:?} (expected \"{FORMAT}\")"),
            ));
        }
        let strip = |e: KinError| match e {
            KinError::Field {
                source_name,
                field,
                message,
            } => KinError::Field {
                source_name,
                field: field.trim_start_matches('.').to_string(),
                message,
            },
            e => e,
        };
        let name = get_str(&n, "", obj, "name").map_err(strip)?.to_string();
        let description = get_opt_str(&n, "", obj, "description")
            .map_err(strip)?
            .unwrap_or("")
            .to_string();
        get_opt_str(&n, "", obj, "source").map_err(strip)?;
        let bodies_v = match obj.get("bodies") {
            None => return Err(n.err("bodies", "missing field (expected an array of bodies)")),
            Some(Value::Array(a)) => a,
            Some(v) => {
                return Err(n.err(
                    "bodies",
                    format!("expected an array, found {}", type_name(v)),
                ));
            }
        };
        if bodies_v.len() < 2 {
            return Err(n.err("bodies", "expected at least the bed and one more body"));
        }
        let raw: Vec<RawBody> = bodies_v
            .iter()
            .enumerate()
            .map(|(i, v)| parse_body(&n, i, v))
            .collect::<Result<_>>()?;

        // names → indices
        let mut index: HashMap<&str, usize> = HashMap::new();
        for (i, b) in raw.iter().enumerate() {
            if let Some(prev) = index.insert(b.name.as_str(), i) {
                return Err(n.err(
                    format!("bodies[{i}].name"),
                    format!("duplicate body name {:?} (also bodies[{prev}])", b.name),
                ));
            }
        }
        let known_bodies = || {
            raw.iter()
                .map(|b| b.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut parents = vec![None; raw.len()];
        for (i, b) in raw.iter().enumerate() {
            if let Some(p) = &b.parent {
                let pi = *index.get(p.as_str()).ok_or_else(|| {
                    n.err(
                        format!("bodies[{i}].parent"),
                        format!("unknown body {p:?} (bodies: {})", known_bodies()),
                    )
                })?;
                if pi == i {
                    return Err(n.err(
                        format!("bodies[{i}].parent"),
                        format!("cycle in the topology: body {:?} is its own parent", b.name),
                    ));
                }
                parents[i] = Some(pi);
            }
        }
        // cycle detection: every body must reach the bed within len steps
        for i in 0..raw.len() {
            let mut j = i;
            let mut path = vec![raw[i].name.clone()];
            let mut steps = 0;
            while let Some(p) = parents[j] {
                j = p;
                path.push(raw[j].name.clone());
                steps += 1;
                if steps > raw.len() {
                    let cyc: Vec<_> = path.iter().take(raw.len() + 1).cloned().collect();
                    return Err(n.err(
                        format!("bodies[{i}].parent"),
                        format!(
                            "cycle in the topology: {} … never reaches the bed {:?}",
                            cyc.join(" → "),
                            raw[0].name
                        ),
                    ));
                }
            }
        }
        let body_ref = |key: &str| -> Result<usize> {
            let nm = get_str(&n, "", obj, key).map_err(strip)?;
            index.get(nm).copied().ok_or_else(|| {
                n.err(
                    key,
                    format!("unknown body {nm:?} (bodies: {})", known_bodies()),
                )
            })
        };
        let tool = body_ref("tool")?;
        let workpiece = body_ref("workpiece")?;
        if tool == workpiece {
            return Err(n.err("tool", "tool and workpiece must be different bodies"));
        }

        // axes in body order, then reorder by axis_order
        let mut axes: Vec<Axis> = Vec::new();
        let mut axis_body_field: Vec<String> = Vec::new();
        for (i, b) in raw.iter().enumerate() {
            if let Some(j) = &b.joint {
                if let Some(k) = axes.iter().position(|a| a.name == j.axis) {
                    return Err(n.err(
                        format!("bodies[{i}].joint.axis"),
                        format!(
                            "duplicate axis name {:?} (also {})",
                            j.axis, axis_body_field[k]
                        ),
                    ));
                }
                axes.push(Axis {
                    name: j.axis.clone(),
                    kind: j.kind,
                    body: i,
                    stroke: j.stroke,
                    direction: j.direction,
                    sign: j.sign,
                    branch: Branch::Neither,
                });
                axis_body_field.push(format!("bodies[{i}].joint.axis"));
            }
        }
        if let Some(order) = obj.get("axis_order") {
            let arr = order.as_array().ok_or_else(|| {
                n.err(
                    "axis_order",
                    format!(
                        "expected an array of axis names, found {}",
                        type_name(order)
                    ),
                )
            })?;
            let known = axes
                .iter()
                .map(|a| a.name.as_str())
                .collect::<Vec<_>>()
                .join(", ");
            let mut ordered = Vec::with_capacity(axes.len());
            for (k, v) in arr.iter().enumerate() {
                let nm = v.as_str().ok_or_else(|| {
                    n.err(
                        format!("axis_order[{k}]"),
                        format!("expected an axis name, found {}", type_name(v)),
                    )
                })?;
                let pos = axes.iter().position(|a| a.name == nm).ok_or_else(|| {
                    n.err(
                        format!("axis_order[{k}]"),
                        format!("unknown axis {nm:?} (machine axes: {known})"),
                    )
                })?;
                if ordered.contains(&pos) {
                    return Err(n.err(
                        format!("axis_order[{k}]"),
                        format!("axis {nm:?} listed twice"),
                    ));
                }
                ordered.push(pos);
            }
            if ordered.len() != axes.len() {
                let missing: Vec<_> = (0..axes.len())
                    .filter(|p| !ordered.contains(p))
                    .map(|p| axes[p].name.clone())
                    .collect();
                return Err(n.err(
                    "axis_order",
                    format!("axes missing from axis_order: {}", missing.join(", ")),
                ));
            }
            axes = ordered.into_iter().map(|p| axes[p].clone()).collect();
        }

        let bodies: Vec<Body> = raw
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let joint = match &b.joint {
                    None => Joint::Fixed,
                    Some(j) => Joint::Axis(
                        axes.iter()
                            .position(|a| a.name == j.axis)
                            .expect("axis registered above"),
                    ),
                };
                Body {
                    name: b.name.clone(),
                    parent: parents[i],
                    offset_mm: b.offset,
                    joint,
                    motion_errors: b.motion_errors.unwrap_or(b.joint.is_some()),
                    branch: Branch::Neither,
                }
            })
            .collect();
        for (i, b) in bodies.iter().enumerate() {
            if matches!(b.joint, Joint::Axis(_)) && !b.motion_errors {
                return Err(n.err(
                    format!("bodies[{i}].motion_errors"),
                    "a moving body always has motion-error slots (expected true or no field)",
                ));
            }
        }
        Ok(Machine::build(
            name,
            description,
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
