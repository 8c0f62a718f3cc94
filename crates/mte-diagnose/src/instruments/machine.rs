//! How a machine's kinematic errors reach an instrument's observations: the named slot effects
//! of a machine from the first-order kinematics ([`Machine::jacobian`]), with the ISO 230-1
//! names of [`mte_errors::catalogue`], and the helpers the machine instruments share.

use mte_errors::catalogue;
use mte_kinematics::{AxisKind, Component, Machine, SlotKind};
use mte_linalg::{DMat, DVec, Vec3};

use crate::Result;
use crate::candidate::{Reference, SlotEffect, SlotRole};
use crate::dataset::{ManifestFile, Table};
use crate::term::{Family, Quantity};

/// The machine a manifest names (field `machine`: a library name or a file beside it).
pub(crate) fn load_machine(manifest: &ManifestFile, name: Option<&str>) -> Result<Machine> {
    let name = name.ok_or_else(|| {
        manifest.missing("machine", "a library machine name or a machine JSON file")
    })?;
    Machine::library_or_file(name, &manifest.dir)
        .map_err(|e| manifest.error(format!("field `machine`: {e}")))
}

/// One variable per machine axis (its values per observation).
pub(crate) fn axis_variables(machine: &Machine, values: &[Vec<f64>]) -> Vec<crate::Variable> {
    machine
        .axes()
        .iter()
        .zip(values)
        .map(|(a, v)| crate::Variable {
            name: a.name.clone(),
            kind: if a.kind == AxisKind::Rotary {
                crate::VariableKind::RotaryAxis
            } else {
                crate::VariableKind::LinearAxis
            },
            values: v.clone(),
        })
        .collect()
}

/// The machine's axis values per observation, in the machine's axis order, from the
/// observations' variables (which [`axis_variables`] made).
fn axis_values(machine: &Machine, obs: &crate::Observations) -> Vec<Vec<f64>> {
    machine
        .axes()
        .iter()
        .map(|a| {
            obs.variable(&a.name)
                .map_or_else(|| vec![0.0; obs.len()], |v| v.values.clone())
        })
        .collect()
}

/// ISO 230-1 letter of component `k` (0–5): X, Y, Z, A, B, C.
fn letter(k: usize) -> char {
    catalogue::component_letter(Component::ALL[k])
}

/// The ISO 230-1 view of one kinematic slot (the catalogue's name, label and meaning) and how
/// it depends on the machine's state.
pub(crate) struct SlotName {
    name: String,
    label: String,
    meaning: String,
    pub(crate) role: SlotRole,
}

/// Names slot `slot` as [`catalogue::slot_name`] does: a component error `E{c}{axis}` of a
/// motion slot, a location error `E{c}0{axis}` of a rotary axis' position slot; the slots of
/// bodies no axis moves are set-up errors.
fn slot_name(machine: &Machine, slot: usize) -> SlotName {
    let named = catalogue::slot_name(machine, slot);
    let s = machine.error_slots()[slot];
    let c = s.component.index();
    let role = match (machine.slot_axis(slot), s.kind) {
        (Some(axis), SlotKind::Motion) => {
            let own = axis_component(machine, slot);
            let (positioning, straightness) = match axis.kind {
                AxisKind::Linear => (c < 3 && own == Some(c), c < 3 && own != Some(c)),
                AxisKind::Rotary => (c >= 3 && own == Some(c), false),
            };
            SlotRole::Component {
                axis: axis.name.clone(),
                positioning,
                straightness,
            }
        }
        (Some(_), SlotKind::Position) => SlotRole::Constant {
            family: Family::Location,
        },
        (None, _) => SlotRole::Constant {
            family: Family::Setup,
        },
    };
    // The tool's place against what carries it: a tool length or offset as a constant; as it
    // changes in time, the spindle's thermal growth (ISO 230-3), the commonest thermal effect.
    let (label, meaning) = if s.body == machine.tool_body() && c < 3 {
        (
            format!(
                "set-up of the tool (spindle nose), offset along {}",
                ['x', 'y', 'z'][c]
            ),
            format!(
                "{}; changing in time, the spindle's thermal growth or drift",
                named.meaning
            ),
        )
    } else {
        (named.label, named.meaning)
    };
    SlotName {
        name: named.name,
        label,
        meaning,
        role,
    }
}

