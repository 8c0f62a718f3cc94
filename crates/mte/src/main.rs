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
    /// Memory limit (GB) of a command that allocates in proportion to a number you give
    /// (--n, --trials, a Sobol' N, a PCE degree); default 4, or MTE_MAX_MEMORY_GB.
    #[arg(long, global = true, value_name = "GB")]
    max_memory_gb: Option<f64>,
}

#[derive(Subcommand)]
enum Command {
    /// Machine definitions: list the bundled machines, show topology and error slots.
    Machine(cmd::machine::Args),
    /// Laser-tracker multilateration: adjust, simulate (seed 004), GUM-S1 uncertainty.
    Tracker(cmd::tracker::Args),
    /// ISO 230-2 evaluation of bidirectional linear-axis runs.
    #[command(name = "iso230-2")]
    Iso230_2(cmd::iso230_2::Args),
    /// Model-discrepancy diagnosis of a measured dataset: what the model gets wrong, the named cause, the gain.
    Diagnose(cmd::diagnose::Args),
    /// ISO 10791-6 R-test: simulate BK1/BK2/BK4, identify rotary-axis location errors (seed 002).
    Rtest(cmd::rtest::Args),
    /// Volumetric error of a machine with an error set over a grid, tool poses or a program.
    Simulate(cmd::simulate::Args),
    /// Sensitivity analysis (Morris, Sobol', sparse PCE, local) of a model over uncertain inputs.
    Sensitivity(cmd::sensitivity::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(gb) = cli.max_memory_gb
        && let Err(err) = mte::limits::set_max_memory_gb(gb)
    {
        eprintln!("error: {err}");
        return ExitCode::FAILURE;
    }
    let result: Result<(), mte::CliError> = match cli.command {
        Command::Machine(args) => cmd::machine::run(&args),
        Command::Tracker(args) => cmd::tracker::run(&args),
        Command::Iso230_2(args) => cmd::iso230_2::run(&args),
        Command::Diagnose(args) => cmd::diagnose::run(&args),
        Command::Rtest(args) => cmd::rtest::run(&args),
        Command::Simulate(args) => cmd::simulate::run(&args),
        Command::Sensitivity(args) => cmd::sensitivity::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err}");
            ExitCode::FAILURE
        }
    }
}
