//! Benches of servobus-trajectory.

use criterion::Criterion;

/// Registers the benches of this module.
pub fn benches(_c: &mut Criterion) {}
