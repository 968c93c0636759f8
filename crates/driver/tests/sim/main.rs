//! The driver's `Bus` against the simulated bus, in virtual time: every
//! transaction, partial SYNC READ, retries, echo, wrong-ID replies,
//! collisions, the EEPROM transaction and corrupt bytes.

use std::time::Duration;

use servobus_driver::scripted::{Received, Script, ScriptedPort};
use servobus_driver::{
    Bus, BusError, BusSettings, Clock, ManualClock, MissingReason, Transport, TransportError,
};
use servobus_protocol::registers::{addr, Series};
use servobus_protocol::{checksum, parse_frame};
use servobus_sim::{Faults, SimBus, SimServo};
use servobus_timing::{Link, StatusLevel, Transaction};

mod baud;
mod broadcast;
mod late;
mod transaction;

const BAUD: u32 = 1_000_000;

fn servo(id: u8) -> SimServo {
    SimServo::sts3215(id)
        .with_return_delay(Duration::ZERO)
        .with_position(1000 + 100 * i32::from(id))
}

/// A simulated bus with servos `ids` and a driver bus over it.
fn setup(ids: &[u8]) -> (Bus<SimBus>, SimBus) {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos(ids.iter().map(|&id| servo(id)));
    let settings = BusSettings::new(Series::Sts).with_retries(2);
    (Bus::new(sim.clone(), settings), sim)
}

fn le(bytes: &[u8]) -> u16 {
    u16::from_le_bytes([bytes[0], bytes[1]])
}

#[test]
fn ping_read_write_reset() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1, 2]);
    assert!(bus.ping(1)?.is_ok());
    let mut model = [0u8; 2];
    bus.read(2, addr::MODEL_NUMBER, &mut model)?;
    assert_eq!(le(&model), 777);
    let mut pos = [0u8; 2];
    bus.read(2, addr::PRESENT_POSITION, &mut pos)?;
    assert_eq!(le(&pos), 1200);

    assert!(bus.write(1, addr::ACCELERATION, &[33])?.is_some());
    assert_eq!(sim.register(1, addr::ACCELERATION), Some(33));
    let reg = Series::Sts.map().get("goal_speed").expect("goal_speed");
    bus.write_register(1, reg, 500)?;
    assert_eq!(bus.read_register(1, reg)?.0, 500);

    // Broadcast: applied by every servo, answered by none.
    assert!(bus.write(0xFE, addr::ACCELERATION, &[44])?.is_none());
    assert_eq!(sim.register(2, addr::ACCELERATION), Some(44));

    assert!(bus.reset(1)?.is_some());
    assert_eq!(sim.register(1, addr::ACCELERATION), Some(0));
    let c = bus.counters();
    assert_eq!((c.timeouts, c.retries, c.failures), (0, 0, 0));
    assert_eq!(bus.servo_counters(1).rtt.count, 5);
    Ok(())
}

#[test]
fn reg_write_waits_for_action() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1, 2]);
    bus.reg_write(1, addr::ACCELERATION, &[9])?;
    bus.reg_write(2, addr::ACCELERATION, &[9])?;
    assert_eq!(sim.register(1, addr::ACCELERATION), Some(0));
    let mut flag = [0u8];
    bus.read(1, addr::ASYNC_FLAG, &mut flag)?;
    assert_eq!(flag, [1]);
    assert!(bus.action(0xFE)?.is_none());
    assert_eq!(sim.register(1, addr::ACCELERATION), Some(9));
    assert_eq!(sim.register(2, addr::ACCELERATION), Some(9));
    Ok(())
}

#[test]
fn sync_write_and_sync_read() -> Result<(), BusError> {
    let ids = [1, 2, 3, 4, 5, 6];
    let (mut bus, sim) = setup(&ids);
    let mut data = [0u8; 12];
    for (i, &id) in ids.iter().enumerate() {
        data[2 * i..2 * i + 2].copy_from_slice(&(10 * u16::from(id)).to_le_bytes());
    }
    bus.sync_write(addr::ACCELERATION, &ids, &data)?;
    assert_eq!(sim.register(4, addr::ACCELERATION), Some(40));
    let r = bus.sync_read(addr::PRESENT_POSITION, 2, &ids)?;
    assert!(r.is_complete());
    for (res, &id) in r.iter().zip(&ids) {
        let reply = res.map_err(|m| BusError::InvalidRequest(reason(m.reason)))?;
        assert_eq!(reply.id, id);
        assert_eq!(i32::from(le(reply.data)), 1000 + 100 * i32::from(id));
    }
    Ok(())
}

