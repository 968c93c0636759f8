//! The joint: motion profile, lag, dead zone, torque, load, protection flags.

use crate::common;

use std::time::Duration;

use common::*;
use servobus_io::ManualClock;
use servobus_protocol::StatusFlags;
use servobus_sim::{addr, SimBus, SimServo};

fn arm(start: i32) -> SimBus {
    SimBus::new(ManualClock::new(), 1_000_000).with_servo(
        SimServo::sts3215(1)
            .with_return_delay(Duration::ZERO)
            .with_position(start),
    )
}

fn go(bus: &mut SimBus, goal: u16, speed: u16, accel: u8) {
    exchange(bus, &write(1, addr::ACCELERATION, &[accel]), MS);
    exchange(bus, &write(1, addr::GOAL_SPEED, &speed.to_le_bytes()), MS);
    exchange(bus, &write(1, addr::TORQUE_ENABLE, &[1]), MS);
    exchange(bus, &write(1, addr::GOAL_POSITION, &goal.to_le_bytes()), MS);
}

#[test]
fn torque_on_without_a_goal_holds_where_the_joint_is() {
    let mut bus = arm(1234);
    assert_eq!(bus.servo(1, |s| s.goal_position()), Some(1234));
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[1]), MS);
    wait(&bus, Duration::from_secs(1));
    assert_eq!(bus.present_position(1), Some(1234));
    assert_eq!(bus.register(1, addr::MOVING), Some(0));
}

#[test]
fn trapezoid_profile_cruises_at_goal_speed_and_arrives() {
    // 2000 ticks at 1000 ticks/s with 5000 ticks/s^2: 0.2 s up, 1.8 s cruise,
    // 0.2 s down: 2.2 s, then the lag settles.
    let mut bus = arm(1000);
    go(&mut bus, 3000, 1000, 50);
    let t0 = now(&bus);
    let mut samples = Vec::new();
    while now(&bus) < t0 + Duration::from_millis(2600) {
        wait(&bus, Duration::from_millis(10));
        let s = bus.snapshot(1).unwrap();
        samples.push((
            (now(&bus) - t0).as_secs_f64(),
            s.present_speed(),
            s.present_position(),
            s.is_moving(),
        ));
    }
    let speed_at = |t: f64| samples.iter().find(|s| s.0 >= t).unwrap().1;
    // The shaft trails the profile by the 10 ms lag: a (t - lag) = 450.
    assert!(
        (430..=520).contains(&speed_at(0.1)),
        "accelerating: {}",
        speed_at(0.1)
    );
    assert!(
        (990..=1010).contains(&speed_at(1.0)),
        "cruising: {}",
        speed_at(1.0)
    );
    assert!(
        samples.iter().all(|s| s.1 <= 1010),
        "never above the goal speed"
    );
    let last = samples.last().unwrap();
    assert!(
        (last.2 - 3000).abs() <= 1,
        "arrived within the dead zone: {}",
        last.2
    );
    assert!(!last.3, "no longer moving");
    // Arrival (first sample within 2 ticks) near 2.2 s plus the lag.
    let arrival = samples.iter().find(|s| (s.2 - 3000).abs() <= 2).unwrap().0;
    assert!((2.15..2.35).contains(&arrival), "arrived at {arrival} s");
}

#[test]
fn goal_speed_zero_means_the_maximum_speed() {
    let mut bus = arm(0);
    go(&mut bus, 4000, 0, 0);
    wait(&bus, Duration::from_millis(500));
    let v = bus.servo(1, |s| s.present_speed()).unwrap();
    assert!((3300..=3400).contains(&v), "{v}");
}

#[test]
fn homing_offset_shifts_present_and_goal() {
    let mut bus = arm(2000);
    exchange(&mut bus, &write(1, addr::OFFSET, &100u16.to_le_bytes()), MS);
    assert_eq!(bus.present_position(1), Some(1900));
    go(&mut bus, 1500, 0, 0);
    wait(&bus, Duration::from_secs(1));
    assert!((bus.present_position(1).unwrap() - 1500).abs() <= 1);
    let shaft = bus.servo(1, |s| s.shaft_position() + 100.0).unwrap();
    assert!(
        (shaft - 1600.0).abs() <= 1.0,
        "the shaft sits at goal + offset: {shaft}"
    );
    // A negative offset (sign-magnitude bit 11): present = actual + 100.
    exchange(
        &mut bus,
        &write(1, addr::OFFSET, &(0x0800u16 | 100).to_le_bytes()),
        MS,
    );
    assert!((bus.present_position(1).unwrap() - 1700).abs() <= 1);
}

