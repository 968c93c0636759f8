//! Wheel joints through the real loop, in virtual time on the simulator: a
//! cart of one arm joint and two wheels (STS3215s, the wheels in operating
//! mode 1). A wheel's speed ramps to its target within its acceleration
//! limit and the simulated wheel turns at it; the goal speed goes out
//! sign-magnitude in a frame of its own; the live timeout and a stop ramp
//! the wheels to 0; a servo in the wrong mode is refused; the joints'
//! `servo:` settings reach the servos; a position-only robot's frames have
//! no goal speed in them.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::common;

use common::{record, robot, sim_buses};
use servobus_driver::{Bus, ManualClock, Transport, TransportError};
use servobus_protocol::registers::{addr, Series};
use servobus_runtime::config::{load_robot, JointMap, Robot, RobotOptions, RobotSource};
use servobus_runtime::{
    bus_settings, Command, Finish, Lead, LiveEvent, LiveTarget, RunError, RunOptions, VirtualRun,
};
use servobus_sim::{SimBus, SimModel, SimServo};

/// The cart's wheels' top speed and acceleration, deg/s and deg/s^2.
const TOP: f64 = 180.0;
const ACCEL: f64 = 900.0;

/// The cart, its joints' `servo:` settings given as `arm` and `wheel`.
fn cart_with(arm: &str, wheel: &str) -> Robot {
    let text = format!(
        "name: cart\nunits: deg\nrate: 200\nbuses:\n  - name: b\n    return_delay_us: 0\n    joints:\n      \
         - {{name: arm, id: 1, model: sts3215, min: -90, max: 90, max_velocity: 100, max_acceleration: 400{arm}}}\n      \
         - {{name: l, id: 2, model: sts3215, mode: wheel, max_velocity: {TOP}, max_acceleration: {ACCEL}{wheel}}}\n      \
         - {{name: r, id: 3, model: sts3215, mode: wheel, max_velocity: {TOP}, max_acceleration: {ACCEL}, inverted: true}}\n"
    );
    let source = RobotSource::Text {
        name: std::path::Path::new("<cart>"),
        text: &text,
    };
    load_robot(source, &RobotOptions::default()).expect("the cart loads")
}

fn cart() -> Robot {
    cart_with("", "")
}

/// The cart's servos on one simulated bus, at the middle of their range;
/// the wheels in operating mode `wheel_mode`.
fn cart_sim(robot: &Robot, wheel_mode: u8) -> SimBus {
    let bus = &robot.buses[0];
    let servos = bus.joints.iter().map(|j| {
        let model = SimModel::by_name(j.model.name).expect("the simulator has the model");
        let servo = SimServo::new(model, j.id)
            .with_return_delay(bus.return_delay)
            .with_position(2048);
        if j.is_wheel() {
            servo.with_byte(addr::MODE, wheel_mode)
        } else {
            servo
        }
    });
    SimBus::new(ManualClock::new(), bus.baud).with_servos(servos)
}

fn options() -> RunOptions {
    RunOptions {
        lead: Lead::None,
        approach: None,
        ..RunOptions::default()
    }
}

/// A live run of the cart on `sim`.
fn live(robot: &Robot, sim: &SimBus) -> Result<VirtualRun<SimBus>, RunError> {
    let bus = Bus::new(sim.clone(), bus_settings(&robot.buses[0]));
    VirtualRun::live(robot, vec![bus], options())
}

/// A target of `l` and `r` deg/s for the wheels at time `t`.
fn wheels(t: f64, l: f64, r: f64) -> LiveTarget {
    LiveTarget::named(
        t,
        vec![("l".into(), l.to_radians()), ("r".into(), r.to_radians())],
    )
}

/// The goal speed of servo `id` in the simulator, steps/s (decoded by the
/// register's own sign-magnitude rule), and its raw high byte.
fn goal_speed(sim: &SimBus, id: u8) -> (i32, u8) {
    let lo = sim.register(id, addr::GOAL_SPEED).expect("a servo");
    let hi = sim.register(id, addr::GOAL_SPEED + 1).expect("a servo");
    let reg = Series::Sts.map().at(addr::GOAL_SPEED).expect("goal speed");
    let v = reg
        .decode(&[lo, hi], Series::Sts.byte_order())
        .expect("decodes");
    (v, hi)
}

