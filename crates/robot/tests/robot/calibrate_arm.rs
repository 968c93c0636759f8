//! Calibration in virtual time on simulated servos fitted at arbitrary
//! angles: a scripted hand moves the joints (torque off) while the same
//! procedure `servobus calibrate` runs watches; then the arm plays a motion
//! and the physical joint angles are compared with the commanded ones.
//!
//! The servos' positions are set directly from a physical angle through a
//! mounting (sensor tick at the joint's zero, direction), and two servos
//! hold a homing offset that puts their joint's range across the 4095 -> 0
//! seam of the present position.

use crate::calib_play;
use crate::common;

use std::path::PathBuf;
use std::time::Duration;

use calib_play::Played;
use servobus_driver::{Bus, Clock, ManualClock};
use servobus_protocol::registers::sign_magnitude;
use servobus_robot::calibrate::{
    calibrate, prepare_servos, store_in_servos, write_homing, LiveJoint, Operator, Step, Store,
    StoreEnd,
};
use servobus_runtime::config::{save_calibration, Calibration, JointMap, Robot};
use servobus_runtime::{bus_settings, Finish};
use servobus_sim::{addr, SimBus, SimServo};

/// How a servo is fitted: its sensor tick at the joint's zero, whether
/// rising ticks turn the joint positive, and the homing offset it holds.
#[derive(Clone, Copy)]
struct Mount {
    zero: f64,
    dir: f64,
    offset: i32,
    stops: (f64, f64),
}

const DEG_PER_TICK: f64 = 360.0 / 4096.0;

/// The SO-101's six joints, fitted badly: shoulder_lift and elbow_flex
/// cross the seam of the present position, three joints are reversed.
fn mounts() -> Vec<Mount> {
    let m = |zero, dir, offset, lo, hi| Mount {
        zero,
        dir,
        offset,
        stops: (lo, hi),
    };
    vec![
        m(2600.0, 1.0, 0, -120.0, 120.0),
        m(1400.0, -1.0, 1500, -105.0, 105.0),
        m(2900.0, 1.0, -700, -95.0, 95.0),
        m(1200.0, -1.0, 0, -100.0, 100.0),
        m(2048.0, 1.0, 0, -165.0, 165.0),
        m(1500.0, -1.0, 0, -5.0, 105.0),
    ]
}

fn offset_of(s: &SimServo) -> i32 {
    let raw = u16::from_le_bytes([s.register(addr::OFFSET), s.register(addr::OFFSET + 1)]);
    sign_magnitude(u32::from(raw), 11)
}

/// An offset as the servo stores it, written out by hand: bit 11 is the
/// sign, the 11 bits below it the size.
fn sign_magnitude_raw(v: i32) -> u16 {
    let mag = v.unsigned_abs() as u16;
    if v < 0 {
        mag | 1 << 11
    } else {
        mag
    }
}

/// The physical angle of a servo's joint, degrees, from its sensor.
fn truth(sim: &SimBus, id: u8, m: Mount) -> f64 {
    let sensor = sim
        .servo(id, |s| s.shaft_position() + f64::from(offset_of(s)))
        .expect("servo");
    m.dir * (sensor - m.zero) * DEG_PER_TICK
}

/// Asserts that servo `id` (of the joint `name`) has its EEPROM lock closed.
fn assert_locked(sim: &SimBus, id: u8, name: &str) {
    assert_eq!(sim.register(id, addr::LOCK), Some(1), "{name}");
}

/// Puts a joint at physical angle `deg`, as a hand turning the horn.
fn place(sim: &SimBus, id: u8, m: Mount, deg: f64) {
    let sensor = (m.zero + m.dir * deg / DEG_PER_TICK).round() as i32;
    sim.servo(id, |s| s.move_joint(sensor - offset_of(s)));
}

fn arm(robot: &Robot) -> (Vec<Bus<SimBus>>, SimBus) {
    let bus = &robot.buses[0];
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), bus.baud).with_servos(
        bus.joints.iter().zip(mounts()).map(|(j, m)| {
            // The offset saved in EEPROM, as set-up software leaves it.
            let [lo, hi] = sign_magnitude_raw(m.offset).to_le_bytes();
            SimServo::sts3215(j.id)
                .with_return_delay(bus.return_delay)
                .with_position(0)
                .with_byte(addr::OFFSET, lo)
                .with_byte(addr::OFFSET + 1, hi)
        }),
    );
    (vec![Bus::new(sim.clone(), bus_settings(bus))], sim)
}

