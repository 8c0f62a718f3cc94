#![doc = include_str!("../README.md")]

pub mod design;
pub mod dist;
pub mod error;
pub mod model;
pub mod qmc;
pub mod special;

pub use design::{Sampling, UnitDesign};
pub use dist::{Distribution, Germ, Input, Problem};
pub use error::{Error, Result};
pub use model::{Model, MultiOutput, testfn};
pub use qmc::SobolSequence;
pub mod sobol;
pub mod stats;
pub use stats::{NoProgress, Progress};
pub mod pce;