/// Steps/s of `deg_s` on the cart's wheel `joint`.
fn steps(robot: &Robot, joint: &str, deg_s: f64) -> f64 {
    let map = JointMap::new(robot.joint(joint).expect("a joint"), robot.units);
    map.raw_ticks(deg_s.to_radians()) - map.raw_ticks(0.0)
}

/// Asserts the commanded speeds of `joint` change by at most the wheels'
/// acceleration per cycle.
fn assert_within_accel(rows: &[f64], period: f64) {
    for w in rows.windows(2) {
        let a = (w[1] - w[0]).abs() / period;
        assert!(a <= ACCEL * (1.0 + 1e-9), "{a} deg/s^2 > {ACCEL}");
    }
}

#[test]
fn a_wheel_reaches_its_speed_within_its_acceleration_and_the_timeout_ramps_it_to_rest() {
    let robot = cart();
    let sim = cart_sim(&robot, 1);
    let mut run = live(&robot, &sim).expect("the cart starts");
    let period = run.period().as_secs_f64();
    let tx = run.targets();
    // Targets every cycle for 1.5 s, then none: the timeout (0.25 s)
    // stops the wheels.
    let rec = record(&mut run, 600, |k| {
        let t = k as f64 * period;
        if t <= 1.5 {
            tx.send(wheels(t, 90.0, -90.0)).expect("a target");
        }
    });
    let l = rec.commanded(1);
    let r = rec.commanded(2);
    assert_within_accel(&l, period);
    assert_within_accel(&r, period);
    // 90 deg/s at 900 deg/s^2 takes 0.1 s: reached well before 1.5 s.
    let at = |k: usize, v: &[f64]| v[k];
    let steady = (1.4 / period) as usize;
    assert!((at(steady, &l) - 90.0).abs() < 1e-9, "{}", at(steady, &l));
    assert!((at(steady, &r) + 90.0).abs() < 1e-9, "{}", at(steady, &r));
    // The simulated wheel turns at it (measured speed, deg/s).
    let measured: Vec<f64> = rec
        .rows
        .iter()
        .filter(|row| row.1 == 1 && (row.0 as f64) * period > 1.0 && (row.0 as f64) * period < 1.5)
        .filter_map(|row| row.4)
        .collect();
    assert!(!measured.is_empty());
    for m in &measured {
        assert!((m - 90.0).abs() < 5.0, "measured {m} deg/s");
    }
    // The stream stopped: timed out, ramped to rest, and 0 on the wire.
    assert!(rec.live.iter().any(|(e, _)| *e == LiveEvent::TimedOut));
    assert_eq!((*l.last().unwrap(), *r.last().unwrap()), (0.0, 0.0));
    assert_eq!(goal_speed(&sim, 2).0, 0);
    assert_eq!(goal_speed(&sim, 3).0, 0);
    let report = run.report();
    let peak = report.joints[1].peak_commanded_speed.expect("a wheel");
    assert!((peak - 90.0).abs() < 1e-9, "{peak}");
    let seen = report.joints[1].peak_measured_speed.expect("a wheel");
    assert!((seen - 90.0).abs() < 5.0, "{seen}");
    assert_eq!(report.joints[0].peak_commanded_speed, None);
}

#[test]
fn the_goal_speed_on_the_wire_is_sign_magnitude() {
    let robot = cart();
    let sim = cart_sim(&robot, 1);
    let mut run = live(&robot, &sim).expect("the cart starts");
    let period = run.period().as_secs_f64();
    let tx = run.targets();
    record(&mut run, 100, |k| {
        tx.send(wheels(k as f64 * period, 90.0, 45.0))
            .expect("a target");
    });
    // `l` turns forwards; `r` is inverted: its servo turns backwards, bit 15.
    let (l, l_hi) = goal_speed(&sim, 2);
    let (r, r_hi) = goal_speed(&sim, 3);
    assert_eq!(f64::from(l), steps(&robot, "l", 90.0).round());
    assert_eq!(f64::from(r), steps(&robot, "r", 45.0).round());
    assert!(r < 0 && l > 0, "{l} {r}");
    assert_eq!(l_hi & 0x80, 0);
    assert_eq!(r_hi & 0x80, 0x80);
    assert_eq!(i32::from(r_hi & 0x7F) << 8, (-r) & 0x7F00);
}

