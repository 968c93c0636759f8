//! `servobus budget` on the shipped robots, with figures worked out by hand.
//!
//! At 1 Mbps a byte takes 10 us. Writing goal positions (2 bytes) to N
//! servos is one SYNC WRITE of 8 + 3N bytes; reading present positions back
//! is a SYNC READ request of 8 + N bytes and N replies of 8 bytes. Each reply
//! also waits the servo's return delay plus the link's default turnaround
//! (50 us). On the built-in simulator (no port in the robot file) each
//! round trip costs the pseudo-terminal's 60 us more and each reply 8 us.

use crate::common;

use std::path::PathBuf;

use common::{arg, edited, exited, json, num, says, servobus, servobus_fails, temp_file};

/// `servobus budget --robot ROBOT --json ARGS`, which must succeed.
fn budget_json(robot: &str, args: &[&str]) -> serde_json::Value {
    common::servobus_json(&[&["budget", "--robot", robot, "--json"], args].concat())
}

/// The SO-101 with one line of its file changed, in a file of its own.
fn so101_with(name: &str, edit: (&str, &str)) -> PathBuf {
    let text = edited("configs/robots/so101.yaml", &[edit]);
    temp_file("budget_cli", name, &text)
}

#[test]
fn so101_at_1mbps_with_return_delay_zero() {
    let v = budget_json("configs/robots/so101.yaml", &[]);
    let buses = v["buses"].as_array().expect("buses list");
    assert_eq!(buses.len(), 1);
    let b = &buses[0];
    assert_eq!(b["name"], "arm");
    assert_eq!(b["servos"], 6);
    // 26 (SYNC WRITE 8 + 6 x 3) + 14 (SYNC READ 8 + 6) + 48 (6 replies of 8).
    assert_eq!(b["bytes_per_cycle"], 88);
    assert_eq!(num(b, "wire_time_us"), 880.0);
    // + 6 turnarounds of 50 us, no return delay, no adapter latency, and
    // the simulator's pty: 60 us for the one round trip, 8 us per reply.
    assert_eq!(num(b, "cycle_time_us"), 1288.0);
    // Where they go: 880 on the wire, 6 x 50 of turnaround, 108 of the pty.
    assert_eq!(num(b, "turnaround_time_us"), 300.0);
    assert_eq!(num(b, "return_delay_time_us"), 0.0);
    assert_eq!(num(b, "latency_time_us"), 0.0);
    assert_eq!(num(b, "overhead_time_us"), 108.0);
    assert_eq!(b["link"], "simulator");
    assert!(b["measured_latency_us"].is_null());
    assert!((num(b, "max_rate_hz") - 1e6 / 1288.0).abs() < 1e-9);
    assert!((num(b, "wire_limited_rate_hz") - 1e6 / 880.0).abs() < 1e-9);
    // The robot's default rate, 200 Hz: 1288 us of every 5000 us.
    assert_eq!(num(b, "rate_hz"), 200.0);
    assert!((num(b, "utilisation") - 0.2576).abs() < 1e-12);
    assert_eq!(b["feasible"], true);
}

#[test]
fn hexapod_on_one_and_two_buses() {
    let one = budget_json("configs/robots/hexapod.yaml", &[]);
    let b = &one["buses"][0];
    // 62 (8 + 18 x 3) + 26 (8 + 18) + 144 (18 x 8) = 232 bytes = 2320 us,
    // 18 turnarounds, one round trip and 18 replies through the pty.
    assert_eq!(b["bytes_per_cycle"], 232);
    assert_eq!(num(b, "wire_time_us"), 2320.0);
    assert_eq!(
        num(b, "cycle_time_us"),
        2320.0 + 18.0 * 50.0 + 60.0 + 18.0 * 8.0
    );

    let two = budget_json("configs/robots/hexapod-2bus.yaml", &["--rate", "500"]);
    let buses = two["buses"].as_array().expect("buses");
    assert_eq!(buses.len(), 2);
    for b in buses {
        // 35 (8 + 9 x 3) + 17 (8 + 9) + 72 (9 x 8) = 124 bytes.
        assert_eq!(b["servos"], 9);
        assert_eq!(b["bytes_per_cycle"], 124);
        assert_eq!(num(b, "cycle_time_us"), 1240.0 + 9.0 * 50.0 + 60.0 + 72.0);
        assert_eq!(num(b, "rate_hz"), 500.0);
        assert!((num(b, "utilisation") - 1822e-6 * 500.0).abs() < 1e-12);
    }
}

