//! An object in the hand: a gripper closing on it stops at its surface plus
//! the squeeze its torque makes, and reads load and current as a servo
//! straining against something does.

use std::time::Duration;

use servobus_protocol::StatusFlags;
use servobus_sim::body::{HandObject, DEFAULT_STIFFNESS};
use servobus_sim::{addr, HandPath, Mount, SimServo};

/// Ticks per degree of an STS3215 (4096 over a full turn).
const TPD: f64 = 4096.0 / 360.0;
/// The object's surface, degrees.
const AT: f64 = 25.0;

/// A gripper at 0 deg (zero tick 2048, rising ticks positive) with a ball
/// at [`AT`] of `stiffness`, its torque on, overload protection not
/// releasing it (so that long holds can be watched).
fn gripper(stiffness: f64) -> SimServo {
    let ball = HandObject::new(AT, stiffness).expect("a valid object");
    let mut s = SimServo::sts3215(1)
        .with_byte(addr::UNLOADING_CONDITION, 0)
        .with_mount(Mount::new(2048.0, false), 0.0)
        .with_hand(HandPath::new([]).with_object(ball));
    s.write(addr::TORQUE_ENABLE, &[1]);
    s
}

fn goal_deg(s: &mut SimServo, deg: f64) {
    let ticks = (2048.0 + deg * TPD).round() as u16;
    s.write(addr::GOAL_POSITION, &ticks.to_le_bytes());
}

fn run(s: &mut SimServo, seconds: f64) {
    let t = s.time() + Duration::from_secs_f64(seconds);
    s.advance_to(t);
}

fn angle(s: &SimServo) -> f64 {
    s.joint_angle().expect("mounted")
}

/// Present current (register 69, magnitude in 6.5 mA units).
fn current(s: &SimServo) -> u16 {
    s.read_u16(addr::PRESENT_CURRENT) & 0x7fff
}

#[test]
fn a_gripper_closing_past_the_object_squeezes_it_at_its_torque_limit() {
    let mut s = gripper(DEFAULT_STIFFNESS);
    // Free motion first: the current of a joint that moves unhindered.
    goal_deg(&mut s, 10.0);
    run(&mut s, 1.0);
    assert!((angle(&s) - 10.0).abs() < 0.2, "free: {}", angle(&s));
    let free_current = current(&s);
    let start_temp = s.register(addr::PRESENT_TEMPERATURE);

    goal_deg(&mut s, 60.0);
    run(&mut s, 1.5);
    let squeeze = angle(&s) - AT;
    // Full torque (limit 1000) squeezes a 20 %/deg object by 5 deg.
    assert!((squeeze - 5.0).abs() < 0.1, "squeeze {squeeze}");
    let load = s.present_load();
    assert!(
        (950..=1000).contains(&load),
        "load towards the goal: {load}"
    );
    assert!(
        current(&s) > free_current + 300,
        "{} vs {free_current}",
        current(&s)
    );
    // Held against the object, the servo stalls (overload after the 2 s
    // protection time) and warms up.
    run(&mut s, 8.5);
    assert!((angle(&s) - AT - 5.0).abs() < 0.1, "still {}", angle(&s));
    assert!(
        s.status().contains(StatusFlags::OVERLOAD),
        "{:?}",
        s.status()
    );
    let temp = s.register(addr::PRESENT_TEMPERATURE);
    assert!(temp > start_temp + 1, "{temp} after {start_temp}");
}

#[test]
fn a_gripper_closing_downwards_reads_a_negative_load() {
    let ball = HandObject::new(-20.0, DEFAULT_STIFFNESS).expect("a valid object");
    let mut s = SimServo::sts3215(1)
        .with_mount(Mount::new(2048.0, false), 0.0)
        .with_hand(HandPath::new([]).with_object(ball));
    s.write(addr::TORQUE_ENABLE, &[1]);
    goal_deg(&mut s, -60.0);
    run(&mut s, 1.5);
    let squeeze = -20.0 - angle(&s);
    assert!((squeeze - 5.0).abs() < 0.1, "squeeze {squeeze}");
    assert!(s.present_load() <= -950, "{}", s.present_load());
}

