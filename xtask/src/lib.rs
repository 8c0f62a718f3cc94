//! Library side of `cargo xtask`: the reproduction generators live here (not in the `mte` CLI
//! crate) so that `cargo xtask reproduce` and the staleness test `tests/reproduction_up_to_date.rs`
//! call the same functions, while users of the CLI never compile paper-reproduction code.

pub mod realistic;
pub mod reproduce;
pub mod scale;
pub mod studies;
