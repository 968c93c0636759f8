//! Each fault, injected in the simulated arm, is detected within 3 cycles
//! and leads to its reaction, reported with the joint, values and time.

use crate::common;

use servobus_protocol::StatusFlags;
use servobus_runtime::{
    Fault, FaultKind, FaultPolicy, Finish, Lead, Reaction, RunOptions, VirtualRun,
};
use servobus_sim::{SimBus, SimServo};
use servobus_trajectory::Trajectory;

const PERIOD: f64 = 0.005;
const WRIST_FLEX: usize = 3;
const WRIST_FLEX_ID: u8 = 4;

/// The cycle at which joint `j` of `path` moves fastest.
fn fastest_cycle(path: &Trajectory, j: usize) -> u64 {
    common::fastest_cycle(path, j, PERIOD)
}

fn arm(policy: FaultPolicy, lead: Lead) -> (VirtualRun<SimBus>, Vec<SimBus>, Trajectory) {
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, sims) = common::sim_buses_at(&robot, &path);
    let options = RunOptions {
        faults: policy,
        lead,
        telemetry_capacity: 256,
        ..RunOptions::default()
    };
    let run = VirtualRun::new(&robot, path.clone(), buses, options).expect("starts");
    (run, sims, path)
}

/// The arm playing arm-wave with the default policy, `fault` done to servo
/// `id` `before` cycles ahead of the wrist's fastest; the run ended, its
/// telemetry, and the cycle of the fault.
fn faulted_arm(
    before: u64,
    id: u8,
    fault: fn(&mut SimServo),
) -> (VirtualRun<SimBus>, Vec<SimBus>, common::Recorded, u64) {
    let (mut run, sims, path) = arm(FaultPolicy::default(), Lead::default());
    let at = fastest_cycle(&path, WRIST_FLEX) - before;
    let rec = common::record_acting_at(&mut run, 5_000, at, || {
        sims[0].servo(id, fault).expect("a servo with this ID");
    });
    (run, sims, rec, at)
}

fn the_fault(run: &VirtualRun<SimBus>, rec: &common::Recorded) -> Fault {
    let f = run.fault().expect("a fault was detected").clone();
    assert_eq!(rec.faults.first(), Some(&f), "and published");
    assert_eq!(run.finished(), Some(Finish::Fault));
    println!("{f}");
    f
}

/// The stop after a fault is jerk-limited: commands stay within the arm's
/// limits (wrist_flex: 240 deg/s, 1200 deg/s^2, 12000 deg/s^3). Finite
/// differences of a path are weighted means of its derivatives, so they
/// keep its limits exactly; 1e-6 is float rounding, and 1 % what a ramp of
/// the run's identified lead may add (the runtime's `LEAD_EXCESS`).
fn assert_smooth_from(rec: &common::Recorded, from: u64) {
    let (v, a, j) = rec.peaks(WRIST_FLEX, from, PERIOD);
    println!("wrist_flex after cycle {from}: {v:.1} deg/s, {a:.0} deg/s^2, {j:.0} deg/s^3");
    let within = 1.0 + 1e-6 + 0.01;
    assert!(
        v <= 240.0 * within && a <= 1200.0 * within && j <= 12_000.0 * within,
        "{v} {a} {j}"
    );
}

#[test]
fn a_vanished_servo_is_detected_within_3_cycles_and_the_arm_stops_smoothly() {
    let (run, _, rec, at) = faulted_arm(0, WRIST_FLEX_ID, |s| s.set_offline(true));
    let f = the_fault(&run, &rec);
    // Reported at the time of its cycle, at most 3 cycles of 5 ms (the
    // arm's 200 Hz) after the path time the servo vanished at.
    let vanished = at as f64 / 200.0;
    assert!(
        f.time_s >= vanished - 1e-9 && f.time_s < vanished + 3.0 / 200.0,
        "fault at {} s, vanished at {vanished} s",
        f.time_s
    );
    assert!(
        matches!(f.kind, FaultKind::Missing { cycles: 3, .. }),
        "{f:?}"
    );
    assert_eq!(f.joint.as_deref(), Some("wrist_flex"));
    assert_eq!(f.servo_id, Some(WRIST_FLEX_ID));
    assert!(
        f.cycle >= at && f.cycle - at < 3,
        "cycle {} vs injection {at}",
        f.cycle
    );
    assert_eq!(f.reaction, Reaction::Stop);
    assert_smooth_from(&rec, at.saturating_sub(5));
}

#[test]
fn a_status_flag_is_detected_at_the_next_reading() {
    let (run, _, rec, at) = faulted_arm(0, 2, |s| s.inject_status(StatusFlags::OVERHEAT));
    let f = the_fault(&run, &rec);
    assert_eq!(
        f.kind,
        FaultKind::Status {
            flags: StatusFlags::OVERHEAT,
            names: "overheat".into()
        }
    );
    assert_eq!(f.joint.as_deref(), Some("shoulder_lift"));
    assert_eq!(f.cycle, at);
    assert_smooth_from(&rec, at.saturating_sub(5));
}

