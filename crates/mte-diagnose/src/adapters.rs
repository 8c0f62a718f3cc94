//! Observation models of machine datasets: how each kinematic error slot reaches the
//! observations, from the machine's first-order kinematics ([`Machine::jacobian`]), and the ISO
//! 230-1 names engineers use for the slots.

use std::path::Path;

use mte_kinematics::{AxisKind, Machine, SlotKind};
use mte_linalg::{DMat, DVec, Vec3};

use crate::candidate::{SlotEffect, SlotRole, physical_effects};
use crate::data::{Observations, Variable, VariableKind};
use crate::dataset::{Manifest, Prepared, Table, read_table};
use crate::term::{Family, Quantity, Term};
use crate::{DiagnoseError, Result};

/// Prepares an R-test or tracker dataset.
pub(crate) fn prepare_machine_dataset(
    kind: &str,
    manifest: &Manifest,
    table: &Table,
    dir: &Path,
    manifest_path: &Path,
) -> Result<Prepared> {
    let field_error = |detail: String| DiagnoseError::Dataset {
        path: manifest_path.display().to_string(),
        detail,
    };
    match kind {
        "tracker" => {
            let machine = load_machine(manifest, dir, manifest_path)?;
            prepare_tracker(manifest, table, &machine, dir, manifest_path)
        }
        other => Err(field_error(format!(
            "field `kind`: `{other}`, expected axis or tracker (R-test data use the mte-rtest/1 manifest)"
        ))),
    }
}

fn load_machine(manifest: &Manifest, dir: &Path, manifest_path: &Path) -> Result<Machine> {
    let name = manifest
        .machine
        .as_deref()
        .ok_or_else(|| DiagnoseError::Dataset {
            path: manifest_path.display().to_string(),
            detail: "field `machine`: missing (a library machine name or a machine JSON file)"
                .into(),
        })?;
    Machine::library_or_file(name, dir).map_err(|e| DiagnoseError::Dataset {
        path: manifest_path.display().to_string(),
        detail: format!("field `machine`: {e}"),
    })
}

/// ISO 230-1 letter of a slot component: X, Y, Z for translations, A, B, C for rotations.
fn component_letter(component: usize) -> char {
    ['X', 'Y', 'Z', 'A', 'B', 'C'][component]
}

/// The ISO 230-1 view of one kinematic slot: name, meaning and role.
struct SlotName {
    name: String,
    label: String,
    meaning: String,
    role: SlotRole,
}

