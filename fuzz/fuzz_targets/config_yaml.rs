//! Fuzz target: robot, motion and calibration YAML through the real
//! loaders, each motion that loads planned. The checks live in
//! `crates/config/examples/common/config_check.rs`, shared with the stable
//! fuzzer (`cargo run --release -p servobus-config --example fuzz_config`)
//! and the regression test that replays `testdata/fuzz-config/`.
//!
//! Run: `cd fuzz && cargo fuzz run -s none config_yaml -- -max_len=16384`.
#![no_main]

use std::path::Path;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

#[path = "../../crates/config/examples/common/config_check.rs"]
mod config_check;

use config_check::{Workspace, MAX_LEN};

/// One scratch directory for the whole run (libFuzzer runs the target in
/// one process, input after input).
fn workspace() -> &'static Workspace {
    static WORKSPACE: OnceLock<Workspace> = OnceLock::new();
    WORKSPACE.get_or_init(|| {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        Workspace::new(&repo).expect("a scratch directory for the inputs")
    })
}

fuzz_target!(|data: &[u8]| {
    // The size cap: larger inputs only test the loaders' own 1 MiB limit.
    if data.len() <= MAX_LEN {
        workspace().check(data);
    }
});
