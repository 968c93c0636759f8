//! The protocol integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

#[path = "../common/mod.rs"]
mod common;

mod command;
mod fuzz_regressions;
mod golden;
mod no_alloc;
mod registers;
