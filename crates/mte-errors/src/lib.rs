#![doc = include_str!("../README.md")]

pub mod csv;
pub mod distribution;
mod error;
pub mod errorset;
pub mod models;
pub mod units;

pub use error::{Error, Result};
