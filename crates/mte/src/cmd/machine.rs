//! `mte machine list|show`: the bundled machines and what a machine file describes.

use std::fmt::Write;
use std::path::Path;

use mte::CliError;
use mte_kinematics::{AxisKind, Branch, Joint, KinError, Machine, SlotKind};

/// Arguments of `mte machine`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    cmd: Sub,
}

#[derive(clap::Subcommand)]
enum Sub {
    /// List the bundled machines (crates/mte-kinematics/machines/*.json).
    List,
    /// Show a machine: axes, topology, lower-order body array, error slots.
    Show {
        /// A library name (see `mte machine list`) or a path to an mte-machine/1 JSON file.
        machine: String,
        /// Print the machine as JSON again (as read) instead of the summary.
        #[arg(long)]
        json: bool,
    },
}

/// Run `mte machine …`.
pub fn run(args: &Args) -> Result<(), CliError> {
    match &args.cmd {
        Sub::List => {
            print!("{}", list()?);
            Ok(())
        }
        Sub::Show { machine, json } => {
            let m = load(machine)?;
            if *json {
                println!("{}", m.json());
            } else {
                print!("{}", show(&m));
            }
            Ok(())
        }
    }
}

/// A library name or a file path ([`Machine::library_or_file`]); an unknown name is a usage
/// error.
pub fn load(name_or_file: &str) -> Result<Machine, CliError> {
    if !Machine::library_names().contains(&name_or_file) {
        mte::report::check_regular_file(Path::new(name_or_file))?;
    }
    Machine::library_or_file(name_or_file, Path::new("")).map_err(|e| match e {
        KinError::NoSuchMachine { .. } => CliError::Usage(e.to_string()),
        e => CliError::Library(e.to_string()),
    })
}

fn list() -> Result<String, CliError> {
    let mut s = String::new();
    for n in Machine::library_names() {
        let m = Machine::library(n).map_err(|e| CliError::Library(e.to_string()))?;
        let axes: Vec<&str> = m.axes().iter().map(|a| a.name.as_str()).collect();
        let _ = writeln!(
            s,
            "{n:<22} axes {:<12} {:>3} error slots",
            axes.join(""),
            m.n_slots()
        );
    }
    Ok(s)
}

fn branch_name(b: Branch) -> &'static str {
    match b {
        Branch::Shared => "shared",
        Branch::Tool => "tool",
        Branch::Workpiece => "workpiece",
        Branch::Neither => "-",
    }
}

/// The human-readable summary of a machine.
pub fn show(m: &Machine) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "machine {}", m.name());
    if !m.description().is_empty() {
        let _ = writeln!(s, "  {}", m.description());
    }
    let _ = writeln!(s, "\naxes (command order):");
    for a in m.axes() {
        let (unit, lo, hi) = match a.kind {
            AxisKind::Linear => ("mm", a.stroke.0, a.stroke.1),
            AxisKind::Rotary => ("deg", a.stroke.0.to_degrees(), a.stroke.1.to_degrees()),
        };
        let _ = writeln!(
            s,
            "  {:<3} {:<6} dir ({:+.3}, {:+.3}, {:+.3}) sign {:+} stroke [{lo}, {hi}] {unit}  {} side",
            a.name,
            if a.kind == AxisKind::Linear {
                "linear"
            } else {
                "rotary"
            },
            a.direction.x,
            a.direction.y,
            a.direction.z,
            a.sign,
            branch_name(a.branch)
        );
    }
    let _ = writeln!(
        s,
        "\nbodies (index, name, parent, joint, offset mm, home mm, branch):"
    );
    for (i, b) in m.bodies().iter().enumerate() {
        let parent = b
            .parent
            .map_or("-".to_string(), |p| m.bodies()[p].name.clone());
        let joint = match b.joint {
            Joint::Fixed => "fixed".to_string(),
            Joint::Axis(k) => format!("axis {}", m.axes()[k].name),
        };
        let h = m.body_home_mm(i);
        let o = b.offset_mm;
        let _ = writeln!(
            s,
            "  {i:>2} {:<10} parent {:<10} {:<8} offset ({}, {}, {}) home ({}, {}, {}) {}",
            b.name,
            parent,
            joint,
            o.x,
            o.y,
            o.z,
            h.x,
            h.y,
            h.z,
            branch_name(b.branch)
        );
    }
    let names = |c: &[usize]| {
        let mut v = vec![m.bodies()[0].name.clone()];
        v.extend(c.iter().map(|&j| m.bodies()[j].name.clone()));
        v.join(" → ")
    };
    let _ = writeln!(
        s,
        "\ntopology:\n  tool branch:      {}",
        names(m.tool_chain())
    );
    let _ = writeln!(s, "  workpiece branch: {}", names(m.workpiece_chain()));
    let _ = writeln!(s, "\nlower-order body array L^n(j) (0-based body indices):");
    let l = m.lower_order_array();
    let _ = write!(s, "  {:<6}", "j");
    for j in 0..m.bodies().len() {
        let _ = write!(s, "{j:>4}");
    }
    let _ = writeln!(s);
    for (n, row) in l.iter().enumerate() {
        let _ = write!(s, "  L^{n:<4}");
        for v in row {
            let _ = write!(s, "{v:>4}");
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "\nerror slots ({}; index, name, axis, kind, component, unit):",
        m.n_slots()
    );
    for (k, slot) in m.error_slots().iter().enumerate() {
        let axis = m.slot_axis(k).map_or("-", |a| a.name.as_str());
        let kind = match slot.kind {
            SlotKind::Position => "position",
            SlotKind::Motion => "motion",
        };
        let unit = if slot.component.is_translation() {
            "mm"
        } else {
            "rad"
        };
        let _ = writeln!(
            s,
            "  {k:>3} {:<22} {axis:<3} {kind:<8} {} {unit}",
            m.slot_name(k),
            slot.component.name()
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn show_lists_slots_and_lower_order_array() {
        let m = Machine::library("seed001-4axis").unwrap();
        let s = show(&m);
        assert!(s.contains("A.motion.ez"), "{s}");
        assert!(s.contains("L^1"), "{s}");
        assert!(s.contains("bed → spindle → tool"), "{s}");
        assert!(list().unwrap().contains("seed003-ac-table"));
        assert!(load("no-such-machine").is_err());
    }
}
