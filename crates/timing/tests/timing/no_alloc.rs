//! Packing and planning never allocate: a counting global allocator watches
//! this thread while they run.

use std::time::Duration;

use servobus_alloc_count::{allocations_during, Counting};
use servobus_timing::{pack_sync_write, plan, sync_write_bytes, Block, Link, Servo};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn packing_and_planning_allocate_nothing() {
    // Everything the calls need is set up before counting starts.
    let ids: [u8; 253] = core::array::from_fn(|i| i as u8);
    let data = [0x5Au8; 253 * 7];
    let mut buf = vec![0u8; sync_write_bytes(253, 7)];
    let link = Link::new(1_000_000).with_latency(Duration::from_millis(1));
    let sts: [Servo; 253] =
        core::array::from_fn(|i| Servo::sts(i as u8, Duration::from_micros(500)));
    let scs: [Servo; 18] = core::array::from_fn(|i| Servo::scs(i as u8 + 1, Duration::ZERO));

    for n in [6, 18, 64, 253] {
        for block in [Block::GOAL_POSITION, Block::ACCEL_POSITION_TIME_SPEED] {
            let len = usize::from(block.len);
            let (count, packed) = allocations_during(|| {
                pack_sync_write(&mut buf, block, &ids[..n], &data[..n * len])
            });
            assert!(packed.is_ok());
            assert_eq!(count, 0, "packing {n} servos x {len} bytes allocated");
        }
    }

    let w = Some(Block::GOAL_POSITION);
    let r = Some(Block::PRESENT_POSITION);
    // A feasible plan, round-robin plans (with every fix searched), an
    // infeasible one and an error: none allocates.
    let cases: [(&[Servo], f64); 5] = [
        (&sts[..18], 100.0),
        (&sts[..18], 1000.0),
        (&sts[..], 100.0),
        (&scs[..], 50.0),
        (&scs[..], 5000.0),
    ];
    for (servos, rate) in cases {
        let (count, result) = allocations_during(|| plan(&link, servos, w, r, rate));
        assert_eq!(
            count,
            0,
            "planning {} servos at {rate} Hz allocated",
            servos.len()
        );
        // Keep the result so the call cannot be optimised away.
        std::hint::black_box(&result);
    }
    // The counter does see allocations.
    let (count, v) = allocations_during(|| vec![0u8; 16]);
    assert_eq!((count, v.len()), (1, 16));
}
