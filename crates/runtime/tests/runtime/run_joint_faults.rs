//! A joint's own fault policy (`faults:` in the robot file) in a played
//! run: the SO-101 plays arm-pick-place, whose gripper closes from 70 to 5
//! deg between 2.5 and 3.3 s and opens to 60 at 7.3 s, with the gripper's
//! shaft blocked half-way through the closing (an object in the jaws).

use std::path::PathBuf;

use crate::common;

use servobus_protocol::StatusFlags;
use servobus_runtime::config::{load_motion, plan_motion, FaultResponse, Robot};
use servobus_runtime::{
    Fault, FaultKind, Finish, RunOptions, StallEvent, Telemetry, VirtualRun, STALL_PUSH,
};
use servobus_sim::{SimBus, SimServo};
use servobus_trajectory::Trajectory;

const GRIPPER: usize = 5;
const GRIPPER_ID: u8 = 6;
/// 200 Hz: the SO-101's rate.
const PERIOD: f64 = 0.005;
/// 2.75 s: the gripper is closing fast (124 deg/s), at about 59 deg.
const BLOCK_AT: u64 = 550;

/// The SO-101's robot file with `faults` (a `faults:` value) given to its
/// gripper, written to a file of its own called `name`.
fn so101_with(name: &str, faults: Option<&str>) -> PathBuf {
    let text = std::fs::read_to_string(common::config("robots/so101.yaml")).expect("so101");
    let home = "        home: 10\n";
    assert_eq!(text.matches(home).count(), 1, "the gripper's home line");
    let text = match faults {
        Some(f) => text.replace(home, &format!("{home}        faults: {f}\n")),
        None => text,
    };
    common::temp_file("run_joint_faults", &format!("{name}.yaml"), &text)
}

/// arm-pick-place planned for the SO-101 with the gripper's `faults`.
fn pick_place(name: &str, faults: Option<&str>) -> (Trajectory, Robot) {
    let robot = so101_with(name, faults);
    let motion = common::config("motions/arm-pick-place.yaml");
    let (m, r) = load_motion(&motion, Some(&robot)).expect("motion loads");
    (plan_motion(&m, &r).expect("motion plans"), r)
}

/// What a run published.
#[derive(Default)]
struct Seen {
    faults: Vec<Fault>,
    stalls: Vec<StallEvent>,
    /// `(cycle, commanded, measured)` of the gripper in the cycles it was
    /// held pressed.
    held: Vec<(u64, f64, f64)>,
}

/// Plays `path` on `robot`'s simulated servos, blocking the gripper's shaft
/// before cycle [`BLOCK_AT`] and doing `then` to its servo before cycle
/// `then_at`; the run once it ended and what it published.
fn play(
    robot: &Robot,
    path: Trajectory,
    then_at: u64,
    then: fn(&mut SimServo),
) -> (VirtualRun<SimBus>, Seen) {
    let (buses, sims) = common::sim_buses_at(robot, &path);
    let options = RunOptions {
        telemetry_capacity: 1024,
        ..RunOptions::default()
    };
    let mut run = VirtualRun::new(robot, path, buses, options).expect("starts");
    let rx = run.telemetry();
    let mut seen = Seen::default();
    for _ in 0..5_000 {
        let k = run.cycle();
        if k == BLOCK_AT {
            sims[0].servo(GRIPPER_ID, |s| s.set_blocked(true));
        }
        if k == then_at {
            sims[0].servo(GRIPPER_ID, then);
        }
        let going = run.step();
        while let Ok(m) = rx.try_recv() {
            match m {
                Telemetry::Fault(f) => seen.faults.push(f),
                Telemetry::Stall(s) => seen.stalls.push(s),
                Telemetry::Cycle(c) => {
                    let held = c.joints().iter().find(|j| j.joint == GRIPPER && j.stalled);
                    if let Some(j) = held {
                        let measured = j.measured.expect("a held joint was read");
                        seen.held.push((c.cycle, j.commanded, measured));
                    }
                }
                _ => {}
            }
        }
        if !going {
            break;
        }
    }
    (run, seen)
}

fn nothing(_: &mut SimServo) {}

#[test]
fn a_gripper_that_holds_its_stall_closes_on_the_object_and_the_run_completes() {
    let (path, robot) = pick_place("hold", Some("{stall: hold}"));
    let gripper = robot.joint("gripper").expect("a gripper");
    assert_eq!(gripper.faults.stall, FaultResponse::Hold);
    let end = (path.duration() / PERIOD) as u64;
    let (run, seen) = play(&robot, path, u64::MAX, nothing);
    assert_eq!(run.finished(), Some(Finish::Completed), "{:?}", run.fault());
    assert!(
        run.fault().is_none() && seen.faults.is_empty(),
        "{:?}",
        seen.faults
    );

    // Held on its 3rd stalled reading: within a few cycles of the block.
    let first = seen.stalls.first().expect("a stall was reported");
    println!("{first:?}");
    assert_eq!(
        (first.joint, first.servo_id, first.held),
        (GRIPPER, GRIPPER_ID, true)
    );
    assert!(
        first.cycle > BLOCK_AT && first.cycle <= BLOCK_AT + 6,
        "held at cycle {}, blocked at {BLOCK_AT}",
        first.cycle
    );
    // Where the shaft stopped: between the closing's 70 and 5 deg; pressed
    // the way the path closes (towards lower angles), by one STALL_PUSH.
    assert!((10.0..65.0).contains(&first.position), "{}", first.position);
    assert!(
        (first.push + STALL_PUSH.to_degrees()).abs() < 1e-9,
        "{}",
        first.push
    );
    // The opening at 7.3 s lets it go: the path comes back within the bound.
    let release = seen.stalls.iter().find(|s| !s.held).expect("let go");
    assert!(
        release.time_s > 6.5 && release.time_s < 8.1,
        "let go at {} s",
        release.time_s
    );
    // While held, the goal sent never went further than STALL_PUSH (1 deg)
    // beyond where the gripper stood, though the path asked 5 deg.
    let pressed: Vec<_> = seen.held.iter().filter(|h| h.0 < release.cycle).collect();
    assert!(pressed.len() > 500, "held {} cycles", pressed.len());
    for &&(k, commanded, measured) in &pressed {
        assert!(
            measured - commanded <= STALL_PUSH.to_degrees() + 0.1 && commanded <= measured,
            "cycle {k}: commanded {commanded}, measured {measured}"
        );
    }
    // And the report counts it.
    let report = run.report();
    let joint = report.joints.get(GRIPPER).expect("the gripper's report");
    assert!(
        joint.stalls >= 1 && joint.stalled_s > 2.5,
        "{} {}",
        joint.stalls,
        joint.stalled_s
    );
    assert!(
        run.cycle() >= end,
        "ran to the end: {} of {end}",
        run.cycle()
    );
}

