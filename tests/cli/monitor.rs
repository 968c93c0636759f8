//! `servobus monitor` on the simulator: one SYNC READ per refresh, a
//! missing servo shown as missing while the others update, the flags by
//! name, the motor current beside the load (none on SCS servos), torque off
//! with one frame, the view drawn, the JSON lines, and the rows of
//! `play --monitor` built from a run's telemetry.

use crate::common;

use std::time::Duration;

use ratatui::backend::TestBackend;
use ratatui::Terminal;
use servobus::monitor::{self, view, Frame, Poller, TelemetryRows, Watched};
use servobus_driver::{Bus, Clock};
use servobus_protocol::registers::addr;
use servobus_runtime::config::{load_motion, load_robot, plan_motion, Robot, RobotOptions};
use servobus_runtime::{RunOptions, Telemetry, VirtualRun};
use servobus_sim::{Faults, SimBus};

use common::virtual_bus;

const PERIOD: Duration = Duration::from_millis(50);

fn robot(file: &str) -> Robot {
    load_robot(
        &common::repo(&format!("configs/robots/{file}")),
        &RobotOptions::default(),
    )
    .expect("robot")
}

/// Polls `n` times, at the next multiples of [`PERIOD`] of virtual time.
fn poll(poller: &mut Poller, bus: &mut Bus<SimBus>, n: u32) -> Frame {
    for _ in 0..n {
        let k = bus.clock().now().as_nanos().div_ceil(PERIOD.as_nanos());
        bus.clock()
            .advance_to(PERIOD * u32::try_from(k).expect("few periods"));
        poller.poll(bus).expect("poll");
    }
    poller.frame(bus.clock(), None)
}

fn row(frame: &Frame, id: u8) -> &monitor::Row {
    frame.servos.iter().find(|r| r.id == id).expect("row")
}

#[test]
fn a_vanished_servo_is_missing_while_the_others_update_with_one_sync_read_each() {
    let arm = robot("so101.yaml");
    let (sim, mut bus) = virtual_bus(&arm, "overheat=3,vanish=5".parse().expect("faults"));
    let mut poller = Poller::new(Watched::of_bus(&arm.buses[0], arm.units));
    // Servo 1 turns towards tick 2548, so its position changes between reads.
    bus.write(1, addr::TORQUE_ENABLE, &[1]).expect("torque");
    bus.write(1, addr::GOAL_POSITION, &2548u16.to_le_bytes())
        .expect("goal");
    let first = poll(&mut poller, &mut bus, 1);
    let requests = sim.stats().requests;
    let frame = poll(&mut poller, &mut bus, 20);
    assert_eq!(
        sim.stats().requests - requests,
        20,
        "one SYNC READ per refresh"
    );

    let five = row(&frame, 5);
    assert!(!five.present);
    assert_eq!(five.missing.as_deref(), Some("no reply"));
    assert_eq!(
        (five.replies, five.timeouts, five.missed_in_row),
        (0, 21, 21)
    );
    for id in [1, 2, 3, 4, 6] {
        let r = row(&frame, id);
        assert!(r.present, "servo {id}");
        assert_eq!((r.replies, r.timeouts), (21, 0), "servo {id}");
        assert!(r.p99_latency_us.is_some_and(|us| us > 0.0), "servo {id}");
    }
    assert_eq!(row(&frame, 3).flags, vec!["overheat"]);
    assert_eq!(row(&frame, 3).temperature_c, Some(70.0));
    assert!(row(&frame, 1).flags.is_empty());
    let (before, after) = (row(&first, 1).position_ticks, row(&frame, 1).position_ticks);
    assert!(after > before, "servo 1 moved: {before:?} -> {after:?}");
    assert_eq!(row(&frame, 1).goal_ticks, Some(2548));
    assert_eq!(row(&frame, 1).torque, Some(true));
    assert_eq!(
        row(&frame, 2).position_deg,
        Some(-90.0),
        "shoulder_lift at home"
    );

    // 20 refreshes a second; each moves 8 + 6 request bytes and five
    // replies of 6 + 31 bytes (torque enable 40 to the present current's
    // last byte 70): 199 bytes, 1.99 ms at 1 Mbps, of every 50 ms.
    assert!(
        (frame.read_rate_hz - 20.0).abs() < 0.5,
        "{}",
        frame.read_rate_hz
    );
    assert!(
        (frame.utilisation - 0.0398).abs() < 0.001,
        "{}",
        frame.utilisation
    );
}

