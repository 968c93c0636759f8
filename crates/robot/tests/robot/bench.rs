//! A bus measured on the simulator in virtual time: every servo answers
//! every cycle, no cycle beats the wire, and a servo that is not there is
//! named.

use std::time::Duration;

use servobus_driver::{MissingReason, PATIENT_TRIES};
use servobus_robot::bench::{measure, BenchError};
use servobus_robot::sim::virtual_buses;
use servobus_robot::Robot;

#[test]
fn the_arm_s_bus_runs_full_cycles_with_every_servo_answering() {
    let robot = Robot::open("so101").expect("the built-in arm");
    let config = robot.config();
    let mut buses = virtual_buses(config).expect("simulated buses");
    let bench = measure(&mut buses[0], &config.buses[0], Duration::from_millis(200))
        .expect("the bus is measured");
    assert_eq!(bench.name, "arm");
    assert_eq!(bench.servos, 6);
    assert!(bench.cycles > 20, "{} cycles", bench.cycles);
    assert_eq!(
        (bench.timeouts, bench.missed_replies, bench.checksum_errors),
        (0, 0, 0)
    );
    assert!(bench.achieved_rate_hz > 0.0);
    // No cycle is faster than the bytes on the wire allow.
    assert!(
        bench.achieved_rate_hz <= bench.wire_limited_rate_hz,
        "{} Hz over the wire's {} Hz",
        bench.achieved_rate_hz,
        bench.wire_limited_rate_hz
    );
    let ids: Vec<u8> = bench.servo_rtt.iter().map(|s| s.id).collect();
    assert_eq!(ids, [1, 2, 3, 4, 5, 6]);
    assert!(bench.servo_rtt.iter().all(|s| s.replies >= bench.cycles));
}

#[test]
fn a_servo_that_is_not_on_the_bus_is_named() {
    let robot = Robot::open("so101").expect("the built-in arm");
    let mut buses = virtual_buses(robot.config()).expect("simulated buses");
    // The robot file lists a seventh servo the simulated bus does not have.
    let mut bus = robot.config().buses[0].clone();
    let mut extra = bus.joints[0].clone();
    extra.id = 42;
    extra.name = "extra".into();
    bus.joints.push(extra);
    match measure(&mut buses[0], &bus, Duration::from_millis(50)) {
        Err(BenchError::Missing {
            bus,
            id,
            reason,
            tries,
        }) => {
            assert_eq!((bus.as_str(), id), ("arm", 42));
            assert_eq!(reason, MissingReason::NoReply);
            assert_eq!(tries, PATIENT_TRIES);
        }
        other => panic!("expected servo 42 missing, got {other:?}"),
    }
}
