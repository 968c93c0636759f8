//! Fault injection: what goes wrong on the simulated bus, drawn from a
//! seeded random source so that every run with the same seed is identical.

use std::time::Duration;

use crate::{addr, SimServo};

mod spec;

pub use spec::FaultSpecError;

/// The faults a [`SimBus`](crate::SimBus) (or the pty server) injects.
///
/// Probabilities apply to each reply a servo sends, independently. Build it
/// with the methods, or parse the `--faults` syntax of `servobus sim`:
///
/// ```
/// use servobus_sim::Faults;
///
/// let f: Faults = "drop=0.01,corrupt=0.01,seed=7,vanish=3".parse().unwrap();
/// assert_eq!(f, Faults::seeded(7).drop(0.01).corrupt(0.01).vanish(3));
/// ```
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Faults {
    /// Seed of the random source.
    pub seed: u64,
    /// Probability that a reply is never sent (the servo executed the
    /// instruction but did not answer).
    pub drop: f64,
    /// Probability that one byte of a reply is corrupted.
    pub corrupt: f64,
    /// Probability that a reply starts late, by [`Faults::delay_by`].
    pub delay: f64,
    /// How late a delayed reply starts.
    pub delay_by: Duration,
    /// Probability that a reply reaches the host late, by
    /// [`Faults::hold_by`]: it left the servo on time, but the host's side
    /// held it (a loaded machine descheduling the reader, a USB adapter's
    /// latency spike, the kernel's hand-off on a pseudo-terminal). Its
    /// bytes stay in order, and nothing behind them is readable earlier.
    pub hold: f64,
    /// How long a held reply is held.
    pub hold_by: Duration,
    /// Echo every request back to the host, as a half-duplex adapter
    /// without direction control does.
    pub echo: bool,
    /// IDs of servos that are disconnected (hear and answer nothing).
    pub vanish: Vec<u8>,
    /// Servos that disconnect during a run: `(id, after)` answers until
    /// `after` has passed since the bus heard its first byte (a cable
    /// working loose mid-motion), then stays silent.
    pub vanish_after: Vec<(u8, Duration)>,
    /// IDs of servos whose shaft is mechanically blocked.
    pub block: Vec<u8>,
    /// IDs of servos that start at their temperature limit (overheat).
    pub overheat: Vec<u8>,
    /// Supply voltages in 0.1 V: for one servo (`Some(id)`) or for every
    /// servo (`None`, applied first so that a servo's own entry wins).
    pub supply: Vec<(Option<u8>, u8)>,
    /// Servos reporting another firmware version: `(id, (major, minor))`.
    pub firmware: Vec<(u8, (u8, u8))>,
    /// Servos whose baud-rate register (6) holds another index:
    /// `(id, index)`; they hear the bus only at that rate.
    pub baud: Vec<(u8, u8)>,
    /// Servos given another servo's ID: `(from, to)` makes servo `from`
    /// answer as `to`, so two servos share ID `to` (applied last).
    pub duplicate: Vec<(u8, u8)>,
}

impl Default for Faults {
    /// No faults (the same as [`Faults::none`]).
    fn default() -> Faults {
        Faults::none()
    }
}

impl Faults {
    /// Default delay of a delayed reply: 2 ms, beyond any derived timeout at 1 Mbps.
    pub const DEFAULT_DELAY: Duration = Duration::from_millis(2);

    /// No faults.
    pub fn none() -> Faults {
        Faults {
            seed: 0,
            drop: 0.0,
            corrupt: 0.0,
            delay: 0.0,
            delay_by: Self::DEFAULT_DELAY,
            hold: 0.0,
            hold_by: Self::DEFAULT_DELAY,
            echo: false,
            vanish: Vec::new(),
            vanish_after: Vec::new(),
            block: Vec::new(),
            overheat: Vec::new(),
            supply: Vec::new(),
            firmware: Vec::new(),
            baud: Vec::new(),
            duplicate: Vec::new(),
        }
    }

    /// No faults yet, with the random source seeded with `seed`.
    pub fn seeded(seed: u64) -> Faults {
        Faults {
            seed,
            ..Faults::none()
        }
    }

    /// The same faults with replies dropped with probability `p`.
    #[must_use]
    pub fn drop(mut self, p: f64) -> Faults {
        self.drop = p;
        self
    }

    /// The same faults with one byte of a reply corrupted with probability `p`.
    #[must_use]
    pub fn corrupt(mut self, p: f64) -> Faults {
        self.corrupt = p;
        self
    }

    /// The same faults with replies delayed by `by` with probability `p`.
    #[must_use]
    pub fn delay(mut self, p: f64, by: Duration) -> Faults {
        self.delay = p;
        self.delay_by = by;
        self
    }

    /// The same faults with replies held on the host's side by `by` with
    /// probability `p` (see [`Faults::hold`]).
    #[must_use]
    pub fn hold(mut self, p: f64, by: Duration) -> Faults {
        self.hold = p;
        self.hold_by = by;
        self
    }

    /// The same faults with request echo on or off.
    #[must_use]
    pub fn echo(mut self, on: bool) -> Faults {
        self.echo = on;
        self
    }

    /// The same faults with servo `id` disconnected.
    #[must_use]
    pub fn vanish(mut self, id: u8) -> Faults {
        self.vanish.push(id);
        self
    }

    /// The same faults with servo `id` disconnecting once `after` has passed
    /// since the bus heard its first byte.
    #[must_use]
    pub fn vanish_after(mut self, id: u8, after: Duration) -> Faults {
        self.vanish_after.push((id, after));
        self
    }

    /// The same faults with servo `id`'s shaft blocked.
    #[must_use]
    pub fn block(mut self, id: u8) -> Faults {
        self.block.push(id);
        self
    }

