//! The control loop allocates nothing in steady state: a counting
//! allocator watches thousands of cycles of the simulated arm (the
//! simulator's own allocations, inside the transport, are not the loop's
//! and are not counted).

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::Duration;

use servobus_driver::{Bus, ManualClock, Transport, TransportError};
use servobus_runtime::{RunOptions, Telemetry, VirtualRun};

struct Counting;

thread_local! {
    /// Counting is on for this thread.
    static ARMED: Cell<bool> = const { Cell::new(false) };
    /// Allocations counted on this thread (tests run in parallel threads).
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

fn armed() -> bool {
    ARMED.try_with(Cell::get).unwrap_or(false)
}

// SAFETY: every call is forwarded unchanged to the system allocator; the
// counter only observes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if armed() {
            count();
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if armed() {
            count();
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// A transport whose own work (the simulator's) is not counted.
struct Uncounted<T>(T);

fn paused<R>(f: impl FnOnce() -> R) -> R {
    let was = armed();
    ARMED.with(|a| a.set(false));
    let r = f();
    ARMED.with(|a| a.set(was));
    r
}

impl<T: Transport> Transport for Uncounted<T> {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        paused(|| self.0.write_all(bytes))
    }
    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        paused(|| self.0.read(buf, deadline))
    }
    fn discard_input(&mut self) -> Result<(), TransportError> {
        paused(|| self.0.discard_input())
    }
}

fn steady_state_allocations(motion: &str, cycles: u64) -> u64 {
    let (path, robot) = common::motion(motion);
    let (buses, _) = common::sim_buses(&robot);
    let buses: Vec<Bus<Uncounted<_>, ManualClock>> = buses
        .into_iter()
        .map(|b| {
            let settings = *b.settings();
            let (t, c) = b.into_parts();
            Bus::new(Uncounted(t), c, settings)
        })
        .collect();
    let options = RunOptions {
        // Keep holding the end long enough for the whole count.
        settle: Duration::from_secs(60),
        telemetry_capacity: 64,
        ..RunOptions::default()
    };
    let mut run = VirtualRun::new(&robot, path, buses, options).expect("starts");
    let telemetry = run.telemetry();
    // Warm up: start-up, the approach, the lead identification.
    for _ in 0..200 {
        assert!(run.step());
    }
    let before = allocations();
    let mut samples = 0u64;
    ARMED.with(|a| a.set(true));
    for _ in 0..cycles {
        assert!(run.step());
        // A consumer reading in the same thread, every few cycles, so that
        // both the full-channel and the sending paths are exercised.
        if run.cycle() % 7 == 0 {
            while let Ok(Telemetry::Cycle(_)) = telemetry.try_recv() {
                samples += 1;
            }
        }
    }
    ARMED.with(|a| a.set(false));
    assert!(samples > 0);
    let report = run.report();
    assert!(
        report.telemetry_dropped > 0,
        "the full channel was exercised"
    );
    allocations() - before
}

#[test]
fn the_arm_loop_allocates_nothing_over_5000_cycles() {
    assert_eq!(steady_state_allocations("arm-wave.yaml", 5_000), 0);
}

#[test]
fn the_18_servo_hexapod_loop_allocates_nothing_over_3000_cycles() {
    assert_eq!(steady_state_allocations("hexapod-tripod.yaml", 3_000), 0);
}

#[test]
fn the_counter_sees_allocations() {
    ARMED.with(|a| a.set(true));
    let v: Vec<u64> = std::hint::black_box(Vec::with_capacity(8));
    ARMED.with(|a| a.set(false));
    drop(v);
    assert!(allocations() > 0);
}