#[test]
fn stop_ramps_the_wheels_to_rest_and_the_last_goal_speed_is_zero() {
    let robot = cart();
    let sim = cart_sim(&robot, 1);
    let mut run = live(&robot, &sim).expect("the cart starts");
    let period = run.period().as_secs_f64();
    let tx = run.targets();
    let commands = run.commands();
    let stop_at = (0.5 / period) as u64;
    let rec = record(&mut run, 2000, |k| {
        let _ = tx.send(wheels(k as f64 * period, -120.0, 120.0));
        if k == stop_at {
            commands.send(Command::Stop).expect("a command");
        }
    });
    assert_eq!(run.finished(), Some(Finish::Stopped));
    let l = rec.commanded(1);
    assert_within_accel(&l, period);
    assert!(
        l.iter().any(|&v| (v + 120.0).abs() < 1e-9),
        "never at speed"
    );
    assert_eq!(*l.last().unwrap(), 0.0);
    assert_eq!(goal_speed(&sim, 2).0, 0);
    assert_eq!(goal_speed(&sim, 3).0, 0);
}

#[test]
fn a_wheel_servo_in_position_mode_is_refused_at_start() {
    let robot = cart();
    let sim = cart_sim(&robot, 0);
    let Err(e) = live(&robot, &sim) else {
        panic!("a wheel in mode 0 starts");
    };
    assert!(
        matches!(
            e,
            RunError::Mode {
                id: 2,
                found: 0,
                wanted: 1,
                ..
            }
        ),
        "{e:?}"
    );
    let text = e.to_string();
    for part in [
        "joint `l`",
        "servo 2",
        "mode 0",
        "mode 1",
        "servobus doctor --robot FILE --port PORT --fix --write-servos",
    ] {
        assert!(text.contains(part), "{text}: no `{part}`");
    }
    // Nothing was enabled.
    assert_eq!(sim.register(2, addr::TORQUE_ENABLE), Some(0));
}

#[test]
fn the_joints_servo_settings_are_written_after_the_profiles_are_released() {
    let robot = cart_with(
        ", servo: {torque_limit: 50}",
        ", servo: {acceleration: 1000}",
    );
    let sim = cart_sim(&robot, 1);
    let _run = live(&robot, &sim).expect("the cart starts");
    let word = |id, a| {
        u16::from_le_bytes([
            sim.register(id, a).expect("a servo"),
            sim.register(id, a + 1).expect("a servo"),
        ])
    };
    assert_eq!(word(1, addr::TORQUE_LIMIT), 500);
    let raw = robot.joint("l").expect("l").servo_writes()[0].raw;
    assert!(raw > 0);
    assert_eq!(
        sim.register(2, addr::ACCELERATION).map(u32::from),
        Some(raw)
    );
    // The others' ramps are released.
    assert_eq!(sim.register(1, addr::ACCELERATION), Some(0));
    assert_eq!(sim.register(3, addr::ACCELERATION), Some(0));
    assert_eq!(sim.register(2, addr::TORQUE_ENABLE), Some(1));
}

#[test]
fn eeprom_settings_the_servos_hold_otherwise_are_reported_and_never_written() {
    // P is EEPROM (a new servo holds 32); the torque limit is RAM.
    let robot = cart_with(", servo: {p: 16, torque_limit: 50}", "");
    let sim = cart_sim(&robot, 1);
    let mut run = live(&robot, &sim).expect("the cart starts");
    run.commands().send(Command::Stop).expect("the run listens");
    while run.step() {}
    let report = run.report();
    let differ = &report.buses[0].eeprom_differences;
    assert_eq!(differ.len(), 1, "{differ:?}");
    let d = &differ[0];
    assert_eq!(
        (
            d.joint.as_str(),
            d.id,
            d.setting,
            d.register,
            d.held,
            d.wanted
        ),
        ("arm", 1, "p", "p_coefficient", 32, 16)
    );
    assert_eq!(sim.register(1, 21), Some(32), "not written");
    // As the robot file asks: nothing to report.
    let robot = cart_with(", servo: {p: 32}", "");
    let sim = cart_sim(&robot, 1);
    let mut run = live(&robot, &sim).expect("the cart starts");
    run.commands().send(Command::Stop).expect("the run listens");
    while run.step() {}
    let report = run.report();
    assert!(report.buses[0].eeprom_differences.is_empty());
}

