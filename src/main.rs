//! `servobus`: the command line of the servobus runtime.
//!
//! Each subcommand lives in its own module under `cmd/`; this file only parses
//! the arguments, dispatches, and turns an error into a message and an exit
//! code (`cmd::exit`).
//!
//! SIGPIPE stays ignored, as Rust leaves it: a write to a closed pipe
//! returns EPIPE, which a command takes as a signal to stop (a motion stops
//! jerk-limited and writes its files) instead of being killed mid-run
//! (`cmd::out`).

mod cmd;
mod record;
mod shared;

fn main() -> std::process::ExitCode {
    let cli = cmd::parse();
    let code = match cmd::run(cli) {
        Ok(code) => code,
        Err(err) => return shared::exit::report(&err),
    };
    // What stdout still buffers is written now, where a failure can still
    // change the exit code (at exit it would be dropped unsaid).
    match shared::out::flush() {
        Ok(()) => code,
        Err(err) => shared::exit::report(&err.into()),
    }
}
