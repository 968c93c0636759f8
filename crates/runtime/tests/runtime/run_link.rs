//! Deadlines that learn the link, in virtual time: the SO-101 arm's robot
//! file says `latency_us: auto`, so the run measures the adapter at start-up
//! and keeps its reply deadlines just above what the link does.

use crate::common;

use std::time::Duration;

use servobus_runtime::{Finish, RunOptions, VirtualRun};
use servobus_sim::SimBus;

const MS: Duration = Duration::from_millis(1);

fn arm() -> (VirtualRun<SimBus>, Vec<SimBus>) {
    let (path, robot) = common::motion("arm-wave.yaml");
    assert!(
        robot.buses[0].latency_auto,
        "so101 ships `latency_us: auto`"
    );
    let (buses, sims) = common::sim_buses_at(&robot, &path);
    let options = RunOptions {
        telemetry_capacity: 256,
        ..RunOptions::default()
    };
    let run = VirtualRun::new(&robot, path, buses, options).expect("starts");
    (run, sims)
}

/// The adapter latency the run's deadlines allow for now.
fn in_force(run: &VirtualRun<SimBus>) -> Duration {
    run.bus(0).expect("bus 0").settings().link.latency
}

#[test]
fn a_link_whose_latency_jumps_to_1_ms_ends_with_deadlines_that_fit_it() {
    let (mut run, sims) = arm();
    let rec = common::record_acting_at(&mut run, 5_000, 200, || sims[0].set_latency(MS));
    assert!(run.cycle() > 400, "the run lasted well past the jump");
    assert!(rec.faults.is_empty(), "{:?}", rec.faults);
    assert_eq!(run.finished(), Some(Finish::Completed));
    assert!(run.fault().is_none());
    // The allowance covers the new 1 ms, with room, and stays bounded.
    let latency = in_force(&run);
    assert!(latency > MS, "{latency:?}");
    assert!(latency <= 3 * MS, "{latency:?}");
    let report = run.report();
    let b = &report.buses[0];
    assert!(b.latency_learned);
    assert_eq!(b.startup_probes, 32);
    // The last reads all came 1 ms late: that is the p99 the run reports,
    // and the deadline in force (SYNC READ of 6: 620 us of wire, 6 x 50 us
    // of turnaround, the allowance, 200 us of margin) holds it.
    assert!((b.latency_p99_us - 1000.0).abs() < 1.0, "{b:?}");
    assert!(
        b.reply_deadline_us > 620.0 + 300.0 + 1000.0 + 200.0,
        "{b:?}"
    );
    // At most the one read in flight when the link slowed down was lost.
    assert!(b.missed_replies <= 6, "{b:?}");
}

#[test]
fn a_fast_link_gets_a_tight_deadline() {
    let (mut run, _sims) = arm();
    let rec = common::record(&mut run, 5_000, |_| {});
    assert!(rec.faults.is_empty());
    assert_eq!(run.finished(), Some(Finish::Completed));
    // The simulator's adapter adds nothing: the allowance is the headroom
    // alone, 100 us, far below the 3 ms a pty is given by default.
    assert_eq!(in_force(&run), Duration::from_micros(100));
}

#[test]
fn a_servo_that_stops_answering_is_still_found_within_3_cycles() {
    let (mut run, sims) = arm();
    let at = 300;
    common::record_acting_at(&mut run, 5_000, at, || {
        sims[0].servo(4, |s| s.set_offline(true)).expect("servo 4");
    });
    let f = run.fault().expect("the silent servo is found").clone();
    assert_eq!(f.servo_id, Some(4));
    assert!(
        f.cycle >= at && f.cycle - at < 3,
        "cycle {} vs {at}",
        f.cycle
    );
    // Its reads time out at the bounded allowance, not later.
    assert!(in_force(&run) <= 3 * MS);
}

#[test]
fn a_number_in_the_robot_file_wins() {
    let (path, mut robot) = common::motion("arm-wave.yaml");
    robot.buses[0].latency = MS;
    robot.buses[0].latency_auto = false;
    let (buses, _sims) = common::sim_buses_at(&robot, &path);
    let mut run = VirtualRun::new(&robot, path, buses, RunOptions::default()).expect("starts");
    while run.step() {}
    assert_eq!(run.finished(), Some(Finish::Completed));
    // Nothing measured at start-up, nothing learned: 1 ms stays in force
    // although the simulated link adds no latency at all.
    assert_eq!(in_force(&run), MS);
    let report = run.report();
    let b = &report.buses[0];
    assert!(!b.latency_learned);
    assert_eq!(b.startup_probes, 0);
    assert!(b.latency_us < 1.0, "{b:?}");
}

#[test]
fn the_goals_wire_time_is_not_taken_for_the_adapters_latency() {
    // A port whose writes return once the bytes are queued, as a real one
    // does: the simulated servos behind `WallBus`, on a manual "wall" clock.
    // Each cycle's SYNC READ then starts on the wire only after the SYNC
    // WRITE of the goals (6 x 7 bytes of data, about 0.5 ms at 1 Mbaud).
    let (path, robot) = common::motion("arm-wave.yaml");
    let wall = servobus_driver::ManualClock::new();
    let buses = common::wall_buses(&robot, &common::start_pose(&robot, &path), &wall);
    let mut run = VirtualRun::new(&robot, path, buses, RunOptions::default()).expect("starts");
    while run.step() {}
    assert_eq!(run.finished(), Some(Finish::Completed));
    let report = run.report();
    let b = &report.buses[0];
    // The simulated adapter adds no latency: what is learned is nothing,
    // not the goals' half millisecond.
    assert_eq!(b.timeouts, 0, "{b:?}");
    assert!(b.latency_learned);
    assert!(b.latency_us < 1.0 && b.latency_p99_us < 1.0, "{b:?}");
}
