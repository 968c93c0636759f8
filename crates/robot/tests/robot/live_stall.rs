//! A joint pressed against a stop does not end a live session (issue 35):
//! in virtual time, the simulated SO-101 follows live targets that close
//! its gripper past a mechanical stop at 20 deg. The gripper stalls there,
//! is held with its goal within `STALL_PUSH` (1 deg) of where it stands, the
//! stall is published and counted in the report, the run goes on, and the
//! gripper follows again once the targets open it. Heat still ends the run.

use std::path::PathBuf;

use servobus_protocol::StatusFlags;
use servobus_robot::sim::{Mounting, SimRobot};
use servobus_runtime::config::Robot;
use servobus_runtime::{
    Command, FaultKind, Finish, Lead, LiveTarget, RunOptions, Telemetry, VirtualRun,
};
use servobus_sim::SimBus;

use crate::common;

const PERIOD: f64 = 0.005;
const GRIPPER: usize = 5;
const GRIPPER_ID: u8 = 6;
/// The stop that closes the gripper short of its limit (0 deg): an object
/// 20 deg wide, or a badly mounted jaw.
const STOP_DEG: f64 = 20.0;
/// `STALL_PUSH` as documented, deg.
const PUSH_DEG: f64 = 1.0;
/// One STS3215 tick, deg: the goal is rounded to a tick.
const TICK_DEG: f64 = 360.0 / 4096.0;

/// The pose the arm starts in and the targets keep for every joint but the
/// gripper, deg (robot file's frame).
const POSE: [f64; 6] = [0.0, 0.0, 0.0, 0.0, 0.0, 40.0];

