//! The error-parameter catalogue of a machine: ISO 230-1 names, the papers' aliases, physical
//! meaning, unit, and how each parameter maps onto the kinematic error slots.
//!
//! A parameter with value `v` (or model `v(ctx)`) contributes `weight · g(q) · v` to each slot
//! of its [`Contribution`]s, with `g = 1` ([`Gain::One`]) or `g = q_axis` ([`Gain::Coordinate`]).
//!
//! Conventions (see `docs/formats.md`, section "Error catalogue"):
//! - **Component errors** `E<c><axis>` (`EXX`, `EBY`, `ECC` …) are the motion slots of the axis'
//!   body: the error motion of the moving body relative to its parent, in the moved body frame
//!   (the convention of seeds 000, 001 and 003). For an axis carrying the workpiece its effect on
//!   the tool relative to the workpiece has the opposite sign.
//! - **Location errors** `E<c>0<axis>` of rotary axes (`EX0C`, `EB0A`, `EC0C` …) are the position
//!   slots of the rotary body, relative to its parent body (the *relative* representation of
//!   stacked rotary axes, as seed 003).
//! - **Squareness** of linear axes: X is the reference, Y is squared to X (`EC0Y`), Z to X and Y
//!   (`EB0Z`, `EA0Z`); a further axis parallel to X carries parallelism `EB0<u>`, `EC0<u>`. A
//!   squareness θ about unit vector n turns the displacement `d = sign·q·dir` of the carrying
//!   axis: `δ = θ·(n × d)`, put on the straightness motion slots (a linearly growing
//!   straightness), so it changes only that axis' direction and does not rotate what the axis
//!   carries. `EC0Y > 0` makes the angle between the +X and +Y motions of the tool relative to
//!   the workpiece larger than 90° (`δx = −EC0Y · y`), for a Y axis on either branch.
//! - **Assembly / setup** slots of linear-axis bodies and fixed bodies (spindle, tool, workpiece)
//!   are named `E<c>0[<body>]`, and motion slots of a fixed body (spindle error motions)
//!   `E<c>[<body>]`.

use crate::error::{Error, Result};
use crate::units::Kind;
use mte_kinematics::{AxisKind, Component, ErrorSlot, Joint, Machine, SlotKind};
use mte_linalg::{DMat, Vec3};
use std::collections::HashMap;

/// What a parameter describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamKind {
    /// Error motion of an axis (function of its coordinate): ISO component errors.
    Component,
    /// Location / assembly error of an axis or body (constant).
    Location,
    /// Squareness (or parallelism) between linear axes.
    Squareness,
    /// Set-up of the tool or workpiece (constant).
    Setup,
}

/// The function g(q) multiplying a parameter's value in one slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Gain {
    /// g = 1.
    One,
    /// g = the coordinate of the parameter's axis (mm): squareness as linear straightness.
    Coordinate,
}

/// One slot a parameter feeds.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Contribution {
    /// Slot index in [`Machine::error_slots`] order.
    pub slot: usize,
    /// Constant factor.
    pub weight: f64,
    /// Position-dependent factor.
    pub gain: Gain,
}

/// One named error parameter.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Parameter {
    /// ISO 230-1 name (or the bracket name of an assembly/setup slot, or the paper's name when
    /// the parameter has no ISO name, e.g. seed 000's `q6e`).
    pub name: String,
    /// Other names (papers' notation, ASCII forms).
    pub aliases: Vec<String>,
    /// Number in the paper's table when the catalogue is a paper view.
    pub number: Option<u32>,
    /// Component, location, squareness or setup.
    pub kind: ParamKind,
    /// The body whose slots it feeds (first contribution).
    pub body: usize,
    /// Axis (index in [`Machine::axes`]) whose coordinate, time and direction feed its model.
    pub axis: Option<usize>,
    /// Length (mm) or angle (rad).
    pub quantity: Kind,
    /// The slots it feeds.
    pub contributions: Vec<Contribution>,
    /// Physical meaning in plain words.
    pub meaning: String,
    /// Names of parameters it cannot be told apart from (exactly or for constant values).
    pub redundant_with: Vec<String>,
}

/// The catalogue of one machine (or a paper's selection from it). Searchable by name or alias
/// (exact, then case-insensitive), axis, kind and slot.
#[derive(Debug, Clone)]
pub struct Catalogue {
    machine: String,
    params: Vec<Parameter>,
    index: HashMap<String, usize>,
}

const LETTERS: [&str; 6] = ["X", "Y", "Z", "A", "B", "C"];
const GREEK: [&str; 3] = ["α", "β", "γ"];

