#![doc = include_str!("../README.md")]

mod error;
mod fk;
mod ik;
mod library;
mod machine;

pub use error::{KinError, Result};
pub use fk::{BranchPoses, Jacobian, PoseError};
pub use machine::{
    Axis, AxisKind, Body, Branch, Component, ErrorSlot, FORMAT, Joint, Machine, SlotKind,
};
