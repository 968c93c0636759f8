//! A counting global allocator for tests that prove a hot path allocates
//! nothing: several crates keep such a test, and one allocator serves them
//! all.
//!
//! Only the calling thread's allocations are counted: the test harness's
//! own threads may allocate at any time without disturbing a measurement.
//!
//! ```
//! use servobus_alloc_count::{allocations_during, Counting};
//!
//! #[global_allocator]
//! static GLOBAL: Counting = Counting;
//!
//! let (count, v) = allocations_during(|| vec![0u8; 16]);
//! assert_eq!((count, v.len()), (1, 16));
//! let (count, sum) = allocations_during(|| v.iter().map(|&b| u32::from(b)).sum::<u32>());
//! assert_eq!((count, sum), (0, 0));
//! ```
#![warn(missing_docs)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    // Const-initialised and without a destructor: reading it from inside the
    // allocator never allocates itself.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// The system allocator, counting this thread's allocations and
/// reallocations. Install it with `#[global_allocator]` in a test crate.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counting;

fn count() {
    // `try_with`: a thread being torn down may still free or allocate.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every call is forwarded unchanged to the system allocator; the
// only addition is a thread-local counter increment, which cannot allocate.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: the caller upholds `GlobalAlloc::realloc`'s contract.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Allocations made on this thread so far (with [`Counting`] installed).
pub fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Allocations made on this thread while `f` runs, and what it returned.
pub fn allocations_during<R>(f: impl FnOnce() -> R) -> (usize, R) {
    let before = allocations();
    let r = f();
    (allocations() - before, r)
}
