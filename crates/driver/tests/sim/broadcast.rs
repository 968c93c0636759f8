//! The broadcast PING ([`Bus::anyone_answers`]): heard at a rate where
//! servos listen, whether one or many answer and whether the adapter
//! echoes; silence at a rate where none does; and the line left quiet for
//! the next request. In virtual time, on the simulator.

use std::time::Duration;

use servobus_driver::{Bus, BusError, BusSettings, Clock, ManualClock};
use servobus_protocol::registers::{addr, Series};
use servobus_sim::SimBus;

use super::{servo, BAUD};

const LISTEN: Duration = Duration::from_millis(40);

#[test]
fn a_broadcast_ping_is_heard_where_servos_listen_and_not_elsewhere() -> Result<(), BusError> {
    for echo in [false, true] {
        let clock = ManualClock::new();
        // Three servos at 1 Mbps; none at 115200.
        let sim = SimBus::new(clock.clone(), BAUD)
            .with_servos([servo(1), servo(2), servo(3)])
            .with_echo(echo);
        let settings = BusSettings::new(Series::Sts)
            .with_retries(0)
            .with_echo(echo);
        let mut bus = Bus::new(sim.clone(), settings);

        let t0 = clock.now();
        assert!(bus.anyone_answers(LISTEN)?, "echo {echo}: three servos");
        // It listened on until the line was quiet for LISTEN after the
        // last reply (three replies of 6 bytes follow each other within a
        // millisecond), and no longer.
        let took = clock.now() - t0;
        assert!(
            took >= LISTEN && took < LISTEN + Duration::from_millis(5),
            "{took:?}"
        );
        // The next request starts on a quiet line: servo 2 answers its own
        // PING, no stray reply is taken for it.
        assert!(bus.ping(2)?.is_ok());
        let mut pos = [0u8; 2];
        bus.read(3, addr::PRESENT_POSITION, &mut pos)?;
        assert_eq!(u16::from_le_bytes(pos), 1300);

        bus.set_baud(115_200)?;
        let t0 = clock.now();
        assert!(
            !bus.anyone_answers(LISTEN)?,
            "echo {echo}: nobody at 115200"
        );
        // Silence costs the first-byte wait only.
        let took = clock.now() - t0;
        assert!(
            took >= LISTEN && took < LISTEN + Duration::from_millis(2),
            "{took:?}"
        );
    }
    Ok(())
}

#[test]
fn one_servo_answers_a_broadcast_ping_and_an_empty_bus_does_not() -> Result<(), BusError> {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos([servo(7)]);
    let mut bus = Bus::new(sim.clone(), BusSettings::new(Series::Sts));
    assert!(bus.anyone_answers(Duration::ZERO)?, "one servo");
    let empty = SimBus::new(clock.clone(), BAUD);
    let mut bus = Bus::new(empty, BusSettings::new(Series::Sts));
    assert!(!bus.anyone_answers(Duration::ZERO)?, "no servo");
    Ok(())
}
