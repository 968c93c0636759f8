//! `servobus completions` and `servobus man`, generated from the command
//! line's own definition so they never fall behind it.

use std::io::Write;
use std::process::ExitCode;

use clap_complete::Shell;

/// Arguments of `servobus completions`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Load now: source <(servobus completions bash)\n\
    Install: servobus completions bash > ~/.local/share/bash-completion/completions/servobus")]
pub struct CompletionsArgs {
    /// The shell.
    pub shell: Shell,
}

/// Arguments of `servobus man`.
#[derive(Debug, clap::Args)]
pub struct ManArgs {}

/// Runs `servobus completions`: the script of `cmd`, the whole command
/// line as the dispatcher defines it.
pub fn completions(args: CompletionsArgs, mut cmd: clap::Command) -> anyhow::Result<ExitCode> {
    // Generated into memory: clap_complete panics on a failed write.
    let mut script = Vec::new();
    clap_complete::generate(args.shell, &mut cmd, "servobus", &mut script);
    crate::shared::out::bytes(&script)?;
    Ok(ExitCode::SUCCESS)
}

/// Runs `servobus man` for `cmd`, the whole command line: the top-level
/// page (clap_mangen), then each
/// subcommand's full help as a section of its own, so one page covers all.
pub fn man(_args: ManArgs, mut cmd: clap::Command) -> anyhow::Result<ExitCode> {
    let mut out = Vec::new();
    clap_mangen::Man::new(cmd.clone()).render(&mut out)?;
    cmd.build();
    for sub in cmd.get_subcommands_mut().filter(|s| !s.is_hide_set()) {
        let help = sub.render_long_help().to_string();
        writeln!(out, ".SH \"SERVOBUS {}\"", sub.get_name().to_uppercase())?;
        writeln!(out, ".nf")?;
        for line in help.lines() {
            writeln!(out, "{}", roff_line(line))?;
        }
        writeln!(out, ".fi")?;
    }
    crate::shared::out::bytes(&out)?;
    Ok(ExitCode::SUCCESS)
}

/// One line of literal text for roff: backslashes doubled, and a line that
/// starts with `.` or `'` (a roff request) guarded by `\&`.
fn roff_line(line: &str) -> String {
    let line = line.replace('\\', "\\\\");
    if line.starts_with('.') || line.starts_with('\'') {
        format!("\\&{line}")
    } else {
        line
    }
}
