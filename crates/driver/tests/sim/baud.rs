//! Changing a bus's baud rate: [`Bus::set_baud`] moves the transport and
//! the deadlines together, and a scan across rates finds each servo at its
//! own.

use std::time::Duration;

use servobus_driver::scripted::ScriptedPort;
use servobus_driver::{Bus, BusError, BusSettings, Clock, ManualClock, TransportError};
use servobus_protocol::registers::{addr, Series};
use servobus_sim::SimBus;

use super::{servo, Misroute, BAUD};

/// A scan across two baud rates through [`Bus::set_baud`]: servo 1 listens
/// at 1 Mbps, servo 2 at 115200 (baud-rate register 6 = index 4), and each
/// is heard at its own rate only. The port and the deadlines move together.
#[test]
fn a_scan_across_two_baud_rates_finds_each_servo_at_its_own() -> Result<(), BusError> {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD)
        .with_servos([servo(1), servo(2).with_byte(addr::BAUD_RATE, 4)]);
    let mut bus = Bus::new(sim.clone(), BusSettings::new(Series::Sts).with_retries(0));
    let mut found = Vec::new();
    for baud in [1_000_000, 115_200] {
        bus.set_baud(baud)?;
        assert_eq!(
            (sim.baud(), bus.baud(), bus.link().baud),
            (baud, baud, baud)
        );
        for id in 1..=2 {
            if bus.ping(id).is_ok() {
                found.push((id, baud));
            }
        }
    }
    assert_eq!(found, [(1, 1_000_000), (2, 115_200)]);

    // The deadline is the one of 115200 baud: a PING of 6 bytes and its
    // reply of 6, each 60 bits = 520 834 ns (rounded up), plus the 50 us
    // turnaround and the 200 us margin, no adapter latency.
    let t0 = clock.now();
    let err = bus.ping(3).unwrap_err();
    let waited = Duration::from_nanos(2 * 520_834 + 50_000 + 200_000);
    assert!(
        matches!(err, BusError::Timeout { id: 3, waited: w } if w == waited),
        "{err:?}"
    );
    assert_eq!(clock.now() - t0, waited);

    // Settings saved at one rate and put back at another keep the rate the
    // transport is at: the baud rate is not theirs to change.
    let saved = *bus.settings();
    bus.set_baud(1_000_000)?;
    bus.set_settings(saved.with_retries(1));
    assert_eq!((bus.baud(), sim.baud()), (1_000_000, 1_000_000));
    assert!(bus.ping(1).is_ok());

    // A rate of 0 is refused and changes nothing.
    let err = bus.set_baud(0).unwrap_err();
    assert!(
        matches!(
            err,
            BusError::Transport(TransportError::BaudRefused {
                requested: 0,
                current: 1_000_000
            })
        ),
        "{err:?}"
    );
    assert_eq!(bus.baud(), 1_000_000);
    Ok(())
}

/// A transport whose rate is fixed refuses a switch, and the bus stays at
/// its rate.
#[test]
fn a_fixed_rate_transport_refuses_a_switch() {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servo(servo(1));
    let t = Misroute {
        inner: sim,
        from: 9,
        to: 9,
    };
    let mut bus = Bus::new(ScriptedPort::new(&clock, t), BusSettings::new(Series::Sts));
    let err = bus.set_baud(115_200).unwrap_err();
    assert!(
        matches!(
            err,
            BusError::Transport(TransportError::BaudRefused {
                requested: 115_200,
                current: BAUD
            })
        ),
        "{err:?}"
    );
    assert_eq!(bus.baud(), BAUD);
    assert!(bus.ping(1).is_ok());
}