fn comp_at(i: usize) -> Component {
    Component::ALL[i]
}

fn principal(d: &Vec3) -> Option<usize> {
    (0..3).find(|&i| (d[i].abs() - 1.0).abs() < 1e-9)
}

/// ISO 230-1 letter of a slot component: X, Y, Z for translations, A, B, C for rotations about
/// X, Y, Z.
///
/// ```
/// use mte_errors::catalogue::component_letter;
/// use mte_kinematics::Component;
/// assert_eq!(component_letter(Component::Ey), 'B');
/// ```
pub fn component_letter(c: Component) -> char {
    LETTERS[c.index()].chars().next().unwrap_or('?')
}

/// The component an ISO 230-1 letter names (inverse of [`component_letter`]).
pub fn component_of_letter(letter: char) -> Option<Component> {
    LETTERS
        .iter()
        .position(|l| l.starts_with(letter))
        .map(comp_at)
}

/// ISO 230-1 name of a location error of `axis` (constant error of component `c` of the body
/// the axis moves, relative to its parent): `E<c>0<axis>`, e.g. `EX0C`, `EB0A`.
pub fn location_error_name(c: Component, axis: &str) -> String {
    format!("E{}0{axis}", component_letter(c))
}

/// ISO 230-1 name of a component error of `axis` (error motion of component `c` as the axis
/// moves): `E<c><axis>`, e.g. `EXX` (positioning of X), `EYX` (straightness), `ECC`.
///
/// ```
/// use mte_errors::catalogue::component_error_name;
/// use mte_kinematics::Component;
/// assert_eq!(component_error_name(Component::Dx, "X"), "EXX");
/// ```
pub fn component_error_name(c: Component, axis: &str) -> String {
    format!("E{}{axis}", component_letter(c))
}

/// ISO 230-1 name of the positioning error of an axis named by its direction letter (`X`, `Y`,
/// `Z` linear, `A`, `B`, `C` rotary): `EXX`, `ECC`; for another name, `E<axis><axis>`.
pub fn positioning_error_name(axis: &str) -> String {
    let mut chars = axis.chars();
    match (chars.next().and_then(component_of_letter), chars.next()) {
        (Some(c), None) => component_error_name(c, axis),
        _ => format!("E{axis}{axis}"),
    }
}

/// Splits an ISO 230-1 location error name `E<c>0<axis>` into its component and axis name;
/// `None` when `name` does not have that form.
///
/// ```
/// use mte_errors::catalogue::parse_location_error_name;
/// use mte_kinematics::Component;
/// assert_eq!(parse_location_error_name("EA0Y"), Some((Component::Ex, "Y")));
/// assert_eq!(parse_location_error_name("EXX"), None);
/// ```
pub fn parse_location_error_name(name: &str) -> Option<(Component, &str)> {
    let rest = name.strip_prefix('E')?;
    let mut chars = rest.chars();
    let c = component_of_letter(chars.next()?)?;
    let axis = chars.as_str().strip_prefix('0')?;
    (!axis.is_empty()).then_some((c, axis))
}

/// IBS / ISO 10791-6 report name of a rotary-axis location error: `<c>O<axis>`, e.g. `XOB`.
pub fn ibs_location_name(c: Component, axis: &str) -> String {
    format!("{}O{axis}", component_letter(c))
}

/// The four location errors across a rotary axis named A, B or C (ISO 230-7; A, B, C turn
/// about X, Y, Z): the two translations and the two tilts not along the axis itself, e.g. for
/// B: X, Z, A, C (`EX0B`, `EZ0B`, `EA0B`, `EC0B`). `None` for another name.
pub fn rotary_location_components(axis: &str) -> Option<[Component; 4]> {
    use Component::{Dx, Dy, Dz, Ex, Ey, Ez};
    Some(match axis {
        "A" => [Dy, Dz, Ey, Ez],
        "B" => [Dx, Dz, Ex, Ez],
        "C" => [Dx, Dy, Ex, Ey],
        _ => return None,
    })
}

/// The squareness errors of the linear axes X, Y, Z: X is the reference, Y is squared to X
/// (`EC0Y`), Z to X and Y (`EB0Z`, `EA0Z`).
pub const SQUARENESS_NAMES: [&str; 3] = ["EC0Y", "EB0Z", "EA0Z"];

