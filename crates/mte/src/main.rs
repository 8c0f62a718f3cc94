//! The `mte` command line. Each capability is one subcommand in `cmd/`.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod cmd;

/// Machine-tool geometric error: models, sensitivity, metrology, R-test and model-discrepancy diagnosis.
#[derive(Parser)]
#[command(name = "mte", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Model-discrepancy diagnosis of a measured dataset: what the model gets wrong, the named cause, the gain.
    Diagnose(cmd::diagnose::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: Result<(), mte::CliError> = match cli.command {
        Command::Diagnose(args) => cmd::diagnose::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err}");
            ExitCode::FAILURE
        }
    }
}
