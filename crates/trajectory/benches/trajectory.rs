//! The trajectory benches alone, built against this crate only (quick to
//! build while working on it): `cargo bench -p servobus-trajectory --bench
//! trajectory`. The same benches run in the workspace's one harness
//! (`cargo bench -- trajectory/`); the code lives there, once.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main};

#[path = "../../../benches/trajectory.rs"]
mod trajectory;

criterion_group!(benches, trajectory::benches);
criterion_main!(benches);