/// The ISO 230-1 view of one error slot ([`slot_name`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SlotName {
    /// The slot's parameter name in [`Catalogue::for_machine`]: `E<c><axis>` for an axis'
    /// error motion, `E<c>0<axis>` for a rotary axis' location, `E<c>0[<body>]` for assembly
    /// and set-up, `E<c>[<body>]` for the error motion of a fixed body.
    pub name: String,
    /// A short label, e.g. "straightness in y of the X axis".
    pub label: String,
    /// Physical meaning in plain words (the catalogue's [`Parameter::meaning`]).
    pub meaning: String,
    /// Component, location or set-up.
    pub kind: ParamKind,
}

/// Names error slot `slot` of `machine` (index in [`Machine::error_slots`] order) as the
/// catalogue does.
///
/// # Panics
/// When `slot` is not below `machine.n_slots()`.
///
/// ```
/// use mte_errors::catalogue::{ParamKind, slot_name};
/// use mte_kinematics::Machine;
/// let m = Machine::library("seed003-ac-table").unwrap();
/// let s = slot_name(&m, m.slot_index_by_name("C.position.dx").unwrap());
/// assert_eq!((s.name.as_str(), s.kind), ("EX0C", ParamKind::Location));
/// assert_eq!(s.label, "location of the C axis line along x");
/// // A line has no place along itself, and its turn about itself is the axis' zero.
/// let along = slot_name(&m, m.slot_index_by_name("A.position.dx").unwrap());
/// assert_eq!(along.label, "shift along the A axis line itself (x), of what A carries");
/// let zero = slot_name(&m, m.slot_index_by_name("A.position.ex").unwrap());
/// assert_eq!(zero.label, "zero of the A axis' angle (its line turned about itself)");
/// ```
pub fn slot_name(machine: &Machine, slot: usize) -> SlotName {
    let s = machine.error_slots()[slot];
    let c = s.component.index();
    let letter = LETTERS[c];
    let xyz = ["x", "y", "z"][c % 3];
    let bodies = machine.bodies();
    let b = &bodies[s.body];
    let parent_name = b.parent.map(|p| bodies[p].name.clone()).unwrap_or_default();
    let axis = match b.joint {
        Joint::Axis(k) => Some(&machine.axes()[k]),
        Joint::Fixed => None,
    };
    match (s.kind, axis) {
        (SlotKind::Position, Some(a)) if a.kind == AxisKind::Rotary => {
            let an = &a.name;
            let along_own_line = principal(&a.direction) == Some(c % 3);
            let (label, meaning) = if c < 3 && along_own_line {
                // A line has no place along itself: this shift moves what the axis carries.
                (
                    format!("shift along the {an} axis line itself ({xyz}), of what {an} carries"),
                    format!(
                        "offset along {xyz}, the {an} axis line's own direction, of {an} and what it carries relative to its parent body `{parent_name}`: not a location error of the line (ISO 230-7 has none), the place of what {an} carries"
                    ),
                )
            } else if along_own_line {
                (
                    format!("zero of the {an} axis' angle (its line turned about itself)"),
                    format!(
                        "angular zero of {an}: {an} and what it carries turned about {an}'s own line relative to its parent body `{parent_name}`"
                    ),
                )
            } else if c < 3 {
                (
                    format!("location of the {an} axis line along {xyz}"),
                    format!(
                        "location of the {an} axis line: offset along {xyz} of {an}'s pivot relative to its parent body `{parent_name}`"
                    ),
                )
            } else {
                (
                    format!("orientation of the {an} axis line about {xyz}"),
                    format!(
                        "orientation of the {an} axis line: tilt about {xyz} relative to its parent body `{parent_name}`"
                    ),
                )
            };
            SlotName {
                name: location_error_name(s.component, an),
                label,
                meaning,
                kind: ParamKind::Location,
            }
        }
        (SlotKind::Position, _) => {
            let tag = axis.map_or(b.name.as_str(), |a| a.name.as_str());
            let what = if c < 3 {
                format!("offset along {xyz}")
            } else {
                format!("tilt about {xyz}")
            };
            let setup = s.body == machine.tool_body() || s.body == machine.workpiece_body();
            let (label, meaning, kind) = if setup {
                (
                    format!("set-up of the {}, {what}", b.name),
                    format!(
                        "set-up of the {}: {what} relative to `{parent_name}`",
                        b.name
                    ),
                    ParamKind::Setup,
                )
            } else {
                (
                    format!("assembly of `{}`, {what}", b.name),
                    format!("assembly of `{}` on `{parent_name}`: {what}", b.name),
                    ParamKind::Location,
                )
            };
            SlotName {
                name: format!("E{letter}0[{tag}]"),
                label,
                meaning,
                kind,
            }
        }
        (SlotKind::Motion, Some(a)) => {
            let an = &a.name;
            let own = principal(&a.direction);
            let what = match (a.kind, c, own) {
                (AxisKind::Linear, c, Some(o)) if c == o => "positioning error".to_string(),
                (AxisKind::Linear, c, _) if c < 3 => format!("straightness in {xyz}"),
                (AxisKind::Linear, c, Some(o)) if c - 3 == o => "roll".to_string(),
                (AxisKind::Linear, _, _) => {
                    format!("angular error motion about {xyz} (pitch/yaw)")
                }
                (AxisKind::Rotary, c, Some(o)) if c < 3 && c == o => {
                    "axial error motion".to_string()
                }
                (AxisKind::Rotary, c, _) if c < 3 => format!("radial error motion in {xyz}"),
                (AxisKind::Rotary, c, Some(o)) if c - 3 == o => {
                    "angular positioning error".to_string()
                }
                (AxisKind::Rotary, _, _) => format!("tilt error motion about {xyz}"),
            };
            let label = format!("{what} of the {an} axis");
            let meaning = format!(
                "{label}: {} of the {an} body relative to `{parent_name}` as {an} moves, in the moved frame",
                if c < 3 {
                    format!("displacement along {xyz}")
                } else {
                    format!("rotation about {xyz}")
                }
            );
            SlotName {
                name: component_error_name(s.component, an),
                label,
                meaning,
                kind: ParamKind::Component,
            }
        }
        (SlotKind::Motion, None) => {
            let dir = if c < 3 {
                format!("along {xyz}")
            } else {
                format!("about {xyz}")
            };
            SlotName {
                name: format!("E{letter}[{}]", b.name),
                label: format!("error motion of `{}` {dir}", b.name),
                meaning: format!(
                    "error motion of `{}` ({dir}; constant here: no axis turns it)",
                    b.name
                ),
                kind: ParamKind::Component,
            }
        }
    }
}

