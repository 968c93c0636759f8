//! Sampling allocates nothing: a counting global allocator around the
//! control-loop calls.

use servobus_trajectory::{plan, JointLimits, JointState, Keyframe, PlanOptions};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    // Counted per thread: the test harness allocates on its own threads.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

// SAFETY: defers to the system allocator; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn sampling_allocates_nothing() {
    let limits = vec![JointLimits::new(3.0, 20.0, Some(200.0)); 18];
    let keyframes: Vec<Keyframe> = (0..20)
        .map(|k| {
            Keyframe::new(
                (0..18)
                    .map(|j| ((k * 7 + j * 3) % 11) as f64 * 0.1)
                    .collect::<Vec<_>>(),
            )
        })
        .collect();
    let traj = plan(&limits, &keyframes, &PlanOptions::default()).expect("plan");
    let mut cursor = traj.cursor();
    let mut out = [JointState::default(); 18];
    let before = allocations();
    let mut t = -0.1;
    let mut checksum = 0.0;
    while t < traj.duration() + 0.1 {
        traj.sample_with(&mut cursor, t, &mut out);
        checksum += out[0].position;
        traj.sample(t * 0.5, &mut out);
        checksum += out[17].velocity;
        t += 0.001;
    }
    traj.final_state(&mut out);
    let after = allocations();
    assert!(checksum.is_finite());
    assert_eq!(
        after - before,
        0,
        "sampling allocated {} times",
        after - before
    );
}
