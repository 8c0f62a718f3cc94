//! `cargo xtask reproduce [paper]` and `cargo xtask bench`.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        _ => {
            eprintln!("usage: cargo xtask <reproduce [seed000|seed002|seed003|seed004|all] | bench>");
            ExitCode::FAILURE
        }
    }
}