fn reason(r: MissingReason) -> &'static str {
    match r {
        MissingReason::NoReply => "no reply",
        _ => "other",
    }
}

#[test]
fn sync_read_keeps_the_others_when_one_is_missing() -> Result<(), BusError> {
    let ids = [1, 2, 3, 4];
    let (mut bus, sim) = setup(&ids);
    sim.set_faults(Faults::none().vanish(3));
    let r = bus.sync_read(addr::PRESENT_POSITION, 2, &ids)?;
    assert_eq!((r.answered(), r.missing()), (3, 1));
    let missing = r.by_id(3).and_then(Result::err).expect("3 is missing");
    assert_eq!(
        (missing.reason, missing.attempts),
        (MissingReason::NoReply, 1)
    );
    let four = r.by_id(4).and_then(Result::ok).expect("4 answered");
    assert_eq!(le(four.data), 1400);
    assert_eq!(bus.servo_counters(3).timeouts, 1);
    assert_eq!(bus.servo_counters(4).timeouts, 0);

    // Re-asking within a budget asks only the missing servo, and stops at the
    // retry limit.
    let before = sim.stats().requests;
    let budget = Duration::from_millis(50);
    let r = bus.sync_read_within(addr::PRESENT_POSITION, 2, &ids, budget)?;
    assert_eq!(
        r.by_id(3).and_then(Result::err).map(|m| m.attempts),
        Some(3)
    );
    // One SYNC READ of all four, then two of servo 3 alone.
    assert_eq!(sim.stats().requests - before, 3);
    assert_eq!(bus.servo_counters(3).retries, 2);
    assert_eq!(bus.servo_counters(1).retries, 0);
    Ok(())
}

#[test]
fn sync_read_reask_recovers_dropped_replies_within_budget() -> Result<(), BusError> {
    let ids: Vec<u8> = (1..=6).collect();
    let (mut bus, sim) = setup(&ids);
    sim.set_faults(Faults::seeded(7).drop(0.3));
    let link = bus.link();
    let round = Transaction::SyncRead { servos: 6, len: 2 };
    let budget = link
        .deadline(round, Duration::ZERO, StatusLevel::All)
        .unwrap()
        * 4;
    let mut complete = 0;
    for _ in 0..50 {
        let t0 = bus.clock().now();
        let r = bus.sync_read_within(addr::PRESENT_POSITION, 2, &ids, budget)?;
        complete += usize::from(r.is_complete());
        assert!(bus.clock().now() - t0 <= budget);
    }
    // With 30 % loss, one shot completes 12 % of the time; three shots far more.
    assert!(complete > 30, "{complete}");
    assert!(bus.counters().retries > 0);
    Ok(())
}

#[test]
fn a_patient_read_waits_for_late_replies_and_leaves_the_settings_alone() -> Result<(), BusError> {
    let ids = [1, 2, 3];
    let (mut bus, sim) = setup(&ids);
    let settings = *bus.settings();
    // Replies 20 ms late: far beyond a cycle's timeout, within the patience.
    sim.set_faults(Faults::seeded(1).delay(1.0, Duration::from_millis(20)));
    assert_eq!(
        bus.sync_read(addr::PRESENT_POSITION, 2, &ids)?.answered(),
        0
    );
    // Let the late replies of that read pass before asking again.
    let later = bus.clock().now() + Duration::from_millis(50);
    bus.clock().sleep_until(later);
    bus.transport_mut()
        .discard_input()
        .map_err(BusError::Transport)?;
    let r = bus.sync_read_patiently(addr::PRESENT_POSITION, 2, &ids)?;
    assert!(r.is_complete());
    assert_eq!(*bus.settings(), settings);

    // A servo that never answers is asked PATIENT_TRIES times in all.
    sim.set_faults(Faults::none().vanish(2));
    let r = bus.sync_read_patiently(addr::PRESENT_POSITION, 2, &ids)?;
    assert_eq!(
        r.by_id(2).and_then(Result::err).map(|m| m.attempts),
        Some(servobus_driver::PATIENT_TRIES)
    );
    assert_eq!(r.answered(), 2);
    assert_eq!(*bus.settings(), settings);
    Ok(())
}

