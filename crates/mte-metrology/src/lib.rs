#![doc = include_str!("../README.md")]
// Dense numeric kernels index several arrays in step; ranges read better there.
#![allow(clippy::needless_range_loop, clippy::type_complexity)]

pub mod adjust;
pub mod error;
pub mod gum;
pub mod io;
pub mod iso230_2;
pub mod network;
pub mod simulate;
pub mod stats;
pub mod uncertainty;

pub use error::{MetrologyError, Result};