/// The papers' aliases of the slot `kind`/`c` of body `bi` (besides its slot name) and the names
/// of parameters it cannot be told apart from.
fn slot_aliases(
    machine: &Machine,
    bi: usize,
    kind: SlotKind,
    c: usize,
) -> (Vec<String>, Vec<String>) {
    let bodies = machine.bodies();
    let axes = machine.axes();
    let b = &bodies[bi];
    let axis = match b.joint {
        Joint::Axis(k) => Some(&axes[k]),
        Joint::Fixed => None,
    };
    let xyz = ["x", "y", "z"][c % 3];
    match (kind, axis) {
        (SlotKind::Position, Some(a)) if a.kind == AxisKind::Rotary => {
            let an = &a.name;
            let rel = b
                .parent
                .filter(|&p| p != 0)
                .map(|p| match bodies[p].joint {
                    Joint::Axis(pk) if axes[pk].kind == AxisKind::Rotary => axes[pk].name.clone(),
                    _ => "M".to_string(),
                })
                .unwrap_or_else(|| "M".into());
            let mut aliases = vec![ibs_location_name(comp_at(c), an)];
            if c < 3 {
                aliases.push(format!("δ{xyz}{an}{rel}"));
            } else {
                aliases.push(format!("{}{an}{rel}", GREEK[c - 3]));
            }
            let mut redundant = vec![];
            if principal(&a.direction) == Some(c % 3) {
                // Along / about the axis itself: commutes with the joint rotation.
                redundant.push(format!("E{}{an}", LETTERS[c]));
            }
            (aliases, redundant)
        }
        (SlotKind::Position, _) => {
            let mut redundant = vec![];
            if let Some(a) = axis
                && c < 3
            {
                redundant.push(format!("E{}{}", LETTERS[c], a.name));
            }
            if axis.is_none() && b.motion_errors {
                redundant.push(format!("E{}[{}]", LETTERS[c], b.name));
            }
            (vec![], redundant)
        }
        (SlotKind::Motion, Some(a)) => {
            let an = &a.name;
            let n = an.to_lowercase();
            let mut aliases = if c < 3 {
                vec![
                    format!("δ{xyz}{n}"),
                    format!("δ{xyz}({n})"),
                    format!("d{xyz}({n})"),
                ]
            } else {
                vec![
                    format!("ε{xyz}{n}"),
                    format!("ε{xyz}({n})"),
                    format!("e{xyz}({n})"),
                ]
            };
            if a.kind == AxisKind::Rotary {
                if c >= 3 {
                    aliases.push(format!("ε{}(θ{an})", ["yz", "xz", "xy"][c - 3]));
                } else {
                    aliases.push(format!("δ{xyz}(θ{an})"));
                }
            }
            (aliases, vec![])
        }
        (SlotKind::Motion, None) => (vec![], vec![format!("E{}0[{}]", LETTERS[c], b.name)]),
    }
}