#[test]
fn retries_are_bounded_and_counted() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1]);
    sim.set_faults(Faults::seeded(3).drop(0.5));
    let mut ok = 0;
    for _ in 0..100 {
        ok += usize::from(bus.ping(1).is_ok());
    }
    let c = *bus.counters();
    // Three tries at 50 %: 87.5 % succeed.
    assert!(ok > 75, "{ok}");
    assert_eq!(c.transactions, 100);
    assert!(c.retries >= c.timeouts - c.failures);
    assert_eq!(c.failures, 100 - ok as u64);
    assert_eq!(c.timeouts, sim.stats().dropped);
    Ok(())
}

#[test]
fn echo_of_the_request_is_skipped() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1, 2, 3]);
    sim.set_faults(Faults::none().echo(true));
    let mut pos = [0u8; 2];
    bus.read(2, addr::PRESENT_POSITION, &mut pos)?;
    assert_eq!(le(&pos), 1200);
    let r = bus.sync_read(addr::PRESENT_POSITION, 2, &[1, 2, 3])?;
    assert!(r.is_complete());
    bus.sync_write(addr::ACCELERATION, &[1, 2, 3], &[1, 2, 3])?;
    assert!(bus.ping(3)?.is_ok());
    assert!(bus.counters().echoes >= 3);
    assert!(sim.stats().echoed_bytes > 0);
    assert_eq!(bus.counters().wrong_replies, 0);
    Ok(())
}

/// Rewrites the ID of replies from `from` to `to` (checksum fixed): a reply
/// that is valid but comes from the wrong servo.
struct Misroute {
    inner: SimBus,
    from: u8,
    to: u8,
}

impl Script for Misroute {
    fn write(&mut self, _clock: &ManualClock, bytes: &[u8]) -> Result<(), TransportError> {
        self.inner.write_all(bytes)
    }
    fn read(&mut self, _clock: &ManualClock, buf: &mut [u8], deadline: Duration) -> Received {
        let n = self.inner.read(buf, deadline)?;
        if let Ok((p, len)) = parse_frame(&buf[..n]) {
            if p.id() == self.from {
                buf[2] = self.to;
                buf[len - 1] = checksum(&buf[2..len - 1]);
            }
        }
        Ok(n)
    }
    fn discard(&mut self, _clock: &ManualClock) {
        // The simulated bus's input is memory: dropping it cannot fail.
        let _ = self.inner.discard_input();
    }
}

#[test]
fn a_reply_from_another_id_is_never_taken() {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos([servo(1), servo(2)]);
    let t = Misroute {
        inner: sim,
        from: 1,
        to: 2,
    };
    // The port shares the simulated bus's clock (a clone of it).
    let mut bus = Bus::new(ScriptedPort::new(&clock, t), BusSettings::new(Series::Sts));
    let mut pos = [0u8; 2];
    let err = bus.read(1, addr::PRESENT_POSITION, &mut pos).unwrap_err();
    assert!(
        matches!(
            err,
            BusError::WrongId {
                expected: 1,
                actual: 2
            }
        ),
        "{err}"
    );
    // In a SYNC READ the misrouted reply is not given to servo 2 either:
    // two frames claim ID 2, so neither is trusted; servo 1 is missing.
    let r = bus
        .sync_read(addr::PRESENT_POSITION, 2, &[1, 2])
        .expect("sync read");
    let reasons: Vec<_> = r.iter().map(|x| x.err().map(|m| m.reason)).collect();
    assert_eq!(
        reasons,
        [Some(MissingReason::NoReply), Some(MissingReason::Ambiguous)]
    );
    assert!(bus.counters().wrong_replies >= 3);
}

#[test]
fn a_late_reply_to_an_earlier_request_is_not_taken() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1, 2]);
    // Servo 2's reply comes 2 ms late, after its deadline.
    sim.set_faults(Faults::seeded(1).delay(1.0, Duration::from_millis(2)));
    bus.set_settings(bus.settings().with_retries(0));
    let mut pos = [0u8; 2];
    assert!(bus.read(2, addr::PRESENT_POSITION, &mut pos).is_err());
    sim.set_faults(Faults::none());
    bus.read(1, addr::PRESENT_POSITION, &mut pos)?;
    assert_eq!(le(&pos), 1100);
    Ok(())
}