/// The raw count servo `id` holds in `present_current` (69, sign bit 15).
fn current_count(bus: &mut Bus<SimBus>, id: u8) -> i32 {
    let mut raw = [0u8; 2];
    bus.read(id, addr::PRESENT_CURRENT, &mut raw)
        .expect("present current");
    let v = i32::from(u16::from_le_bytes(raw));
    if v & 0x8000 != 0 {
        -(v & 0x7fff)
    } else {
        v
    }
}

#[test]
fn the_current_is_read_beside_the_load_in_6_5_ma_counts() {
    let arm = robot("so101.yaml");
    let (sim, mut bus) = virtual_bus(&arm, Faults::none());
    let mut poller = Poller::new(Watched::of_bus(&arm.buses[0], arm.units));
    // Servo 2 blocked and driven 500 ticks away: it strains at its full
    // torque. Servo 4 holds against a load of a fifth of its torque.
    // Servo 6 has its torque off.
    for id in [2, 4] {
        bus.write(id, addr::TORQUE_ENABLE, &[1]).expect("torque");
    }
    sim.servo(2, |s| s.set_blocked(true)).expect("servo 2");
    let goal = sim.present_position(2).expect("position") + 500;
    bus.write(2, addr::GOAL_POSITION, &(goal as u16).to_le_bytes())
        .expect("goal");
    sim.servo(4, |s| s.set_external_load(0.2)).expect("servo 4");
    // Half a second: well inside the 2 s before the overload protection.
    let frame = poll(&mut poller, &mut bus, 10);

    let blocked = row(&frame, 2);
    let ma = blocked.current_ma.expect("an STS3215 reports its current");
    // An STS3215 stalls at about 2.7 A on 12 V.
    assert!((2000.0..=3200.0).contains(&ma), "blocked: {ma} mA");
    assert!(
        blocked.load_pct.is_some_and(|l| l.abs() >= 99.0),
        "{blocked:?}"
    );
    let held = row(&frame, 4);
    let held_ma = held.current_ma.expect("servo 4's current");
    assert!(held_ma > 100.0 && held_ma < ma * 0.8, "held: {held_ma} mA");
    assert_eq!(
        row(&frame, 6).current_ma,
        Some(0.0),
        "torque off: no current"
    );
    // The figure is the register's count in 6.5 mA (the servo at rest now,
    // so the count the row was made of still stands).
    for id in [2, 4, 6] {
        let count = current_count(&mut bus, id);
        let shown = row(&frame, id).current_ma.expect("a current");
        assert!(
            (shown - 6.5 * f64::from(count)).abs() < 1e-9,
            "servo {id}: {shown} mA of {count} counts"
        );
    }
}

#[test]
fn scs_servos_show_no_current() {
    let mini = robot("scs-mini.yaml");
    let (sim, mut bus) = virtual_bus(&mini, Faults::none());
    let mut poller = Poller::new(Watched::of_bus(&mini.buses[0], mini.units));
    let first = mini.buses[0].joints[0].id;
    bus.write(first, addr::TORQUE_ENABLE, &[1]).expect("torque");
    sim.servo(first, |s| s.set_external_load(0.3))
        .expect("servo");
    let frame = poll(&mut poller, &mut bus, 4);
    assert!(row(&frame, first).load_pct.is_some_and(|l| l.abs() > 10.0));
    assert!(
        frame
            .servos
            .iter()
            .all(|r| r.present && r.current_ma.is_none()),
        "{:?}",
        frame.servos
    );
}

