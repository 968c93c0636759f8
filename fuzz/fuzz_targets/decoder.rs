//! Fuzz target: the streaming decoder on arbitrary bytes in arbitrary chunks.
//! The checks live in `crates/protocol/tests/common/fuzz_check.rs`, shared
//! with the regression test that replays `testdata/fuzz/`.
//!
//! Run: `cd fuzz && cargo fuzz run -s none decoder -- -runs=10000000`.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../../crates/protocol/tests/common/fuzz_check.rs"]
mod fuzz_check;

fuzz_target!(|data: &[u8]| fuzz_check::check_input(data));