/// A hand following keyframes of physical angles (linear between them),
/// one pose per keyframe, times from the start of the procedure.
struct Hand {
    sim: SimBus,
    ids: Vec<u8>,
    keys: Vec<(f64, Vec<f64>)>,
    steps: Vec<Step>,
    /// Times at which the person presses Enter (none: never).
    enter_at: Vec<f64>,
    now: f64,
}

impl Hand {
    /// The scripted hand on `sim`'s joints `ids`, pressing Enter at `enter_at`.
    fn new(sim: &SimBus, ids: Vec<u8>, enter_at: Vec<f64>) -> Hand {
        Hand {
            sim: sim.clone(),
            ids,
            keys: script(),
            steps: Vec::new(),
            enter_at,
            now: 0.0,
        }
    }

    fn pose_at(&self, t: f64) -> Vec<f64> {
        let last = self.keys.last().expect("keys");
        if t >= last.0 {
            return last.1.clone();
        }
        let k = self
            .keys
            .iter()
            .position(|(at, _)| *at > t)
            .unwrap_or(0)
            .max(1);
        let (t0, a) = &self.keys[k - 1];
        let (t1, b) = &self.keys[k];
        let u = ((t - t0) / (t1 - t0)).clamp(0.0, 1.0);
        a.iter().zip(b).map(|(x, y)| x + (y - x) * u).collect()
    }
}

impl Operator for Hand {
    fn step(&mut self, step: Step) {
        self.steps.push(step);
    }
    fn watch(&mut self, at: Duration, _joints: &[LiveJoint]) {
        self.now = at.as_secs_f64();
        let pose = self.pose_at(self.now);
        for ((&id, m), deg) in self.ids.iter().zip(mounts()).zip(pose) {
            place(&self.sim, id, m, deg);
        }
    }
    fn confirmed(&mut self) -> bool {
        match self.enter_at.first() {
            Some(&t) if self.now >= t => {
                self.enter_at.remove(0);
                true
            }
            _ => false,
        }
    }
}

/// Somewhere, then the calibration pose (all zeros) held, then each joint
/// to its positive stop, its negative stop and back, then held.
fn script() -> Vec<(f64, Vec<f64>)> {
    let start = vec![30.0, -60.0, 70.0, 20.0, -40.0, 50.0];
    let zero = vec![0.0; 6];
    let mut keys = vec![(0.0, start), (1.0, zero.clone()), (4.0, zero.clone())];
    let mut t = 4.0;
    for (j, m) in mounts().iter().enumerate() {
        let mut at = |deg: f64, dt: f64, keys: &mut Vec<(f64, Vec<f64>)>| {
            t += dt;
            let mut p = zero.clone();
            p[j] = deg;
            keys.push((t, p));
        };
        // A person presses each joint against its stop for a moment.
        at(m.stops.1, 1.0, &mut keys);
        at(m.stops.1, 0.2, &mut keys);
        at(m.stops.0, 1.5, &mut keys);
        at(m.stops.0, 0.2, &mut keys);
        at(0.0, 1.0, &mut keys);
    }
    keys
}

fn calibrated_arm() -> (Robot, Vec<Bus<SimBus>>, SimBus, PathBuf) {
    let (robot, buses, sim, path, _) = measured_arm();
    (robot, buses, sim, path)
}

/// The arm calibrated by the hand, and the calibration as measured.
fn measured_arm() -> (Robot, Vec<Bus<SimBus>>, SimBus, PathBuf, Calibration) {
    let design = common::robot("so101.yaml");
    let (mut buses, sim) = arm(&design);
    let ids: Vec<u8> = design.joints().map(|j| j.id).collect();
    for (&id, m) in ids.iter().zip(mounts()) {
        place(&sim, id, m, 30.0f64.clamp(m.stops.0, m.stops.1));
    }
    let mut hand = Hand::new(&sim, ids, Vec::new());
    let options = calib_play::procedure(true);
    let cal = calibrate(&design, &mut buses, &mut hand, &options).expect("calibrates");
    assert_eq!(
        hand.steps,
        [Step::TorqueOff, Step::HoldPose, Step::Sweep, Step::Done]
    );
    // It ended once the hand had finished and held still for 2 s.
    let end = buses[0].clock().now().as_secs_f64();
    let last = script().last().expect("keys").0;
    assert!(
        end > last + 1.5 && end < last + 2.5,
        "ended at {end} s, hand done at {last} s"
    );
    let path = common::temp_path("calibrate_arm", "so101.calibration.yaml");
    save_calibration(&cal, &path).expect("saves");
    let robot = common::calibrated("so101.yaml", &path);
    (robot, buses, sim, path, cal)
}

