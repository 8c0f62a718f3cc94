#![doc = include_str!("../README.md")]

pub mod catalogue;
pub mod csv;
pub mod distribution;
mod error;
pub mod errorset;
pub mod evaluator;
pub mod models;
pub mod pose_model;
pub mod units;
pub mod volumetric;

pub use catalogue::{Catalogue, ParamKind, Parameter};
pub use error::{Error, Result};
pub use errorset::ErrorSet;
pub use evaluator::{AxisState, Evaluator};
pub use models::{Context, Direction, ErrorModel};
