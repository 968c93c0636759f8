//! A grasp that holds (issue 39), in virtual time: the simulated SO-101's
//! hand puts an object between the gripper's jaws at 25 deg (a hand file's
//! `object:`), and a live target tells the gripper to grasp with 30 % of
//! its torque. It closes at its closing speed, stops within 2 deg of the
//! object, and holds it for 60 s of simulated time with its temperature
//! under the warning level; a position target releases it and the torque
//! limit is put back. The same gripper written a raw position goal past the
//! object (as a program writing Goal_Position does) strains at full torque
//! and heats until the simulator's overheat protection lets go. A held
//! grasp that draws near its protection current is eased, and one whose
//! effort draws past it lets go, with no fault.

use std::path::PathBuf;
use std::time::Duration;

use servobus_driver::Clock;
use servobus_protocol::StatusFlags;
use servobus_robot::sim::{new_truth, Hand, SimRobot};
use servobus_runtime::config::{JointMap, Robot};
use servobus_runtime::grasp::{GraspEvent, DEFAULT_MAX_TEMPERATURE_C, WARNING_BELOW_LIMIT_C};
use servobus_runtime::{Lead, LiveTarget, RunOptions, Telemetry, VirtualRun};
use servobus_sim::addr;

use crate::common;

const PERIOD: f64 = 0.005;
const GRIPPER: usize = 5;
const GRIPPER_ID: u8 = 6;
/// Where the object meets the jaws, deg.
const CONTACT_DEG: f64 = 25.0;
/// The effort asked, percent.
const EFFORT: f64 = 30.0;
/// The pose the arm starts in and the other joints' targets keep, deg.
const POSE: [f64; 6] = [0.0, 0.0, 0.0, 0.0, 0.0, 40.0];

