//! Late replies: a reply that reaches the host after its deadline came
//! from a servo that answered, so it is counted as late, not as a timeout;
//! a silent servo keeps every timeout. In virtual time, on the simulator.

use std::time::Duration;

use servobus_driver::{Bus, BusSettings, Clock, ManualClock};
use servobus_protocol::registers::{addr, Series};
use servobus_sim::{Faults, SimBus};

use super::{servo, BAUD};

const MS: Duration = Duration::from_millis(1);
const US: Duration = Duration::from_micros(1);

/// Servos `ids` with no retries (one timeout per servo per read) and 1 ms
/// of adapter latency in the deadlines.
fn setup(ids: &[u8], faults: Faults) -> (Bus<SimBus>, SimBus, ManualClock) {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD)
        .with_servos(ids.iter().map(|&id| servo(id)))
        .with_faults(faults);
    let settings = BusSettings::new(Series::Sts)
        .with_retries(0)
        .with_latency(MS);
    (Bus::new(sim.clone(), settings), sim, clock)
}

#[test]
fn replies_held_5_ms_past_the_deadline_are_late_not_lost() {
    // Every reply starts 5 ms late: past the SYNC READ's deadline of
    // 14 + 3 x 8 bytes, 3 turnarounds, 1 ms of latency and the margin.
    let (mut bus, _sim, clock) = setup(&[1, 2, 3], Faults::none().delay(1.0, 5 * MS));
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1, 2, 3])
        .expect("a read");
    assert_eq!(read.missing(), 3);
    assert_eq!(bus.counters().timeouts, 3);
    assert_eq!(bus.counters().late_replies, 0);

    // Each servo answers 5 ms late, after the one before it (the replies
    // of a SYNC READ follow one another): all within the next 20 ms. Three
    // late replies, no timeout.
    let began = clock.now();
    assert_eq!(bus.await_late_replies(20 * MS).expect("no port failure"), 3);
    assert!(clock.now() - began < 20 * MS, "returns once all came");
    assert_eq!(bus.counters().timeouts, 0);
    assert_eq!(bus.counters().late_replies, 3);
    assert_eq!(bus.servo_counters(2).timeouts, 0);
    assert_eq!(bus.servo_counters(2).late_replies, 1);
    // Nothing more is overdue: a further wait returns at once.
    let now = clock.now();
    assert_eq!(bus.await_late_replies(10 * MS).expect("no port failure"), 0);
    assert_eq!(clock.now(), now);
}

#[test]
fn a_late_reply_is_seen_when_the_next_request_is_sent() {
    let (mut bus, sim, clock) = setup(&[1, 2], Faults::none().delay(1.0, 5 * MS));
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1, 2])
        .expect("a read");
    assert_eq!(read.missing(), 2);
    // The host does something else meanwhile; the replies arrive.
    clock.advance(20 * MS);
    sim.set_faults(Faults::none());
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1, 2])
        .expect("a read");
    assert_eq!(read.missing(), 0, "the fresh replies are taken");
    assert_eq!(bus.counters().timeouts, 0);
    assert_eq!(bus.counters().late_replies, 2);
}

#[test]
fn a_silent_servo_keeps_its_timeouts() {
    let (mut bus, _sim, _clock) = setup(&[1, 2, 3], Faults::none().vanish(2));
    for read_number in 1..=3u64 {
        let read = bus
            .sync_read(addr::PRESENT_POSITION, 2, &[1, 2, 3])
            .expect("a read");
        assert_eq!(read.missing(), 1);
        assert_eq!(bus.await_late_replies(10 * MS).expect("no failure"), 0);
        assert_eq!(bus.servo_counters(2).timeouts, read_number);
    }
    assert_eq!(bus.counters().late_replies, 0);
    assert_eq!(bus.servo_counters(1).timeouts, 0);
}

/// One servo whose first reply starts 2 ms late: past the first read's
/// deadline (13 + 8 bytes, 50 us of turnaround, 1 ms of latency and 200 us
/// of margin: 1.46 ms), but inside the next read's, sent at once. The
/// first read is made: it timed out.
fn first_read_late() -> (Bus<SimBus>, SimBus) {
    let (mut bus, sim, _clock) = setup(&[1], Faults::none().delay(1.0, 2 * MS));
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1])
        .expect("a read");
    assert_eq!(read.missing(), 1);
    assert_eq!(bus.counters().timeouts, 1);
    (bus, sim)
}

