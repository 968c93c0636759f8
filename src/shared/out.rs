//! Writing to stdout and stderr without a panic.
//!
//! `println!` panics when stdout cannot be written (`> /dev/full`), and with
//! SIGPIPE at its default a closed pipe (`| head`) kills the process mid-run
//! with the torque on. The command line keeps SIGPIPE ignored (Rust's
//! default) and writes through this module instead, so a failed write is an
//! error the command acts on:
//!
//! | what happened          | [`StdoutError`] | what a command does                         |
//! |------------------------|-----------------|---------------------------------------------|
//! | the reader went away   | `Closed`        | stops as on Ctrl-C (a motion: jerk-limited), writes its files, exits 1 |
//! | any other failure      | `Failed`        | an output error: exits 1 once nothing moves |
//!
//! Stderr is where errors are said: when it cannot be written there is no
//! one left to tell, so [`errln!`] and [`err!`] drop what they cannot write.
//!
//! ```ignore
//! use crate::shared::out::outln;
//! outln!("{} servos", n)?; // Result<(), StdoutError>
//! ```

use std::fmt;
use std::io::{self, Write};

/// Stdout could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StdoutError {
    /// The program reading stdout ended (EPIPE): `| head` has what it
    /// wanted. A running motion takes it as a signal to stop.
    #[error("stdout was closed (the program reading it ended)")]
    Closed,
    /// Any other failure: a full disk, an I/O error.
    #[error("cannot write to stdout: {}", super::os_error::os_text(.0))]
    Failed(io::Error),
}

impl StdoutError {
    /// The error for a failed write to stdout, `Closed` for EPIPE.
    pub fn of(err: io::Error) -> StdoutError {
        if err.kind() == io::ErrorKind::BrokenPipe {
            StdoutError::Closed
        } else {
            StdoutError::Failed(err)
        }
    }

    /// Whether the reader went away (rather than the write failing).
    pub fn is_closed(&self) -> bool {
        matches!(self, StdoutError::Closed)
    }
}

/// Writes `args` to stdout, then a newline when `newline`. Stdout is line
/// buffered: a line is written through at its newline.
///
/// # Errors
/// [`StdoutError::Closed`] when the reader has gone, else
/// [`StdoutError::Failed`].
pub fn write(args: fmt::Arguments<'_>, newline: bool) -> Result<(), StdoutError> {
    let mut out = io::stdout().lock();
    out.write_fmt(args).map_err(StdoutError::of)?;
    if newline {
        out.write_all(b"\n").map_err(StdoutError::of)?;
    }
    Ok(())
}

/// Writes `bytes` to stdout as they are (a generated script, a page) and
/// flushes them.
///
/// # Errors
/// As [`write`].
pub fn bytes(bytes: &[u8]) -> Result<(), StdoutError> {
    let mut out = io::stdout().lock();
    out.write_all(bytes).map_err(StdoutError::of)?;
    out.flush().map_err(StdoutError::of)
}

/// Writes out what stdout still buffers (text without a final newline).
///
/// # Errors
/// As [`write`].
pub fn flush() -> Result<(), StdoutError> {
    io::stdout().lock().flush().map_err(StdoutError::of)
}

/// Writes `args` to stderr, then a newline when `newline`; a failure is
/// dropped (see the module's docs).
pub fn write_err(args: fmt::Arguments<'_>, newline: bool) {
    let mut err = io::stderr().lock();
    let _ = err.write_fmt(args);
    if newline {
        let _ = err.write_all(b"\n");
    }
}

/// `println!` that returns `Result<(), StdoutError>` instead of panicking.
macro_rules! outln {
    () => {
        $crate::shared::out::write(format_args!(""), true)
    };
    ($($arg:tt)*) => {
        $crate::shared::out::write(format_args!($($arg)*), true)
    };
}

/// `print!` that returns `Result<(), StdoutError>` instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::shared::out::write(format_args!($($arg)*), false)
    };
}

/// `eprintln!` that never panics: what stderr cannot take is dropped.
macro_rules! errln {
    () => {
        $crate::shared::out::write_err(format_args!(""), true)
    };
    ($($arg:tt)*) => {
        $crate::shared::out::write_err(format_args!($($arg)*), true)
    };
}

/// `eprint!` that never panics: what stderr cannot take is dropped.
macro_rules! err {
    ($($arg:tt)*) => {
        $crate::shared::out::write_err(format_args!($($arg)*), false)
    };
}

#[allow(unused_imports)] // each is used by some commands, not all
pub(crate) use {err, errln, out, outln};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_broken_pipe_is_a_closed_stdout_and_a_full_disk_a_failure() {
        let closed = StdoutError::of(io::Error::from(io::ErrorKind::BrokenPipe));
        assert!(closed.is_closed());
        let full = StdoutError::of(io::Error::from_raw_os_error(28));
        assert!(!full.is_closed());
        assert_eq!(full.to_string(), "cannot write to stdout: the disk is full");
    }
}