#[test]
fn a_port_alone_is_scanned_for_its_servos_first() {
    let arm = robot("so101.yaml");
    let (_sim, mut bus) = virtual_bus(&arm, "vanish=5".parse().expect("faults"));
    let found = Poller::scan(&mut bus).expect("scan");
    let ids: Vec<u8> = found.iter().map(|w| w.id).collect();
    assert_eq!(ids, [1, 2, 3, 4, 6]);
    assert!(found
        .iter()
        .all(|w| w.model.name == "STS3215" && w.joint.is_none()));
    let mut poller = Poller::new(found);
    let frame = poll(&mut poller, &mut bus, 2);
    // Without a robot file, degrees are the servo's from its mid-travel.
    assert_eq!(row(&frame, 2).position_deg, Some(-90.0));
}

#[test]
fn scs_servos_are_read_one_by_one() {
    let mini = robot("scs-mini.yaml");
    let (sim, mut bus) = virtual_bus(&mini, Faults::none());
    let mut poller = Poller::new(Watched::of_bus(&mini.buses[0], mini.units));
    poll(&mut poller, &mut bus, 1);
    let requests = sim.stats().requests;
    let frame = poll(&mut poller, &mut bus, 5);
    let n = mini.buses[0].joints.len() as u64;
    assert_eq!(sim.stats().requests - requests, 5 * n);
    assert!(frame
        .servos
        .iter()
        .all(|r| r.present && r.voltage_v == Some(6.0)));
}

#[test]
fn torque_off_reaches_every_servo_in_one_frame() {
    let arm = robot("so101.yaml");
    let (sim, mut bus) = virtual_bus(&arm, Faults::none());
    let ids: Vec<u8> = arm.buses[0].joints.iter().map(|j| j.id).collect();
    bus.sync_write(addr::TORQUE_ENABLE, &ids, &vec![1; ids.len()])
        .expect("torque on");
    assert!(ids
        .iter()
        .all(|&id| sim.snapshot(id).is_some_and(|s| s.torque_enabled())));
    let requests = sim.stats().requests;
    monitor::torque_off(&mut bus, &ids).expect("torque off");
    assert_eq!(sim.stats().requests - requests, 1);
    assert!(ids
        .iter()
        .all(|&id| sim.snapshot(id).is_some_and(|s| !s.torque_enabled())));
}

#[test]
fn the_view_shows_flags_missing_servos_and_keys() {
    let arm = robot("so101.yaml");
    let (_sim, mut bus) = virtual_bus(&arm, "overheat=3,vanish=5".parse().expect("faults"));
    let mut poller = Poller::new(Watched::of_bus(&arm.buses[0], arm.units));
    let frame = poll(&mut poller, &mut bus, 4);
    let mut terminal = Terminal::new(TestBackend::new(160, 14)).expect("terminal");
    terminal
        .draw(|f| view::draw(f, &frame, "so101"))
        .expect("drawn");
    let buffer = terminal.backend().buffer();
    let lines: Vec<String> = (0..buffer.area.height)
        .map(|y| {
            (0..buffer.area.width)
                .map(|x| buffer[(x, y)].symbol().to_string())
                .collect()
        })
        .collect();
    let line_of = |id: &str| {
        lines
            .iter()
            .find(|l| l.starts_with(&format!("{id:<4}")))
            .cloned()
            .unwrap_or_default()
    };
    assert!(line_of("3").contains("OVERHEAT"), "{lines:#?}");
    assert!(line_of("5").contains("MISSING (no reply)"), "{lines:#?}");
    assert!(line_of("1").contains(" ok "), "{lines:#?}");
    assert!(lines.iter().any(|l| l.contains(view::KEYS)), "{lines:#?}");
    // The reply column says what it measures (it grows along the bus).
    assert!(
        lines.iter().any(|l| l.contains("reply p99 us")),
        "{lines:#?}"
    );
    assert!(
        lines
            .iter()
            .any(|l| l.contains("servos answer one SYNC READ in turn")),
        "{lines:#?}"
    );
}