/// The slot component (0–5) that lies along the axis' own direction, if the axis is parallel
/// to a machine axis.
fn axis_component(machine: &Machine, slot: usize) -> Option<usize> {
    let axis = machine.slot_axis(slot)?;
    let d = axis.direction;
    let k = (0..3).find(|&k| (d[k].abs() - 1.0).abs() < 1e-9)?;
    Some(match axis.kind {
        AxisKind::Linear => k,
        AxisKind::Rotary => k + 3,
    })
}

/// Squareness of a linear axis: the linear part of its straightness. The axis, whose body moves
/// by `travel · a` per unit of its coordinate `s` (`travel` = its sign times its direction's
/// component along `a`: −1 for a table axis, ISO 841), tilted by θ about the third direction `r`
/// moves by `θ travel (r × a)` per unit, so its straightness in direction `d` grows as
/// `θ travel ((r × a)·d) · s` (`mte-errors`' convention: `EC0Y > 0` → δx = −EC0Y·y at the tool
/// relative to the workpiece, whichever branch Y is on).
fn squareness_effect(
    name: &SlotName,
    column: &DVec,
    coordinate: &[f64],
    slot_dir: usize,
    (axis_dir, travel): (usize, f64),
) -> Option<SlotEffect> {
    let SlotRole::Component {
        axis,
        straightness: true,
        ..
    } = &name.role
    else {
        return None;
    };
    let r = 3 - slot_dir - axis_dir;
    let (mut rv, mut av, mut dv) = (Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
    rv[r] = 1.0;
    av[axis_dir] = 1.0;
    dv[slot_dir] = 1.0;
    let sign = travel * rv.cross(&av).dot(&dv);
    let plane: String = [axis_dir.min(slot_dir), axis_dir.max(slot_dir)]
        .map(letter)
        .iter()
        .collect();
    let iso = catalogue::location_error_name(Component::ALL[r + 3], axis);
    Some(SlotEffect {
        name: iso.clone(),
        label: format!("squareness of {axis} in the {plane} plane ({iso})"),
        meaning: format!(
            "the {axis} axis is not square to the machine frame in the {plane} plane: it moves along a slightly tilted line"
        ),
        quantity: Quantity::Angle,
        role: SlotRole::Constant {
            family: Family::Squareness,
        },
        column: DVec::from_fn(column.len(), |i, _| sign * column[i] * coordinate[i]),
        separated_by: None,
        reference: None,
    })
}

/// Builds the named slot effects of a machine from the per-observation sensitivities `s`
/// (n × n_slots), the axis values of the observations' variables, and hints on what separates
/// them. With reference `poses` (where the instrument was zeroed: sensitivities to the
/// slots' values there, the axis values and the time), an error acts at both poses.
///
/// Position slots of linear axes are left out: their translations are constant offsets (setup
/// errors say the same) and their rotations turn the whole branch downstream, which the
/// squareness and angular component errors describe in the terms engineers use.
pub(crate) fn slot_effects(
    machine: &Machine,
    s: &DMat,
    obs: &crate::Observations,
    poses: Option<ReferencePoses<'_>>,
    hint: &dyn Fn(&SlotName) -> Option<String>,
) -> Vec<SlotEffect> {
    let axes = axis_values(machine, obs);
    let mut out = Vec::new();
    for j in 0..machine.n_slots() {
        let slot = machine.error_slots()[j];
        let c = slot.component.index();
        let axis = machine.slot_axis(j);
        // A head axis' line moves against the tool it carries: its position error is the
        // slot with the tool kept in place (the slot alone shifts the head rigidly).
        let slots = (slot.kind == SlotKind::Position)
            .then(|| machine.position_error_slots(slot.body, slot.component))
            .flatten()
            .unwrap_or_else(|| vec![(j, 1.0)]);
        let against_tool = slots.len() > 1;
        let column_of = |m: &DMat| {
            slots
                .iter()
                .fold(DVec::zeros(m.nrows()), |acc, &(k, f)| acc + m.column(k) * f)
        };
        let column = match (axis.map(|a| a.kind), slot.kind) {
            (Some(AxisKind::Linear), SlotKind::Position) => continue,
            _ => column_of(s),
        };
        let axis_k = axis.and_then(|a| machine.axis_index(&a.name));
        let reference = poses.map(|poses| Reference {
            column: column_of(poses.sensitivity),
            coordinate: axis_k
                .map(|k| poses.axes[k].clone())
                .unwrap_or_else(|| vec![0.0; column.len()]),
            time_s: poses.time_s.to_vec(),
        });
        if column.amax() < 1e-12 && reference.as_ref().is_none_or(|r| r.column.amax() < 1e-12) {
            continue;
        }
        let mut name = slot_name(machine, j);
        // What separates an error from the model is the instrument's to say, except for a
        // rotary line's own direction, which no measurement of positions separates: a line has
        // no place along itself (the shift is the place of what the axis carries), and its turn
        // about itself is the axis' angular zero, which only a reference of that angle shows.
        let own = axis_component(machine, j)
            .filter(|_| slot.kind == SlotKind::Position)
            .filter(|_| axis.is_some_and(|a| a.kind == AxisKind::Rotary));
        let separated_by = match axis {
            Some(a) if own == Some(c) => Some(format!(
                "a reference of {an}'s own angle at its zero (a level, or a face of what {an} carries probed, at {an} = 0)",
                an = a.name
            )),
            _ if own == Some(c + 3) => None,
            _ => hint(&name),
        };
        if against_tool {
            name.label = format!("{} (the line against the tool)", name.label);
            name.meaning = format!(
                "{}; on the head, the axis line is off its place against the tool it carries (pivot offset)",
                name.meaning
            );
        }
        if let (Some(axis), SlotKind::Motion) = (axis, slot.kind) {
            if axis.kind == AxisKind::Linear && c < 3 {
                if let (Some(k), Some(own)) =
                    (machine.axis_index(&axis.name), axis_component(machine, j))
                {
                    let own = (own, axis.sign * axis.direction[own]);
                    if let Some(mut sq) = squareness_effect(&name, &column, &axes[k], c, own) {
                        // A squareness is a constant: its effect at the reference pose adds in.
                        if let Some(r) = &reference {
                            if let Some(at_ref) =
                                squareness_effect(&name, &r.column, &r.coordinate, c, own)
                            {
                                sq.column += at_ref.column;
                            }
                        }
                        sq.separated_by = separated_by.clone();
                        out.push(sq);
                    }
                }
            }
        }
        if let (Some(axis), SlotKind::Position) = (axis, slot.kind) {
            if let Some(child) =
                carried_in_place(machine, slot.body).filter(|_| axis.kind == AxisKind::Rotary)
            {
                let col = absolute_location_column(machine, s, slot.body, child, c);
                let reference = reference.as_ref().and_then(|own| {
                    let r = poses?.sensitivity;
                    absolute_location_column(machine, r, slot.body, child, c).map(|column| {
                        Reference {
                            column,
                            ..own.clone()
                        }
                    })
                });
                if let Some(col) = col.filter(|c| c.amax() > 1e-12) {
                    let carried = match machine.axis_moving(child) {
                        Some(_) => format!("{} axis", machine.bodies()[child].name),
                        None => machine.bodies()[child].name.clone(),
                    };
                    out.push(SlotEffect {
                        name: format!("{}{ABSOLUTE}", name.name),
                        label: format!(
                            "{} with the {carried} kept in place (absolute)",
                            name.label
                        ),
                        meaning: format!(
                            "{}; the {carried} it carries keeps its own place and direction",
                            name.meaning
                        ),
                        quantity: if c < 3 {
                            Quantity::Length
                        } else {
                            Quantity::Angle
                        },
                        role: name.role.clone(),
                        column: col,
                        separated_by: separated_by.clone(),
                        reference,
                    });
                }
            }
        }
        out.push(SlotEffect {
            separated_by,
            name: name.name,
            label: name.label,
            meaning: name.meaning,
            quantity: if c < 3 {
                Quantity::Length
            } else {
                Quantity::Angle
            },
            role: name.role,
            column,
            reference,
        });
    }
    out
}

/// Each observation's setup reference pose (an R-test's centring), as [`slot_effects`] takes
/// it.
#[derive(Clone, Copy)]
pub(crate) struct ReferencePoses<'a> {
    /// Sensitivity of every observation to each slot's value there (n × slots).
    pub sensitivity: &'a DMat,
    /// The axis values there, one vector (one value per observation) per axis.
    pub axes: &'a [Vec<f64>],
    /// Its time, s (one per observation).
    pub time_s: &'a [f64],
}

