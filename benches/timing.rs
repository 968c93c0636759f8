//! Benches of servobus-timing: SYNC WRITE packing and cycle planning, the
//! two things a control loop does every cycle or before it starts.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion};
use servobus_timing::{pack_sync_write, plan, sync_write_bytes, Block, Link, Servo};

/// Registers the benches of this module.
pub fn benches(c: &mut Criterion) {
    pack(c);
    planning(c);
}

/// Packing 6, 18 and 64 servos' goals with L = 2 and L = 7 (target: at most
/// 100 ns for 18 servos x 7 bytes).
fn pack(c: &mut Criterion) {
    let mut group = c.benchmark_group("timing/pack");
    let ids: [u8; 64] = core::array::from_fn(|i| i as u8 + 1);
    let data: [u8; 64 * 7] = core::array::from_fn(|i| i as u8);
    let mut buf = vec![0u8; sync_write_bytes(64, 7)];
    for block in [Block::GOAL_POSITION, Block::ACCEL_POSITION_TIME_SPEED] {
        let len = usize::from(block.len);
        for n in [6usize, 18, 64] {
            group.bench_function(BenchmarkId::new(format!("L{len}"), n), |b| {
                b.iter(|| {
                    pack_sync_write(
                        black_box(&mut buf),
                        black_box(block),
                        black_box(&ids[..n]),
                        black_box(&data[..n * len]),
                    )
                })
            });
        }
    }
    // Reference: the protocol encoder alone writing one frame of 18 x 7, the
    // floor under the packer's own cost.
    group.bench_function("encoder_only/L7/18", |b| {
        b.iter(|| {
            servobus_protocol::encode::sync_write_flat(
                black_box(&mut buf),
                41,
                7,
                black_box(&ids[..18]),
                black_box(&data[..18 * 7]),
            )
        })
    });
    group.finish();
}

/// Planning an 18-servo hexapod cycle (target: at most 1 us), feasible and
/// round-robin (with every fix searched).
fn planning(c: &mut Criterion) {
    let mut group = c.benchmark_group("timing/plan");
    let link = Link::new(1_000_000).with_latency(Duration::from_millis(1));
    let servos: [Servo; 18] = core::array::from_fn(|i| Servo::sts(i as u8 + 1, Duration::ZERO));
    let w = Some(Block::GOAL_POSITION);
    let r = Some(Block::PRESENT_POSITION);
    for (name, rate) in [("18_feasible", 200.0), ("18_round_robin", 400.0)] {
        group.bench_function(name, |b| {
            b.iter(|| plan(black_box(&link), black_box(&servos), w, r, black_box(rate)))
        });
    }
    group.finish();
}
