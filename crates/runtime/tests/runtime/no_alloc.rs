//! The control loop allocates nothing in steady state: a counting
//! allocator watches thousands of cycles of the simulated arm (the
//! simulator's own allocations, inside the transport, are not the loop's
//! and are not counted).

use crate::common;

use std::time::Duration;

use servobus_alloc_count::{allocations_during, uncounted, Counting};
use servobus_driver::{Bus, Transport, TransportError};
use servobus_runtime::config::{JointMap, Robot};
use servobus_runtime::{LiveTarget, RunOptions, Telemetry, VirtualRun};
use servobus_sim::SimBus;

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

/// The robot's simulated buses, the simulator's work left out of counts.
fn uncounted_buses(robot: &Robot) -> Vec<Bus<Uncounted<SimBus>>> {
    let (buses, _) = common::sim_buses(robot);
    buses
        .into_iter()
        .map(|b| {
            let settings = *b.settings();
            let t = b.into_transport();
            Bus::new(Uncounted(t), settings)
        })
        .collect()
}

fn options() -> RunOptions {
    RunOptions {
        // Keep holding the end long enough for the whole count.
        settle: Duration::from_secs(60),
        telemetry_capacity: 64,
        ..RunOptions::default()
    }
}

/// The allocations of `cycles` cycles of `run` after 200 of warm-up
/// (start-up, the approach, the lead identification). `feed(k)` runs
/// before cycle `k`, uncounted: it stands for another thread's work.
fn counted_cycles(
    run: &mut VirtualRun<Uncounted<SimBus>>,
    cycles: u64,
    mut feed: impl FnMut(u64),
) -> usize {
    let telemetry = run.telemetry();
    for _ in 0..200 {
        uncounted(|| feed(run.cycle()));
        assert!(run.step());
    }
    let (count, samples) = allocations_during(|| {
        let mut samples = 0u64;
        for _ in 0..cycles {
            uncounted(|| feed(run.cycle()));
            assert!(run.step());
            // A consumer reading in the same thread, every few cycles, so
            // that both the full-channel and the sending paths are
            // exercised.
            if run.cycle().is_multiple_of(7) {
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

fn steady_state_allocations(motion: &str, cycles: u64) -> usize {
    let (path, robot) = common::motion(motion);
    let buses = uncounted_buses(&robot);
    let mut run = VirtualRun::new(&robot, path, buses, options()).expect("starts");
    counted_cycles(&mut run, cycles, |_| {})
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
fn a_live_loop_following_a_30_hz_stream_allocates_nothing_over_3000_cycles() {
    let robot = common::robot("so101.yaml");
    let buses = uncounted_buses(&robot);
    let mut run = VirtualRun::live(&robot, buses, options()).expect("starts");
    let tx = run.targets();
    let period = 1.0 / robot.rate_hz;
    // The middle of each servo's range, where the simulated joints start.
    let start: Vec<f64> = robot
        .joints()
        .map(|j| JointMap::new(j, robot.units).from_ticks(2048))
        .collect();
    let mut sent = 0u64;
    // Every joint sways by up to 0.2 rad around its start, a target about every
    // 33 ms (stamped with its cycle's time), all run long.
    let count = counted_cycles(&mut run, 3_000, |k| {
        let t = k as f64 * period;
        if t * 30.0 >= sent as f64 {
            let q = start
                .iter()
                .enumerate()
                .map(|(j, q0)| q0 + 0.2 * (t * (1.0 + 0.2 * j as f64)).sin())
                .collect();
            assert_eq!(tx.send(LiveTarget::all(t, q)), Ok(0));
            sent += 1;
        }
    });
    assert_eq!(count, 0);
    let live = run.report().live.expect("targets counted");
    // Followed all the way: none refused, the stream never timed out.
    assert_eq!((live.received, live.refused, live.timeouts), (sent, 0, 0));
    assert!(sent > 90, "{sent}");
}

#[test]
fn the_counter_sees_allocations() {
    let (count, ()) = allocations_during(|| {
        let v: Vec<u64> = std::hint::black_box(Vec::with_capacity(8));
        drop(v);
    });
    assert!(count > 0);
}
