//! `servobus list`: the built-in robots, motions and simulator examples.

use std::io::IsTerminal;
use std::process::ExitCode;

use servobus::builtin::{self, Kind};

use crate::shared::out::outln;

/// Arguments of `servobus list`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `servobus list`.
///
/// On a terminal each description is its first sentence cut to about 70
/// characters at a word; elsewhere (a pipe, a file) it is whole.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    let width = builtin::all().map(|b| b.name.len()).max().unwrap_or(0);
    let short = std::io::stdout().is_terminal();
    let robot_width = builtin::all()
        .filter_map(|b| b.robot())
        .map(|r| r.len())
        .max()
        .unwrap_or(0);
    for kind in Kind::ALL {
        let title = match kind {
            Kind::Robot => "Robots (use the name where a file is asked for):",
            Kind::Motion => "Motions (name, the robot it is for, what it does):",
            Kind::Mounting => "Simulator mountings (servobus sim --mounting NAME):",
            Kind::Hand => "Simulator hands (servobus sim --hand NAME):",
        };
        outln!("{title}")?;
        for b in builtin::all().filter(|b| b.kind == kind) {
            let what = if short { b.summary() } else { b.sentence() };
            match b.robot() {
                Some(robot) => outln!("  {:width$}  {robot:robot_width$}  {what}", b.name)?,
                None => outln!("  {:width$}  {what}", b.name)?,
            }
        }
        outln!()?;
    }
    outln!(
        "Try: servobus play arm-wave; servobus budget --robot hexapod; servobus init;\n     \
         servobus sim --robot so101 --mounting so101-mounting --hand so101-hand --link /tmp/arm"
    )?;
    Ok(ExitCode::SUCCESS)
}
