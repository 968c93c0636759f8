//! `servobus`: the command line of the servobus runtime.
//!
//! Each subcommand lives in its own module under `cmd/`; this file only parses
//! the arguments, dispatches, and turns an error into a message and an exit
//! code (`cmd::exit`).

mod cmd;
mod record;

fn main() -> std::process::ExitCode {
    restore_sigpipe();
    let cli = cmd::parse();
    match cmd::run(cli) {
        Ok(code) => code,
        Err(err) => cmd::exit::report(&err),
    }
}

/// Lets `servobus ... | head` end quietly, as other command-line tools do,
/// instead of failing on a closed pipe.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to the default is always
    // sound; no handler runs Rust code.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
