//! The simulated bus: wire time in virtual time, reply timing, collisions,
//! echo and injected faults.

use crate::common;

use std::time::Duration;

use common::*;
use servobus_io::{ManualClock, Transport, TransportError};
use servobus_sim::{addr, Faults, SimBus, SimServo};

const US: Duration = Duration::from_micros(1);

/// The STS3215's turnaround before each reply, in us: the figure the budget
/// charges (a guess, see `REPLY_TURNAROUND`).
const T: u32 = 50;

#[test]
fn the_simulator_charges_the_budgets_turnaround() {
    let model = servobus_protocol::registers::model_by_name("STS3215").unwrap();
    assert_eq!(model.turnaround, T * US);
    assert_eq!(servobus_timing::Link::DEFAULT_TURNAROUND, T * US);
}

#[test]
fn a_request_costs_its_wire_time_and_the_reply_its_return_delay() {
    let clock = ManualClock::new();
    let mut bus = SimBus::new(clock.clone(), 1_000_000)
        .with_servo(SimServo::sts3215(1).with_return_delay(Duration::from_micros(100)));
    // READ is 8 bytes: 80 us on the wire.
    bus.write_all(&read(1, addr::PRESENT_POSITION, 2)).unwrap();
    assert_eq!(now(&bus), 80 * US);
    // The 8-byte reply starts a turnaround and 100 us later, read as one burst.
    let mut buf = [0u8; 64];
    let n = bus.read(&mut buf, Duration::from_secs(1)).unwrap();
    assert_eq!(n, 8);
    assert_eq!(now(&bus), (80 + T + 100 + 80) * US);
    // Nothing else comes: the read waits to the deadline.
    let deadline = now(&bus) + 500 * US;
    assert!(matches!(
        bus.read(&mut buf, deadline),
        Err(TransportError::TimedOut)
    ));
    assert_eq!(now(&bus), deadline);
}

#[test]
fn a_deadline_inside_a_reply_returns_what_arrived_by_then() {
    let mut bus = bus_with(&[1]);
    bus.write_all(&read(1, addr::PRESENT_POSITION, 2)).unwrap();
    let mut buf = [0u8; 64];
    // The reply's bytes arrive at 90, 100, ... 160 us after the turnaround.
    assert!(matches!(
        bus.read(&mut buf, (85 + T) * US),
        Err(TransportError::TimedOut)
    ));
    let n = bus.read(&mut buf, (125 + T) * US).unwrap();
    assert_eq!((n, now(&bus)), (4, (120 + T) * US));
    let n = bus.read(&mut buf, Duration::from_secs(1)).unwrap();
    assert_eq!((n, now(&bus)), (4, (160 + T) * US));
}

#[test]
fn sync_read_replies_follow_each_other_with_each_return_delay() {
    let clock = ManualClock::new();
    let mut bus = SimBus::new(clock, 1_000_000).with_servos([
        SimServo::sts3215(1).with_return_delay(Duration::from_micros(20)),
        SimServo::sts3215(2).with_return_delay(Duration::from_micros(40)),
    ]);
    // Request: 8 + 2 = 10 bytes = 100 us. Replies of 8 bytes, each after a
    // turnaround of T: servo 1 from 170 to 250 us, servo 2 from 340 to 420 us.
    bus.write_all(&sync_read(addr::PRESENT_POSITION, 2, &[1, 2]))
        .unwrap();
    let mut buf = [0u8; 64];
    assert_eq!(bus.read(&mut buf, Duration::from_secs(1)).unwrap(), 8);
    assert_eq!(now(&bus), (100 + T + 20 + 80) * US);
    assert_eq!(bus.read(&mut buf, Duration::from_secs(1)).unwrap(), 8);
    assert_eq!(now(&bus), (100 + 2 * (T + 80) + 20 + 40) * US);
}

#[test]
fn the_six_servo_cycle_costs_what_the_budget_says() {
    // 6 servos at return delay 0: SYNC WRITE of goal positions 26 bytes, SYNC
    // READ of 2 bytes 14 + 48 bytes: 88 bytes = 0.88 ms at 1 Mbps.
    let mut bus = bus_with(&[1, 2, 3, 4, 5, 6]);
    let goal = 2048u16.to_le_bytes();
    let items: Vec<(u8, &[u8])> = (1..=6).map(|id| (id, &goal[..])).collect();
    bus.write_all(&sync_write(addr::GOAL_POSITION, &items))
        .unwrap();
    assert_eq!(now(&bus), 260 * US);
    bus.write_all(&sync_read(addr::PRESENT_POSITION, 2, &[1, 2, 3, 4, 5, 6]))
        .unwrap();
    // Read as the bytes come, with a deadline far away: the clock then
    // stands where the last of them arrived.
    let mut got = Vec::new();
    let mut buf = [0u8; 64];
    while got.len() < 48 {
        let n = bus.read(&mut buf, Duration::from_secs(1)).unwrap();
        got.extend_from_slice(&buf[..n]);
    }
    assert_eq!(frames(&got).len(), 6);
    assert_eq!(bus.stats().replies, 6);
    // The request ends at 260 + 140 = 400 us; six 8-byte replies follow,
    // each after the model's turnaround (return delay 0): the last byte at
    // 400 + 6 x (50 + 80) = 1180 us, the budget's cycle time for this bus.
    assert_eq!(now(&bus), (400 + 6 * (T + 80)) * US);
    assert_eq!(now(&bus), 1180 * US);
}

