//! Loading and planning the shipped spatial motions end to end (the
//! motion file read, the walk or line sampled by inverse kinematics, the
//! samples checked by planning, then the whole motion planned):
//! `hexapod-walk-turn` (a 16 s walk), `hexapod-tripod` (two 8 s walks) and
//! `arm-line` (three tool lines).
//!
//! `cargo bench -p servobus-config --bench spatial`
#![allow(missing_docs)]

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use servobus_config::{load_motion, plan_motion};

fn motion(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../configs/motions/{name}"))
}

fn spatial(c: &mut Criterion) {
    for name in [
        "hexapod-walk-turn.yaml",
        "hexapod-tripod.yaml",
        "arm-line.yaml",
    ] {
        let path = motion(name);
        c.bench_function(&format!("config/load_and_plan/{name}"), |b| {
            b.iter(|| {
                let (m, r) = load_motion(black_box(&path), None).expect("loads");
                black_box(plan_motion(&m, &r).expect("plans"))
            });
        });
        // The planner's share: the loaded motion's samples planned once.
        let (m, r) = load_motion(&path, None).expect("loads");
        c.bench_function(&format!("config/plan_only/{name}"), |b| {
            b.iter(|| black_box(plan_motion(black_box(&m), &r).expect("plans")));
        });
    }
}

criterion_group!(benches, spatial);
criterion_main!(benches);
