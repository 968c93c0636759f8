//! Exit codes and error messages, the same for every command.
//!
//! `0` ok, `1` a problem was found (a servo missing, a fault, a bad frame,
//! an output that could not be written), `2` a usage or input error (the
//! command line, a robot or motion file, a port that cannot be opened, an
//! output path that cannot be a file). clap already exits 2 for a bad
//! command line.

use std::process::ExitCode;

use servobus_driver::OpenError;
use servobus_io::OutputError;
use servobus_runtime::config::{is_builtin_path, ConfigError};

/// Exit code: a problem was found.
pub const PROBLEM: u8 = 1;
/// Exit code: usage or input error.
pub const USAGE: u8 = 2;

/// An error in what the user gave (exits 2): a command line that parses but
/// makes no sense, a value out of range.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct InputError(pub String);

/// An [`InputError`] as an `anyhow::Error`, for `return Err(input(...))`.
pub fn input(message: impl Into<String>) -> anyhow::Error {
    InputError(message.into()).into()
}

/// Prints `err` (each cause once) and returns its exit code.
pub fn report(err: &anyhow::Error) -> ExitCode {
    eprintln!("error: {}", message(err));
    ExitCode::from(code(err))
}

/// The exit code for `err`: 2 for input errors, 1 otherwise.
pub fn code(err: &anyhow::Error) -> u8 {
    let input = err.chain().any(|e| {
        e.is::<ConfigError>()
            || e.is::<InputError>()
            || OpenError::find(e).is_some()
            || e.downcast_ref::<OutputError>()
                .is_some_and(OutputError::is_bad_path)
    });
    if input {
        USAGE
    } else {
        PROBLEM
    }
}

/// The message for `err`: the context chain joined by `: `, each cause said
/// once. A cause already spelled out by the message before it is skipped
/// (`I/O error: X: denied` followed by its source `X: denied`); a port that
/// cannot be opened is said by its [`OpenError`], which names the remedy.
pub fn message(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for e in err.chain() {
        if let Some(open) = OpenError::find(e) {
            // Outer context (`cannot open X`) is said again by the OpenError.
            parts.retain(|p| !p.starts_with("cannot open"));
            parts.push(open.to_string());
            break;
        }
        let text = e.to_string();
        if parts.last().is_some_and(|prev| prev.contains(&text)) {
            continue;
        }
        parts.push(text);
    }
    let mut text = parts.join(": ");
    if let Some(ConfigError::Read { path, error }) = err.downcast_ref::<ConfigError>() {
        if error.kind() == std::io::ErrorKind::NotFound && !is_builtin_path(path) {
            text.push_str(
                "; give a file path or the name of a built-in robot or motion (`servobus list`)",
            );
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cause_is_said_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "x: gone");
        let err =
            anyhow::Error::new(servobus_driver::TransportError::Io(io)).context("cannot use x");
        assert_eq!(message(&err), "cannot use x: I/O error: x: gone");
        assert_eq!(code(&err), PROBLEM);
        assert_eq!(code(&input("bad")), USAGE);
    }
}