#[test]
fn two_servos_with_one_id_collide_into_corrupted_bytes() {
    let clock = ManualClock::new();
    let mut bus = SimBus::new(clock, 1_000_000).with_servos([
        SimServo::sts3215(1)
            .with_return_delay(Duration::ZERO)
            .with_position(0x0F0F),
        SimServo::sts3215(1)
            .with_return_delay(Duration::ZERO)
            .with_position(0x00F0),
    ]);
    let got = exchange(&mut bus, &read(1, addr::PRESENT_POSITION, 2), MS);
    assert_eq!(got.len(), 8, "the replies overlap byte for byte");
    assert!(servobus_protocol::parse_frame(&got).is_err());
    assert_eq!(bus.stats().collided_bytes, 8);
    // A ping collides too, but identical replies AND into the same bytes.
    let got = exchange(&mut bus, &ping(1), MS);
    assert_eq!(got, status(1, 0, &[]));
}

#[test]
fn echo_returns_the_request_before_the_reply() {
    let mut bus = bus_with(&[1]).with_echo(true);
    let req = ping(1);
    let got = exchange(&mut bus, &req, MS);
    let mut want = req.clone();
    want.extend(status(1, 0, &[]));
    assert_eq!(got, want);
    assert_eq!(bus.stats().echoed_bytes, 6);
}

#[test]
fn dropped_and_corrupted_replies_follow_the_seed() {
    let run = |seed| {
        let mut bus = bus_with(&[1, 2, 3]).with_faults(Faults::seeded(seed).drop(0.2).corrupt(0.2));
        let mut got = Vec::new();
        for _ in 0..200 {
            got.extend(exchange(
                &mut bus,
                &sync_read(addr::PRESENT_POSITION, 2, &[1, 2, 3]),
                MS,
            ));
        }
        (got, bus.stats())
    };
    let (a, stats) = run(7);
    let (b, _) = run(7);
    assert_eq!(a, b, "same seed, same bytes");
    assert_ne!(run(8).0, a);
    // 600 replies at 20 %: each count well inside 60..180.
    assert!((60..180).contains(&stats.dropped), "{stats:?}");
    assert!((60..180).contains(&stats.corrupted), "{stats:?}");
    assert_eq!(stats.replies, 600 - stats.dropped);
}

#[test]
fn a_delayed_reply_misses_a_tight_deadline_and_arrives_later() {
    let mut bus =
        bus_with(&[1]).with_faults(Faults::seeded(1).delay(1.0, Duration::from_millis(2)));
    assert!(exchange(&mut bus, &ping(1), MS).is_empty());
    // It is still on its way: the next read finds it.
    let mut buf = [0u8; 16];
    let n = bus.read(&mut buf, now(&bus) + 5 * MS).unwrap();
    assert_eq!(&buf[..n], &status(1, 0, &[])[..]);
    assert_eq!(bus.stats().delayed, 1);
}

#[test]
fn a_vanished_servo_answers_nothing_and_the_others_keep_their_turn() {
    let mut bus = bus_with(&[1, 2, 3]).with_faults(Faults::none().vanish(2));
    let got = exchange(&mut bus, &sync_read(addr::ID, 1, &[1, 2, 3]), MS);
    assert_eq!(frames(&got), vec![status(1, 0, &[1]), status(3, 0, &[3])]);
    bus.servo(2, |s| s.set_offline(false));
    assert_eq!(exchange(&mut bus, &ping(2), MS), status(2, 0, &[]));
}

#[test]
fn discard_input_drops_only_what_has_arrived() {
    let mut bus = bus_with(&[1]);
    bus.write_all(&ping(1)).unwrap();
    // The reply is still on the wire: nothing to discard yet.
    bus.discard_input().unwrap();
    assert_eq!(bus.pending_bytes(), 6);
    wait(&bus, MS);
    bus.discard_input().unwrap();
    assert_eq!(bus.pending_bytes(), 0);
}

#[test]
fn an_unplugged_adapter_reports_disconnected() {
    let mut bus = bus_with(&[1]);
    bus.set_disconnected(true);
    assert!(matches!(
        bus.write_all(&ping(1)),
        Err(TransportError::Disconnected(_))
    ));
    let mut buf = [0u8; 4];
    assert!(matches!(
        bus.read(&mut buf, MS),
        Err(TransportError::Disconnected(_))
    ));
}

#[test]
fn adapter_latency_delays_every_byte() {
    let mut bus = bus_with(&[1]).with_latency(MS);
    bus.write_all(&ping(1)).unwrap();
    let mut buf = [0u8; 16];
    assert_eq!(bus.read(&mut buf, Duration::from_secs(1)).unwrap(), 6);
    assert_eq!(now(&bus), (120 + T) * US + MS);
}

#[test]
fn a_held_reply_is_handed_over_whole_after_the_hold() {
    // Sent on time, held on the host's side (a loaded machine): nothing is
    // readable until the whole reply is, 1 ms after its last byte arrived.
    let mut bus = bus_with(&[1]).with_faults(Faults::seeded(1).hold(1.0, MS));
    bus.write_all(&ping(1)).unwrap();
    let mut buf = [0u8; 16];
    assert!(matches!(
        bus.read(&mut buf, (120 + T) * US + MS - US),
        Err(TransportError::TimedOut)
    ));
    let n = bus.read(&mut buf, Duration::from_secs(1)).unwrap();
    assert_eq!(&buf[..n], &status(1, 0, &[])[..]);
    assert_eq!(now(&bus), (120 + T) * US + MS);
    assert_eq!(bus.stats().held, 1);
    assert_eq!(bus.stats().delayed, 0);
}