#[test]
fn a_late_reply_that_comes_during_the_next_read_is_not_taken_for_its_answer() {
    let (mut bus, sim) = first_read_late();
    sim.set_faults(Faults::none());
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1])
        .expect("a read");
    // Two frames came in the second read's window: one of them was the
    // first read's reply, so that read's timeout is taken back.
    assert_eq!(read.missing(), 0);
    assert_eq!(bus.counters().late_replies, 1);
    assert_eq!(bus.counters().timeouts, 0);
}

#[test]
fn another_servos_late_reply_during_a_read_is_late_not_wrong() {
    // Servo 1's reply starts 1.3 ms late: past its READ's deadline (8 + 8
    // bytes, 50 us of turnaround, 1 ms of latency, 200 us of margin:
    // 1.41 ms), and it comes while servo 2 is being read.
    let (mut bus, sim, _clock) = setup(&[1, 2], Faults::none().delay(1.0, 1300 * US));
    let mut buf = [0u8; 2];
    assert!(bus.read(1, addr::PRESENT_POSITION, &mut buf).is_err());
    assert_eq!(bus.counters().timeouts, 1);
    sim.set_faults(Faults::none());
    bus.read(2, addr::PRESENT_POSITION, &mut buf)
        .expect("servo 2 answers");
    assert_eq!(bus.counters().late_replies, 1);
    assert_eq!(bus.counters().timeouts, 0);
    assert_eq!(bus.counters().wrong_replies, 0);
}

#[test]
fn a_reply_really_lost_keeps_its_timeout_and_the_servo_reads_on() {
    // Servo 1's first reply is dropped: it never comes.
    let (mut bus, sim, clock) = setup(&[1], Faults::none().drop(1.0));
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1])
        .expect("a read");
    assert_eq!(read.missing(), 1);
    sim.set_faults(Faults::none());
    // The next two reads take its one frame as the answer, though each
    // waits to its deadline in case it was the late reply; then reads end
    // as soon as it answers again.
    let mut took = Vec::new();
    for _ in 0..3 {
        let began = clock.now();
        let read = bus
            .sync_read(addr::PRESENT_POSITION, 2, &[1])
            .expect("a read");
        assert_eq!(read.missing(), 0);
        took.push(clock.now() - began);
    }
    assert!(took[2] < took[0] && took[2] < took[1], "{took:?}");
    assert_eq!(bus.counters().timeouts, 1);
    assert_eq!(bus.counters().late_replies, 0);
}

#[test]
fn a_reading_is_stamped_when_the_servo_heard_the_request() {
    let (mut bus, _sim, clock) = setup(&[1, 2], Faults::none());
    clock.advance(10 * MS);
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1, 2])
        .expect("a read");
    // The SYNC READ of two servos is 10 bytes (header 2, ID, length,
    // instruction, address, size, two IDs, checksum): 100 us at 1 Mbps,
    // sent at 10 ms. Both servos took their positions when they had heard
    // it, however long their replies then took to come.
    for r in read.iter() {
        let r = r.expect("answered");
        assert_eq!(r.sampled, 10 * MS + 100 * US);
        assert!(!r.in_doubt);
    }
    assert_eq!(bus.heard(), 10 * MS + 100 * US);
    assert!(clock.now() > bus.heard());
}

#[test]
fn a_late_reply_taken_in_place_of_a_lost_one_is_in_doubt() {
    let (mut bus, sim) = first_read_late();
    // The answer to the second read is lost; the late reply to the first
    // comes in its window. Which of the two the one frame is cannot be
    // told: the reading is the servo's, but in doubt.
    sim.set_faults(Faults::none().drop(1.0));
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1])
        .expect("a read");
    let r = read.get(0).expect("one servo").expect("a frame came");
    assert!(r.in_doubt);
    // A read with the servo answering on time again is not.
    sim.set_faults(Faults::none());
    let _ = bus.await_late_replies(10 * MS).expect("no port failure");
    for _ in 0..2 {
        let _ = bus
            .sync_read(addr::PRESENT_POSITION, 2, &[1])
            .expect("a read");
    }
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1])
        .expect("a read");
    let r = read.get(0).expect("one servo").expect("answered");
    assert!(!r.in_doubt);
}
