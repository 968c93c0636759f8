//! `servobus bench` on the simulator: the JSON report of the architecture
//! page, figures that respect the wire, every bus of a robot, busy polling.
//!
//! Rates depend on the machine, so these tests check what must hold on any
//! machine: the simulator never beats the wire, every cycle is counted, the
//! distributions are ordered. The 95 % target is measured by running
//! `servobus bench` itself (see the README).

use crate::common;

use common::{num, servobus, servobus_json};

fn check_bus_figures(b: &serde_json::Value) {
    let cycles = num(b, "cycles");
    let achieved = num(b, "achieved_rate_hz");
    let wire = num(b, "wire_limited_rate_hz");
    let planned = num(b, "planned_rate_hz");
    assert!(cycles >= 1.0, "no cycle ran: {b}");
    assert!(achieved > 0.0, "{b}");
    // The simulator delivers each reply when its last byte would arrive on
    // the wire: no bus can run faster than the wire allows.
    assert!(achieved <= wire * 1.01, "faster than the wire: {b}");
    assert!(planned <= wire, "{b}");
    let e = &b["period_error_us"];
    assert!(
        num(e, "p50") <= num(e, "p99") && num(e, "p99") <= num(e, "max"),
        "{b}"
    );
    // Overruns are cycles, so never more than ran.
    assert!(num(b, "overruns") <= cycles, "{b}");
    // The pty's own floor, measured in the same run on the same bytes: it
    // cannot beat the wire either, and the ratio is the two mean rates'.
    let floor = num(b, "floor_rate_hz");
    assert!(floor > 0.0, "no floor measured on the simulator: {b}");
    assert!(floor <= wire * 1.01, "floor faster than the wire: {b}");
    assert!(
        (num(b, "floor_ratio") - achieved / floor).abs() < 1e-9,
        "{b}"
    );
}

/// The counters of one bus add up: every cycle reads every servo once, and each
/// read is a reply (with its round trip), a timeout or a garbled reply; a missed
/// reply is a timeout or a reply that could not be used.
fn check_counters(b: &serde_json::Value) {
    let count = |v: &serde_json::Value, key: &str| {
        v[key]
            .as_u64()
            .unwrap_or_else(|| panic!("{key} is a count: {v}"))
    };
    let reads = count(b, "cycles") * count(b, "servos");
    let servos = b["servo_rtt"].as_array().expect("per-servo round trips");
    let replies: u64 = servos.iter().map(|s| count(s, "replies")).sum();
    let timeouts: u64 = servos.iter().map(|s| count(s, "timeouts")).sum();
    // A reply garbled on the wire (a checksum error, e.g. when a late reply
    // collides with the next request) is neither a reply nor a timeout, and
    // a reply that came after its deadline (the host delivered it late) is
    // a late reply.
    let corrupt = count(b, "checksum_errors");
    let late = count(b, "late_replies");
    assert!(
        replies + timeouts <= reads && reads <= replies + timeouts + late + corrupt,
        "{b}"
    );
    assert_eq!(count(b, "timeouts"), timeouts, "{b}");
    let missed = count(b, "missed_replies");
    assert!(timeouts <= missed && missed <= reads, "{b}");
    count(b, "retries");
}

#[test]
fn bench_reports_the_arm_against_its_wire_limit() {
    let v = servobus_json(&["bench", "--seconds", "0.4", "--json"]);
    assert_eq!(v["robot"], "so101");
    // 6 servos at 1 Mbps: 26 + 14 + 6 x 8 = 88 bytes, 880 us a cycle.
    assert!((num(&v, "wire_limited_rate_hz") - 1_000_000.0 / 880.0).abs() < 0.01);
    check_bus_figures(&v);
    assert_eq!(num(&v, "overruns"), num(&v["buses"][0], "overruns"));
    check_counters(&v["buses"][0]);
    let count = |key: &str| v[key].as_u64().unwrap_or_else(|| panic!("{key}: {v}"));
    assert!(count("overruns") <= count("cycles"), "{v}");
    assert_eq!(count("timeouts"), v["buses"][0]["timeouts"], "{v}");
    assert_eq!(
        count("missed_replies"),
        v["buses"][0]["missed_replies"],
        "{v}"
    );
    let buses = v["buses"].as_array().expect("a list of buses");
    assert_eq!(buses.len(), 1);
    assert_eq!(buses[0]["busy_poll"], false);
    assert_eq!(buses[0]["servos"], 6);
    let servos = buses[0]["servo_rtt"]
        .as_array()
        .expect("per-servo round trips");
    assert_eq!(servos.len(), 6);
}

#[test]
fn bench_with_busy_polling_and_two_buses() {
    let v = servobus_json(&[
        "bench",
        "--robot",
        "configs/robots/hexapod-2bus.yaml",
        "--seconds",
        "0.4",
        "--busy-poll",
        "--json",
    ]);
    let buses = v["buses"].as_array().expect("a list of buses");
    assert_eq!(buses.len(), 2);
    for b in buses {
        assert_eq!(b["busy_poll"], true, "{b}");
        assert_eq!(b["servos"], 9, "{b}");
        check_bus_figures(b);
        check_counters(b);
    }
}

#[test]
fn bench_refuses_a_senseless_duration() {
    let out = servobus(&["bench", "--seconds", "0"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--seconds"), "{err}");
}
