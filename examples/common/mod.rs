//! What the motion examples share: one optional MOTION argument, `--help`,
//! and errors printed in words with exit code 1.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The result every example's body returns.
pub type Outcome = Result<(), Box<dyn std::error::Error>>;

/// Reads the MOTION argument (`default` when absent), prints `usage` on
/// `--help`, and otherwise runs `body` with the motion's argument and path.
pub fn run_motion(usage: &str, default: &str, body: fn(&str, &Path) -> Outcome) -> ExitCode {
    let arg = std::env::args()
        .nth(1)
        .unwrap_or_else(|| default.to_owned());
    if arg == "--help" || arg == "-h" {
        println!("{usage}");
        return ExitCode::SUCCESS;
    }
    let path: PathBuf = servobus::builtin::motion_path_or_name(Path::new(&arg));
    match body(&arg, &path) {
        Ok(()) => ExitCode::SUCCESS,
        // In words, not the error's `Debug` form.
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