#[test]
fn scs_servos_are_read_one_by_one() {
    let v = budget_json("configs/robots/scs-mini.yaml", &[]);
    let b = &v["buses"][0];
    // SYNC WRITE 8 + 4 x 3 = 20; four READs of 8 bytes each answered by 8:
    // four round trips through the pty, each charged its 60 + 8 us.
    assert_eq!(b["bytes_per_cycle"], 20 + 4 * 16);
    assert_eq!(num(b, "cycle_time_us"), 840.0 + 4.0 * 50.0 + 4.0 * 68.0);
    assert_eq!(num(b, "overhead_time_us"), 272.0);
}

#[test]
fn factory_return_delay_and_what_would_fit() {
    // The factory setting: 500 us.
    let edit = ("return_delay_us: 0 ", "return_delay_us: 500 ");
    let p = so101_with("factory.yaml", edit);
    let path = arg(&p);
    let out = servobus(&["budget", "--robot", path, "--json", "--rate", "300"]);
    // The rate does not fit: a problem found, and still the full figures.
    exited(&out, 1);
    let v = json(&out);
    let b = &v["buses"][0];
    // Same 88 bytes, but each of the 6 replies waits 500 + 50 us.
    assert_eq!(b["bytes_per_cycle"], 88);
    assert_eq!(num(b, "cycle_time_us"), 880.0 + 6.0 * 550.0 + 108.0);
    assert_eq!(num(b, "return_delay_time_us"), 6.0 * 500.0);
    assert_eq!(num(b, "turnaround_time_us"), 6.0 * 50.0);
    assert_eq!(b["feasible"], false);
    let first_fix = b["fixes"][0].as_str().expect("a fix");
    assert!(
        first_fix.contains("return delay (register 7) to 0"),
        "{first_fix}"
    );

    let (stdout, _) = exited(&servobus(&["budget", "--robot", path, "--rate", "300"]), 1);
    says(
        &stdout,
        &[
            "88 bytes",
            "where the 4288 us go: wire 880; turnaround 6 x 50 = 300 (a guess per reply); \
             return delay 6 x 500 = 3000; adapter latency 1 x 0 = 0; link overhead 1 x 60 \
             + 6 x 8 = 108 (the built-in simulator's pseudo-terminal)",
            "set the servos' return delay (register 7) to 0",
        ],
    );
}

#[test]
fn a_rate_no_plan_can_meet_fails() {
    let out = servobus(&[
        "budget",
        "--robot",
        "configs/robots/so101.yaml",
        "--rate",
        "5000",
    ]);
    assert!(!out.status.success());
    says(&common::stdout(&out), &["cannot run"]);
}

#[test]
fn a_bad_robot_file_is_reported_with_its_position() {
    let p = temp_file("budget_cli", "bad.yaml", "name: bad\nbuses:\n  - name: b\n    joints:\n      - {name: j, id: 300, model: sts3215, min: 0, max: 1, max_velocity: 1, max_acceleration: 1}\n");
    let stderr = servobus_fails(&["budget", "--robot", arg(&p)]);
    let want = format!(
        "{}:5:23: buses[0].joints[0].id: servo IDs go from 0 to 253",
        p.display()
    );
    says(&stderr, &[&want]);
}

/// The README's FTDI figure: with the 16 ms default latency timer, the
/// SO-101's cycle (one SYNC WRITE, one SYNC READ round trip) takes 880 us
/// on the wire + 6 turnarounds of 50 us + 16,000 us of adapter latency =
/// 17,180 us, and the budget (with no port in the file) charges the
/// simulator's pty its 108 us too: 17,288 us, 57.8 Hz at most.
#[test]
fn ftdi_default_latency_caps_the_so101_near_58_hz() {
    let edit = ("latency_us: auto ", "latency_us: 16000 ");
    let p = so101_with("ftdi.yaml", edit);
    let v = json(&servobus(&["budget", "--robot", arg(&p), "--json"]));
    let b = &v["buses"][0];
    assert_eq!(
        num(b, "cycle_time_us"),
        880.0 + 6.0 * 50.0 + 16_000.0 + 108.0
    );
    assert!((num(b, "max_rate_hz") - 1e6 / 17_288.0).abs() < 1e-9, "{b}");
    assert_eq!(b["feasible"], false, "not at the robot's 200 Hz");
}