#[test]
fn the_hand_calibrates_a_badly_fitted_arm_and_angles_become_physical() {
    let (robot, mut buses, sim, _) = calibrated_arm();
    let joints: Vec<_> = robot.joints().cloned().collect();
    let cals: Vec<_> = joints
        .iter()
        .map(|j| j.calibration.clone().expect("calibrated"))
        .collect();
    // Directions found from the first way each joint was moved.
    let dirs: Vec<i8> = cals.iter().map(|c| c.direction).collect();
    assert_eq!(dirs, [1, -1, 1, -1, 1, -1]);
    // The two joints fitted across the seam were measured across it.
    let crossing: Vec<bool> = cals.iter().map(|c| c.crosses_seam()).collect();
    assert_eq!(crossing, [false, true, true, false, false, false]);
    // Limits: the measured range less the margin, inside the design's.
    // elbow_flex: stops at +-95, design +-97: the stops less 3 deg decide.
    let el = &joints[2];
    assert!(
        (el.min + 92.0).abs() < 0.1 && (el.max - 92.0).abs() < 0.1,
        "{} {}",
        el.min,
        el.max
    );
    // shoulder_lift: stops at +-105: the design's +-100 decide.
    assert_eq!((joints[1].min, joints[1].max), (-100.0, 100.0));
    // Before playing, the crossing joints are put in a centred frame; then
    // every reading maps to the physical angle.
    prepare_servos(&robot, &mut buses).expect("servos match");
    for (j, m) in joints.iter().zip(mounts()) {
        let map = JointMap::new(j, robot.units);
        for deg in [
            j.min,
            0.5 * (j.min + j.max),
            j.max,
            0.0f64.clamp(j.min, j.max),
        ] {
            place(&sim, j.id, m, deg);
            let tick = sim.present_position(j.id).expect("servo");
            let read = map.from_ticks(tick).to_degrees();
            assert!(
                (read - deg).abs() < 0.1,
                "{}: {deg} deg read as {read}",
                j.name
            );
        }
        place(&sim, j.id, m, 0.0f64.clamp(j.min, j.max));
    }
    // The crossing joints were given their centred offset for the session
    // (with the lock closed), the others kept theirs; a power cycle brings
    // back what the EEPROM holds.
    let held: Vec<i32> = joints
        .iter()
        .map(|j| sim.servo(j.id, |s| offset_of(s)).expect("servo"))
        .collect();
    let fitted: Vec<i32> = mounts().iter().map(|m| m.offset).collect();
    for (i, (h, f)) in held.iter().zip(&fitted).enumerate() {
        assert_eq!(h != f, crossing[i], "joint {i}: offset {h}, fitted {f}");
        assert_eq!(sim.register(joints[i].id, addr::LOCK), Some(1));
    }
    sim.power_cycle();
    let after: Vec<i32> = joints
        .iter()
        .map(|j| sim.servo(j.id, |s| offset_of(s)).expect("servo"))
        .collect();
    assert_eq!(after, fitted, "nothing persisted without --write-servos");
}

/// Plays arm-wave on the arm; the truth from the servos' sensors.
fn play_wave(
    robot: &Robot,
    cal: Option<&PathBuf>,
    buses: Vec<Bus<SimBus>>,
    sim: &SimBus,
) -> Played {
    let ids: Vec<u8> = robot.joints().map(|j| j.id).collect();
    calib_play::play(
        &common::config("motions/arm-wave.yaml"),
        &common::config("robots/so101.yaml"),
        robot,
        cal.map(|p| p.as_path()),
        buses,
        || {
            ids.iter()
                .zip(mounts())
                .map(|(&id, m)| truth(sim, id, m))
                .collect()
        },
    )
}

