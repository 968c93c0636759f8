//! Planning motion in space on the shipped robots: a 10 s tripod walk of
//! the hexapod (target at most 5 ms) and a 100-sample straight tool line
//! of the SO-101 (target at most 2 ms).
//!
//! `cargo bench -p servobus-kinematics --bench spatial`
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use servobus_kinematics::{
    plan_walk, sample_line, ArmIk, Gait, Held, Legs, LineOptions, PoseLine, Walk, WalkSegment,
};

#[path = "../tests/kinematics/robots.rs"]
mod robots;

fn walk(c: &mut Criterion) {
    let s = robots::shipped("hexapod");
    let legs = Legs::new(&s.model).expect("six legs");
    let start = robots::standing(&s);
    // 10 s of walking: forward, turning, sideways (and the steps to stop).
    let plan = Walk {
        gait: Gait::Tripod,
        stride_mm: None,
        lift_mm: 25.0,
        period_s: 2.0,
        segments: vec![
            WalkSegment {
                velocity_mm_s: [50.0, 0.0],
                turn_rad_s: 0.0,
                duration_s: 4.0,
            },
            WalkSegment {
                velocity_mm_s: [0.0, 0.0],
                turn_rad_s: 0.2,
                duration_s: 3.0,
            },
            WalkSegment {
                velocity_mm_s: [0.0, -40.0],
                turn_rad_s: 0.0,
                duration_s: 3.0,
            },
        ],
        step_s: 0.02,
    };
    c.bench_function("kinematics/walk_10s", |b| {
        b.iter(|| black_box(plan_walk(&legs, black_box(&plan), &start)).ok());
    });
}

fn line(c: &mut Criterion) {
    let s = robots::shipped("so101");
    let arm = ArmIk::new(&s.model, "tool").expect("an arm");
    // 220, 60, 120 to 220, 60, 70 with the tool pitched down 60 deg (the
    // first line of configs/motions/arm-line.yaml), over 5 s: 100 samples
    // 50 ms apart.
    let start = robots::pose(
        &s,
        &[
            ("shoulder_pan", 15.27),
            ("shoulder_lift", -16.1),
            ("elbow_flex", 37.2),
            ("wrist_flex", 38.9),
        ],
    );
    let chain: Vec<f64> = arm.joints().iter().map(|&j| start[j]).collect();
    let from = arm.frame_pose(&chain);
    let mut to = from;
    to.translation.vector.z -= 50.0;
    let line = PoseLine::new(from, to);
    let held = Held {
        pitch: true,
        roll: false,
    };
    let options = LineOptions::default();
    let smooth = |t: f64| {
        let u = (t / 5.0).clamp(0.0, 1.0);
        u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
    };
    let n = sample_line(&arm, &line, held, &chain, 5.0, smooth, &options)
        .expect("a line the arm can follow")
        .samples
        .len();
    println!("{n} samples");
    c.bench_function("kinematics/line_100_samples", |b| {
        b.iter(|| {
            black_box(sample_line(
                &arm,
                black_box(&line),
                held,
                &chain,
                5.0,
                smooth,
                &options,
            ))
            .ok()
        });
    });
}

criterion_group!(benches, walk, line);
criterion_main!(benches);