impl Catalogue {
    fn from_params(machine: &str, params: Vec<Parameter>) -> Catalogue {
        let mut index = HashMap::new();
        for (i, p) in params.iter().enumerate() {
            for n in std::iter::once(&p.name).chain(&p.aliases) {
                index.entry(n.clone()).or_insert(i);
            }
        }
        for (i, p) in params.iter().enumerate() {
            for n in std::iter::once(&p.name).chain(&p.aliases) {
                index.entry(n.to_lowercase()).or_insert(i);
            }
        }
        Catalogue {
            machine: machine.to_string(),
            params,
            index,
        }
    }

    /// The full catalogue of `machine`: every error slot under its ISO (or bracket) name, plus
    /// the squareness of its linear axes.
    ///
    /// ```
    /// use mte_kinematics::Machine;
    /// use mte_errors::catalogue::{Catalogue, ParamKind};
    /// let m = Machine::library("seed004-3axis").unwrap();
    /// let c = Catalogue::for_machine(&m);
    /// assert_eq!(c.find("EXY").unwrap().kind, ParamKind::Component);
    /// assert_eq!(c.find("δx(y)").unwrap().name, "EXY");
    /// assert_eq!(c.by_kind(ParamKind::Squareness).len(), 3);
    /// ```
    pub fn for_machine(machine: &Machine) -> Catalogue {
        let bodies = machine.bodies();
        let axes = machine.axes();
        let mut params = Vec::new();
        let slot = |body: usize, kind: SlotKind, c: usize| {
            machine.slot_index(ErrorSlot {
                body,
                kind,
                component: comp_at(c),
            })
        };
        for (bi, b) in bodies.iter().enumerate().skip(1) {
            let axis = match b.joint {
                Joint::Axis(k) => Some(k),
                Joint::Fixed => None,
            };
            for kind in [SlotKind::Position, SlotKind::Motion] {
                for c in 0..6 {
                    let Some(s) = slot(bi, kind, c) else {
                        continue;
                    };
                    let named = slot_name(machine, s);
                    let (mut aliases, mut redundant) = slot_aliases(machine, bi, kind, c);
                    aliases.push(machine.slot_name(s).to_string());
                    redundant.sort();
                    params.push(Parameter {
                        name: named.name,
                        aliases,
                        number: None,
                        kind: named.kind,
                        body: bi,
                        axis,
                        quantity: if c < 3 { Kind::Length } else { Kind::Angle },
                        contributions: vec![Contribution {
                            slot: s,
                            weight: 1.0,
                            gain: Gain::One,
                        }],
                        meaning: named.meaning,
                        redundant_with: redundant,
                    });
                }
            }
        }
        // Redundancy is symmetric: location along/about a rotary axis ↔ its constant component.
        let names: Vec<(String, Vec<String>)> = params
            .iter()
            .map(|p| (p.name.clone(), p.redundant_with.clone()))
            .collect();
        for p in params.iter_mut() {
            for (n, r) in &names {
                if r.contains(&p.name) && !p.redundant_with.contains(n) {
                    p.redundant_with.push(n.clone());
                }
            }
        }
        // Squareness / parallelism of linear axes.
        let mut x_ref_seen = false;
        for (k, a) in axes.iter().enumerate() {
            if a.kind != AxisKind::Linear {
                continue;
            }
            let Some(dir_i) = principal(&a.direction) else {
                continue;
            };
            // (rotation axis n, reference description) pairs carried by this axis.
            let turns: Vec<(usize, &str)> = match dir_i {
                0 => {
                    if !x_ref_seen {
                        x_ref_seen = true;
                        vec![]
                    } else {
                        vec![
                            (1, "parallelism to X in the xz plane"),
                            (2, "parallelism to X in the xy plane"),
                        ]
                    }
                }
                1 => vec![(2, "squareness of Y to X (xy plane)")],
                _ => vec![
                    (0, "squareness of Z to Y (yz plane)"),
                    (1, "squareness of Z to X (xz plane)"),
                ],
            };
            for (n_i, what) in turns {
                let mut n = Vec3::zeros();
                n[n_i] = 1.0;
                let w = (n.cross(&a.direction)) * a.sign;
                let mut contributions = Vec::new();
                for c in 0..3 {
                    if w[c].abs() > 0.0
                        && let Some(s) = slot(a.body, SlotKind::Motion, c)
                    {
                        contributions.push(Contribution {
                            slot: s,
                            weight: w[c],
                            gain: Gain::Coordinate,
                        });
                    }
                }
                let name = location_error_name(comp_at(3 + n_i), &a.name);
                let plane = match (dir_i, n_i) {
                    (1, 2) => "Sxy",
                    (2, 0) => "Syz",
                    (2, 1) => "Sxz",
                    _ => "",
                };
                let mut aliases = vec![];
                if !plane.is_empty() {
                    aliases.push(plane.to_string());
                }
                params.push(Parameter {
                    name,
                    aliases,
                    number: None,
                    kind: ParamKind::Squareness,
                    body: a.body,
                    axis: Some(k),
                    quantity: Kind::Angle,
                    contributions,
                    meaning: format!(
                        "{what}: the {} motion direction turned about {} by this angle (a straightness growing linearly with {})",
                        a.name,
                        ["x", "y", "z"][n_i],
                        a.name
                    ),
                    redundant_with: vec![],
                });
            }
        }
        Catalogue::from_params(machine.name(), params)
    }

