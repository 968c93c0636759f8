//! The `--faults` syntax of `servobus sim`: parsing a specification into
//! [`Faults`], and why one is refused.

use std::str::FromStr;
use std::time::Duration;

use super::Faults;

/// Why a `--faults` specification was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FaultSpecError {
    /// A key the syntax does not have.
    #[error("unknown fault `{key}` (known: drop, corrupt, delay, delay_us, hold, hold_us, seed, echo, vanish, block, overheat, supply, firmware, baud, duplicate)")]
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
    /// `drop=P`, `corrupt=P`, `delay=P`, `hold=P` (probabilities 0..=1),
    /// `delay_us=N`, `hold_us=N`,
    /// `seed=N`, `echo` (or `echo=true`), and `vanish=ID` (or `vanish=ID@SECONDS`:
    /// silent from that long after the bus's first byte), `block=ID`,
    /// `overheat=ID` (repeatable); `supply=V` (every servo) or
    /// `supply=ID:V` (volts), `firmware=ID:MAJOR.MINOR`, `baud=ID:RATE`
    /// (a rate of the servo baud table) and `duplicate=FROM:TO`
    /// (repeatable). An empty string means no faults.
    fn from_str(spec: &str) -> Result<Faults, FaultSpecError> {
        let mut f = Faults::none();
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            f.add_item(SpecItem::split(item))?;
        }
        Ok(f)
    }
}

impl Faults {
    /// Adds the fault of one `key=value` item of the `--faults` syntax.
    fn add_item(&mut self, item: SpecItem<'_>) -> Result<(), FaultSpecError> {
        match item.key {
            "drop" => self.drop = item.probability()?,
            "corrupt" => self.corrupt = item.probability()?,
            "delay" => self.delay = item.probability()?,
            "delay_us" => self.delay_by = item.micros()?,
            "hold" => self.hold = item.probability()?,
            "hold_us" => self.hold_by = item.micros()?,
            "seed" => {
                self.seed = item
                    .value
                    .parse()
                    .map_err(|_| item.bad("an unsigned integer"))?;
            }
            "echo" => self.echo = item.switch()?,
            "vanish" => match item.value.split_once('@') {
                // `vanish=ID@SECONDS`: answers until then.
                Some((who, after)) => self.vanish_after.push(item.vanish_after(who, after)?),
                None => self.vanish.push(item.id()?),
            },
            "block" => self.block.push(item.id()?),
            "overheat" => self.overheat.push(item.id()?),
            "supply" => self.supply.push(item.supply()?),
            "firmware" => self.firmware.push(item.firmware()?),
            "baud" => self.baud.push(item.baud()?),
            "duplicate" => self.duplicate.push(item.duplicate()?),
            _ => {
                return Err(FaultSpecError::UnknownKey {
                    key: item.key.to_owned(),
                })
            }
        }
        Ok(())
    }
}

/// One `key=value` item of a `--faults` specification, both trimmed.
#[derive(Clone, Copy)]
struct SpecItem<'a> {
    /// The key as written.
    key: &'a str,
    /// The value as written (empty without `=`).
    value: &'a str,
}