/// The suffix of a location error's name in the absolute representation (`EX0B abs`).
const ABSOLUTE: &str = " abs";

/// The relative form of an absolute location error's name (`EX0B` of `EX0B abs`). As constants
/// the two differ by the carried body's own location errors: where those and the relative form
/// hold it, no measurement separates them.
pub(crate) fn relative_form(name: &str) -> Option<&str> {
    name.strip_suffix(ABSOLUTE)
}

/// A location error's name in the other representation: the relative form of an absolute one
/// (`EX0B` of `EX0B abs`), the absolute form of a relative one.
pub(crate) fn other_form(name: &str) -> String {
    relative_form(name).map_or_else(|| format!("{name}{ABSOLUTE}"), String::from)
}

/// The body after `body` on its kinematic branch that a location error of `body`'s line can
/// leave in place: the next rotary axis' body, or on the workpiece branch the workpiece the last
/// rotary axis carries (no axis moves it). (On the tool branch the body a swivel head carries
/// is already kept in place by the line's own slots, [`Machine::position_error_slots`].)
fn carried_in_place(machine: &Machine, body: usize) -> Option<usize> {
    let (child, tool) = machine.next_on_branch(body)?;
    match machine.axis_moving(child) {
        Some(axis) => (axis.kind == AxisKind::Rotary).then_some(child),
        None => (!tool).then_some(child),
    }
}