#[test]
fn the_calibrated_arm_plays_where_it_is_told_and_the_uncalibrated_one_misses() {
    let (robot, mut buses, sim, cal) = calibrated_arm();
    prepare_servos(&robot, &mut buses).expect("servos match");
    let played = play_wave(&robot, Some(&cal), buses, &sim);
    println!(
        "calibrated: worst miss at a keyframe {:.3} deg",
        played.worst
    );
    assert_eq!(played.finish, Some(Finish::Completed));
    assert_eq!(played.reached, 9, "every keyframe reached");
    assert!(
        played.worst < 1.0,
        "calibrated arm misses by {:.2} deg",
        played.worst
    );

    // The same arm, the same motion, without the calibration.
    let design = common::robot("so101.yaml");
    let (buses, sim) = arm(&design);
    for (j, m) in design.joints().zip(mounts()) {
        place(&sim, j.id, m, 0.0);
    }
    // Read through the design's mapping, the joints are tens of degrees
    // from where they physically are...
    let misread = design
        .joints()
        .zip(mounts())
        .map(|(j, m)| {
            let tick = sim.present_position(j.id).expect("servo");
            let read = JointMap::new(j, design.units).from_ticks(tick).to_degrees();
            (read - truth(&sim, j.id, m)).abs()
        })
        .fold(0.0, f64::max);
    assert!(
        misread > 30.0,
        "uncalibrated readings off by only {misread:.1} deg"
    );
    // ...so the motion either stops on a fault before it plays, or misses.
    let played = play_wave(&design, None, buses, &sim);
    calib_play::assert_uncalibrated_fails(&played, misread, 0);
}

#[test]
fn write_servos_stores_centring_offsets_and_plays_the_same() {
    let (robot, mut buses, sim, _, mut cal) = measured_arm();
    for (joint, jc) in robot.joints().zip(cal.joints.iter_mut()) {
        *jc = write_homing(&mut buses[0], joint, jc).expect("EEPROM written");
    }
    for (joint, m) in robot.joints().zip(mounts()) {
        // The offset that brings the middle of the stops to tick 2048:
        // present = sensor - offset, so offset = sensor middle - 2048,
        // taken round the turn into -2047..=2047.
        let sensor = |deg: f64| (m.zero + m.dir * deg / DEG_PER_TICK).round();
        let middle = 0.5 * (sensor(m.stops.0) + sensor(m.stops.1));
        let mut expect = (middle - 2048.0).rem_euclid(4096.0);
        if expect > 2048.0 {
            expect -= 4096.0;
        }
        let raw = sim
            .servo(joint.id, |s| {
                u16::from_le_bytes([s.register(addr::OFFSET), s.register(addr::OFFSET + 1)])
            })
            .expect("servo");
        // Sign-magnitude: bit 11 is the sign, the 11 bits below the size.
        let magnitude = f64::from(raw & 0x7ff);
        let value = if raw & 0x800 != 0 {
            -magnitude
        } else {
            magnitude
        };
        assert_eq!(
            raw & !0xfff,
            0,
            "{}: nothing above bit 11 in {raw:#x}",
            joint.name
        );
        assert!(
            (value - expect).abs() <= 1.0,
            "{}: offset {value}, expected {expect}",
            joint.name
        );
        // Present_Position reads through it, as a real servo does.
        place(&sim, joint.id, m, 0.0f64.clamp(m.stops.0, m.stops.1));
        let sensor_now = sim
            .servo(joint.id, |s| s.shaft_position() + f64::from(offset_of(s)))
            .expect("servo");
        let present = sim.present_position(joint.id).expect("servo");
        assert_eq!(
            f64::from(present),
            (sensor_now - value).rem_euclid(4096.0).round(),
            "{}",
            joint.name
        );
        // The lock is closed again, and the offset survives a power cycle.
        assert_locked(&sim, joint.id, &joint.name);
    }
    sim.power_cycle();
    for joint in robot.joints() {
        let cal_offset = cal
            .joints
            .iter()
            .find(|c| c.name == joint.name)
            .expect("joint")
            .homing_offset;
        let kept = sim.servo(joint.id, |s| offset_of(s)).expect("servo");
        assert_eq!(kept, cal_offset, "{}: offset kept in EEPROM", joint.name);
    }
    // No range crosses the seam any more; nothing is written before playing.
    assert!(cal.joints.iter().all(|c| !c.crosses_seam()));
    let path = common::temp_path("calibrate_arm", "so101-written.calibration.yaml");
    save_calibration(&cal, &path).expect("saves");
    let robot = common::calibrated("so101.yaml", &path);
    prepare_servos(&robot, &mut buses).expect("servos match");
    for joint in robot.joints() {
        assert_eq!(sim.register(joint.id, addr::LOCK), Some(1));
    }
    let played = play_wave(&robot, Some(&path), buses, &sim);
    println!(
        "written offsets: worst miss at a keyframe {:.3} deg",
        played.worst
    );
    assert_eq!(played.finish, Some(Finish::Completed));
    assert!(played.worst < 1.0, "misses by {:.2} deg", played.worst);
}