#[test]
fn a_lower_torque_limit_squeezes_less_and_loads_less_in_proportion() {
    let mut s = gripper(DEFAULT_STIFFNESS);
    goal_deg(&mut s, 60.0);
    run(&mut s, 1.5);
    let (full_squeeze, full_load) = (angle(&s) - AT, s.present_load());
    let full_current = current(&s);
    s.write(addr::TORQUE_LIMIT, &300u16.to_le_bytes());
    run(&mut s, 1.5);
    let (squeeze, load) = (angle(&s) - AT, s.present_load());
    assert!(
        (squeeze / full_squeeze - 0.3).abs() < 0.02,
        "{squeeze} of {full_squeeze}"
    );
    assert!(
        (f64::from(load) / f64::from(full_load) - 0.3).abs() < 0.02,
        "{load} of {full_load}"
    );
    assert!(current(&s) < full_current / 2, "{}", current(&s));
    // And back up: the object gives way again.
    s.write(addr::TORQUE_LIMIT, &1000u16.to_le_bytes());
    run(&mut s, 1.5);
    assert!((angle(&s) - AT - full_squeeze).abs() < 0.1, "{}", angle(&s));
}

#[test]
fn commanding_the_gripper_back_opens_it_freely() {
    let mut s = gripper(DEFAULT_STIFFNESS);
    goal_deg(&mut s, 60.0);
    run(&mut s, 1.5);
    assert!(angle(&s) > AT + 4.0, "{}", angle(&s));
    goal_deg(&mut s, 5.0);
    run(&mut s, 1.0);
    assert!(
        (angle(&s) - 5.0).abs() < 0.2,
        "follows its goal: {}",
        angle(&s)
    );
    assert!(s.present_load().abs() < 50, "no load: {}", s.present_load());
    // It closes again onto the object, and up to it without one.
    goal_deg(&mut s, 20.0);
    run(&mut s, 1.0);
    assert!((angle(&s) - 20.0).abs() < 0.2, "{}", angle(&s));
}

#[test]
fn a_stiffer_object_squeezes_less() {
    let squeeze = |stiffness: f64| {
        let mut s = gripper(stiffness);
        goal_deg(&mut s, 60.0);
        run(&mut s, 2.0);
        (angle(&s) - AT, s.present_load())
    };
    let (soft, soft_load) = squeeze(20.0);
    let (hard, hard_load) = squeeze(200.0);
    assert!((hard - 0.5).abs() < 0.05, "{hard}");
    assert!(hard < soft / 5.0, "{hard} vs {soft}");
    assert!(
        hard_load >= 950 && soft_load >= 950,
        "{hard_load} {soft_load}"
    );
}

#[test]
fn with_torque_off_a_hand_cannot_push_the_joint_through_the_object() {
    let ball = HandObject::new(AT, DEFAULT_STIFFNESS).expect("a valid object");
    let mut s = SimServo::sts3215(1)
        .with_mount(Mount::new(2048.0, false), 0.0)
        .with_hand(HandPath::new([(0.0, 0.0), (1.0, 60.0), (2.0, 10.0)]).with_object(ball));
    run(&mut s, 0.4);
    assert!(angle(&s) < AT, "{}", angle(&s));
    run(&mut s, 0.6);
    assert!(
        (angle(&s) - AT).abs() < 1e-9,
        "at the surface: {}",
        angle(&s)
    );
    run(&mut s, 1.0);
    assert!((angle(&s) - 10.0).abs() < 1e-9, "back out: {}", angle(&s));
}

#[test]
fn a_joint_starting_above_the_object_has_it_below() {
    let ball = HandObject::new(AT, DEFAULT_STIFFNESS).expect("a valid object");
    let mut s = SimServo::sts3215(1)
        .with_mount(Mount::new(2048.0, false), 40.0)
        .with_hand(HandPath::new([]).with_object(ball));
    s.write(addr::TORQUE_ENABLE, &[1]);
    // Up is free; down stops at the object.
    goal_deg(&mut s, 80.0);
    run(&mut s, 1.0);
    assert!((angle(&s) - 80.0).abs() < 0.2, "{}", angle(&s));
    goal_deg(&mut s, 0.0);
    run(&mut s, 2.0);
    assert!((AT - angle(&s) - 5.0).abs() < 0.1, "{}", angle(&s));
}

#[test]
fn the_same_run_gives_the_same_squeeze() {
    let once = || {
        let mut s = gripper(50.0);
        goal_deg(&mut s, 45.0);
        run(&mut s, 0.7);
        (angle(&s).to_bits(), s.present_load(), current(&s))
    };
    assert_eq!(once(), once());
}
