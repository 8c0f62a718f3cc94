#![doc = include_str!("../README.md")]

mod basis;
pub mod candidate;
pub mod data;
mod dataset;
pub mod engine;
mod fit;
pub mod instruments;
pub mod model;
pub mod report;
pub mod structure;
pub mod term;

pub use candidate::{
    Alternatives, BaseModelSpec, Candidate, ComponentSpec, Reference, Requires, Role, Score,
    Shorthand, SlotEffect, SlotRole, Spread, SpreadVariants, physical_effects,
};
pub use data::{Observations, Variable, VariableKind};
pub use engine::{
    Compound, DETECTION_POWER, DetectionLimit, DeterminedTogether, DiagnoseParams, Diagnosis,
    Exchange, Finding, FirstOrderFit, FitQuality, HeldOut, Outlier, PruneReason, Pruned, Rival,
    TOGETHER_CORRELATION, VariantLimit, Verdict, diagnose, diagnose_with_progress, progress_units,
};
pub use instruments::{load, load_with_noise};
pub use model::{BaseModelUsed, DriftOf, Effects, ObservationModel, Prepared, prepare};
pub use mte_linalg::progress::{NoProgress, Progress};
pub use structure::StructureTest;
pub use term::{Estimate, Family, Interval, Quantity, Summary, Term};

/// What can go wrong in a diagnosis.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DiagnoseError {
    /// The observations or the model are malformed.
    #[error("invalid data in {field}: {detail}")]
    InvalidData {
        /// The field or column.
        field: String,
        /// What is wrong.
        detail: String,
    },
    /// The base model cannot be identified from these data.
    #[error("the base model is not identifiable from these data; these parameter combinations cannot be told apart: {}", combinations.join("; "))]
    NotIdentifiable {
        /// The undetermined combinations, e.g. "EX0B − 1.00·EX0C".
        combinations: Vec<String>,
    },
    /// Too few observations for the base model and cross-validation.
    #[error(
        "{observations} observations are too few: the base model and the cross-validation need at least {needed}"
    )]
    TooFewObservations {
        /// How many there are.
        observations: usize,
        /// How many are needed.
        needed: usize,
    },
    /// The candidates' designs would take more memory than allowed.
    #[error(
        "{observations} observations × {columns} candidate columns need {needed_gb:.1} GB of memory, more than the limit of {limit_gb:.1} GB (DiagnoseParams::max_memory_gb; `mte --max-memory-gb` or MTE_MAX_MEMORY_GB): thin the data (e.g. every k-th reading of a continuous log) or raise the limit"
    )]
    TooLarge {
        /// Observations.
        observations: usize,
        /// Columns of every candidate variant together.
        columns: usize,
        /// Memory the designs need, GB.
        needed_gb: f64,
        /// The limit, GB.
        limit_gb: f64,
    },
    /// A dataset file could not be read or parsed.
    #[error("{path}: {detail}")]
    Dataset {
        /// The file.
        path: String,
        /// What is wrong, with the line or field.
        detail: String,
    },
}

/// Result of this crate.
pub type Result<T> = std::result::Result<T, DiagnoseError>;