#[test]
fn without_the_key_the_same_block_is_a_stall_fault() {
    let (path, robot) = pick_place("default", None);
    assert_eq!(
        robot.joint("gripper").expect("gripper").faults.stall,
        FaultResponse::Fault
    );
    let (run, seen) = play(&robot, path, u64::MAX, nothing);
    assert_eq!(run.finished(), Some(Finish::Fault));
    let f = run.fault().expect("a fault");
    println!("{f}");
    assert!(
        matches!(f.kind, FaultKind::Stall { cycles: 3, .. }),
        "{f:?}"
    );
    assert_eq!(f.joint.as_deref(), Some("gripper"));
    assert!(f.cycle > BLOCK_AT && f.cycle <= BLOCK_AT + 6, "{}", f.cycle);
    assert!(seen.stalls.is_empty(), "{:?}", seen.stalls);
}

#[test]
fn ignoring_the_stall_leaves_the_following_error_to_end_the_run() {
    // Not checked for stalls, the blocked gripper falls behind its closing
    // path until it is 15 deg off it: a following error.
    let (path, robot) = pick_place("ignore", Some("{stall: ignore}"));
    let (run, seen) = play(&robot, path, u64::MAX, nothing);
    let f = run.fault().expect("a fault");
    println!("{f}");
    assert!(
        matches!(f.kind, FaultKind::FollowingError { error, cycles: 3, .. } if error.abs() > 15.0),
        "{f:?}"
    );
    assert_eq!(f.joint.as_deref(), Some("gripper"));
    assert!(seen.stalls.is_empty(), "{:?}", seen.stalls);
}

#[test]
fn the_gripper_may_have_its_own_tolerance_and_hold_its_following_error() {
    // Stalls unchecked and a tolerance of 5 deg: the following error is
    // found sooner than at the run's 15 deg, and reported at 5.
    let (path, robot) = pick_place("tolerance", Some("{stall: ignore, following_tolerance: 5}"));
    let (run, _) = play(&robot, path, u64::MAX, nothing);
    let f = run.fault().expect("a fault");
    println!("{f}");
    assert!(
        matches!(f.kind, FaultKind::FollowingError { error, tolerance, cycles: 3 }
            if error.abs() > 5.0 && error.abs() < 15.0 && (tolerance - 5.0).abs() < 1e-9),
        "{f:?}"
    );
    assert!(f.cycle < 574, "sooner than at 15 deg: cycle {}", f.cycle);

    // The same following error held: the gripper is pressed, the run goes on.
    let faults = "{stall: ignore, following_error: hold, following_tolerance: 5}";
    let (path, robot) = pick_place("following-hold", Some(faults));
    let (run, seen) = play(&robot, path, u64::MAX, nothing);
    assert_eq!(run.finished(), Some(Finish::Completed), "{:?}", run.fault());
    let first = seen.stalls.first().expect("reported");
    assert!(first.held && first.joint == GRIPPER, "{first:?}");
    assert!(
        first.cycle > BLOCK_AT && first.cycle < 574,
        "{}",
        first.cycle
    );
}

/// A held gripper's servo `fault`, done 200 cycles (1 s) after the block;
/// the run's fault.
fn held_then(name: &str, fault: fn(&mut SimServo)) -> Fault {
    let (path, robot) = pick_place(name, Some("{stall: hold, following_error: hold}"));
    let at = BLOCK_AT + 200;
    let (run, seen) = play(&robot, path, at, fault);
    assert!(
        seen.stalls.first().is_some_and(|s| s.held && s.cycle < at),
        "held first: {:?}",
        seen.stalls
    );
    assert_eq!(run.finished(), Some(Finish::Fault));
    let f = run.fault().expect("a fault").clone();
    println!("{f}");
    assert_eq!(seen.faults.first(), Some(&f), "and published");
    assert_eq!(f.joint.as_deref(), Some("gripper"));
    assert!(
        f.cycle >= at && f.cycle < at + 4,
        "at {at}, fault at {}",
        f.cycle
    );
    f
}

#[test]
fn a_held_gripper_that_overheats_still_ends_the_run() {
    let f = held_then("overheat", |s| s.inject_status(StatusFlags::OVERHEAT));
    assert_eq!(
        f.kind,
        FaultKind::Status {
            flags: StatusFlags::OVERHEAT,
            names: "overheat".into()
        }
    );
}

#[test]
fn a_held_gripper_whose_servo_goes_missing_still_ends_the_run() {
    let f = held_then("missing", |s| s.set_offline(true));
    assert!(
        matches!(f.kind, FaultKind::Missing { cycles: 3, .. }),
        "{f:?}"
    );
}