#[test]
fn a_blocked_joint_is_found_stalled_within_3_cycles_and_held() {
    let (run, sims, rec, at) = faulted_arm(10, WRIST_FLEX_ID, |s| s.set_blocked(true));
    let f = the_fault(&run, &rec);
    assert!(
        matches!(f.kind, FaultKind::Stall { error, planned_velocity, measured_velocity, cycles: 3 }
            if error.abs() > 2.0 && measured_velocity.abs() < 0.25 * planned_velocity.abs()),
        "{f:?}"
    );
    // The condition (error beyond 2 deg while the joint does not follow)
    // first showed in telemetry at `onset`; detection is on its 3rd cycle.
    let onset = rec
        .rows
        .iter()
        .find(|r| r.1 == WRIST_FLEX && r.0 > at && r.3.abs() > 2.0)
        .map(|r| r.0)
        .expect("the error grew");
    assert!(f.cycle - onset <= 2, "onset {onset}, detected {}", f.cycle);
    assert_eq!(f.reaction, Reaction::Hold);
    // Hold: the blocked joint is now commanded where it stands.
    let held = sims[0].servo(WRIST_FLEX_ID, |s| {
        (s.goal_position() - s.present_position()).abs()
    });
    assert!(held.is_some_and(|d| d <= 1), "{held:?}");
}

#[test]
fn a_following_error_is_detected_on_its_third_cycle_and_torque_goes_off() {
    // Without lead the arm trails its path by up to 3.6 deg: a tolerance of
    // 1.5 deg is exceeded.
    let policy = FaultPolicy {
        following_error: 1.5f64.to_radians(),
        on_following_error: Reaction::TorqueOff,
        stall_error: f64::INFINITY,
        ..FaultPolicy::default()
    };
    let (mut run, sims, _) = arm(policy, Lead::None);
    let rec = common::record(&mut run, 5_000, |_| {});
    let f = the_fault(&run, &rec);
    assert!(
        matches!(f.kind, FaultKind::FollowingError { error, tolerance, cycles: 3 }
            if error.abs() > tolerance && (tolerance - 1.5).abs() < 1e-9),
        "{f:?}"
    );
    // The row of the joint at fault in the telemetry: its place in the robot.
    let index = common::robot("so101.yaml")
        .joints()
        .position(|j| Some(&j.name) == f.joint.as_ref())
        .expect("a joint of the arm");
    let onset = rec
        .rows
        .iter()
        .find(|r| r.1 == index && r.3.abs() > 1.5)
        .map(|r| r.0)
        .expect("the error grew");
    assert_eq!(f.cycle, onset + 2);
    for id in 1..=6 {
        assert_eq!(
            sims[0].servo(id, |s| s.torque_enabled()),
            Some(false),
            "servo {id}"
        );
    }
}

#[test]
fn a_lost_port_stops_the_other_bus_of_the_hexapod() {
    let (path, robot) = common::planned(
        "motions/hexapod-tripod.yaml",
        Some("robots/hexapod-2bus.yaml"),
    );
    let (buses, sims) = common::sim_buses_at(&robot, &path);
    let options = RunOptions {
        telemetry_capacity: 256,
        ..RunOptions::default()
    };
    let mut run = VirtualRun::new(&robot, path, buses, options).expect("starts");
    let at = 150;
    let rec = common::record_acting_at(&mut run, 5_000, at, || sims[1].set_disconnected(true));
    let f = run.fault().expect("a fault").clone();
    println!("{f}");
    assert!(matches!(f.kind, FaultKind::PortGone { .. }));
    assert_eq!((f.bus.as_str(), f.cycle), ("right", at));
    assert_eq!(f.reaction, Reaction::Stop);
    assert_eq!(run.finished(), Some(Finish::Fault));
    // The left bus stopped along its jerk-limited path (period 10 ms at
    // 100 Hz; hexapod legs: at most 240 deg/s, 1500 deg/s^2, 15000 deg/s^3).
    for j in 0..9 {
        let (v, a, jerk) = rec.peaks(j, at - 5, 0.01);
        assert!(
            v <= 240.0 * 1.05 && a <= 1500.0 * 1.05 && jerk <= 15_000.0 * 1.05,
            "{j}: {v} {a} {jerk}"
        );
    }
}

#[test]
fn start_up_waits_for_slow_replies_but_names_a_servo_that_never_answers() {
    use servobus_runtime::RunError;
    use servobus_sim::Faults;
    use std::time::Duration;

    // Every reply 20 ms late: far beyond a cycle's timeout at 1 Mbps, well
    // within the patience of start-up, which is not timed.
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, sims) = common::sim_buses_at(&robot, &path);
    sims[0].set_faults(Faults::seeded(1).delay(1.0, Duration::from_millis(20)));
    let run = VirtualRun::new(&robot, path.clone(), buses, RunOptions::default())
        .unwrap_or_else(|e| panic!("start-up waits for slow replies: {e}"));
    assert!(run.fault().is_none() && run.finished().is_none());
    // It waited for them: six servos each answering 20 ms late take at
    // least 120 ms of the simulator's clock.
    let waited = servobus_driver::Clock::now(sims[0].clock());
    assert!(waited >= Duration::from_millis(120), "{waited:?}");

    // A servo that is not there at all is named, with its joint.
    let (buses, sims) = common::sim_buses_at(&robot, &path);
    sims[0].set_faults(Faults::none().vanish(WRIST_FLEX_ID));
    match VirtualRun::new(&robot, path, buses, RunOptions::default()) {
        Err(RunError::NoServo { id, joint, .. }) => {
            assert_eq!((id, joint.as_str()), (WRIST_FLEX_ID, "wrist_flex"));
        }
        other => panic!("expected a missing servo, got {:?}", other.err()),
    }
}
