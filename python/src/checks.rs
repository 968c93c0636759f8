//! The numbers Python gives, range-checked before anything is opened or
//! moved: the same ranges as the command line's (`servobus --baud`,
//! `--rate`, `--timeout`), so no `Duration::from_secs_f64` meets a NaN, a
//! negative number or one too large for a `Duration` (which panics), and a
//! Python int too large for its parameter is servobus's exception, not
//! `OverflowError`.
//!
//! | check              | takes                               | range                         | raises        |
//! |--------------------|-------------------------------------|-------------------------------|---------------|
//! | [`baud`]           | a baud rate                         | the servos' table             | `ConfigError` |
//! | [`latency`]        | an adapter latency, s               | 0 to `limits::MAX_LATENCY`    | `UsageError`  |
//! | [`timeout`]        | how long to wait for something, s   | 1 ms to an hour               | `UsageError`  |
//! | [`rate`]           | a control rate, Hz                  | `limits::check_rate_hz`       | `UsageError`  |
//! | [`whole`]          | an integer argument                 | what the caller says          | `UsageError`  |

use std::time::Duration;

use pyo3::prelude::*;
use servobus_config::limits::{self, Rounded};

use crate::errors::{Class, Failure, Field, Outcome};

/// The shortest timeout, s: below a millisecond a wait is shorter than one
/// exchange on any bus (the command line's `MIN_TIMEOUT_S`).
pub(crate) const MIN_TIMEOUT_S: f64 = 0.001;

/// The longest timeout, s: an hour; a longer wait is no timeout (the
/// command line's `MAX_TIMEOUT_S`).
pub(crate) const MAX_TIMEOUT_S: f64 = 3600.0;

/// The Python number `value` as a baud rate the servos can be set to
/// (register 6's table).
pub(crate) fn baud(value: &Bound<'_, PyAny>) -> Outcome<u32> {
    match value.extract::<i64>() {
        Ok(b) => baud_number(b),
        Err(_) => Err(refused_baud(
            value.str().map(|s| s.to_string()).unwrap_or_default(),
        )),
    }
}

/// A baud rate refused, shown as `shown`.
fn refused_baud(shown: String) -> Failure {
    Failure::new(
        Class::ConfigError,
        format!(
            "{shown} baud is not a rate the servos can be set to; use one of {}",
            baud_list()
        ),
    )
    .with("field", Field::Str("baud".to_owned()))
}

/// `baud` if the servos can be set to it (register 6's table).
pub(crate) fn baud_number(baud: i64) -> Outcome<u32> {
    u32::try_from(baud)
        .ok()
        .and_then(|b| limits::check_baud(b).ok())
        .ok_or_else(|| refused_baud(baud.to_string()))
}

/// The servos' baud rates, as a message lists them.
fn baud_list() -> String {
    let rates: Vec<String> = servobus_protocol::registers::BAUD_RATES
        .iter()
        .map(u32::to_string)
        .collect();
    rates.join(", ")
}

/// An adapter latency of `s` seconds: 0 to [`limits::MAX_LATENCY`].
pub(crate) fn latency(s: f64) -> Outcome<Duration> {
    let max = limits::MAX_LATENCY.as_secs_f64();
    if (0.0..=max).contains(&s) {
        if let Ok(d) = Duration::try_from_secs_f64(s) {
            return Ok(d);
        }
    }
    Err(Failure::usage(format!(
        "latency {} s is outside the adapter latencies servobus allows, 0 to {max} s \
         (the largest FTDI latency timer)",
        Rounded(s)
    ))
    .with("value", Field::Float(s)))
}

/// A timeout of `s` seconds, named `what` in the message:
/// [`MIN_TIMEOUT_S`] to [`MAX_TIMEOUT_S`].
pub(crate) fn timeout(what: &str, s: f64) -> Outcome<Duration> {
    if (MIN_TIMEOUT_S..=MAX_TIMEOUT_S).contains(&s) {
        if let Ok(d) = Duration::try_from_secs_f64(s) {
            return Ok(d);
        }
    }
    Err(Failure::usage(format!(
        "{what} {} s is outside the timeouts servobus takes, {MIN_TIMEOUT_S} to \
         {MAX_TIMEOUT_S} s (an hour)",
        Rounded(s)
    ))
    .with("value", Field::Float(s)))
}

/// A control rate of `hz` (None: the robot's own).
pub(crate) fn rate(hz: Option<f64>) -> Outcome<Option<f64>> {
    match hz {
        None => Ok(None),
        Some(hz) => limits::check_rate_hz(hz)
            .map(Some)
            .map_err(|e| Failure::usage(e.to_string()).with("value", Field::Float(hz))),
    }
}

/// The Python int `value`, named `what`, within `min..=max`.
pub(crate) fn whole(value: &Bound<'_, PyAny>, what: &str, min: i64, max: i64) -> Outcome<i64> {
    let out_of_range = || {
        let shown = value
            .str()
            .map(|s| s.to_string())
            .unwrap_or_else(|_| "?".to_owned());
        Failure::usage(format!(
            "{what} {shown}: give a whole number from {min} to {max}"
        ))
    };
    match value.extract::<i64>() {
        Ok(v) if (min..=max).contains(&v) => Ok(v),
        _ => Err(out_of_range()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bauds_outside_the_table_are_refused() {
        assert_eq!(baud_number(1_000_000).ok(), Some(1_000_000));
        assert_eq!(baud_number(115_200).ok(), Some(115_200));
        for bad in [0, -1, 1, 999_999, i64::MAX] {
            assert!(baud_number(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn durations_that_would_panic_are_refused() {
        for bad in [f64::NAN, f64::INFINITY, -1.0, 1e300, 1e-300] {
            assert!(timeout("timeout", bad).is_err(), "{bad}");
        }
        assert_eq!(
            timeout("timeout", 0.25).ok(),
            Some(Duration::from_millis(250))
        );
        for bad in [f64::NAN, f64::INFINITY, -0.001, 1e300, 0.256] {
            assert!(latency(bad).is_err(), "{bad}");
        }
        assert_eq!(latency(0.0).ok(), Some(Duration::ZERO));
        for bad in [0.0, -1.0, f64::NAN, 1e300, 1e-300] {
            assert!(rate(Some(bad)).is_err(), "{bad}");
        }
        assert_eq!(rate(Some(100.0)).ok(), Some(Some(100.0)));
    }
}