/// Names a slot the way ISO 230-1 does: a component error `E{dir}{axis}` for a motion slot of
/// an axis (EXX positioning, EYX straightness, EAX roll …), a location error `E{dir}0{axis}`
/// for a position slot of an axis, a setup error for the tool and the workpiece.
fn slot_name(machine: &Machine, slot: usize) -> SlotName {
    let s = machine.error_slots()[slot];
    let c = s.component.index();
    let letter = component_letter(c);
    let body = &machine.bodies()[s.body];
    match (machine.slot_axis(slot), s.kind) {
        (Some(axis), SlotKind::Motion) => {
            let a = axis.name.as_str();
            let own = axis_component(machine, slot);
            let (positioning, straightness) = match axis.kind {
                AxisKind::Linear => (c < 3 && own == Some(c), c < 3 && own != Some(c)),
                AxisKind::Rotary => (c >= 3 && own == Some(c), false),
            };
            let what = match (axis.kind, c < 3, positioning, straightness) {
                (_, _, true, _) => "positioning error".to_string(),
                (_, _, _, true) => format!("straightness error in {letter}"),
                (AxisKind::Linear, false, _, _) => {
                    format!("angular error about {}", ['X', 'Y', 'Z'][c - 3])
                }
                (AxisKind::Rotary, true, _, _) => format!(
                    "{} error motion in {letter}",
                    if own.is_some_and(|o| o == c + 3) {
                        "axial"
                    } else {
                        "radial"
                    }
                ),
                _ => format!("tilt error motion about {}", ["X", "Y", "Z"][c.max(3) - 3]),
            };
            SlotName {
                name: format!("E{letter}{a}"),
                label: format!("{what} of {a}"),
                meaning: format!("{what} of the {a} axis, a function of its position"),
                role: SlotRole::Component {
                    axis: a.to_string(),
                    positioning,
                    straightness,
                },
            }
        }
        (Some(axis), SlotKind::Position) => {
            let a = axis.name.as_str();
            let what = if c < 3 {
                format!("position of the {a} axis line in {letter}")
            } else {
                format!(
                    "orientation of the {a} axis about {}",
                    ['X', 'Y', 'Z'][c - 3]
                )
            };
            SlotName {
                name: format!("E{letter}0{a}"),
                label: format!("location error {what}"),
                meaning: format!("{what} differs from nominal (a location error of ISO 230-7)"),
                role: SlotRole::Constant {
                    family: Family::Location,
                },
            }
        }
        (None, _) => SlotName {
            name: format!(
                "{} {}{}",
                body.name,
                if c < 3 { "offset " } else { "tilt " },
                letter
            ),
            label: format!(
                "setup error of the {} ({}{})",
                body.name,
                if c < 3 { "offset in " } else { "tilt about " },
                letter
            ),
            meaning: format!("the {} sits off its nominal place (setup error)", body.name),
            role: SlotRole::Constant {
                family: Family::Setup,
            },
        },
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

/// Squareness of a linear axis: the linear part of its straightness. The axis `a` tilted by θ
/// about the third direction `r` moves by `θ (r × a)` per unit travel, so the straightness in
/// direction `d` grows as `θ ((r × a)·d) · s` with the axis coordinate `s`.
fn squareness_effect(
    name: &SlotName,
    column: &DVec,
    coordinate: &[f64],
    slot_dir: usize,
    axis_dir: usize,
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
    let sign = rv.cross(&av).dot(&dv);
    let plane: String = [component_letter(axis_dir), component_letter(slot_dir)]
        .iter()
        .collect();
    let iso = format!("E{}0{axis}", component_letter(r + 3));
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
/// (n × n_slots), the axis values per observation, and hints on what separates them. With a
/// `reference` (sensitivities to the slots' values at each observation's reference pose, and
/// the axis values there), an error acts at both poses.
///
/// Position slots of linear axes are left out: their translations are constant offsets (setup
/// errors say the same) and their rotations turn the whole branch downstream, which the
/// squareness and angular component errors describe in the terms engineers use.
fn slot_effects(
    machine: &Machine,
    s: &DMat,
    axes: &[Vec<f64>],
    reference: Option<(&DMat, &[Vec<f64>])>,
    hint: &dyn Fn(&SlotName) -> Option<String>,
) -> Vec<SlotEffect> {
    let reference_matrix = reference;
    let mut out = Vec::new();
    for j in 0..machine.n_slots() {
        let slot = machine.error_slots()[j];
        let c = slot.component.index();
        let axis = machine.slot_axis(j);
        let column = match (axis.map(|a| a.kind), slot.kind) {
            (Some(AxisKind::Linear), SlotKind::Position) => continue,
            _ => s.column(j).into_owned(),
        };
        let axis_k = axis.and_then(|a| machine.axis_index(&a.name));
        let reference = reference.map(|(r, ref_axes)| {
            let coordinate = axis_k
                .map(|k| ref_axes[k].clone())
                .unwrap_or_else(|| vec![0.0; column.len()]);
            (r.column(j).into_owned(), coordinate)
        });
        if column.amax() < 1e-12 && reference.as_ref().is_none_or(|(r, _)| r.amax() < 1e-12) {
            continue;
        }
        let name = slot_name(machine, j);
        if let (Some(axis), SlotKind::Motion) = (axis, slot.kind) {
            if axis.kind == AxisKind::Linear && c < 3 {
                if let (Some(k), Some(own)) =
                    (machine.axis_index(&axis.name), axis_component(machine, j))
                {
                    if let Some(mut sq) = squareness_effect(&name, &column, &axes[k], c, own) {
                        // A squareness is a constant: its effect at the reference pose adds in.
                        if let Some((r, coordinate)) = &reference {
                            if let Some(at_ref) = squareness_effect(&name, r, coordinate, c, own) {
                                sq.column += at_ref.column;
                            }
                        }
                        sq.separated_by = hint(&name);
                        out.push(sq);
                    }
                }
            }
        }
        if let (Some(axis), SlotKind::Position) = (axis, slot.kind) {
            if let Some(child) =
                rotary_child(machine, slot.body).filter(|_| axis.kind == AxisKind::Rotary)
            {
                let col = absolute_location_column(machine, s, slot.body, child, c);
                let reference = reference.as_ref().and_then(|(_, coordinate)| {
                    let (r, _) = reference_matrix?;
                    absolute_location_column(machine, r, slot.body, child, c)
                        .map(|r| (r, coordinate.clone()))
                });
                if let Some(col) = col.filter(|c| c.amax() > 1e-12) {
                    let carried = &machine.bodies()[child].name;
                    out.push(SlotEffect {
                        name: format!("{} abs", name.name),
                        label: format!(
                            "{} with the {carried} axis kept in place (absolute)",
                            name.label
                        ),
                        meaning: format!(
                            "{}; the {carried} axis it carries keeps its own place and direction",
                            name.meaning
                        ),
                        quantity: if c < 3 {
                            Quantity::Length
                        } else {
                            Quantity::Angle
                        },
                        role: name.role.clone(),
                        column: col,
                        separated_by: hint(&name),
                        reference,
                    });
                }
            }
        }
        out.push(SlotEffect {
            separated_by: hint(&name),
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

/// The body after `body` on its kinematic branch, when it is moved by a rotary axis.
fn rotary_child(machine: &Machine, body: usize) -> Option<usize> {
    let child = [machine.tool_chain(), machine.workpiece_chain()]
        .into_iter()
        .find_map(|chain| {
            chain
                .iter()
                .position(|&b| b == body)
                .and_then(|k| chain.get(k + 1).copied())
        })?;
    let k = machine.axes().iter().position(|a| a.body == child)?;
    (machine.axes()[k].kind == AxisKind::Rotary).then_some(child)
}

/// A location error of a rotary axis that carries another rotary axis exists in two
/// representations (ISO 230-7): *relative*, the carried axis moves with it (the slot itself),
/// and *absolute*, the carried axis keeps its place and direction at home. The absolute one is
/// the axis' slot with twist e plus the carried body's slot with `−(v − t × ω, ω)` (t the
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
fn read_axes(machine: &Machine, table: &Table) -> Result<Vec<Vec<f64>>> {
    machine
        .axes()
        .iter()
        .map(|axis| {
            let lower = axis.name.to_lowercase();
            match axis.kind {
                AxisKind::Linear => Ok(table.numbers(table.require(&format!("{lower}_mm"))?)?),
                AxisKind::Rotary => Ok(table
                    .numbers(table.require(&format!("{lower}_deg"))?)?
                    .into_iter()
                    .map(f64::to_radians)
                    .collect()),
            }
        })
        .collect()
}

/// An ISO 10791-6 R-test dataset in the `mte-rtest/1` format, observed through mte-rtest's
/// measurement model: each reading `d = p_ball − p_nest` (machine coordinates), with the ball
/// centred in the nest at each setup's centring pose, so an error acts through its value at the
/// reading and at the centring ([`mte_rtest::RowSensitivity`]).
pub(crate) fn prepare_rtest(manifest_path: &Path, noise_um: Option<f64>) -> Result<Prepared> {
    use mte_rtest::model::{NuisanceKind, ObservationModel};
    let path = manifest_path.display().to_string();
    let dataset_error = |e: mte_rtest::RtestError| DiagnoseError::Dataset {
        path: path.clone(),
        detail: e.to_string(),
    };
    let text = std::fs::read_to_string(manifest_path).map_err(|e| DiagnoseError::Dataset {
        path: path.clone(),
        detail: e.to_string(),
    })?;
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| DiagnoseError::Dataset {
            path: path.clone(),
            detail: e.to_string(),
        })?;
    let machine_name = value
        .get("machine")
        .and_then(|v| v.as_str())
        .ok_or_else(|| DiagnoseError::Dataset {
            path: path.clone(),
            detail: "field `machine`: missing".into(),
        })?;
    let dir = manifest_path.parent().unwrap_or(Path::new("."));
    let machine =
        Machine::library_or_file(machine_name, dir).map_err(|e| DiagnoseError::Dataset {
            path: path.clone(),
            detail: format!("field `machine`: {e}"),
        })?;
    let rotary = |name: &str| {
        machine
            .axis_index(name)
            .is_some_and(|k| machine.axes()[k].kind == AxisKind::Rotary)
    };
    let data = mte_rtest::io::read_dataset(manifest_path, &rotary).map_err(dataset_error)?;
    let model = ObservationModel::new(&machine, &data).map_err(dataset_error)?;
    let sens = model.sensitivity();
    let rows = data.readings.len();
    let n = 3 * rows;
    let per_obs = |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..n).map(|i| f(i / 3)).collect() };
    let mut variables: Vec<Variable> = machine
        .axes()
        .iter()
        .enumerate()
        .map(|(k, a)| Variable {
            name: a.name.clone(),
            kind: if a.kind == AxisKind::Rotary {
                VariableKind::RotaryAxis
            } else {
                VariableKind::LinearAxis
            },
            values: per_obs(&|r| data.readings[r].q[k]),
        })
        .collect();
    variables.push(Variable {
        name: "t".into(),
        kind: VariableKind::Time,
        values: per_obs(&|r| data.readings[r].t_s),
    });
    let observations = Observations {
        values: DVec::from_fn(n, |i, _| data.readings[i / 3].d_mm[i % 3]),
        sigma: noise_um.map(|u| DVec::from_element(n, u * 1e-3)),
        variables,
        setup: (0..n).map(|i| data.readings[i / 3].setup).collect(),
        setup_names: data.setups.iter().map(|s| s.id.clone()).collect(),
        channel: (0..n).map(|i| i % 3).collect(),
        channel_names: vec!["dx".into(), "dy".into(), "dz".into()],
        setup_kind: "ball position".into(),
        quantity: Quantity::Length,
    };
    observations.validate()?;
    let n_slots = machine.n_slots();
    let mut at_row = DMat::zeros(n, n_slots);
    let mut at_ref = DMat::zeros(n, n_slots);
    for (r, rs) in sens.iter().enumerate() {
        for ch in 0..3 {
            at_row.row_mut(3 * r + ch).copy_from(&rs.at_row.row(ch));
            at_ref
                .row_mut(3 * r + ch)
                .copy_from(&rs.at_centring.row(ch));
        }
    }
    let axes_per_obs: Vec<Vec<f64>> = (0..machine.axes().len())
        .map(|k| per_obs(&|r| data.readings[r].q[k]))
        .collect();
    let axes_at_centring: Vec<Vec<f64>> = (0..machine.axes().len())
        .map(|k| per_obs(&|r| data.setups[data.readings[r].setup].centring_q[k]))
        .collect();
    let hint = |name: &SlotName| {
        match name.role {
        SlotRole::Constant { family: Family::Location } => Some(
            "a second ball position at another height or distance along the rotary axis (e.g. the ball turned to the other side of the table by C, or raised in Z)".to_string(),
        ),
        _ => None,
    }
    };
    let effects = slot_effects(
        &machine,
        &at_row,
        &axes_per_obs,
        Some((&at_ref, &axes_at_centring)),
        &hint,
    );
    // Base: the sensor's zero in each setup, and the positions of the rotary axis lines.
    let mut base: Vec<Term> = Vec::new();
    let mut setup_candidates: Vec<Box<dyn crate::Candidate>> = Vec::new();
    for (k, setup) in data.setups.iter().enumerate() {
        for (kind, what) in [
            (NuisanceKind::SensorZero, "sensor zero"),
            (NuisanceKind::NestOffset, "nest offset"),
            (NuisanceKind::BallOffset, "ball centring offset"),
        ] {
            for a in 0..3 {
                let col = DVec::from_fn(n, |i, _| {
                    if data.readings[i / 3].setup == k {
                        sens[i / 3].nuisance(kind)[(i % 3, a)]
                    } else {
                        0.0
                    }
                });
                let axis = ['x', 'y', 'z'][a];
                let family = if kind == NuisanceKind::SensorZero {
                    Family::Base
                } else {
                    Family::Setup
                };
                let t = Term::single(
                    format!("{} {what} {axis}", setup.id),
                    format!("{what} in {axis} (setup {})", setup.id),
                    format!("the R-test's {what} in this setup"),
                    family,
                    col,
                    Quantity::Length,
                )
                .separated_by("a second nest length, or the ball position probed on the table");
                if kind == NuisanceKind::SensorZero {
                    base.push(t);
                } else {
                    setup_candidates.push(Box::new(t));
                }
            }
        }
    }
    // The base model: what the user states, by default the location errors of every rotary
    // axis (position and orientation of its line) as IBS, KinematicsOpt and CYCLE996 identify
    // them; the engine leaves out what the setups cannot separate, and says so.
    let spec = crate::dataset::base_spec(
        value.get("base_model"),
        manifest_path,
        crate::BaseModelSpec {
            location: true,
            ..Default::default()
        },
    )?;
    let (terms, completions) = crate::dataset::spec_terms(
        &spec,
        &observations,
        &effects,
        &location_names(&machine),
        manifest_path,
    )?;
    base.extend(terms);
    // A constant in the base is no candidate; its drift is (as one of the base's).
    let candidate_effects: Vec<SlotEffect> = effects
        .into_iter()
        .filter(|e| {
            !(matches!(e.role, SlotRole::Constant { .. }) && base.iter().any(|b| b.name == e.name))
        })
        .collect();
    let drifting: Vec<&Term> = base.iter().collect();
    let mut candidates = physical_effects(&observations, &candidate_effects, &drifting);
    candidates.extend(setup_candidates);
    candidates.extend(completions);
    let title = if data.note.is_empty() {
        format!("R-test on {}", machine.name())
    } else {
        format!("R-test on {} ({})", machine.name(), data.note)
    };
    Ok(Prepared {
        observations,
        base,
        candidates,
        title,
    })
}

/// The location errors of every rotary axis (ISO 230-7) across its line: the position of the
/// line in the two directions across the axis and its orientation about them (EX0B, EZ0B, EA0B,
/// EC0B for a B axis along Y). Errors along and about the axis' own direction are a shift along
/// the line and the angular zero, which these instruments see as setup errors.
fn location_names(machine: &Machine) -> Vec<String> {
    let mut names = Vec::new();
    for axis in machine.axes().iter().filter(|a| a.kind == AxisKind::Rotary) {
        let own = (0..3).find(|&k| (axis.direction[k].abs() - 1.0).abs() < 1e-9);
        for k in 0..6 {
            if Some(k % 3) != own {
                names.push(format!("E{}0{}", component_letter(k), axis.name));
            }
        }
    }
    names
}

/// Laser-tracker multilateration data (seed 004): interferometric lengths from several stations
/// to targets the machine visits. The network is first adjusted as a free network
/// (`mte-metrology`, datum on the nominal targets) to get the stations and dead paths; then the
/// lengths themselves are the observations, linearised there: station positions and dead paths
/// are the base model, and the machine's errors enter through the target positions,
/// `δℓᵢⱼ = uᵢⱼ·(δPⱼ − δQᵢ) − δdᵢ` with uᵢⱼ the unit vector from station to target. Working on the
/// lengths keeps their independent noise, so the tests of significance are exact.
fn prepare_tracker(
    manifest: &Manifest,
    lengths: &Table,
    machine: &Machine,
    dir: &Path,
    manifest_path: &Path,
) -> Result<Prepared> {
    use mte_metrology::adjust::{AdjustParams, adjust};
    use mte_metrology::network::{DeadPath, LengthObservation, Network, Station, Target};
    let missing = |field: &str, what: &str| DiagnoseError::Dataset {
        path: manifest_path.display().to_string(),
        detail: format!("field `{field}`: missing ({what})"),
    };
    let noise_um = manifest.noise_um.ok_or_else(|| {
        missing(
            "noise_um",
            "the standard uncertainty of one tracker length, µm",
        )
    })?;
    let targets_file = manifest
        .targets
        .as_deref()
        .ok_or_else(|| missing("targets", "the targets table: id and commanded axes"))?;
    let targets = read_table(&dir.join(targets_file))?;
    let axes = read_axes(machine, &targets)?;
    let id_col = targets.require("id")?;
    let ids: Vec<String> = (0..targets.len())
        .map(|r| targets.text(r, id_col).to_string())
        .collect();
    let zero = vec![0.0; machine.n_slots()];
    let q_of = |r: usize| axes.iter().map(|a| a[r]).collect::<Vec<_>>();
    let nominal: Vec<Vec3> = (0..targets.len())
        .map(|r| {
            machine
                .tool_in_workpiece(&q_of(r), &zero)
                .translation
                .vector
        })
        .collect();
    if manifest.setups.len() < 4 {
        return Err(DiagnoseError::Dataset {
            path: manifest_path.display().to_string(),
            detail: format!(
                "field `setups`: {} stations, a multilateration needs at least 4",
                manifest.setups.len()
            ),
        });
    }
    let mut stations = Vec::new();
    for s in &manifest.setups {
        let p = s
            .station_mm
            .ok_or_else(|| missing("setups[].station_mm", "approximate station position, mm"))?;
        stations.push(Station {
            id: s.id.clone(),
            position_mm: Vec3::new(p[0], p[1], p[2]),
            dead_path_mm: 0.0,
            dead_path: DeadPath::Free,
        });
    }
    let (cs, ct, cl) = (
        lengths.require("station")?,
        lengths.require("target")?,
        lengths.require("length_mm")?,
    );
    let mut observations = Vec::new();
    for r in 0..lengths.len() {
        let station = manifest
            .setups
            .iter()
            .position(|s| s.id == lengths.text(r, cs))
            .ok_or_else(|| {
                lengths.error(
                    lengths.line(r),
                    format!(
                        "column `station`: `{}` is not a station of the manifest",
                        lengths.text(r, cs)
                    ),
                )
            })?;
        let target = ids
            .iter()
            .position(|t| t == lengths.text(r, ct))
            .ok_or_else(|| {
                lengths.error(
                    lengths.line(r),
                    format!(
                        "column `target`: `{}` is not in {targets_file}",
                        lengths.text(r, ct)
                    ),
                )
            })?;
        observations.push(LengthObservation {
            station,
            target,
            length_mm: lengths.number(r, cl)?,
            sigma_mm: noise_um * 1e-3,
        });
    }
    let network = Network {
        stations,
        targets: ids
            .iter()
            .zip(&nominal)
            .map(|(id, p)| Target {
                id: id.clone(),
                nominal_mm: *p,
            })
            .collect(),
        observations,
    };
    let adjustment =
        adjust(&network, &AdjustParams::default()).map_err(|e| DiagnoseError::Dataset {
            path: lengths.source_name.clone(),
            detail: format!("network adjustment: {e}"),
        })?;
    let n = network.observations.len();
    let ns = network.stations.len();
    let station_of: Vec<usize> = network.observations.iter().map(|o| o.station).collect();
    let target_of: Vec<usize> = network.observations.iter().map(|o| o.target).collect();
    let q: Vec<Vec3> = adjustment.stations.iter().map(|s| s.position_mm).collect();
    let d: Vec<f64> = adjustment.stations.iter().map(|s| s.dead_path_mm).collect();
    let u: Vec<Vec3> = (0..n)
        .map(|k| (nominal[target_of[k]] - q[station_of[k]]).normalize())
        .collect();
    let values = DVec::from_fn(n, |k, _| {
        network.observations[k].length_mm
            - ((nominal[target_of[k]] - q[station_of[k]]).norm() - d[station_of[k]])
    });
    let mut variables: Vec<Variable> = machine
        .axes()
        .iter()
        .zip(&axes)
        .map(|(a, v)| Variable {
            name: a.name.clone(),
            kind: if a.kind == AxisKind::Rotary {
                VariableKind::RotaryAxis
            } else {
                VariableKind::LinearAxis
            },
            values: target_of.iter().map(|&j| v[j]).collect(),
        })
        .collect();
    if let Some(c) = targets.column("t_s") {
        let t = targets.numbers(c)?;
        variables.push(Variable {
            name: "t".into(),
            kind: VariableKind::Time,
            values: target_of.iter().map(|&j| t[j]).collect(),
        });
    }
    let observations = Observations {
        values,
        sigma: Some(DVec::from_element(n, noise_um * 1e-3)),
        variables,
        setup: station_of.clone(),
        setup_names: network.stations.iter().map(|s| s.id.clone()).collect(),
        channel: vec![0; n],
        channel_names: vec!["length".into()],
        setup_kind: "tracker station".into(),
        quantity: Quantity::Length,
    };
    observations.validate()?;
    // Base: each station's position and dead path.
    let mut base = Vec::new();
    for i in 0..ns {
        let id = &network.stations[i].id;
        for k in 0..3 {
            let letter = component_letter(k);
            let direction = Vec3::ith(k, 1.0);
            base.push(Term::single(
                format!("{id} {}", letter.to_ascii_lowercase()),
                format!("station {id} position in {letter}"),
                "tracker station coordinate",
                Family::Base,
                DVec::from_fn(n, |r, _| {
                    if station_of[r] == i {
                        -u[r].dot(&direction)
                    } else {
                        0.0
                    }
                }),
                Quantity::Length,
            ));
        }
        base.push(Term::single(
            format!("{id} dead path"),
            format!("station {id} dead-path length"),
            "length from the tracker's origin to its interferometer zero",
            Family::Base,
            DVec::from_fn(n, |r, _| if station_of[r] == i { -1.0 } else { 0.0 }),
            Quantity::Length,
        ));
    }
    // Slot sensitivities: the tool tip (reflector) error at each commanded pose, along the line of sight.
    let mut tip = vec![DMat::zeros(3, machine.n_slots()); nominal.len()];
    let mut jac = DMat::zeros(6, machine.n_slots());
    for (r, t) in tip.iter_mut().enumerate() {
        machine.jacobian_into(&q_of(r), &mut jac);
        t.copy_from(&jac.rows(0, 3));
    }
    let mut s = DMat::zeros(n, machine.n_slots());
    for k in 0..n {
        s.row_mut(k)
            .copy_from(&(u[k].transpose() * &tip[target_of[k]]));
    }
    let axes_per_obs: Vec<Vec<f64>> = axes
        .iter()
        .map(|v| target_of.iter().map(|&j| v[j]).collect())
        .collect();
    let mut effects = slot_effects(machine, &s, &axes_per_obs, None, &|_| None);
    // A point measurement sees the tip's position errors along axes that move; constant offsets
    // of the machine are a rigid shift of all targets, which the stations absorb.
    effects.retain(|e| {
        !matches!(
            e.role,
            SlotRole::Constant {
                family: Family::Setup | Family::Location
            }
        )
    });
    effects.push(SlotEffect {
        name: "tracker scale".into(),
        label: "scale error of the tracker's lengths".into(),
        meaning: "every interferometric length is too long or too short in proportion (wavelength or air-refraction compensation, tracker temperature)".into(),
        quantity: Quantity::Ratio,
        role: SlotRole::Constant { family: Family::Instrument },
        column: DVec::from_fn(n, |k, _| (nominal[target_of[k]] - q[station_of[k]]).norm()),
        separated_by: Some("a calibrated reference length (scale bar) measured by the tracker, or the machine's own scale checked with a laser interferometer".into()),
        reference: None,
    });
    // The user's model of the machine (volumetric compensation: component errors as
    // polynomials, squareness) on top of the stations; none by default.
    let spec = crate::dataset::base_spec(
        manifest.base_model.as_ref(),
        manifest_path,
        crate::BaseModelSpec::default(),
    )?;
    let (terms, completions) =
        crate::dataset::spec_terms(&spec, &observations, &effects, &[], manifest_path)?;
    base.extend(terms);
    effects.retain(|e| {
        !(matches!(e.role, SlotRole::Constant { .. }) && base.iter().any(|b| b.name == e.name))
    });
    let mut candidates = physical_effects(&observations, &effects, &[]);
    candidates.extend(completions);
    let title = manifest
        .description
        .clone()
        .unwrap_or_else(|| format!("laser-tracker multilateration on {}", machine.name()));
    Ok(Prepared {
        observations,
        base,
        candidates,
        title,
    })
}