/// The screen `frame` draws on a `width` by 14 terminal, line by line.
fn screen(frame: &Frame, width: u16) -> Vec<String> {
    let mut terminal = Terminal::new(TestBackend::new(width, 14)).expect("terminal");
    terminal
        .draw(|f| view::draw(f, frame, "so101"))
        .expect("drawn");
    let buffer = terminal.backend().buffer();
    (0..buffer.area.height)
        .map(|y| {
            (0..buffer.area.width)
                .map(|x| buffer[(x, y)].symbol().to_string())
                .collect()
        })
        .collect()
}

#[test]
fn the_view_gives_units_and_sources_and_cuts_no_status_mid_word() {
    let arm = robot("so101.yaml");
    let (_sim, mut bus) = virtual_bus(&arm, Faults::default());
    let mut poller = Poller::new(Watched::of_bus(&arm.buses[0], arm.units));
    let mut frame = poll(&mut poller, &mut bus, 4);
    // Servo 2 with every flag set, servo 4 missing for the longest reason.
    let all_flags = [
        "voltage",
        "angle sensor",
        "overheat",
        "over-current",
        "overload",
    ];
    frame.servos[1].flags = all_flags.to_vec();
    let four = &mut frame.servos[3];
    four.present = false;
    four.position_ticks = None;
    four.missing = Some("reply of the wrong length".into());
    let lines = screen(&frame, 160);
    let header = lines
        .iter()
        .find(|l| l.starts_with("ID "))
        .cloned()
        .unwrap_or_default();
    assert!(header.contains("reply p99 us"), "{lines:#?}");
    // The current beside the load, in mA (none drawn, the torque being off).
    let (Some(ma), Some(volt)) = (header.find("cur mA"), header.find("volt")) else {
        panic!("no current column in {header:?}");
    };
    assert!(
        header.find("load %").is_some_and(|load| load < ma),
        "{header}"
    );
    let cell = |id: &str| -> String {
        let line = lines
            .iter()
            .find(|l| l.starts_with(&format!("{id:<4}")))
            .cloned()
            .unwrap_or_default();
        line.chars()
            .skip(ma)
            .take(volt - ma)
            .collect::<String>()
            .trim()
            .to_string()
    };
    assert_eq!(cell("1"), "0", "{lines:#?}");
    // The summary names where the figures come from, in words.
    assert!(!lines[0].contains("(bus)"), "{lines:#?}");
    assert!(
        lines[0].contains("figures: read from the bus by the monitor"),
        "{lines:#?}"
    );
    // The status column: from its header to the next column's.
    let (Some(from), Some(to)) = (header.find("status"), header.find("replies")) else {
        panic!("no status column in {header:?}");
    };
    let status = |id: &str| -> String {
        let line = lines
            .iter()
            .find(|l| l.starts_with(&format!("{id:<4}")))
            .cloned()
            .unwrap_or_default();
        line.chars()
            .skip(from)
            .take(to - from)
            .collect::<String>()
            .trim()
            .to_string()
    };
    // Whole flag names, and how many did not fit.
    assert_eq!(status("2"), "VOLTAGE, ANGLE SENSOR +3", "{lines:#?}");
    // Whole words of the reason, and a mark that there is more.
    assert_eq!(status("4"), "MISSING (reply of the…", "{lines:#?}");
}

