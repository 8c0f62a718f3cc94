//! One module per subcommand.
pub mod diagnose;