#[test]
fn two_servos_with_one_id_collide() {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos([
        servo(5),
        SimServo::sts3215(5)
            .with_return_delay(Duration::ZERO)
            .with_position(3000),
    ]);
    let mut bus = Bus::new(sim.clone(), BusSettings::new(Series::Sts));
    // Identical PING replies may merge into one valid frame on a wired-AND
    // line; replies that differ (the positions) garble.
    let mut pos = [0u8; 2];
    let err = bus.read(5, addr::PRESENT_POSITION, &mut pos).unwrap_err();
    assert!(matches!(err, BusError::Corrupt { id: 5 }), "{err}");
    assert!(bus.counters().checksum_errors > 0);
    assert!(sim.stats().collided_bytes > 0);
}

#[test]
fn corrupt_bytes_are_counted_and_retried() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1]);
    sim.set_faults(Faults::seeded(11).corrupt(1.0));
    let err = bus.ping(1).unwrap_err();
    assert!(matches!(err, BusError::Corrupt { id: 1 }), "{err}");
    assert_eq!(bus.counters().failures, 1);
    sim.set_faults(Faults::seeded(11).corrupt(0.3));
    let mut pos = [0u8; 2];
    for _ in 0..20 {
        if bus.read(1, addr::PRESENT_POSITION, &mut pos).is_ok() {
            assert_eq!(le(&pos), 1100);
        }
    }
    let c = bus.counters();
    assert!(c.checksum_errors + c.discarded_bytes > 0);
    assert!(c.retries > 0);
    Ok(())
}

#[test]
fn eeprom_write_persists_and_plain_write_does_not() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1]);
    let reg = Series::Sts.map().get("max_temperature").expect("register");
    // A plain WRITE applies at once but is lost at power-off (lock closed).
    bus.write(1, reg.address, &[60])?;
    assert_eq!(sim.register(1, reg.address), Some(60));
    sim.power_cycle();
    assert_eq!(sim.register(1, reg.address), Some(70));
    // The transaction persists it and leaves the lock closed.
    let w = bus.write_eeprom(1, reg.address, &[65])?;
    assert_eq!(w.id, 1);
    assert_eq!(sim.register(1, addr::LOCK), Some(1));
    sim.power_cycle();
    assert_eq!(sim.register(1, reg.address), Some(65));
    Ok(())
}

#[test]
fn eeprom_id_change_relocks_at_the_new_id() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1, 2]);
    let w = bus.write_eeprom(1, addr::ID, &[7])?;
    assert_eq!(w.id, 7);
    assert!(bus.ping(7).is_ok());
    assert_eq!(sim.register(7, addr::LOCK), Some(1));
    assert!(sim.register(1, addr::ID).is_none());
    sim.power_cycle();
    assert!(bus.ping(7).is_ok());
    assert!(bus.ping(1).is_err());
    // The ID-write reply came from the old ID and was accepted: no
    // retries, no wrong replies.
    assert_eq!(bus.counters().wrong_replies, 0);
    Ok(())
}

