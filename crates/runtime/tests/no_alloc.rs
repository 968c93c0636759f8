//! The control loop allocates nothing in steady state: a counting
//! allocator watches thousands of cycles of the simulated arm (the
//! simulator's own allocations, inside the transport, are not the loop's
//! and are not counted).

mod common;

use std::time::Duration;

use servobus_alloc_count::{allocations_during, uncounted, Counting};
use servobus_driver::{Bus, ManualClock, Transport, TransportError};
use servobus_runtime::{RunOptions, Telemetry, VirtualRun};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// A transport whose own work (the simulator's) is not counted.
struct Uncounted<T>(T);

impl<T: Transport> Transport for Uncounted<T> {
    type Clock = T::Clock;
    fn clock(&self) -> &T::Clock {
        self.0.clock()
    }
    fn baud(&self) -> u32 {
        uncounted(|| self.0.baud())
    }
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        uncounted(|| self.0.write_all(bytes))
    }
    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        uncounted(|| self.0.read(buf, deadline))
    }
    fn discard_input(&mut self) -> Result<(), TransportError> {
        uncounted(|| self.0.discard_input())
    }
}

fn steady_state_allocations(motion: &str, cycles: u64) -> usize {
    let (path, robot) = common::motion(motion);
    let (buses, _) = common::sim_buses(&robot);
    let buses: Vec<Bus<Uncounted<_>, ManualClock>> = buses
        .into_iter()
        .map(|b| {
            let settings = *b.settings();
            let (t, _) = b.into_parts();
            Bus::new(Uncounted(t), settings)
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
    let (count, samples) = allocations_during(|| {
        let mut samples = 0u64;
        for _ in 0..cycles {
            assert!(run.step());
            // A consumer reading in the same thread, every few cycles, so
            // that both the full-channel and the sending paths are
            // exercised.
            if run.cycle() % 7 == 0 {
                while let Ok(Telemetry::Cycle(_)) = telemetry.try_recv() {
                    samples += 1;
                }
            }
        }
        samples
    });
    assert!(samples > 0);
    let report = run.report();
    assert!(
        report.telemetry_dropped > 0,
        "the full channel was exercised"
    );
    count
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
    let (count, ()) = allocations_during(|| {
        let v: Vec<u64> = std::hint::black_box(Vec::with_capacity(8));
        drop(v);
    });
    assert!(count > 0);
}