/// A mounting file for `robot`: the robot file's own, with the gripper
/// blocked at [`STOP_DEG`] on its closing side.
fn mounting_file(robot: &Robot) -> PathBuf {
    let design = Mounting::of_robot_file(robot);
    let g = &design.mounts()[GRIPPER];
    let dir = std::env::temp_dir().join(format!("servobus-live-stall-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("mounting.yaml");
    let yaml = format!(
        "gripper: {{zero_tick: {}, direction: {}, stops: [{STOP_DEG}, 102]}}\n",
        g.zero_tick, g.direction as i64
    );
    std::fs::write(&file, yaml).expect("writes the mounting");
    file
}

fn live_run() -> (VirtualRun<SimBus>, Vec<SimBus>, Robot) {
    let robot = common::robot("so101.yaml");
    let mounting = Mounting::load(&mounting_file(&robot), &robot).expect("the mounting loads");
    let sim = SimRobot::builder(&robot)
        .mounting(mounting)
        .pose(&POSE)
        .build()
        .expect("simulates");
    let options = RunOptions {
        lead: Lead::None,
        approach: None,
        telemetry_capacity: 1 << 16,
        ..RunOptions::default()
    };
    let run = VirtualRun::live(&robot, sim.driver_buses(), options).expect("a live run starts");
    (run, sim.buses().to_vec(), robot)
}

/// The gripper's target at `t` s, deg: held at 40, closed to 0 (20 deg past
/// the stop) over 0.5 s, held closed 2 s, opened to 60 over 0.5 s, held.
fn gripper_target(t: f64) -> f64 {
    let ramp = |t: f64, t0: f64, a: f64, b: f64| {
        let s = ((t - t0) / 0.5).clamp(0.0, 1.0);
        a + (b - a) * s
    };
    if t < 1.0 {
        ramp(t, 0.5, 40.0, 0.0)
    } else {
        ramp(t, 3.0, 0.0, 60.0)
    }
}

/// One cycle's gripper figures: time, commanded, measured, held.
struct Row {
    t: f64,
    commanded: f64,
    measured: Option<f64>,
    stalled: bool,
}

/// What the run published.
#[derive(Default)]
struct Seen {
    rows: Vec<Row>,
    stalls: Vec<servobus_runtime::Telemetry>,
    faults: Vec<servobus_runtime::Fault>,
    /// Every commanded angle of every joint, deg, with its joint.
    commanded: Vec<(usize, f64)>,
}

/// Runs the live session for `seconds`, sending a target every 20 ms
/// (50 Hz), calling `act(cycle)` before each cycle; stops when the run
/// ends. Returns what it published and whether it was still going.
fn follow(run: &mut VirtualRun<SimBus>, seconds: f64, mut act: impl FnMut(u64)) -> (Seen, bool) {
    let tx = run.targets();
    let rx = run.telemetry();
    let mut seen = Seen::default();
    let cycles = (seconds / PERIOD).round() as u64;
    let mut going = true;
    for _ in 0..cycles {
        let k = run.cycle();
        let t = k as f64 * PERIOD;
        if k.is_multiple_of(4) {
            let mut q: Vec<f64> = POSE.iter().map(|a| a.to_radians()).collect();
            q[GRIPPER] = gripper_target(t).to_radians();
            // A target refused at the end of a run is no failure here.
            let _ = tx.send(LiveTarget::all(t, q));
        }
        act(k);
        going = run.step();
        while let Ok(m) = rx.try_recv() {
            match m {
                Telemetry::Cycle(c) => {
                    for j in c.joints() {
                        seen.commanded.push((j.joint, j.commanded));
                        if j.joint == GRIPPER {
                            seen.rows.push(Row {
                                t: c.time_s,
                                commanded: j.commanded,
                                measured: j.measured,
                                stalled: j.stalled,
                            });
                        }
                    }
                }
                Telemetry::Fault(f) => seen.faults.push(f),
                s @ Telemetry::Stall(_) => seen.stalls.push(s),
                _ => {}
            }
        }
        if !going {
            break;
        }
    }
    (seen, going)
}

#[test]
fn a_gripper_closed_past_its_stop_is_held_with_bounded_effort_and_the_session_goes_on() {
    let (mut run, _sims, robot) = live_run();
    let (seen, going) = follow(&mut run, 4.5, |_| {});
    assert!(seen.faults.is_empty(), "{:?}", seen.faults);
    assert!(going, "the session goes on after the stall");
    assert_eq!(run.finished(), None);

    // Published: held once, let go once, in that order, on the gripper.
    let events: Vec<_> = seen
        .stalls
        .iter()
        .filter_map(|m| match m {
            Telemetry::Stall(e) => Some(*e),
            _ => None,
        })
        .collect();
    assert_eq!(events.len(), 2, "{events:?}");
    let (held, released) = (events[0], events[1]);
    assert!(held.held && !released.held, "{events:?}");
    assert_eq!((held.joint, held.servo_id), (GRIPPER, GRIPPER_ID));
    assert!((held.position - STOP_DEG).abs() < 0.5, "{held:?}");
    // Pushed towards closing, by the documented bound.
    assert!((held.push + PUSH_DEG).abs() < 1e-9, "{held:?}");
    // Found within a few cycles of reaching the stop (the targets reach it
    // at 0.75 s, the follower some cycles later) and let go once the
    // targets open past it (from 3.0 s).
    assert!((0.75..1.1).contains(&held.time_s), "{held:?}");
    assert!((3.0..3.3).contains(&released.time_s), "{released:?}");

    // The effort bound, from the samples alone: while held, the goal is
    // never more than STALL_PUSH (plus the tick it is rounded to) past
    // where the gripper was measured, and it does not go through the stop.
    let held_rows: Vec<&Row> = seen.rows.iter().filter(|r| r.stalled).collect();
    assert!(held_rows.len() > 300, "held about 2 s: {}", held_rows.len());
    for r in &held_rows {
        let m = r.measured.expect("a reading");
        assert!(m > STOP_DEG - 0.5, "at {:.3} s the gripper is at {m}", r.t);
        let beyond = m - r.commanded;
        assert!(
            beyond <= PUSH_DEG + TICK_DEG + 1e-9,
            "at {:.3} s the goal {} is {beyond} deg past the measured {m}",
            r.t,
            r.commanded
        );
    }
    // Every goal of every joint stays within its joint limits.
    let limits: Vec<(f64, f64)> = robot.joints().map(|j| (j.min, j.max)).collect();
    for (joint, c) in &seen.commanded {
        let (lo, hi) = limits[*joint];
        assert!((lo - 1e-9..=hi + 1e-9).contains(c), "joint {joint}: {c}");
    }
    // Let go, it follows the targets again: open at 60 by the end.
    let last = seen.rows.last().expect("rows");
    let m = last.measured.expect("a reading");
    assert!((m - 60.0).abs() < 1.0, "the gripper ends at {m}");
    assert!(!last.stalled);

    // The report counts the stall; the run stops when asked, with no fault.
    run.commands()
        .send(Command::Stop)
        .expect("the run takes commands");
    for _ in 0..400 {
        if !run.step() {
            break;
        }
    }
    let report = run.report();
    assert_eq!(report.finish, Finish::Stopped);
    assert!(report.fault.is_none());
    let g = &report.joints[GRIPPER];
    assert_eq!(g.stalls, 1, "{g:?}");
    // Held from the stall (about 0.83 s) until the targets' path opens past
    // the bound (21 deg, about 3.2 s).
    assert!((2.2..2.6).contains(&g.stalled_s), "{g:?}");
    assert_eq!(report.stalled_joints().count(), 1);
}

#[test]
fn a_held_gripper_that_overheats_still_ends_the_run() {
    let (mut run, sims, _) = live_run();
    // 1.5 s in, the gripper is held on its stop; then its motor reaches
    // its temperature limit (the simulator's `overheat` fault).
    let at = (1.5 / PERIOD) as u64;
    let (seen, going) = follow(&mut run, 3.0, |k| {
        if k == at {
            sims[0]
                .servo(GRIPPER_ID, |s| s.set_temperature(100.0, 100.0))
                .expect("the gripper's servo");
        }
    });
    assert!(
        matches!(seen.stalls.as_slice(), [Telemetry::Stall(e)] if e.held && e.time_s < 1.5),
        "held before it overheats: {:?}",
        seen.stalls
    );
    let f = run.fault().expect("a fault ends the run").clone();
    assert!(
        matches!(f.kind, FaultKind::Status { flags, .. } if flags & StatusFlags::OVERHEAT != 0),
        "{f}"
    );
    assert_eq!(f.joint.as_deref(), Some("gripper"));
    assert_eq!(seen.faults.first(), Some(&f));
    // Its reaction (a jerk-limited stop) carried out, the run is over.
    assert!(!going);
    assert_eq!(run.finished(), Some(Finish::Fault));
}
