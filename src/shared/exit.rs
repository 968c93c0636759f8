//! Exit codes and error messages, the same for every command.
//!
//! `0` ok, `1` a problem was found (a servo missing, a fault, a bad frame,
//! an output that could not be written), `2` a usage or input error (the
//! command line, a robot or motion file, a port that cannot be opened, an
//! output path that cannot be a file). clap already exits 2 for a bad
//! command line. Stdout that cannot be written ([`super::out::StdoutError`]:
//! closed by its reader, or full) is a problem (1), never a panic.

use std::process::ExitCode;

use servobus_config::{is_builtin_path, ConfigError};
use servobus_robot::bus::OpenError;
use servobus_robot::files::OutputError;
use servobus_robot::sim::{FaultSpecError, PtyError};
use servobus_robot::teach::TeachError;

use super::os_error::os_text;

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

/// An error of any kind that came from what the user gave (exits 2): a file
/// that is missing or malformed, a path that cannot be written. Says what
/// the error inside says.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct Invalid(Box<dyn std::error::Error + Send + Sync + 'static>);

/// `err` marked as an input error (exits 2), its message unchanged: for
/// `.map_err(invalid)` where a failure can only mean a bad input.
pub fn invalid(err: anyhow::Error) -> anyhow::Error {
    Invalid(err.into()).into()
}

/// The exit code of a run that ended as `finish`: 0 when it completed or
/// was stopped as asked, 1 when a fault (or torque off) ended it.
pub fn of_finish(finish: servobus_robot::Finish) -> ExitCode {
    match finish {
        servobus_robot::Finish::Completed | servobus_robot::Finish::Stopped => ExitCode::SUCCESS,
        _ => ExitCode::from(PROBLEM),
    }
}

/// Prints `err` (each cause once) and returns its exit code.
pub fn report(err: &anyhow::Error) -> ExitCode {
    super::out::errln!("error: {}", message(err));
    ExitCode::from(code(err))
}

/// The exit code for `err`: 2 for input errors, 1 otherwise.
pub fn code(err: &anyhow::Error) -> u8 {
    let input = err.chain().any(|e| {
        e.is::<ConfigError>()
            || e.is::<InputError>()
            || e.is::<Invalid>()
            || e.is::<FaultSpecError>()
            || matches!(
                e.downcast_ref::<PtyError>(),
                Some(PtyError::LinkOccupied(_) | PtyError::LinkServed { .. })
            )
            || matches!(
                e.downcast_ref::<TeachError>(),
                Some(TeachError::UnknownJoint { .. })
            )
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
/// (`I/O error: X: denied` followed by its source `X: denied`), and a
/// context the cause repeats is said by the cause alone (`servo 42`
/// followed by `servo 42: no reply`); a port that cannot be opened is said
/// by its [`OpenError`], which names the remedy. The operating system's
/// errors are said in the user's terms ([`os_text`]).
pub fn message(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for e in err.chain() {
        if let Some(open) = OpenError::find(e) {
            // Outer context (`cannot open X`) is said again by the OpenError.
            parts.retain(|p| !p.starts_with("cannot open"));
            parts.push(open.to_string());
            break;
        }
        let text = match e.downcast_ref::<std::io::Error>() {
            Some(io) if io.get_ref().is_none() => os_text(io),
            _ => e.to_string(),
        };
        let text = text.strip_prefix("I/O error: ").unwrap_or(&text).to_owned();
        if parts.last().is_some_and(|prev| prev.contains(&text)) {
            continue;
        }
        if let Some(prev) = parts.last_mut() {
            if text.starts_with(prev.as_str()) {
                *prev = text;
                continue;
            }
            // `servo 42 at 1000000 baud` then `servo 42: no reply`: the
            // cause's subject is said already.
            if let Some((subject, rest)) = text.split_once(": ") {
                if prev.starts_with(subject) {
                    parts.push(rest.to_owned());
                    continue;
                }
            }
        }
        parts.push(text);
    }
    let mut text = parts.join(": ");
    if let Some(ConfigError::Read { path, error }) = err.downcast_ref::<ConfigError>() {
        if error.kind() == std::io::ErrorKind::NotFound && !is_builtin_path(path) {
            match path.to_str().and_then(servobus::builtin::nearest) {
                Some(b) => text.push_str(&format!(
                    "; did you mean the built-in {} `{}`? (`servobus list` lists them)",
                    b.kind.word(),
                    b.name
                )),
                None => text.push_str(
                    "; give a file path or the name of a built-in robot or motion (`servobus list`)",
                ),
            }
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
            anyhow::Error::new(servobus_robot::bus::TransportError::Io(io)).context("cannot use x");
        assert_eq!(message(&err), "cannot use x: x: gone");
        assert_eq!(code(&err), PROBLEM);
        assert_eq!(code(&input("bad")), USAGE);
    }

    #[test]
    fn a_context_the_cause_repeats_is_said_once() {
        let err = anyhow::anyhow!("servo 42: no reply within 300 us").context("servo 42");
        assert_eq!(message(&err), "servo 42: no reply within 300 us");
        let err = anyhow::anyhow!("servo 42: no reply within 300 us")
            .context("servo 42 at 1000000 baud (scan to find it)");
        assert_eq!(
            message(&err),
            "servo 42 at 1000000 baud (scan to find it): no reply within 300 us"
        );
        let gone = std::io::Error::other("I/O error");
        let err = anyhow::Error::new(servobus_robot::bus::TransportError::Io(gone));
        assert_eq!(message(&err), "I/O error");
    }

    #[test]
    fn stdout_that_cannot_be_written_is_a_problem() {
        use super::super::out::StdoutError;
        let closed = anyhow::Error::new(StdoutError::Closed);
        assert_eq!(code(&closed), PROBLEM);
        let full = StdoutError::of(std::io::Error::from_raw_os_error(28));
        let full = anyhow::Error::new(full);
        assert_eq!(code(&full), PROBLEM);
        assert_eq!(message(&full), "cannot write to stdout: the disk is full");
    }

    #[test]
    fn os_errors_are_said_in_the_users_terms() {
        let dir = std::io::Error::from_raw_os_error(21);
        let err = anyhow::Error::new(dir).context("--log /tmp: cannot write there");
        assert_eq!(
            message(&err),
            "--log /tmp: cannot write there: it is a directory"
        );
        let tty = std::io::Error::from_raw_os_error(25);
        assert_eq!(os_text(&tty), "not a serial port");
        let marked = invalid(err);
        assert_eq!(code(&marked), USAGE);
        assert_eq!(
            message(&marked),
            "--log /tmp: cannot write there: it is a directory"
        );
    }
}