/// A hand file with the object in the gripper's way, for test `name`.
fn hand_file(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("servobus-grasp-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("hand.yaml");
    std::fs::write(
        &file,
        format!("object: {{joint: gripper, at: {CONTACT_DEG}, stiffness: 20}}\n"),
    )
    .expect("writes the hand file");
    file
}

fn arm_with_object(robot: &Robot, name: &str) -> (SimRobot, servobus_sim::Truth) {
    let hand = Hand::load(&hand_file(name), robot).expect("the hand file loads");
    let truth = new_truth(robot);
    let sim = SimRobot::builder(robot)
        .hand(hand)
        .truth(&truth)
        .pose(&POSE)
        .build()
        .expect("simulates");
    (sim, truth)
}

/// A live run of `sim`'s arm.
fn live_run(robot: &Robot, sim: &SimRobot) -> VirtualRun<servobus_sim::SimBus> {
    let options = RunOptions {
        lead: Lead::None,
        approach: None,
        telemetry_capacity: 1 << 12,
        ..RunOptions::default()
    };
    VirtualRun::live(robot, sim.driver_buses(), options).expect("a live run")
}

/// What a run published about the grasp.
#[derive(Default)]
struct Seen {
    grasps: Vec<servobus_runtime::grasp::GraspReport>,
    stalls: Vec<servobus_runtime::StallEvent>,
    faults: Vec<servobus_runtime::Fault>,
}

impl Seen {
    /// Takes in what `rx` holds.
    fn take(&mut self, rx: &crossbeam_channel::Receiver<Telemetry>) {
        while let Ok(m) = rx.try_recv() {
            match m {
                Telemetry::Grasp(g) => self.grasps.push(g),
                Telemetry::Stall(s) => self.stalls.push(s),
                Telemetry::Fault(f) => self.faults.push(f),
                _ => {}
            }
        }
    }
}

/// The other joints' targets at `t`, rad: where they are.
fn arm_target(t: f64) -> LiveTarget {
    let names = [
        "shoulder_pan",
        "shoulder_lift",
        "elbow_flex",
        "wrist_flex",
        "wrist_roll",
    ];
    LiveTarget::named(
        t,
        names
            .iter()
            .zip(POSE)
            .map(|(n, a)| ((*n).to_owned(), a.to_radians()))
            .collect(),
    )
}

#[test]
fn a_grasp_stops_at_the_object_and_holds_it_a_minute_without_heating() {
    let robot = common::robot("so101.yaml");
    let (sim, truth) = arm_with_object(&robot, "hold");
    let mut run = live_run(&robot, &sim);
    let (tx, rx) = (run.targets(), run.telemetry());
    let mut seen = Seen::default();
    let seconds = 62.0;
    let release_at = 61.0;
    for _ in 0..(seconds / PERIOD) as u64 {
        let k = run.cycle();
        let t = k as f64 * PERIOD;
        if k.is_multiple_of(6) {
            let target = if t >= release_at {
                LiveTarget::named(t, vec![("gripper".into(), 60f64.to_radians())])
            } else if k == 60 {
                arm_target(t).with_grasps(vec![("gripper".into(), EFFORT)])
            } else {
                arm_target(t)
            };
            tx.send(target).expect("a good target");
        }
        let going = run.step();
        seen.take(&rx);
        assert!(going, "the run goes on: {:?}", seen.faults);
    }
    let Seen {
        grasps,
        stalls,
        faults,
    } = seen;
    assert!(faults.is_empty(), "{faults:?}");
    // Closing, then released: never lowered or let go.
    let events: Vec<GraspEvent> = grasps.iter().map(|g| g.event).collect();
    assert_eq!(
        events,
        vec![
            GraspEvent::Closing { effort_pct: EFFORT },
            GraspEvent::Released
        ],
        "{grasps:?}"
    );
    assert!(grasps.iter().all(|g| g.joint == GRIPPER));
    // Contact: the stall that held it, near the object.
    let contact = stalls.first().expect("the gripper met the object");
    assert!(contact.held && contact.joint == GRIPPER, "{contact:?}");
    assert!((contact.position - CONTACT_DEG).abs() < 2.0, "{contact:?}");

    // The truth: closed onto the object, and held there within 2 deg of
    // where it met it, from a second after the grasp to the release.
    sim.settle();
    let rows = truth.rows();
    let held: Vec<f64> = rows
        .iter()
        .filter(|r| r.time_s >= 1.5 && r.time_s < release_at)
        .map(|r| r.angles_deg[GRIPPER])
        .collect();
    assert!(held.len() > 5000, "{}", held.len());
    let (lo, hi) = held
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    println!("held between {lo:.2} and {hi:.2} deg (object at {CONTACT_DEG})");
    assert!(
        lo > CONTACT_DEG - 2.0 && hi <= CONTACT_DEG + 0.5,
        "{lo} {hi}"
    );

    // Cool: under the warning level all the minute, and the servo was at
    // 30 % effort: its torque limit then was 300.
    let warm_from = DEFAULT_MAX_TEMPERATURE_C - WARNING_BELOW_LIMIT_C;
    let temperature = |sim: &SimRobot| {
        sim.buses()[0]
            .register(GRIPPER_ID, addr::PRESENT_TEMPERATURE)
            .map(f64::from)
            .expect("the gripper's servo")
    };
    let temp = temperature(&sim);
    println!(
        "temperature after a minute's hold and the release: {temp} C (warning from {warm_from})"
    );
    assert!(temp < warm_from, "{temp}");
    // Released: the torque limit back to what the servo held, and open.
    let byte = |a: u8| sim.buses()[0].register(GRIPPER_ID, a).expect("the servo");
    let limit = u16::from_le_bytes([byte(48), byte(49)]);
    assert_eq!(limit, 1000);
    let last = rows.last().expect("rows").angles_deg[GRIPPER];
    assert!(last > 50.0, "opened: {last}");
}

#[test]
fn a_raw_goal_past_the_object_heats_the_gripper_until_its_protection_lets_go() {
    let robot = common::robot("so101.yaml");
    let (sim, truth) = arm_with_object(&robot, "raw");
    let mut bus = sim.driver_buses().remove(0);
    let joint = robot.joints().nth(GRIPPER).expect("a gripper");
    let map = JointMap::new(joint, robot.units);
    let regs = bus.settings().series.map();
    let (goal, torque) = (
        regs.get("goal_position").expect("a goal register"),
        regs.get("torque_enable").expect("a torque register"),
    );
    bus.write_register(GRIPPER_ID, goal, map.to_ticks(0.0))
        .expect("the servo answers");
    bus.write_register(GRIPPER_ID, torque, 1)
        .expect("the servo answers");
    let start = bus.clock().now();
    let status = regs.get("status").expect("a status register");
    let mut tripped = None;
    for s in 1..=12_000u64 {
        bus.clock()
            .sleep_until(start + Duration::from_millis(100 * s));
        let (flags, _) = bus
            .read_register(GRIPPER_ID, status)
            .expect("the servo answers");
        let flags = StatusFlags(u8::try_from(flags).unwrap_or(0));
        if flags.contains(StatusFlags::OVERHEAT) || flags.contains(StatusFlags::OVERLOAD) {
            tripped = Some((s, flags));
            break;
        }
    }
    let (after, flags) = tripped.expect("the protection trips within 20 minutes");
    let after = after as f64 / 10.0;
    println!("a raw goal past the object: the protection ({flags:?}) trips after {after} s");
    let _ = truth;
}

#[test]
fn a_warm_grasp_is_eased_and_a_hot_one_lets_go_before_the_servo_protects_itself() {
    let robot = common::robot("so101.yaml");
    let heat = |sim: &SimRobot, c: f64| {
        sim.buses()[0].servo(GRIPPER_ID, |s| s.set_temperature(c, c));
    };
    // Warm from 2 s (above the warning level), hot from 4 s (within the
    // let-go margin of its limit, still under the limit itself).
    let (seen, sim) = grasp_for(&robot, "warm", EFFORT, 6.0, |k, sim| {
        if k == 400 {
            heat(sim, DEFAULT_MAX_TEMPERATURE_C - WARNING_BELOW_LIMIT_C + 2.0);
        }
        if k == 800 {
            heat(sim, DEFAULT_MAX_TEMPERATURE_C - 2.0);
        }
    });
    let (grasps, faults) = (seen.grasps, seen.faults);
    assert!(faults.is_empty(), "{faults:?}");
    let lowered: Vec<f64> = grasps
        .iter()
        .filter_map(|g| match g.event {
            GraspEvent::Lowered { effort_pct, .. } => Some(effort_pct),
            _ => None,
        })
        .collect();
    println!("lowered to {lowered:?}; {grasps:?}");
    assert!(!lowered.is_empty(), "{grasps:?}");
    assert!(lowered.windows(2).all(|w| w[1] < w[0]), "{lowered:?}");
    assert!(lowered[0] < EFFORT, "{lowered:?}");
    let let_go = grasps
        .iter()
        .find(|g| matches!(g.event, GraspEvent::LetGo { .. }))
        .expect("it let go");
    assert!(let_go.time_s >= 4.0 && let_go.time_s < 4.3, "{let_go:?}");
    // Backed off: no load on the servo since (the jaws off the object).
    let byte = |a: u8| sim.buses()[0].register(GRIPPER_ID, a).expect("the servo");
    let load = u16::from_le_bytes([byte(60), byte(61)]) & 0x3ff;
    assert!(load < 50, "still pushing: {load}");
}

/// A motion that grasps the object at 1 s and lets it go at 4 s.
const GRASPING_MOTION: &str = "\
robot: so101
units: deg
keyframes:
  - pose: {shoulder_pan: 0, shoulder_lift: 0, elbow_flex: 0, wrist_flex: 0, wrist_roll: 0, gripper: 40}
  - {at: 1.0, pose: {shoulder_pan: 10}, grasp: {gripper: {effort: 30}}}
  - {at: 3.0, pose: {shoulder_pan: -10}}
  - {at: 4.0, pose: {gripper: 60}}
";

#[test]
fn a_motions_keyframe_grasps_the_object_holds_it_through_the_next_move_and_lets_it_go() {
    let robot = common::robot("so101.yaml");
    let dir = std::env::temp_dir().join(format!("servobus-grasp-motion-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("grasp.yaml");
    std::fs::write(&file, GRASPING_MOTION).expect("writes the motion");
    let (motion, _) = servobus_robot::config::load_motion(&file, None).expect("the motion loads");
    // The grasping keyframe closes the gripper towards its min (0 deg).
    assert_eq!(motion.keyframes[1].positions[GRIPPER], 0.0);
    let trajectory = servobus_robot::config::plan_motion(&motion, &robot).expect("plans");
    let grasps = servobus_robot::motion_grasps(&motion, &trajectory);
    assert_eq!(grasps.len(), 2, "{grasps:?}");
    assert_eq!((grasps[0].effort, grasps[1].effort), (Some(0.3), None));
    assert!(
        grasps[0].at_s < 0.01 && (grasps[1].at_s - 3.0).abs() < 1e-9,
        "{grasps:?}"
    );

    let (sim, truth) = arm_with_object(&robot, "motion");
    let options = RunOptions {
        lead: Lead::None,
        approach: None,
        telemetry_capacity: 1 << 14,
        grasps,
        ..RunOptions::default()
    };
    let mut run =
        VirtualRun::new(&robot, trajectory, sim.driver_buses(), options).expect("a played run");
    let rx = run.telemetry();
    let mut seen = Seen::default();
    while run.step() {
        seen.take(&rx);
    }
    seen.take(&rx);
    assert!(seen.faults.is_empty(), "{:?}", seen.faults);
    assert_eq!(run.finished(), Some(servobus_runtime::Finish::Completed));
    let events: Vec<GraspEvent> = seen.grasps.iter().map(|g| g.event).collect();
    assert_eq!(
        events,
        vec![
            GraspEvent::Closing { effort_pct: EFFORT },
            GraspEvent::Released
        ]
    );
    let contact = seen.stalls.first().expect("the gripper met the object");
    assert!((contact.position - CONTACT_DEG).abs() < 2.0, "{contact:?}");
    // Held on the object while the arm moved (1.5 to 2.9 s), then open.
    sim.settle();
    let rows = truth.rows();
    for r in rows.iter().filter(|r| r.time_s > 1.5 && r.time_s < 2.9) {
        let g = r.angles_deg[GRIPPER];
        assert!(
            g > CONTACT_DEG - 2.0 && g <= CONTACT_DEG + 0.5,
            "{} s: {g}",
            r.time_s
        );
    }
    let last = rows.last().expect("rows").angles_deg[GRIPPER];
    assert!(last > 55.0, "opened: {last}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The SO-101 with its gripper's protection current at `ma` (`servo:
/// protection_current`), for test `name`.
fn arm_protected_at(ma: f64, name: &str) -> Robot {
    let text = std::fs::read_to_string(common::repo("configs/robots/so101.yaml")).expect("so101");
    let text = text.replace(
        "        offset: -20          # servo angle at \"closed\", from its midpoint\n",
        &format!("        offset: -20\n        servo: {{protection_current: {ma}}}\n"),
    );
    assert!(
        text.contains("protection_current"),
        "the gripper's entry moved"
    );
    let dir = std::env::temp_dir().join(format!("servobus-grasp-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("so101.yaml");
    std::fs::write(&file, text).expect("writes the robot file");
    servobus_robot::config::load_robot(&file, &servobus_robot::config::RobotOptions::default())
        .expect("the robot file loads")
}

/// Grasps the object with `effort` % on `robot` for `seconds` (from 0.3 s;
/// `each` called before every cycle `k` with the simulator): what was
/// seen, and the simulator.
fn grasp_for(
    robot: &Robot,
    name: &str,
    effort: f64,
    seconds: f64,
    mut each: impl FnMut(u64, &SimRobot),
) -> (Seen, SimRobot) {
    let (sim, _truth) = arm_with_object(robot, name);
    let mut run = live_run(robot, &sim);
    let (tx, rx) = (run.targets(), run.telemetry());
    let mut seen = Seen::default();
    for _ in 0..(seconds / PERIOD) as u64 {
        let k = run.cycle();
        let t = k as f64 * PERIOD;
        if k.is_multiple_of(6) {
            let target = if k == 60 {
                arm_target(t).with_grasps(vec![("gripper".into(), effort)])
            } else {
                arm_target(t)
            };
            tx.send(target).expect("a good target");
        }
        each(k, &sim);
        let going = run.step();
        seen.take(&rx);
        assert!(going, "the run goes on: {:?}", seen.faults);
    }
    (seen, sim)
}

#[test]
fn a_grasp_drawing_much_current_is_eased_and_one_at_its_protection_current_lets_go() {
    use servobus_runtime::grasp::GraspCause;
    // Held at 30 %, the simulated gripper draws about 650 mA: over 80 % of
    // a 780 mA protection current, under 95 % of it.
    let (seen, _sim) = grasp_for(
        &arm_protected_at(780.0, "eased"),
        "current-eased",
        EFFORT,
        4.0,
        |_, _| {},
    );
    assert!(seen.faults.is_empty(), "{:?}", seen.faults);
    let eased: Vec<(f64, Option<f64>)> = seen
        .grasps
        .iter()
        .filter_map(|g| match g.event {
            GraspEvent::Lowered {
                effort_pct,
                current_ma,
                cause: GraspCause::Current,
                ..
            } => Some((effort_pct, current_ma)),
            _ => None,
        })
        .collect();
    println!("eased {eased:?}; {:?}", seen.grasps);
    assert!(!eased.is_empty(), "{:?}", seen.grasps);
    assert!(eased[0].0 < EFFORT, "{eased:?}");
    let ma = eased[0].1.expect("the current read");
    assert!((0.8 * 780.0..0.95 * 780.0).contains(&ma), "{eased:?}");
    assert!(
        !seen
            .grasps
            .iter()
            .any(|g| matches!(g.event, GraspEvent::LetGo { .. })),
        "{:?}",
        seen.grasps
    );

    // At 60 % against a 600 mA protection current it lets go, reported,
    // before the servo's own protection ends anything.
    let (seen, sim) = grasp_for(
        &arm_protected_at(600.0, "let-go"),
        "current-let-go",
        60.0,
        4.0,
        |_, _| {},
    );
    assert!(seen.faults.is_empty(), "{:?}", seen.faults);
    let let_go = seen
        .grasps
        .iter()
        .find_map(|g| match g.event {
            GraspEvent::LetGo {
                current_ma, cause, ..
            } => Some((current_ma, cause)),
            _ => None,
        })
        .expect("it let go");
    println!("let go {let_go:?}; {:?}", seen.grasps);
    assert_eq!(let_go.1, GraspCause::Current, "{let_go:?}");
    assert!(
        let_go.0.expect("the current read") >= 0.95 * 600.0,
        "{let_go:?}"
    );
    let byte = |a: u8| sim.buses()[0].register(GRIPPER_ID, a).expect("the servo");
    let load = u16::from_le_bytes([byte(60), byte(61)]) & 0x3ff;
    assert!(load < 50, "still pushing: {load}");
}