#[test]
fn a_person_pressing_enter_ends_each_step_instead_of_stillness() {
    let design = common::robot("so101.yaml");
    let (mut buses, sim) = arm(&design);
    let ids: Vec<u8> = design.joints().map(|j| j.id).collect();
    let last = script().last().expect("keys").0;
    // Enter once the pose is held (the hand holds it from 1 s to 4 s), and
    // again 10 s after the sweep is over.
    let mut hand = Hand::new(&sim, ids, vec![3.0, last + 10.0]);
    for (&id, m) in hand.ids.iter().zip(mounts()) {
        place(&sim, id, m, 30.0f64.clamp(m.stops.0, m.stops.1));
    }
    let options = calib_play::procedure(false);
    let cal = calibrate(&design, &mut buses, &mut hand, &options).expect("calibrates");
    // Without Enter, stillness would have ended the sweep 2 s after the hand.
    let end = buses[0].clock().now().as_secs_f64();
    assert!((end - (last + 10.0)).abs() < 0.1, "ended at {end} s");
    let dirs: Vec<i8> = cal.joints.iter().map(|c| c.direction).collect();
    assert_eq!(dirs, [1, -1, 1, -1, 1, -1]);
}

#[test]
fn a_store_that_meets_a_silent_servo_says_what_it_wrote_and_keeps_the_frames() {
    let (robot, mut buses, sim, _, measured) = measured_arm();
    let before: Vec<(i32, Option<u8>)> = robot
        .joints()
        .map(|j| {
            let offset = sim.servo(j.id, |s| offset_of(s)).expect("servo");
            (offset, sim.register(j.id, addr::MIN_ANGLE_LIMIT))
        })
        .collect();
    // The third servo stops answering before its turn comes.
    let third = robot.joints().nth(2).expect("a third joint").clone();
    sim.set_faults(servobus_sim::Faults::default().vanish(third.id));
    let mut told = Vec::new();
    let stored = store_in_servos(
        &robot,
        &mut buses,
        measured.clone(),
        Store::Centred,
        |joint, _| told.push(joint.name.clone()),
    );
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    assert_eq!(stored.written, names[..2]);
    assert_eq!(told, names[..2]);
    assert_eq!(stored.not_written, names[2..]);
    match &stored.ended {
        Some(StoreEnd::Failed(e)) => {
            assert_eq!((e.joint.as_str(), e.id), (third.name.as_str(), third.id));
        }
        other => panic!("ended {other:?}"),
    }
    // The joints written are in their new frame; the others as measured.
    for (i, (joint, jc)) in robot.joints().zip(&stored.calibration.joints).enumerate() {
        let kept = sim.servo(joint.id, |s| offset_of(s)).expect("servo");
        if i < 2 {
            assert_eq!(kept, jc.homing_offset, "{}: the frame written", joint.name);
        } else {
            assert_eq!(jc, &measured.joints[i], "{}: as measured", joint.name);
            assert_eq!(kept, before[i].0, "{}: untouched", joint.name);
            assert_eq!(
                sim.register(joint.id, addr::MIN_ANGLE_LIMIT),
                before[i].1,
                "{}: untouched",
                joint.name
            );
        }
        assert_locked(&sim, joint.id, &joint.name);
    }
}