    /// Seed 003's 41 errors (Zheng et al. 2024, Table 1) with the paper's numbering 1–41, for an
    /// AC double-turntable machine with axes X, Y, Z, A, C (C carried by A):
    /// 1–30 the component errors δx, δy, δz, εx, εy, εz of X, Y, Z, A, C; 31–33 Sxy, Syz, Sxz;
    /// 34–39 A's location relative to the machine δxAM … γAM; 40–41 C relative to A δyCA, βCA.
    ///
    /// # Errors
    /// [`Error::Invalid`] when the machine lacks one of the axes.
    pub fn seed003(machine: &Machine) -> Result<Catalogue> {
        let full = Catalogue::for_machine(machine);
        let mut names: Vec<(String, String)> = Vec::new();
        for ax in ["X", "Y", "Z", "A", "C"] {
            let n = ax.to_lowercase();
            for (c, l) in LETTERS.iter().enumerate() {
                let al = if c < 3 {
                    format!("δ{}{n}", ["x", "y", "z"][c])
                } else {
                    format!("ε{}{n}", ["x", "y", "z"][c - 3])
                };
                names.push((format!("E{l}{ax}"), al));
            }
        }
        for (iso, al) in [("EC0Y", "Sxy"), ("EA0Z", "Syz"), ("EB0Z", "Sxz")] {
            names.push((iso.into(), al.into()));
        }
        for (c, l) in LETTERS.iter().enumerate() {
            let al = if c < 3 {
                format!("δ{}AM", ["x", "y", "z"][c])
            } else {
                format!("{}AM", GREEK[c - 3])
            };
            names.push((format!("E{l}0A"), al));
        }
        names.push(("EY0C".into(), "δyCA".into()));
        names.push(("EB0C".into(), "βCA".into()));
        full.view(machine, "seed 003", &names)
    }

