//! The simulated body: mounting across the seam, reversed joints, stops,
//! the hand, the truth recorder and the homing offset on a mounted servo.

use crate::common;

use std::time::Duration;

use common::*;
use servobus_io::ManualClock;
use servobus_protocol::{parse_frame, StatusFlags};
use servobus_sim::{addr, HandPath, Mount, SimBus, SimServo, Truth};

/// Ticks per degree of an STS3215 (4096 over a full turn).
const TPD: f64 = 4096.0 / 360.0;

fn mounted(id: u8, mount: Mount, angle: f64) -> SimServo {
    SimServo::sts3215(id)
        .with_return_delay(Duration::ZERO)
        .with_mount(mount, angle)
}

fn bus_of(servos: impl IntoIterator<Item = SimServo>) -> SimBus {
    SimBus::new(ManualClock::new(), 1_000_000).with_servos(servos)
}

/// Present position as a client reads it over the wire.
fn read_position(bus: &mut SimBus, id: u8) -> u16 {
    let reply = exchange(bus, &read(id, addr::PRESENT_POSITION, 2), MS);
    let (status, _) = parse_frame(&reply).expect("a status reply");
    u16::from_le_bytes([status.params()[0], status.params()[1]])
}

fn write_u16(bus: &mut SimBus, id: u8, address: u8, v: u16) {
    exchange(bus, &write(id, address, &v.to_le_bytes()), MS);
}

/// The raw tick a mounting reads at `angle`, computed here from the
/// definition (not by the simulator).
fn expected_raw(zero: f64, dir: f64, angle: f64) -> u16 {
    ((zero + dir * angle * TPD).round() as i64).rem_euclid(4096) as u16
}

#[test]
fn mounting_reads_raw_ticks_across_the_seam() {
    // The joint's zero sits 96 ticks below the seam: +20 deg is past it.
    let mut bus = bus_of([mounted(1, Mount::new(4000.0, false), -10.0)]);
    let hand = HandPath::new([(0.0, -10.0), (2.0, 20.0)]);
    bus.servo(1, |s| s.set_hand(Some(hand)));
    let mut last_angle = -10.0;
    for step in 0..=20 {
        let t = Duration::from_millis(100 * step);
        bus.clock().advance_to(t);
        let angle = bus
            .servo(1, |s| s.joint_angle())
            .flatten()
            .expect("mounted");
        assert!(
            angle >= last_angle - 1e-9,
            "the angle is continuous: {angle}"
        );
        last_angle = angle;
        let raw = read_position(&mut bus, 1);
        let want = expected_raw(4000.0, 1.0, angle);
        // The short way round the seam, by hand.
        let diff = (i32::from(raw) - i32::from(want) + 2048).rem_euclid(4096) - 2048;
        assert!(diff.abs() <= 1, "at {angle:.2} deg read {raw}, want {want}");
    }
    assert!((last_angle - 20.0).abs() < 0.01, "{last_angle}");
    let raw = read_position(&mut bus, 1);
    assert!(raw < 200, "past the seam the raw tick is small: {raw}");
}

#[test]
fn a_reversed_joint_reads_falling_ticks() {
    let mut bus = bus_of([mounted(1, Mount::new(100.0, true), 0.0)]);
    assert_eq!(read_position(&mut bus, 1), 100);
    bus.servo(1, |s| {
        s.set_hand(Some(HandPath::new([(0.0, 0.0), (1.0, 10.0)])))
    });
    wait(&bus, Duration::from_secs(1));
    // 100 - 10 * 4096 / 360 = -13.8 -> 4082 after the seam.
    assert_eq!(read_position(&mut bus, 1), expected_raw(100.0, -1.0, 10.0));
    assert_eq!(expected_raw(100.0, -1.0, 10.0), 4082);
    // A goal of higher ticks turns the joint negative: tick 4093 is
    // (100 - (4093 - 4096)) / (4096 / 360) = 9.05 deg.
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[1]), MS);
    write_u16(&mut bus, 1, addr::GOAL_POSITION, 4093);
    wait(&bus, Duration::from_secs(1));
    let angle = bus.servo(1, |s| s.joint_angle()).flatten().unwrap();
    assert!((angle - 103.0 / TPD).abs() < 0.1, "{angle}");
}

#[test]
fn stops_hold_the_joint_and_load_the_servo() {
    let mount = Mount::new(2048.0, false).with_stops(-30.0, 30.0);
    let mut bus = bus_of([mounted(1, mount, 0.0)]);
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[1]), MS);
    // Goal at +60 deg, beyond the stop at +30.
    write_u16(
        &mut bus,
        1,
        addr::GOAL_POSITION,
        (2048.0 + 60.0 * TPD) as u16,
    );
    wait(&bus, Duration::from_millis(300));
    let (angle, load) = bus
        .servo(1, |s| (s.joint_angle(), s.present_load()))
        .unwrap();
    assert!((angle.unwrap() - 30.0).abs() < 1e-6, "{angle:?}");
    assert!(load >= 900, "the servo strains against the stop: {load}");
    let raw = read_position(&mut bus, 1);
    assert_eq!(raw, expected_raw(2048.0, 1.0, 30.0));
    // Straining at the torque limit past the protection time overloads it.
    wait(&bus, Duration::from_secs(3));
    let status = bus.servo(1, |s| s.status()).unwrap();
    assert!(status.0 & StatusFlags::OVERLOAD != 0, "{status:?}");
    // The hand cannot push a torque-off joint through a stop either.
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[0]), MS);
    let t = now(&bus).as_secs_f64();
    bus.servo(1, |s| {
        s.set_hand(Some(HandPath::new([(t, 30.0), (t + 1.0, -50.0)])))
    });
    wait(&bus, Duration::from_secs(1));
    let angle = bus.servo(1, |s| s.joint_angle()).flatten().unwrap();
    assert!((angle + 30.0).abs() < 1e-6, "{angle}");
}

