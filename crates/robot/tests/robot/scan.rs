//! A scan on the simulator in virtual time: each servo at its own baud
//! rate, its model and firmware read, and an adapter slower than assumed
//! caught.

use std::time::Duration;

use servobus_driver::scripted::{Received, Script, ScriptedPort};
use servobus_driver::{Bus, BusSettings, ManualClock, Transport, TransportError};
use servobus_protocol::parse_frame;
use servobus_protocol::registers::{addr, Series};
use servobus_robot::scan::{scan, table_bauds, ScanError, SlowLink};
use servobus_sim::{Faults, SimBus, SimServo};

/// An STS3215 that answers at once (no return delay).
fn sts(id: u8) -> SimServo {
    SimServo::sts3215(id).with_return_delay(Duration::ZERO)
}

fn bus(sim: &SimBus) -> Bus<SimBus> {
    Bus::new(sim.clone(), BusSettings::new(Series::Sts))
}

#[test]
fn each_servo_is_found_at_its_own_baud_rate_and_identified() -> Result<(), ScanError> {
    // Servo 2's baud-rate register holds index 4: 115200 baud.
    let sim = SimBus::new(ManualClock::new(), 1_000_000).with_servos([
        sts(1).with_position(1000),
        sts(2).with_byte(addr::BAUD_RATE, 4),
        SimServo::scs0009(7),
    ]);
    let mut bus = bus(&sim);
    let found = scan(&mut bus, &[1_000_000, 115_200], false)?;
    let at: Vec<(u8, u32)> = found.found.iter().map(|f| (f.id, f.baud)).collect();
    assert_eq!(at, [(1, 1_000_000), (7, 1_000_000), (2, 115_200)]);
    assert!(found.collisions.is_empty());
    assert_eq!(found.slow, None);
    let first = &found.found[0];
    assert_eq!(first.model.map(|m| m.name), Some("STS3215"));
    assert_eq!(first.position, Some(1000));
    assert_eq!(found.found[1].model.map(|m| m.name), Some("SCS0009"));
    // The port is left at the last rate asked.
    assert_eq!(sim.baud(), 115_200);
    Ok(())
}

#[test]
fn the_table_has_eight_rates_fastest_first() {
    assert_eq!(
        table_bauds(),
        [1_000_000, 500_000, 250_000, 128_000, 115_200, 76_800, 57_600, 38_400]
    );
}

#[test]
fn an_adapter_slower_than_assumed_is_reported_and_the_silent_ids_asked_again(
) -> Result<(), ScanError> {
    // 150 us of adapter latency each way; the bus assumes none, and its
    // margin lets the first pass hear the servo anyway.
    let sim = SimBus::new(ManualClock::new(), 1_000_000)
        .with_latency(Duration::from_micros(150))
        .with_servos([sts(3)]);
    let mut bus = bus(&sim);
    let found = scan(&mut bus, &[1_000_000], true)?;
    let Some(SlowLink { measured, assumed }) = found.slow else {
        panic!("the slow adapter is reported: {found:?}");
    };
    assert_eq!(assumed, Duration::ZERO);
    assert!(measured >= Duration::from_micros(150), "{measured:?}");
    assert_eq!(found.found.len(), 1);
    assert_eq!(found.found[0].id, 3);
    Ok(())
}

#[test]
fn servos_whose_replies_come_late_are_asked_again_and_found() -> Result<(), ScanError> {
    // A loaded machine: replies now and then reach the host after their
    // deadline. Each servo that answered late is asked again; none is lost.
    let ids = [1u8, 2, 3, 5, 8, 13];
    for seed in 0..6 {
        let faults = Faults::seeded(seed).hold(0.3, Duration::from_micros(400));
        let sim = SimBus::new(ManualClock::new(), 1_000_000)
            .with_servos(ids.map(sts))
            .with_faults(faults);
        let mut bus = bus(&sim);
        let found = scan(&mut bus, &[1_000_000], false)?;
        let got: Vec<u8> = found.found.iter().map(|f| f.id).collect();
        assert_eq!(got, ids, "seed {seed}: {found:?}");
        assert!(found.collisions.is_empty(), "seed {seed}: {found:?}");
    }
    Ok(())
}

/// Garbles the first `left` replies from servo `id` (a flipped checksum
/// byte), as noise on a line that has just come up does.
struct GarbleFirst {
    inner: SimBus,
    id: u8,
    left: usize,
}

impl Script for GarbleFirst {
    fn write(&mut self, _clock: &ManualClock, bytes: &[u8]) -> Result<(), TransportError> {
        self.inner.write_all(bytes)
    }
    fn read(&mut self, _clock: &ManualClock, buf: &mut [u8], deadline: Duration) -> Received {
        let n = self.inner.read(buf, deadline)?;
        if self.left > 0 {
            if let Ok((p, len)) = parse_frame(&buf[..n]) {
                if p.id() == self.id {
                    buf[len - 1] ^= 0xFF;
                    self.left -= 1;
                }
            }
        }
        Ok(n)
    }
    fn discard(&mut self, _clock: &ManualClock) {
        // The simulated bus's input is memory: dropping it cannot fail.
        let _ = self.inner.discard_input();
    }
}

/// One garbled reply is noise, not two servos sharing an ID: the ID is
/// asked again and the servo found. Garbled at every ask, it is a collision.
#[test]
fn one_garbled_reply_is_asked_again_and_a_collision_takes_more() -> Result<(), ScanError> {
    for (garbles, collision) in [(1, false), (2, true), (usize::MAX, true)] {
        let clock = ManualClock::new();
        let sim = SimBus::new(clock.clone(), 1_000_000).with_servos([1, 4, 6].map(sts));
        let port = ScriptedPort::new(
            &clock,
            GarbleFirst {
                inner: sim,
                id: 4,
                left: garbles,
            },
        );
        let mut bus = Bus::new(port, BusSettings::new(Series::Sts));
        let found = scan(&mut bus, &[1_000_000], false)?;
        let got: Vec<u8> = found.found.iter().map(|f| f.id).collect();
        if collision {
            assert_eq!(got, [1, 6], "{garbles} garbled: {found:?}");
            assert_eq!(found.collisions, [(4, 1_000_000)], "{garbles} garbled");
        } else {
            assert_eq!(got, [1, 4, 6], "{garbles} garbled: {found:?}");
            assert!(found.collisions.is_empty(), "{garbles} garbled: {found:?}");
        }
    }
    Ok(())
}

/// Two servos that really share an ID are still a collision, however often
/// they are asked.
#[test]
fn two_servos_sharing_an_id_are_a_collision() -> Result<(), ScanError> {
    let sim = SimBus::new(ManualClock::new(), 1_000_000).with_servos([
        sts(1),
        sts(4).with_position(0x0F0F),
        sts(4).with_position(0x00F0),
        sts(6),
    ]);
    let mut bus = bus(&sim);
    let found = scan(&mut bus, &[1_000_000], false)?;
    let got: Vec<u8> = found.found.iter().map(|f| f.id).collect();
    assert_eq!(got, [1, 6], "{found:?}");
    assert_eq!(found.collisions, [(4, 1_000_000)], "{found:?}");
    Ok(())
}
