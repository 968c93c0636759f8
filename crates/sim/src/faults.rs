//! Fault injection: what goes wrong on the simulated bus, drawn from a
//! seeded random source so that every run with the same seed is identical.

use std::str::FromStr;
use std::time::Duration;

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
    /// Echo every request back to the host, as a half-duplex adapter
    /// without direction control does.
    pub echo: bool,
    /// IDs of servos that are disconnected (hear and answer nothing).
    pub vanish: Vec<u8>,
    /// IDs of servos whose shaft is mechanically blocked.
    pub block: Vec<u8>,
    /// IDs of servos that start at their temperature limit (overheat).
    pub overheat: Vec<u8>,
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
            echo: false,
            vanish: Vec::new(),
            block: Vec::new(),
            overheat: Vec::new(),
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

    /// Whether any reply can be altered (so the random source is used).
    pub fn any_random(&self) -> bool {
        self.drop > 0.0 || self.corrupt > 0.0 || self.delay > 0.0
    }
}

/// Why a `--faults` specification was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FaultSpecError {
    /// A key the syntax does not have.
    #[error("unknown fault `{key}` (known: drop, corrupt, delay, delay_us, seed, echo, vanish, block, overheat)")]
    UnknownKey {
        /// The key as written.
        key: String,
    },
    /// A value that does not parse or is out of range.
    #[error("bad value `{value}` for `{key}`: {expected}")]
    BadValue {
        /// The key.
        key: String,
        /// The value as written.
        value: String,
        /// What was expected.
        expected: &'static str,
    },
}

impl FromStr for Faults {
    type Err = FaultSpecError;

    /// Parses `key=value` items separated by commas:
    /// `drop=P`, `corrupt=P`, `delay=P` (probabilities 0..=1), `delay_us=N`,
    /// `seed=N`, `echo` (or `echo=true`), and `vanish=ID`, `block=ID`,
    /// `overheat=ID` (repeatable). An empty string means no faults.
    fn from_str(spec: &str) -> Result<Faults, FaultSpecError> {
        let mut f = Faults::none();
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (key, value) = item.split_once('=').unwrap_or((item, ""));
            let (key, value) = (key.trim(), value.trim());
            let bad = |expected| FaultSpecError::BadValue {
                key: key.to_owned(),
                value: value.to_owned(),
                expected,
            };
            let prob = || -> Result<f64, FaultSpecError> {
                match value.parse::<f64>() {
                    Ok(p) if (0.0..=1.0).contains(&p) => Ok(p),
                    _ => Err(bad("a probability between 0 and 1")),
                }
            };
            let id = || -> Result<u8, FaultSpecError> {
                match value.parse::<u8>() {
                    Ok(id) if id <= servobus_protocol::MAX_ID => Ok(id),
                    _ => Err(bad("a servo ID 0..=253")),
                }
            };
            match key {
                "drop" => f.drop = prob()?,
                "corrupt" => f.corrupt = prob()?,
                "delay" => f.delay = prob()?,
                "delay_us" => {
                    let us = value.parse::<u64>().map_err(|_| bad("microseconds"))?;
                    f.delay_by = Duration::from_micros(us);
                }
                "seed" => f.seed = value.parse().map_err(|_| bad("an unsigned integer"))?,
                "echo" => {
                    f.echo = match value {
                        "" | "1" | "true" | "on" => true,
                        "0" | "false" | "off" => false,
                        _ => return Err(bad("true or false")),
                    }
                }
                "vanish" => f.vanish.push(id()?),
                "block" => f.block.push(id()?),
                "overheat" => f.overheat.push(id()?),
                _ => {
                    return Err(FaultSpecError::UnknownKey {
                        key: key.to_owned(),
                    })
                }
            }
        }
        Ok(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_parses_every_key_and_refuses_nonsense() {
        let f: Faults =
            "drop=0.5, corrupt=0.25,delay=0.1,delay_us=300,seed=9,echo,block=2,overheat=4"
                .parse()
                .unwrap();
        assert_eq!(
            f,
            Faults::seeded(9)
                .drop(0.5)
                .corrupt(0.25)
                .delay(0.1, Duration::from_micros(300))
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
}