/// A location error of a rotary axis that carries another rotary axis, or the workpiece, exists
/// in two representations (ISO 230-7): *relative*, what it carries moves with it (the slot
/// itself), and *absolute*, the carried axis or workpiece keeps its place and direction at home
/// ([`carried_in_place`]). The two differ by what the carried body's own location errors, or a
/// workpiece's set-up, hold while they are constant, not when the line drifts. The absolute one
/// is the axis' slot with twist e plus the carried body's slot with `−(v − t × ω, ω)` (t the
/// carried body's offset; home frames are parallel, so the adjoint reduces to this).
fn absolute_location_column(
    machine: &Machine,
    s: &DMat,
    body: usize,
    child: usize,
    component: usize,
) -> Option<DVec> {
    let slot = |b: usize, k: usize| {
        machine
            .error_slots()
            .iter()
            .position(|e| e.body == b && e.kind == SlotKind::Position && e.component.index() == k)
    };
    let t = machine.body_home_mm(child) - machine.body_home_mm(body);
    let (mut v, mut w) = (Vec3::zeros(), Vec3::zeros());
    if component < 3 {
        v[component] = 1.0
    } else {
        w[component - 3] = 1.0
    }
    let v_child = -(v - t.cross(&w));
    let mut col = s.column(slot(body, component)?).into_owned();
    for k in 0..6 {
        let coef = if k < 3 { v_child[k] } else { -w[k - 3] };
        if coef != 0.0 {
            col += s.column(slot(child, k)?) * coef;
        }
    }
    Some(col)
}