impl<'a> SpecItem<'a> {
    /// Splits `item` at its first `=`.
    fn split(item: &'a str) -> SpecItem<'a> {
        let (key, value) = item.split_once('=').unwrap_or((item, ""));
        SpecItem {
            key: key.trim(),
            value: value.trim(),
        }
    }

    /// The refusal of this item's value, saying what was `expected`.
    fn bad(&self, expected: &'static str) -> FaultSpecError {
        FaultSpecError::BadValue {
            key: self.key.to_owned(),
            value: self.value.to_owned(),
            expected,
        }
    }

    /// The value as a probability between 0 and 1.
    fn probability(&self) -> Result<f64, FaultSpecError> {
        match self.value.parse::<f64>() {
            Ok(p) if (0.0..=1.0).contains(&p) => Ok(p),
            _ => Err(self.bad("a probability between 0 and 1")),
        }
    }

    /// The value as a servo ID.
    fn id(&self) -> Result<u8, FaultSpecError> {
        match self.value.parse::<u8>() {
            Ok(id) if id <= servobus_protocol::MAX_ID => Ok(id),
            _ => Err(self.bad("a servo ID 0..=253")),
        }
    }

    /// The value as a duration in microseconds.
    fn micros(&self) -> Result<Duration, FaultSpecError> {
        let us = self
            .value
            .parse::<u64>()
            .map_err(|_| self.bad("microseconds"))?;
        Ok(Duration::from_micros(us))
    }

    /// The value as on or off (on when empty).
    fn switch(&self) -> Result<bool, FaultSpecError> {
        match self.value {
            "" | "1" | "true" | "on" => Ok(true),
            "0" | "false" | "off" => Ok(false),
            _ => Err(self.bad("true or false")),
        }
    }

    /// `ID@SECONDS`, split at the `@` into `who` and `after`.
    fn vanish_after(&self, who: &str, after: &str) -> Result<(u8, Duration), FaultSpecError> {
        let expected = "ID or ID@SECONDS, e.g. 3@1.5";
        let who = parse_id(who).ok_or_else(|| self.bad(expected))?;
        let after = after
            .parse::<f64>()
            .ok()
            .and_then(|s| Duration::try_from_secs_f64(s).ok())
            .ok_or_else(|| self.bad(expected))?;
        Ok((who, after))
    }

    /// `V` (every servo) or `ID:V`, in volts.
    fn supply(&self) -> Result<(Option<u8>, u8), FaultSpecError> {
        let (who, volts) = match self.value.split_once(':') {
            Some((who, v)) => (Some(parse_id(who).ok_or_else(|| self.bad(SUPPLY))?), v),
            None => (None, self.value),
        };
        let dv = parse_decivolts(volts).ok_or_else(|| self.bad(SUPPLY))?;
        Ok((who, dv))
    }

    /// `ID:MAJOR.MINOR`.
    fn firmware(&self) -> Result<(u8, (u8, u8)), FaultSpecError> {
        let parsed = self.value.split_once(':').and_then(|(who, v)| {
            let (major, minor) = v.split_once('.')?;
            Some((parse_id(who)?, (major.parse().ok()?, minor.parse().ok()?)))
        });
        parsed.ok_or_else(|| self.bad("ID:MAJOR.MINOR, e.g. 3:3.9"))
    }

    /// `ID:RATE`, the rate turned into its baud-table index.
    fn baud(&self) -> Result<(u8, u8), FaultSpecError> {
        let parsed = self.value.split_once(':').and_then(|(who, rate)| {
            let rate = rate.parse::<u32>().ok()?;
            Some((
                parse_id(who)?,
                servobus_protocol::registers::baud_index(rate)?,
            ))
        });
        parsed.ok_or_else(|| self.bad("ID:RATE with a rate of the servo baud table, e.g. 3:115200"))
    }

    /// `FROM:TO` servo IDs.
    fn duplicate(&self) -> Result<(u8, u8), FaultSpecError> {
        let parsed = self
            .value
            .split_once(':')
            .and_then(|(from, to)| Some((parse_id(from)?, parse_id(to)?)));
        parsed.ok_or_else(|| self.bad("FROM:TO servo IDs, e.g. 6:5"))
    }
}

/// What a `supply` value must be.
const SUPPLY: &str = "volts (0..25.5), or ID:volts";

/// A servo ID as written, if it is a valid one.
fn parse_id(text: &str) -> Option<u8> {
    text.trim()
        .parse::<u8>()
        .ok()
        .filter(|&id| id <= servobus_protocol::MAX_ID)
}

/// Volts as written to 0.1 V units, as the servo's voltage register holds them.
fn parse_decivolts(text: &str) -> Option<u8> {
    let v = text.trim().parse::<f64>().ok()?;
    (0.0..=25.5).contains(&v).then(|| (v * 10.0).round() as u8)
}
