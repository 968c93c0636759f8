//! Inverse kinematics on the shipped robots: all six hexapod legs (target
//! at most 1 us) and one SO-101 tool pose (target at most 20 us).
//!
//! `cargo bench -p servobus-kinematics`
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use servobus_kinematics::{ArmIk, ArmTarget, LegIk, Point3, Poses};

#[path = "../tests/kinematics/robots.rs"]
mod robots;

fn legs(c: &mut Criterion) {
    let s = robots::shipped("hexapod");
    let names = robots::LEGS;
    let legs: Vec<LegIk> = names
        .iter()
        .map(|n| LegIk::new(&s.model, &format!("foot_{n}")).expect("a leg"))
        .collect();
    // Standing (femur 30, tibia -60) with every foot moved 20 mm forward.
    let mut poses = Poses::new(&s.model);
    s.model.forward(&robots::standing(&s), &mut poses);
    let targets: Vec<Point3<f64>> = names
        .iter()
        .map(|n| {
            let f = s.model.frame_index(&format!("foot_{n}")).expect("foot");
            let p = poses.frame(f).expect("foot").translation.vector;
            Point3::new(p.x + 20.0, p.y, p.z)
        })
        .collect();
    let previous = [0.0, 30f64.to_radians(), -60f64.to_radians()];
    c.bench_function("kinematics/ik_six_legs", |b| {
        b.iter(|| {
            for (leg, t) in legs.iter().zip(&targets) {
                black_box(leg.solve(black_box(t), previous).ok());
            }
        });
    });
}

fn so101(c: &mut Criterion) {
    let s = robots::shipped("so101");
    let ik = ArmIk::new(&s.model, "tool").expect("an arm");
    // From a pose in front of the table to one 20 mm away from it, gripper
    // pitched down 45 deg: a step of a move, solved from the last answer.
    let start = ArmTarget {
        xyz: Point3::new(220.0, 0.0, 120.0),
        pitch: Some(45f64.to_radians()),
        roll: Some(0.0),
    };
    let mut previous = [0.0; 5];
    let home = [
        0.0,
        -90f64.to_radians(),
        90f64.to_radians(),
        45f64.to_radians(),
        0.0,
    ];
    ik.solve(&start, &home, &mut previous).expect("reachable");
    let step = ArmTarget {
        xyz: Point3::new(230.0, 15.0, 110.0),
        ..start
    };
    let mut out = [0.0; 5];
    c.bench_function("kinematics/ik_so101_pose", |b| {
        b.iter(|| black_box(ik.solve(black_box(&step), &previous, &mut out)).ok());
    });
    // From the home pose, a whole move away.
    c.bench_function("kinematics/ik_so101_pose_from_home", |b| {
        b.iter(|| black_box(ik.solve(black_box(&step), &home, &mut out)).ok());
    });
    // Out of reach: every restart is tried, with and without limits,
    // before the answer is no (the worst case).
    let far = ArmTarget {
        xyz: Point3::new(600.0, 0.0, 149.1),
        pitch: None,
        roll: None,
    };
    c.bench_function("kinematics/ik_so101_unreachable", |b| {
        b.iter(|| black_box(ik.solve(black_box(&far), &previous, &mut out)).err());
    });
}

criterion_group!(benches, legs, so101);
criterion_main!(benches);
