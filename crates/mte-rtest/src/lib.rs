#![doc = include_str!("../README.md")]

pub mod compensate;
pub mod error;
pub mod identify;
pub mod io;
mod kin;
pub mod model;
pub mod names;
pub mod program;
pub mod simulate;
pub mod thermal;

pub use error::{Result, RtestError};
pub use identify::{
    Combination, Consistency, Estimate, Fit, FitSpec, Identifiability, ParamKind, design_matrix,
    identify, setup_consistency,
};
pub use kin::AxisInfo;
pub use model::{
    Dataset, ErrorField, NuisanceKind, ObservationModel, Reading, RowSensitivity, Setup,
    SetupNuisance,
};
pub use names::{NamedSlot, location_errors, slot_by_name, squareness_errors};
pub use program::{Program, ProgramSample, command_linear_axes, command_program};
pub use simulate::{PlanItem, SetupSpec, SimOptions, Simulated, command_plan, simulate};