#[test]
fn the_view_shows_a_dash_for_an_scs_servos_current() {
    let mini = robot("scs-mini.yaml");
    let (_sim, mut bus) = virtual_bus(&mini, Faults::none());
    let mut poller = Poller::new(Watched::of_bus(&mini.buses[0], mini.units));
    let frame = poll(&mut poller, &mut bus, 2);
    let lines = screen(&frame, 160);
    let header = lines
        .iter()
        .find(|l| l.starts_with("ID "))
        .cloned()
        .unwrap_or_default();
    let (Some(ma), Some(volt)) = (header.find("cur mA"), header.find("volt")) else {
        panic!("no current column in {header:?}");
    };
    for r in &frame.servos {
        let line = lines
            .iter()
            .find(|l| l.starts_with(&format!("{:<4}", r.id)))
            .cloned()
            .unwrap_or_default();
        let cell: String = line.chars().skip(ma).take(volt - ma).collect();
        assert_eq!(cell.trim(), "-", "servo {}: {lines:#?}", r.id);
    }
}

#[test]
fn play_monitor_rows_follow_the_telemetry() {
    let (motion, arm) =
        load_motion(&common::repo("configs/motions/arm-wave.yaml"), None).expect("motion");
    let trajectory = plan_motion(&motion, &arm).expect("plan");
    let (_sim, bus) = virtual_bus(&arm, "overheat=3".parse().expect("faults"));
    let options = RunOptions {
        units: Some(motion.units),
        ..RunOptions::default()
    };
    let rate = arm.rate_hz;
    let runner = VirtualRun::new(&arm, trajectory, vec![bus], options)
        .and_then(VirtualRun::spawn)
        .expect("run");
    let mut rows = TelemetryRows::new(&arm, motion.units, 1.0 / rate);
    let mut hot_seen = false;
    for message in runner.telemetry().iter() {
        if let Telemetry::Cycle(sample) = message {
            rows.record(&sample);
            hot_seen |= rows.frame(None).servos[2].flags.contains(&"overheat");
        }
    }
    let _ = runner.join();
    let frame = rows.frame(None);
    assert_eq!(frame.source, "telemetry");
    assert!(hot_seen, "servo 3's overheat flag reached the rows");
    for (r, joint) in frame.servos.iter().zip(arm.joints()) {
        assert!(r.replies > 0, "{}", joint.name);
        let deg = r.position_deg.expect("a position");
        assert!(
            deg >= joint.min - 1.0 && deg <= joint.max + 1.0,
            "{}: {deg}",
            joint.name
        );
        assert!(r.goal_ticks.is_some());
    }
}

#[test]
fn monitor_json_prints_one_line_per_refresh_at_10_hz_or_more() {
    let out = common::servobus(&[
        "monitor",
        "--robot",
        "configs/robots/so101.yaml",
        "--json",
        "--count",
        "15",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let frames: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    assert_eq!(frames.len(), 15);
    let last = &frames[14];
    assert!(common::num(last, "read_rate_hz") >= 10.0, "{last}");
    let servos = last["servos"].as_array().expect("servos");
    assert_eq!(servos.len(), 6);
    assert!(servos
        .iter()
        .all(|s| s["present"] == true && s["replies"] == 15));
    // The current beside the load: none drawn, the torque being off.
    assert!(servos.iter().all(|s| s["current_ma"] == 0.0), "{last}");
    let line = text.lines().last().unwrap_or_default();
    let at = |key: &str| line.find(&format!("\"{key}\":"));
    assert!(
        at("load_pct") < at("current_ma") && at("current_ma") < at("voltage_v"),
        "{line}"
    );
}

#[test]
fn monitor_json_gives_scs_servos_no_current() {
    let out = common::servobus(&[
        "monitor",
        "--robot",
        "configs/robots/scs-mini.yaml",
        "--json",
        "--count",
        "2",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let last: serde_json::Value =
        serde_json::from_str(text.lines().last().unwrap_or_default()).expect("a JSON line");
    let servos = last["servos"].as_array().expect("servos");
    assert!(!servos.is_empty());
    for s in servos {
        assert!(s["load_pct"].is_number(), "{s}");
        assert!(s["current_ma"].is_null(), "{s}");
    }
}
