//! ISO 230-1 names of the constant (location and squareness) errors the R-test identifies, the
//! IBS/ISO 10791-6 report names (XOB, ZOB, AOB, COB; XOC, YOC, AOC, BOC …), and their slots.
//! The names are `mte-errors`' ([`mte_errors::catalogue`]); this module finds their slots.
//!
//! A name `E<c>0<axis>` means the constant error of component `<c>` (X, Y, Z: translation;
//! A, B, C: rotation about X, Y, Z) of the body moved by `<axis>`, relative to its parent body,
//! i.e. the position-error slot of that body (`EX0B` = δx of the B axis line, `EA0Y` = rotation
//! of the Y axis about X). Slot values are mm and rad.

use crate::error::{Result, RtestError};
use crate::kin;
use mte_errors::catalogue::{
    SQUARENESS_NAMES, component_of_letter, ibs_location_name, location_error_name,
    parse_location_error_name, rotary_location_components,
};
use mte_kinematics::Machine;
use serde::{Deserialize, Serialize};

/// A named constant error and its slot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NamedSlot {
    /// ISO 230-1 name, e.g. "EX0B".
    pub iso: String,
    /// IBS / ISO 10791-6 report name for rotary-axis location errors, e.g. "XOB".
    pub ibs: Option<String>,
    /// The entries of the machine's error vector the error moves, with their factors: its
    /// body's slot, and for the line of a swivel head the tool's at −1
    /// ([`Machine::position_error_slots`]).
    pub slots: Vec<(usize, f64)>,
    /// Angular (rad) rather than linear (mm).
    pub angular: bool,
}

impl NamedSlot {
    /// The body's own slot, which holds the error's value (for the line of a swivel head the
    /// tool's slot holds its negative: [`NamedSlot::add_to`] sets both).
    pub fn slot(&self) -> usize {
        self.slots[0].0
    }

    /// Adds `value` (mm or rad) of this error to the error vector `e`.
    pub fn add_to(&self, e: &mut [f64], value: f64) {
        for &(slot, factor) in &self.slots {
            e[slot] += factor * value;
        }
    }

    /// The derivative of a reading with respect to this error, from its derivatives with
    /// respect to the slots (`of_slot`).
    pub fn derivative(&self, of_slot: impl Fn(usize) -> f64) -> f64 {
        self.slots.iter().map(|&(slot, f)| f * of_slot(slot)).sum()
    }
}

/// Looks up `E<c>0<axis>` on a machine.
///
/// # Errors
/// [`RtestError::UnknownParameter`] for a malformed name, [`RtestError::UnknownAxis`] for an
/// axis the machine does not have.
pub fn slot_by_name(m: &Machine, name: &str) -> Result<NamedSlot> {
    let bad = |msg: &str| RtestError::UnknownParameter {
        name: name.into(),
        message: msg.into(),
    };
    let (c, axis) = parse_location_error_name(name).ok_or_else(|| {
        let letter_ok = name
            .chars()
            .nth(1)
            .is_some_and(|l| component_of_letter(l).is_some());
        if name.starts_with('E') && !letter_ok {
            bad("second letter must be X, Y, Z (translation) or A, B, C (rotation)")
        } else {
            bad("expected an ISO 230-1 constant error name E<X|Y|Z|A|B|C>0<axis>, e.g. EX0B, EA0Y")
        }
    })?;
    let angular = c.index() >= 3;
    let Some(i) = m.axis_index(axis) else {
        return Err(kin::unknown_axis(
            m,
            axis,
            &format!("in parameter `{name}`"),
        ));
    };
    // The line of a swivel head moves against the tool it carries.
    let slots = m
        .position_error_slots(m.axes()[i].body, c)
        .ok_or_else(|| bad("the machine has no constant error slot for this component"))?;
    let rotary = kin::axes(m).iter().any(|a| a.name == axis && a.rotary);
    let ibs = rotary.then(|| ibs_location_name(c, axis));
    Ok(NamedSlot {
        iso: name.into(),
        ibs,
        slots,
        angular,
    })
}

/// The four location errors of every rotary axis A, B or C (ISO 230-7): the two translations
/// across the axis and the two tilts, e.g. EX0B, EZ0B, EA0B, EC0B and EX0C, EY0C, EA0C, EB0C.
///
/// # Errors
/// [`RtestError::UnknownAxis`] for a rotary axis not named A, B or C.
pub fn location_errors(m: &Machine) -> Result<Vec<NamedSlot>> {
    let mut out = Vec::new();
    for a in kin::axes(m).iter().filter(|a| a.rotary) {
        let components = rotary_location_components(&a.name).ok_or_else(|| {
            kin::unknown_axis(
                m,
                &a.name,
                "rotary axes must be named A, B or C to name their location errors",
            )
        })?;
        for c in components {
            out.push(slot_by_name(m, &location_error_name(c, &a.name))?);
        }
    }
    Ok(out)
}

/// The three squareness errors of the linear axes X, Y, Z in this crate's convention (X is the
/// reference, Y squared to it in the XY plane, Z squared to both): EC0Y, EB0Z, EA0Z.
///
/// # Errors
/// [`RtestError::UnknownAxis`] when the machine lacks X, Y or Z.
pub fn squareness_errors(m: &Machine) -> Result<Vec<NamedSlot>> {
    SQUARENESS_NAMES
        .iter()
        .map(|n| slot_by_name(m, n))
        .collect()
}