#[test]
fn the_hand_moves_torque_off_joints_and_a_torque_on_joint_resists() {
    let m = Mount::new(2048.0, false);
    let mut bus = bus_of([mounted(1, m, 0.0), mounted(2, m, 0.0), mounted(3, m, 5.0)]);
    let path = HandPath::new([(0.5, 0.0), (2.0, 40.0), (3.0, 40.0)]);
    bus.servo(1, |s| s.set_hand(Some(path.clone())));
    bus.servo(2, |s| s.set_hand(Some(path.clone())));
    // Servo 2 holds its position with torque on; servo 3 has no hand.
    exchange(&mut bus, &write(2, addr::TORQUE_ENABLE, &[1]), MS);
    for ms in (600..=3000).step_by(100) {
        bus.clock().advance_to(Duration::from_millis(ms));
        let t = ms as f64 / 1000.0;
        let want = path.angle_at(t).unwrap();
        let a1 = bus.servo(1, |s| s.joint_angle()).flatten().unwrap();
        assert!(
            (a1 - want).abs() < 0.01,
            "torque-off follows: {a1} vs {want}"
        );
        let a2 = bus.servo(2, |s| s.joint_angle()).flatten().unwrap();
        assert!(a2.abs() < 2.5, "torque-on resists: {a2} at {t}");
        let a3 = bus.servo(3, |s| s.joint_angle()).flatten().unwrap();
        assert_eq!(a3, 5.0, "an unnamed joint stays where it is");
    }
    let load = bus.servo(2, |s| s.present_load()).unwrap();
    assert!(load.abs() >= 200, "the push shows in the load: {load}");
    // The hand lets go after its last keyframe: joint 1 stays at 40 deg.
    wait(&bus, Duration::from_secs(1));
    let a1 = bus.servo(1, |s| s.joint_angle()).flatten().unwrap();
    assert!((a1 - 40.0).abs() < 0.01, "{a1}");
    // And the resisting servo returns to its goal.
    let a2 = bus.servo(2, |s| s.joint_angle()).flatten().unwrap();
    assert!(a2.abs() < 0.2, "{a2}");
}

#[test]
fn truth_is_recorded_on_a_grid_while_the_bus_runs() {
    let truth = Truth::new(vec!["a".into(), "b".into()], Duration::from_millis(10));
    let m = Mount::new(1000.0, true);
    let bus = bus_of([
        mounted(1, m, 0.0)
            .with_hand(HandPath::new([(0.0, 0.0), (1.0, 30.0)]))
            .with_truth(&truth, 0),
        mounted(2, m, -5.0).with_truth(&truth, 1),
    ]);
    assert_eq!(truth.csv_header(), "time_s,a,b");
    wait(&bus, Duration::from_secs(2));
    bus.settle();
    let rows = truth.rows();
    assert_eq!(rows.len(), 201, "0..=2 s every 10 ms");
    for w in rows.windows(2) {
        assert!((w[1].time_s - w[0].time_s - 0.01).abs() < 1e-9);
    }
    let at = |t: f64| rows.iter().find(|r| (r.time_s - t).abs() < 1e-9).unwrap();
    assert!((at(0.5).angles_deg[0] - 15.0).abs() < 0.01);
    assert!((at(1.5).angles_deg[0] - 30.0).abs() < 0.01);
    assert_eq!(at(1.5).angles_deg[1], -5.0);
}

#[test]
fn homing_offset_moves_the_seam_for_present_and_goal() {
    // Zero at raw 4000, stops at +-90 deg: the range crosses the raw seam.
    let mount = Mount::new(4000.0, false).with_stops(-90.0, 90.0);
    let mut bus = bus_of([mounted(1, mount, 0.0)]);
    assert_eq!(read_position(&mut bus, 1), 4000);
    // Present = actual - offset: an offset of 4000 - 2047 = 1953 makes the
    // joint's zero read 2047, half a turn away from the seam.
    write_u16(&mut bus, 1, addr::OFFSET, 1953);
    assert_eq!(read_position(&mut bus, 1), 2047);
    // Goals are taken in the same shifted frame: +300 ticks crosses the raw
    // seam (raw 4300 = 204) but not the shifted one.
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[1]), MS);
    write_u16(&mut bus, 1, addr::GOAL_POSITION, 2347);
    wait(&bus, Duration::from_secs(1));
    assert!(read_position(&mut bus, 1).abs_diff(2347) <= 1);
    let angle = bus.servo(1, |s| s.joint_angle()).flatten().unwrap();
    assert!((angle - 300.0 / TPD).abs() < 0.1, "{angle}");
    let raw = bus.servo(1, |s| s.raw_position()).unwrap();
    assert!((203..=205).contains(&raw), "{raw}");
    // A negative offset (sign-magnitude, bit 11): -100 reads actual + 100.
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[0]), MS);
    write_u16(&mut bus, 1, addr::OFFSET, 0x0800 | 100);
    assert_eq!(i32::from(read_position(&mut bus, 1)), raw + 100);
    // Without the offset the same joint cannot cross the raw seam: a goal
    // just below it (raw 4050 = +4.4 deg) sends the servo the long way
    // round, up into the upper stop.
    write_u16(&mut bus, 1, addr::OFFSET, 0);
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[1]), MS);
    write_u16(&mut bus, 1, addr::GOAL_POSITION, 4050);
    wait(&bus, Duration::from_secs(3));
    let angle = bus.servo(1, |s| s.joint_angle()).flatten().unwrap();
    assert!(
        (angle - 90.0).abs() < 1e-6,
        "ends on the upper stop: {angle}"
    );
}
