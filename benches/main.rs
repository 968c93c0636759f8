//! The criterion benches of servobus: one harness, one binary, a module per crate.
//!
//! Run them with `cargo bench`, or one group with e.g. `cargo bench -- protocol/`.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main};

mod driver;
mod protocol;
mod runtime;
mod timing;
mod trajectory;

criterion_group!(
    benches,
    driver::benches,
    protocol::benches,
    runtime::benches,
    timing::benches,
    trajectory::benches
);
criterion_main!(benches);