#[test]
fn a_speed_beyond_the_top_speed_is_clamped_and_counted() {
    let robot = cart();
    let sim = cart_sim(&robot, 1);
    let mut run = live(&robot, &sim).expect("the cart starts");
    let period = run.period().as_secs_f64();
    let tx = run.targets();
    let mut clamped = 0;
    let rec = record(&mut run, 200, |k| {
        clamped += tx
            .send(wheels(k as f64 * period, 400.0, -30.0))
            .expect("a target");
    });
    assert_eq!(clamped, 200);
    let l = rec.commanded(1);
    assert!(l.iter().all(|v| v.abs() <= TOP + 1e-9));
    assert!((l.last().unwrap() - TOP).abs() < 1e-9, "{l:?}");
    let live = run.report().live.expect("a live report");
    assert_eq!(live.clamped, 200);
}

/// A transport that keeps every byte written to it.
struct Recording {
    inner: SimBus,
    sent: Arc<Mutex<Vec<u8>>>,
}

impl Transport for Recording {
    type Clock = ManualClock;
    fn clock(&self) -> &ManualClock {
        self.inner.clock()
    }
    fn baud(&self) -> u32 {
        self.inner.baud()
    }
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.sent
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend_from_slice(bytes);
        self.inner.write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        self.inner.read(buf, deadline)
    }
    fn discard_input(&mut self) -> Result<(), TransportError> {
        self.inner.discard_input()
    }
}

/// The SYNC WRITE frames in `bytes`: `(address, servo IDs)`.
fn sync_writes(bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 5 < bytes.len() {
        if bytes[i] != 0xFF || bytes[i + 1] != 0xFF {
            i += 1;
            continue;
        }
        let len = usize::from(bytes[i + 3]);
        let end = i + 4 + len;
        if end > bytes.len() {
            break;
        }
        if bytes[i + 2] == 0xFE && bytes[i + 4] == 0x83 {
            let address = bytes[i + 5];
            let block = usize::from(bytes[i + 6]) + 1;
            let params = &bytes[i + 7..end - 1];
            out.push((address, params.chunks(block).map(|c| c[0]).collect()));
        }
        i = end;
    }
    out
}

/// The SYNC WRITE frames of 100 live cycles of `robot` on `sims`, a target
/// for every joint (`target`, rad) sent each cycle.
fn frames_of(robot: &Robot, sims: &[SimBus], target: Vec<f64>) -> Vec<(u8, Vec<u8>)> {
    let sent = Arc::new(Mutex::new(Vec::new()));
    let buses = sims
        .iter()
        .zip(&robot.buses)
        .map(|(s, b)| {
            let t = Recording {
                inner: s.clone(),
                sent: Arc::clone(&sent),
            };
            Bus::new(t, bus_settings(b))
        })
        .collect();
    let mut run = VirtualRun::live(robot, buses, options()).expect("the run starts");
    let tx = run.targets();
    let period = run.period().as_secs_f64();
    record(&mut run, 100, |k| {
        let _ = tx.send(LiveTarget::all(k as f64 * period, target.clone()));
    });
    let bytes = sent.lock().unwrap_or_else(|e| e.into_inner()).clone();
    sync_writes(&bytes)
}

#[test]
fn a_position_only_robot_sends_no_goal_speed_and_a_cart_sends_it_to_its_wheels_alone() {
    let so101 = robot("so101.yaml");
    let (_, sims) = sim_buses(&so101);
    let pose = vec![0.0; so101.joint_count()];
    let frames = frames_of(&so101, &sims, pose);
    assert!(frames.iter().any(|(a, _)| *a == addr::GOAL_POSITION));
    assert!(
        frames.iter().all(|(a, _)| *a != addr::GOAL_SPEED),
        "a goal speed frame on a position-only robot"
    );
    let cart = cart();
    let sim = cart_sim(&cart, 1);
    let frames = frames_of(&cart, &[sim], vec![0.1, 1.0, 1.0]);
    let goals: Vec<&Vec<u8>> = frames
        .iter()
        .filter(|(a, _)| *a == addr::GOAL_POSITION)
        .map(|(_, ids)| ids)
        .collect();
    let speeds: Vec<&Vec<u8>> = frames
        .iter()
        .filter(|(a, _)| *a == addr::GOAL_SPEED)
        .map(|(_, ids)| ids)
        .collect();
    assert!(
        goals.len() >= 100 && speeds.len() >= 100,
        "{} {}",
        goals.len(),
        speeds.len()
    );
    assert!(goals.iter().all(|ids| **ids == [1]));
    assert!(speeds.iter().all(|ids| **ids == [2, 3]));
}