    /// The same faults with servo `id` at its temperature limit.
    #[must_use]
    pub fn overheat(mut self, id: u8) -> Faults {
        self.overheat.push(id);
        self
    }

    /// The same faults with servo `id`'s supply (or every servo's, for
    /// `None`) at `decivolts` (0.1 V units).
    #[must_use]
    pub fn supply(mut self, id: Option<u8>, decivolts: u8) -> Faults {
        self.supply.push((id, decivolts));
        self
    }

    /// The same faults with servo `id` reporting firmware `major.minor`.
    #[must_use]
    pub fn firmware(mut self, id: u8, major: u8, minor: u8) -> Faults {
        self.firmware.push((id, (major, minor)));
        self
    }

    /// The same faults with servo `id` listening at baud-rate index `index`
    /// (see [`baud_rate`](servobus_protocol::registers::baud_rate)).
    #[must_use]
    pub fn baud(mut self, id: u8, index: u8) -> Faults {
        self.baud.push((id, index));
        self
    }

    /// The same faults with servo `from` answering as ID `to`.
    #[must_use]
    pub fn duplicate(mut self, from: u8, to: u8) -> Faults {
        self.duplicate.push((from, to));
        self
    }

    /// Puts the faults that are states of a servo rather than of a reply
    /// (disconnected, blocked, hot, supply, firmware, baud rate, ID) into
    /// `servo`. Saved registers (baud rate, ID) are written to its EEPROM,
    /// as a set-up tool would have left them.
    pub(crate) fn apply_to(&self, servo: &mut SimServo) {
        let id = servo.id();
        if self.vanish.contains(&id) {
            servo.set_offline(true);
        }
        if self.block.contains(&id) {
            servo.set_blocked(true);
        }
        if self.overheat.contains(&id) {
            let limit = f64::from(servo.register(addr::MAX_TEMPERATURE));
            servo.set_temperature(limit, limit);
        }
        let supply = self.supply.iter().filter(|s| s.0.is_none());
        for (_, dv) in supply.chain(self.supply.iter().filter(|s| s.0 == Some(id))) {
            servo.set_supply_voltage(Some(*dv));
        }
        for (_, (major, minor)) in self.firmware.iter().filter(|f| f.0 == id) {
            servo.poke(addr::FIRMWARE_MAJOR, &[*major, *minor]);
        }
        for (_, index) in self.baud.iter().filter(|b| b.0 == id) {
            *servo = servo.clone().with_byte(addr::BAUD_RATE, *index);
        }
        for (_, to) in self.duplicate.iter().filter(|d| d.0 == id) {
            *servo = servo.clone().with_byte(addr::ID, *to);
        }
    }

    /// Whether any reply can be altered (so the random source is used).
    pub fn any_random(&self) -> bool {
        self.drop > 0.0 || self.corrupt > 0.0 || self.delay > 0.0 || self.hold > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_parses_every_key_and_refuses_nonsense() {
        let f: Faults =
            "drop=0.5, corrupt=0.25,delay=0.1,delay_us=300,hold=0.2,hold_us=700,seed=9,echo,block=2,overheat=4"
                .parse()
                .unwrap();
        assert_eq!(
            f,
            Faults::seeded(9)
                .drop(0.5)
                .corrupt(0.25)
                .delay(0.1, Duration::from_micros(300))
                .hold(0.2, Duration::from_micros(700))
                .echo(true)
                .block(2)
                .overheat(4)
        );
        assert_eq!("".parse::<Faults>(), Ok(Faults::none()));
        assert!(matches!(
            "drop=2".parse::<Faults>(),
            Err(FaultSpecError::BadValue { .. })
        ));
        assert!(matches!(
            "vanish=254".parse::<Faults>(),
            Err(FaultSpecError::BadValue { .. })
        ));
        assert!(matches!(
            "explode=1".parse::<Faults>(),
            Err(FaultSpecError::UnknownKey { .. })
        ));
    }

    #[test]
    fn servo_state_faults_parse_and_refuse_nonsense() {
        let f: Faults = "supply=5.5,supply=3:13.1,firmware=2:3.9,baud=4:115200,duplicate=6:5"
            .parse()
            .unwrap();
        assert_eq!(
            f,
            Faults::none()
                .supply(None, 55)
                .supply(Some(3), 131)
                .firmware(2, 3, 9)
                .baud(4, 4)
                .duplicate(6, 5)
        );
        for bad in [
            "supply=30",
            "supply=x:5",
            "firmware=2:3",
            "baud=4:9600",
            "duplicate=6",
        ] {
            assert!(
                matches!(bad.parse::<Faults>(), Err(FaultSpecError::BadValue { .. })),
                "{bad}"
            );
        }
    }

    #[test]
    fn servo_state_faults_change_the_servo() {
        let faults = Faults::none()
            .supply(None, 55)
            .supply(Some(1), 131)
            .firmware(1, 3, 9)
            .baud(1, 4)
            .duplicate(1, 7);
        let mut one = SimServo::sts3215(1);
        faults.apply_to(&mut one);
        assert_eq!(one.register(addr::PRESENT_VOLTAGE), 131);
        assert_eq!(
            (one.register(addr::FIRMWARE_MAJOR), one.register(1)),
            (3, 9)
        );
        assert_eq!((one.baud_index(), one.id()), (4, 7));
        // EEPROM faults survive a power cycle, as a set-up tool's would.
        one.power_cycle();
        assert_eq!((one.baud_index(), one.id()), (4, 7));
        let mut two = SimServo::sts3215(2);
        faults.apply_to(&mut two);
        assert_eq!(two.register(addr::PRESENT_VOLTAGE), 55);
        assert_eq!((two.baud_index(), two.id()), (0, 2));
    }
}