    /// Seed 000's 53 errors (Fan et al. 2019, Table 1) numbered in the table's reading order, for
    /// the CA swing-head gantry (axes X, Y, Z, C, A and a `spindle` body with motion errors):
    /// 1–36 εx, εy, εz, δx, δy, δz of X, Y, Z, C, A and the spindle; 37–45 the perpendicularity
    /// errors εxy02, εxz23, εyz23, εxz34, εyz34, εxy45, εzx45, εxz56, εyz56; 46–51 the assembly
    /// errors q1e … q6e of X, Y, Z, C, A and the spindle; 52–53 the angle errors (θA)e, (θC)e.
    ///
    /// Choices where the paper is silent: εxz·· is a tilt about y and εyz·· about x (`E B0·`,
    /// `E A0·`), εxy45 about z; q_ke is a scalar offset of body k along its nominal position
    /// vector q_k (along the axis direction when q_k = 0); (θA)e and (θC)e are the zero-angle
    /// offsets `EA0A`, `EC0C` (redundant with the constant part of `EAA`, `ECC`).
    ///
    /// # Errors
    /// [`Error::Invalid`] when the machine lacks an axis or the spindle.
    pub fn seed000(machine: &Machine) -> Result<Catalogue> {
        let full = Catalogue::for_machine(machine);
        let mut names: Vec<(String, String)> = Vec::new();
        let order = [3usize, 4, 5, 0, 1, 2]; // εx εy εz δx δy δz
        for ax in ["X", "Y", "Z", "C", "A", "spindle"] {
            for &c in &order {
                let xyz = ["x", "y", "z"][c % 3];
                let arg = match ax {
                    "X" | "Y" | "Z" => ax.to_lowercase(),
                    "spindle" => "φ".into(),
                    a => format!("θ{a}"),
                };
                let al = match (ax, c) {
                    ("X" | "Y" | "Z", c) if c < 3 => format!("δ{xyz}({arg})"),
                    ("X" | "Y" | "Z", _) => format!("ε{xyz}({arg})"),
                    (_, c) if c < 3 => format!("δ{xyz}({arg})"),
                    (_, c) => format!("ε{}({arg})", ["yz", "xz", "xy"][c - 3]),
                };
                let iso = if ax == "spindle" {
                    format!("E{}[spindle]", LETTERS[c])
                } else {
                    format!("E{}{ax}", LETTERS[c])
                };
                names.push((iso, al));
            }
        }
        for (iso, al) in [
            ("EC0Y", "εxy02"),
            ("EB0Z", "εxz23"),
            ("EA0Z", "εyz23"),
            ("EB0C", "εxz34"),
            ("EA0C", "εyz34"),
            ("EC0A", "εxy45"),
            ("EB0A", "εzx45"),
            ("EB0[spindle]", "εxz56"),
            ("EA0[spindle]", "εyz56"),
        ] {
            names.push((iso.into(), al.into()));
        }
        let mut view = full.view(machine, "seed 000", &names)?;
        // q1e … q6e: assembly offsets along the nominal position vectors.
        let bodies = machine.bodies();
        for (k, bname) in ["X", "Y", "Z", "C", "A", "spindle"].iter().enumerate() {
            let bi = machine.body_index(bname).ok_or_else(|| {
                crate::error::invalid(
                    "seed 000 catalogue",
                    format!("machine `{}` has no body `{bname}`", machine.name()),
                )
            })?;
            let b = &bodies[bi];
            let axis = match b.joint {
                Joint::Axis(a) => Some(a),
                Joint::Fixed => None,
            };
            let dir = if b.offset_mm.norm() > 0.0 {
                b.offset_mm / b.offset_mm.norm()
            } else if let Some(a) = axis {
                machine.axes()[a].direction
            } else {
                Vec3::z()
            };
            let mut contributions = Vec::new();
            for c in 0..3 {
                if dir[c] != 0.0
                    && let Some(s) = machine.slot_index(ErrorSlot {
                        body: bi,
                        kind: SlotKind::Position,
                        component: comp_at(c),
                    })
                {
                    contributions.push(Contribution {
                        slot: s,
                        weight: dir[c],
                        gain: Gain::One,
                    });
                }
            }
            view.params.push(Parameter {
                name: format!("q{}e", k + 1),
                aliases: vec![format!("q{}_e", k + 1)],
                number: Some(46 + k as u32),
                kind: ParamKind::Location,
                body: bi,
                axis,
                quantity: Kind::Length,
                contributions,
                meaning: format!(
                    "assembly position error of `{bname}` (seed 000 q{}e): offset along its nominal position vector q{} = [{:.0}, {:.0}, {:.0}] mm",
                    k + 1,
                    k + 1,
                    b.offset_mm.x,
                    b.offset_mm.y,
                    b.offset_mm.z
                ),
                redundant_with: (0..3).map(|c| format!("E{}0[{bname}]", LETTERS[c])).collect(),
            });
        }
        for (iso, al) in [("EA0A", "(θA)e"), ("EC0C", "(θC)e")] {
            let mut p = full.find(iso)?.clone();
            p.aliases.insert(0, al.to_string());
            p.number = Some(view.params.len() as u32 + 1);
            view.params.push(p);
        }
        Ok(Catalogue::from_params(machine.name(), view.params))
    }

    /// A numbered selection `(name in this catalogue, paper alias)`.
    fn view(
        &self,
        machine: &Machine,
        paper: &str,
        names: &[(String, String)],
    ) -> Result<Catalogue> {
        let mut params = Vec::with_capacity(names.len());
        for (i, (iso, al)) in names.iter().enumerate() {
            let mut p = self
                .get(iso)
                .ok_or_else(|| {
                    crate::error::invalid(
                        format!("{paper} catalogue"),
                        format!(
                            "machine `{}` has no parameter `{iso}` (needs the paper's axes)",
                            machine.name()
                        ),
                    )
                })?
                .clone();
            p.aliases.retain(|a| a != al);
            p.aliases.insert(0, al.clone());
            p.number = Some(i as u32 + 1);
            params.push(p);
        }
        Ok(Catalogue::from_params(machine.name(), params))
    }

