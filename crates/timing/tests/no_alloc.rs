//! Packing and planning never allocate: a counting global allocator watches
//! this thread while they run.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::Duration;

use servobus_timing::{pack_sync_write, plan, sync_write_bytes, Block, Link, Servo};

struct Counting;

thread_local! {
    // Const-initialised and without a destructor, so reading it from inside
    // the allocator never allocates itself.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: every call is forwarded unchanged to the system allocator; the
// only addition is a thread-local counter increment.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: the caller upholds `GlobalAlloc::realloc`'s contract.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made on this thread while `f` runs.
fn allocations_during<R>(f: impl FnOnce() -> R) -> (usize, R) {
    let before = ALLOCATIONS.with(Cell::get);
    let r = f();
    (ALLOCATIONS.with(Cell::get) - before, r)
}

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
