//! `servobus list`: the built-in robots and motions.

use std::process::ExitCode;

use servobus::builtin::{self, Kind};

/// Arguments of `servobus list`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `servobus list`.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    let width = builtin::all().map(|b| b.name.len()).max().unwrap_or(0);
    for (kind, title) in [(Kind::Robot, "Robots"), (Kind::Motion, "Motions")] {
        println!("{title} (use the name where a file is asked for):");
        for b in builtin::all().filter(|b| b.kind == kind) {
            println!("  {:width$}  {}", b.name, b.summary());
        }
        println!();
    }
    println!("Try: servobus play arm-wave; servobus budget --robot hexapod; servobus init");
    Ok(ExitCode::SUCCESS)
}
