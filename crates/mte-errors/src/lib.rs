#![doc = include_str!("../README.md")]

pub mod csv;
mod error;
pub mod models;
pub mod units;

pub use error::{Error, Result};