#[test]
fn reply_timeouts_at_1mbps_are_a_few_milliseconds() -> Result<(), BusError> {
    // 1 Mbps, return delay 0, 1 ms adapter latency, default turnaround
    // (50 us) and margin (200 us).
    let link = Link::new(BAUD).with_latency(Duration::from_millis(1));
    let rd = Duration::ZERO;
    let us = |tx: Transaction| {
        link.deadline(tx, rd, StatusLevel::All)
            .map(|d| d.as_micros())
    };
    // PING: 6 + 6 bytes = 120 us on the wire.
    assert_eq!(us(Transaction::Ping), Some(120 + 50 + 1000 + 200));
    // READ of 2 bytes: 8 + 8 bytes.
    assert_eq!(
        us(Transaction::Read { len: 2 }),
        Some(160 + 50 + 1000 + 200)
    );
    // WRITE of 2 bytes: 9 + 6 bytes.
    assert_eq!(
        us(Transaction::Write { len: 2 }),
        Some(150 + 50 + 1000 + 200)
    );
    // SYNC READ of 2 bytes from 6 servos: 14 + 6 x 8 bytes, 6 turnarounds.
    let six = Transaction::SyncRead { servos: 6, len: 2 };
    assert_eq!(us(six), Some(620 + 300 + 1000 + 200));
    // From 18 servos: 26 + 18 x 8 bytes.
    let eighteen = Transaction::SyncRead { servos: 18, len: 2 };
    assert_eq!(us(eighteen), Some(1700 + 900 + 1000 + 200));

    // And the bus waits exactly that long for a servo that is not there.
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD);
    let settings = BusSettings::new(Series::Sts)
        .with_link(link.delays())
        .with_retries(0);
    let mut bus = Bus::new(sim, settings);
    let t0 = clock.now();
    let err = bus.ping(9).unwrap_err();
    assert!(
        matches!(err, BusError::Timeout { id: 9, waited } if waited == Duration::from_micros(1370))
    );
    assert_eq!(clock.now() - t0, Duration::from_micros(1370));
    let t0 = clock.now();
    let r = bus.sync_read(addr::PRESENT_POSITION, 2, &[1, 2, 3, 4, 5, 6])?;
    assert_eq!(r.missing(), 6);
    assert_eq!(clock.now() - t0, Duration::from_micros(2120));
    Ok(())
}

#[test]
fn measured_latency_matches_the_adapter() -> Result<(), BusError> {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD)
        .with_servo(servo(1))
        .with_latency(Duration::from_micros(800));
    let mut bus = Bus::new(sim, BusSettings::new(Series::Sts));
    let m = bus.measure_latency(1, 10, Duration::from_millis(20))?;
    assert_eq!(m.samples, 10);
    // By hand: each round trip is the wire both ways, the return delay, the
    // servo's turnaround of 50 us and the adapter's 800 us; the simulated
    // servo waits the same turnaround the measurement takes off (one model
    // on both sides), so 800 us, every time (virtual time).
    assert_eq!(m.min, Duration::from_micros(800), "{m:?}");
    assert_eq!(m.max, Duration::from_micros(800), "{m:?}");
    bus.set_latency(m.max);
    assert!(bus.ping(1).is_ok());
    Ok(())
}

#[test]
fn scs_servos_are_big_endian_and_read_one_by_one() -> Result<(), BusError> {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD)
        .with_servos([1, 2].map(|id| SimServo::scs0009(id).with_return_delay(Duration::ZERO)));
    let mut bus = Bus::new(sim.clone(), BusSettings::new(Series::Scs));
    let reg = Series::Scs.map().get("model_number").expect("register");
    let (model, _) = bus.read_register(1, reg)?;
    let number = sim.snapshot(1).map(|s| s.model().model.number);
    assert_eq!(Some(model), number.map(i32::from));
    let r = bus.sync_read(addr::PRESENT_POSITION, 2, &[1, 2])?;
    assert!(r.is_complete());
    // The EEPROM transaction uses the SCS lock register (48).
    bus.write_eeprom(2, addr::ID, &[3])?;
    assert!(bus.ping(3).is_ok());
    Ok(())
}

/// A servo with the voltage flag alone, on a port that does not echo: its
/// PING reply is the PING's own bytes. The first PING on a fresh bus cannot
/// tell that copy from an echo; it asks the servo for one byte, learns the
/// port does not echo, and takes the copy as the reply: no timeout, no
/// retry. From then on a PING is answered at the first wait.
#[test]
fn a_port_that_does_not_echo_takes_a_ping_reply_identical_to_the_request() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1, 2]);
    sim.servo(2, |s| s.set_supply_voltage(Some(30)));
    assert_eq!(bus.port_echoes(), None);
    assert_eq!(bus.ping(2)?.0, 0x01);
    assert_eq!(bus.port_echoes(), Some(false));
    let c = *bus.counters();
    assert_eq!((c.timeouts, c.retries, c.failures), (0, 0, 0), "{c:?}");
    // Known now: the next PING is one exchange, well under a millisecond
    // at 1 Mbaud (a wait to the deadline would be longer).
    let before = bus.clock().now();
    assert_eq!(bus.ping(2)?.0, 0x01);
    let took = bus.clock().now() - before;
    assert!(took < Duration::from_micros(400), "{took:?}");
    assert_eq!(bus.counters().echoes, c.echoes);
    // A servo that is not there is still not there.
    assert!(bus.ping(3).is_err_and(|e| e.is_timeout()));
    Ok(())
}