#[test]
fn torque_off_joint_stays_put_or_sags_under_load() {
    let bus = arm(2000);
    wait(&bus, Duration::from_secs(2));
    assert_eq!(bus.present_position(1), Some(2000));
    bus.servo(1, |s| s.set_external_load(0.5));
    wait(&bus, Duration::from_millis(500));
    let p = bus.present_position(1).unwrap();
    assert!(p < 1950, "sagged to {p}");
    // The goal follows the sagging shaft while torque is off.
    assert_eq!(bus.servo(1, |s| s.goal_position()), Some(p));
}

#[test]
fn under_load_the_servo_holds_with_an_error_and_reports_load_and_current() {
    let mut bus = arm(2000);
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[1]), MS);
    bus.servo(1, |s| s.set_external_load(0.4));
    wait(&bus, Duration::from_secs(1));
    let s = bus.snapshot(1).unwrap();
    let sag = 2000 - s.present_position();
    assert!((5..=40).contains(&sag), "holds with a small error: {sag}");
    assert!(
        (350..=450).contains(&s.present_load()),
        "load {}",
        s.present_load()
    );
    let current = s.read_u16(addr::PRESENT_CURRENT);
    assert!(current > 100, "current {current}");
    assert!(
        s.register(addr::PRESENT_VOLTAGE) < 120,
        "the supply sags a little"
    );
    assert!(s.status().is_ok());
}

#[test]
fn a_blocked_joint_overloads_after_the_protection_time_and_releases_torque() {
    let mut bus = arm(1000);
    bus.servo(1, |s| s.set_blocked(true));
    go(&mut bus, 3000, 0, 0);
    wait(&bus, Duration::from_millis(500));
    assert_eq!(bus.present_position(1), Some(1000));
    assert!(bus.servo(1, |s| s.status().is_ok()).unwrap());
    assert_eq!(bus.servo(1, |s| s.present_load()), Some(1000));
    // Protection time 200 x 10 ms = 2 s.
    wait(&bus, Duration::from_secs(2));
    let got = exchange(&mut bus, &ping(1), MS);
    assert_eq!(got, status(1, StatusFlags::OVERLOAD, &[]));
    assert_eq!(
        bus.servo(1, |s| s.present_load()),
        Some(0),
        "torque released"
    );
    // Unblocked and re-enabled: it clears and moves.
    bus.servo(1, |s| s.set_blocked(false));
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[1]), MS);
    assert_eq!(exchange(&mut bus, &ping(1), MS), status(1, 0, &[]));
    wait(&bus, Duration::from_secs(1));
    assert!((bus.present_position(1).unwrap() - 3000).abs() <= 1);
}

#[test]
fn overheat_is_flagged_at_the_temperature_limit_and_clears_when_cool() {
    let mut bus = arm(1000);
    bus.servo(1, |s| s.set_temperature(71.0, 25.0));
    wait(&bus, Duration::from_millis(10));
    assert_eq!(
        exchange(&mut bus, &ping(1), MS),
        status(1, StatusFlags::OVERHEAT, &[])
    );
    assert_eq!(
        exchange(&mut bus, &read(1, addr::PRESENT_TEMPERATURE, 1), MS),
        status(1, StatusFlags::OVERHEAT, &[71])
    );
    wait(&bus, Duration::from_secs(120));
    assert_eq!(exchange(&mut bus, &ping(1), MS), status(1, 0, &[]));
}

#[test]
fn low_supply_voltage_raises_the_voltage_flag() {
    let mut bus = arm(1000);
    bus.servo(1, |s| s.set_supply_voltage(Some(35)));
    assert_eq!(
        exchange(&mut bus, &ping(1), MS),
        status(1, StatusFlags::VOLTAGE, &[])
    );
}

#[test]
fn the_dynamics_are_deterministic() {
    let run = || {
        let mut bus = arm(500);
        go(&mut bus, 3500, 2000, 30);
        let mut trace = Vec::new();
        for _ in 0..300 {
            wait(&bus, Duration::from_millis(7));
            trace.push(exchange(&mut bus, &read(1, addr::PRESENT_POSITION, 4), MS));
        }
        trace
    };
    assert_eq!(run(), run());
}