/// Reads the commanded axes of a machine from `<axis>_mm` / `<axis>_deg` columns (rad inside).
pub(crate) fn read_axes(machine: &Machine, table: &Table) -> Result<Vec<Vec<f64>>> {
    machine
        .axes()
        .iter()
        .map(|axis| {
            let lower = axis.name.to_lowercase();
            match axis.kind {
                AxisKind::Linear => Ok(table.numbers_within(
                    table.require(&format!("{lower}_mm"))?,
                    LINEAR_LIMIT_MM,
                    "a linear axis command of 10 km or more is no machine position",
                )?),
                AxisKind::Rotary => Ok(table
                    .numbers_within(
                        table.require(&format!("{lower}_deg"))?,
                        ROTARY_LIMIT_DEG,
                        "a rotary axis command of 10⁶° or more is no machine position",
                    )?
                    .into_iter()
                    .map(f64::to_radians)
                    .collect()),
            }
        })
        .collect()
}

/// The vectors of three columns (`names`: x, y, z) of every row, each number's magnitude below
/// `max_abs` (`meaning` says why).
pub(crate) fn read_vectors(
    table: &Table,
    names: [&str; 3],
    max_abs: f64,
    meaning: &str,
) -> Result<Vec<Vec3>> {
    let at = names
        .iter()
        .map(|c| table.require(c))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let columns = at
        .into_iter()
        .map(|c| table.numbers_within(c, max_abs, meaning))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    Ok((0..table.len())
        .map(|r| Vec3::new(columns[0][r], columns[1][r], columns[2][r]))
        .collect())
}

/// [`read_vectors`] for optional columns: `None` when none of the three is in the table (all
/// three are required once one is).
pub(crate) fn read_optional_vectors(
    table: &Table,
    names: [&str; 3],
    max_abs: f64,
    meaning: &str,
) -> Result<Option<Vec<Vec3>>> {
    if names.iter().all(|c| table.column(c).is_none()) {
        return Ok(None);
    }
    read_vectors(table, names, max_abs, meaning).map(Some)
}

/// Largest linear axis command (mm) and rotary axis command (°) a dataset may hold.
pub(crate) const LINEAR_LIMIT_MM: f64 = 1e7;
/// See [`LINEAR_LIMIT_MM`].
pub(crate) const ROTARY_LIMIT_DEG: f64 = 1e6;

/// Reads the optional time column `t_s` (below 10⁹ s, about 30 years).
pub(crate) fn read_times(table: &Table) -> Result<Option<Vec<f64>>> {
    table
        .column("t_s")
        .map(|c| {
            table
                .numbers_within(
                    c,
                    1e9,
                    "a time of 10⁹ s (30 years) or more is not a measuring time",
                )
                .map_err(Into::into)
        })
        .transpose()
}

/// The location errors of every rotary axis (ISO 230-7) across its line: the position of the
/// line in the two directions across the axis and its orientation about them (EX0B, EZ0B, EA0B,
/// EC0B for a B axis along Y), then the same in the absolute representation (`EX0C abs`: the
/// line off its place under what it carries, which keeps its own). The engine keeps the first
/// of those the setups separate: on a table the relative form, the absolute one being a
/// combination of it and the next axis'; on a fork head (C carrying A carrying the tool) the
/// relative form of C moves the whole head, tool included, which no reading against the
/// centring sees, and the absolute one is the tool off the C line. Errors along and about the
/// axis' own direction are a shift along the line and the angular zero, which these
/// instruments see as setup errors.
pub(crate) fn location_names(machine: &Machine) -> Vec<String> {
    let mut names = Vec::new();
    for axis in machine.axes().iter().filter(|a| a.kind == AxisKind::Rotary) {
        let own = (0..3).find(|&k| (axis.direction[k].abs() - 1.0).abs() < 1e-9);
        for k in (0..6).filter(|&k| Some(k % 3) != own) {
            names.push(catalogue::location_error_name(
                Component::ALL[k],
                &axis.name,
            ));
        }
    }
    let absolute: Vec<String> = names.iter().map(|n| format!("{n}{ABSOLUTE}")).collect();
    names.extend(absolute);
    names
}