/// Replies with no copy of the request before them teach the bus that the
/// port does not echo; a copy of a WRITE (which no servo sends back) that
/// it does.
#[test]
fn the_bus_learns_whether_its_port_echoes_from_the_traffic() -> Result<(), BusError> {
    let (mut bus, _sim) = setup(&[1]);
    let mut pos = [0u8; 2];
    for _ in 0..3 {
        assert_eq!(bus.port_echoes(), None);
        bus.read(1, addr::PRESENT_POSITION, &mut pos)?;
    }
    assert_eq!(bus.port_echoes(), Some(false));

    let (mut bus, sim) = setup(&[1]);
    sim.set_faults(Faults::none().echo(true));
    bus.write(1, addr::ACCELERATION, &[5])?;
    assert_eq!(bus.port_echoes(), Some(true));
    for _ in 0..5 {
        bus.read(1, addr::PRESENT_POSITION, &mut pos)?;
    }
    assert_eq!(bus.port_echoes(), Some(true));
    assert_eq!(bus.counters().wrong_replies, 0);
    Ok(())
}

/// Behind an echoing adapter a missing servo's PING comes back as its
/// echo alone: that copy is never taken for a reply, whether the bus has
/// learned the port echoes yet or not. A servo with the voltage flag
/// answers after the echo, and that second copy is its reply.
#[test]
fn an_echoing_adapter_never_answers_for_a_missing_servo() -> Result<(), BusError> {
    for learned in [false, true] {
        let (mut bus, sim) = setup(&[1, 2]);
        sim.set_faults(Faults::none().echo(true));
        sim.servo(2, |s| s.set_supply_voltage(Some(30)));
        if learned {
            bus.write(1, addr::ACCELERATION, &[5])?;
            assert_eq!(bus.port_echoes(), Some(true));
        }
        for _ in 0..3 {
            let r = bus.ping(7);
            assert!(
                r.as_ref().is_err_and(|e| e.is_timeout()),
                "learned {learned}: {r:?}"
            );
        }
        assert_eq!(bus.port_echoes(), Some(true), "learned {learned}");
        let before = bus.counters().retries;
        assert_eq!(bus.ping(2)?.0, 0x01, "learned {learned}");
        assert_eq!(bus.counters().retries, before, "learned {learned}");
        assert!(bus.ping(1)?.is_ok());
    }
    Ok(())
}

/// With echo handling turned off in the settings nothing is skipped and
/// nothing is learned: the voltage-flagged PING is answered first try.
#[test]
fn with_echo_off_a_ping_reply_identical_to_the_request_is_taken_at_once() -> Result<(), BusError> {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos([servo(2)]);
    sim.servo(2, |s| s.set_supply_voltage(Some(30)));
    let settings = BusSettings::new(Series::Sts)
        .with_retries(2)
        .with_echo(false);
    let mut bus = Bus::new(sim.clone(), settings);
    assert_eq!(bus.ping(2)?.0, 0x01);
    let c = *bus.counters();
    assert_eq!((c.timeouts, c.retries, c.echoes), (0, 0, 0), "{c:?}");
    assert_eq!(bus.port_echoes(), None);
    Ok(())
}

/// A servo whose only status flag is the voltage one (0x01) answers a PING
/// with the PING's own bytes, which the driver skips as the adapter's echo:
/// the ping must still find it, with its flag.
#[test]
fn a_ping_answered_with_the_requests_own_bytes_still_finds_the_servo() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1, 2]);
    // 3.0 V, under the factory minimum voltage: the voltage flag alone.
    sim.servo(2, |s| s.set_supply_voltage(Some(30)));
    let flags = bus.ping(2)?;
    assert_eq!(flags.0, 0x01, "{flags:?}");
    // A servo that is not there is still silent.
    assert!(bus.ping(3).is_err_and(|e| e.is_timeout()));
    // The others answer as before.
    assert!(bus.ping(1)?.is_ok());
    Ok(())
}
