//! One module per subcommand.
pub mod diagnose;
pub mod iso230_2;
pub mod machine;
pub mod rtest;
pub mod sensitivity;
pub mod simulate;
pub mod tracker;
