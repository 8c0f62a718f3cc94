#![doc = include_str!("../README.md")]
// Numeric kernels index several arrays in lock-step; NaN-aware `!(a > b)` tests are deliberate.
#![allow(
    clippy::type_complexity,
    clippy::too_many_arguments,
    clippy::needless_range_loop,
    clippy::neg_cmp_op_on_partial_ord
)]

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
pub mod local;
pub mod morris;
pub mod pce;
