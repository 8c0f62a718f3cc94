#![doc = include_str!("../README.md")]

pub use faer;
pub use nalgebra;

pub mod geometry;
pub use geometry::{
    DMat, DVec, Iso3, Mat3, Mat4, Mat6, Vec3, Vec6, error_transform, error_transform_small,
    quaternion_from_rotation_vector, se3, skew, so3, unskew,
};

pub mod json;
pub mod progress;
pub mod stats;
pub mod text;

pub mod csv;

pub mod bridge;
pub mod error;
pub mod lstsq;
pub use error::{LinalgError, Result};