    /// Name of the machine.
    pub fn machine_name(&self) -> &str {
        &self.machine
    }
    /// All parameters, in catalogue order.
    pub fn parameters(&self) -> &[Parameter] {
        &self.params
    }
    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.params.len()
    }
    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }
    /// Index of a parameter by ISO name or alias (exact, then case-insensitive).
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.index
            .get(name)
            .or_else(|| self.index.get(&name.to_lowercase()))
            .copied()
    }
    /// A parameter by ISO name or alias.
    pub fn get(&self, name: &str) -> Option<&Parameter> {
        self.index_of(name).map(|i| &self.params[i])
    }
    /// A parameter by name, or an error suggesting close names.
    ///
    /// # Errors
    /// [`Error::UnknownParameter`] with up to 3 suggestions.
    pub fn find(&self, name: &str) -> Result<&Parameter> {
        self.get(name).ok_or_else(|| Error::UnknownParameter {
            name: name.to_string(),
            machine: self.machine.clone(),
            suggestions: self.suggest(name, 3),
        })
    }
    /// Up to `k` names (ISO or alias) closest to `name` by edit distance (ties: catalogue order).
    pub fn suggest(&self, name: &str, k: usize) -> Vec<String> {
        let low = name.to_lowercase();
        let mut all: Vec<(usize, usize, String)> = Vec::new();
        for (i, p) in self.params.iter().enumerate() {
            for n in std::iter::once(&p.name).chain(&p.aliases) {
                all.push((levenshtein(&low, &n.to_lowercase()), i, n.clone()));
            }
        }
        all.sort_by_key(|(d, i, _)| (*d, *i));
        let mut out: Vec<String> = Vec::new();
        for (d, _, n) in all {
            if d > 3.max(name.chars().count() / 2) || out.len() >= k {
                break;
            }
            if !out.contains(&n) {
                out.push(n);
            }
        }
        out
    }
    /// Parameters belonging to the axis named `axis`.
    pub fn by_axis<'a>(&'a self, machine: &Machine, axis: &str) -> Vec<&'a Parameter> {
        let k = machine.axis_index(axis);
        self.params
            .iter()
            .filter(|p| k.is_some() && p.axis == k)
            .collect()
    }
    /// Parameters of one kind.
    pub fn by_kind(&self, kind: ParamKind) -> Vec<&Parameter> {
        self.params.iter().filter(|p| p.kind == kind).collect()
    }
    /// Parameters feeding slot `slot`.
    pub fn by_slot(&self, slot: usize) -> Vec<&Parameter> {
        self.params
            .iter()
            .filter(|p| p.contributions.iter().any(|c| c.slot == slot))
            .collect()
    }

    /// The 6 × n_slots × … mapping of parameter values to slot values at axis coordinates `q`:
    /// `e[slot] += weight · g(q) · value`. Writes the n_slots × len() matrix into `out`.
    ///
    /// # Panics
    /// When `out` is not n_slots × len() or `q` is shorter than the machine's axes.
    pub fn slot_matrix_into(&self, machine: &Machine, q: &[f64], out: &mut DMat) {
        assert_eq!(
            out.shape(),
            (machine.n_slots(), self.params.len()),
            "slot matrix shape"
        );
        out.fill(0.0);
        for (j, p) in self.params.iter().enumerate() {
            for c in &p.contributions {
                let g = match c.gain {
                    Gain::One => 1.0,
                    Gain::Coordinate => p.axis.map(|a| q[a]).unwrap_or(0.0),
                };
                out[(c.slot, j)] += c.weight * g;
            }
        }
    }

    /// Effect of each parameter (unit constant value) on the pose error at `q`, to first order:
    /// the 6 × len() matrix `J(q) · G(q)` (rows px, py, pz, ox, oy, oz; mm or rad per mm or rad).
    /// This is what an identification regresses on for constant parameters.
    ///
    /// # Errors
    /// [`Error::Dimension`] when `q` does not have one entry per machine axis.
    pub fn effect_matrix(&self, machine: &Machine, q: &[f64]) -> Result<DMat> {
        if q.len() != machine.axes().len() {
            return Err(Error::Dimension {
                what: "axis commands q".into(),
                expected: machine.axes().len(),
                got: q.len(),
            });
        }
        let j = machine.jacobian(q);
        let mut g = DMat::zeros(machine.n_slots(), self.params.len());
        self.slot_matrix_into(machine, q, &mut g);
        Ok(&j.matrix * g)
    }
}

/// Edit distance on chars.
fn levenshtein(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut cur = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            cur[j] = (prev[j] + 1).min(cur[j - 1] + 1).min(prev[j - 1] + cost);
        }
        prev = cur;
    }
    prev[b.len()]
}
