//! The command line's numbers, range-checked as they are parsed.
//!
//! Every duration, rate, timeout and count a command takes goes through one
//! of these parsers (`#[arg(value_parser = super::args::run_seconds_arg)]`),
//! so a value out of range is a usage error (exit 2) that names the range,
//! before anything is opened or moved, and no later
//! `Duration::from_secs_f64` can meet a NaN, a negative number or one too
//! large for a `Duration` (which panics).
//!
//! | parser                 | takes                                 | range                      |
//! |------------------------|---------------------------------------|----------------------------|
//! | [`rate_arg`]           | a control rate, Hz                    | [`limits::check_rate_hz`]  |
//! | [`refresh_rate_arg`]   | a display's refreshes per second      | 0.1 to 1000                |
//! | [`run_seconds_arg`]    | how long a run lasts, s               | 0.001 s to a day           |
//! | [`measure_seconds_arg`] | how long a measurement lasts, s     | 0.001 s to an hour         |
//! | [`timeout_arg`]        | how long to wait for something, s     | 0.001 s to an hour         |
//! | [`count_arg`]          | how many times                        | 1 to a billion             |
//! | [`angle_arg`]          | an angle in a robot file's units      | finite                     |
//! | [`tolerance_deg_arg`]  | how close, degrees                    | 0.001 to 90                |
//! | [`baud_arg`]           | a baud rate                           | [`limits::check_baud`]     |
//! | [`latency_us_arg`]     | an adapter latency, us                | [`limits::check_latency_us`] |

use std::time::Duration;

use servobus_config::limits::{self, Rounded};

/// The longest run a command takes (`--seconds`, `--duration`): a day, as
/// long as one motion may be ([`limits::MAX_MOTION_DURATION_S`]).
pub(crate) const MAX_RUN_S: f64 = limits::MAX_MOTION_DURATION_S;

/// The shortest timeout, s: below a millisecond a wait is shorter than one
/// exchange on any bus.
pub(crate) const MIN_TIMEOUT_S: f64 = 0.001;

/// The longest timeout, s: an hour; a longer wait is no timeout.
pub(crate) const MAX_TIMEOUT_S: f64 = 3600.0;

/// Refreshes per second of a live display: from one every 10 s to the
/// fastest a terminal shows.
pub(crate) const REFRESH_RATE_HZ: (f64, f64) = (0.1, 1000.0);

/// The largest count (`--count`): a billion.
pub(crate) const MAX_COUNT: u64 = 1_000_000_000;

/// `arg` as a finite number, or a message saying it is not a `what`.
fn finite(arg: &str, what: &str) -> Result<f64, String> {
    match arg.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("`{arg}` is not a finite number of {what}")),
        Err(_) => Err(format!("`{arg}` is not a number of {what}")),
    }
}

/// The shortest run or measurement, s: a millisecond (a shorter one is
/// not one control cycle).
pub(crate) const MIN_RUN_S: f64 = 0.001;

/// `arg` as seconds in `min_s..=max_s`, said as `range` when it is not.
fn seconds_in(arg: &str, min_s: f64, max_s: f64, range: &str) -> Result<Duration, String> {
    let s = finite(arg, "seconds")?;
    if !(min_s..=max_s).contains(&s) {
        return Err(format!("{} s is outside {range}", Rounded(s)));
    }
    Duration::try_from_secs_f64(s).map_err(|_| format!("{} s is outside {range}", Rounded(s)))
}

/// Parses how long a run lasts (`--seconds`, `--duration`): [`MIN_RUN_S`]
/// to [`MAX_RUN_S`] (a day).
pub(crate) fn run_seconds_arg(arg: &str) -> Result<Duration, String> {
    seconds_in(
        arg,
        MIN_RUN_S,
        MAX_RUN_S,
        &format!("the lengths a run takes, {MIN_RUN_S} to {MAX_RUN_S} s (a day)"),
    )
}

/// The longest measurement (`bench --seconds`): an hour, which bounds
/// the period samples kept.
pub(crate) const MAX_MEASURE_S: f64 = 3600.0;

/// Parses how long a measurement lasts (`bench --seconds`): [`MIN_RUN_S`]
/// to [`MAX_MEASURE_S`] (an hour).
pub(crate) fn measure_seconds_arg(arg: &str) -> Result<Duration, String> {
    seconds_in(
        arg,
        MIN_RUN_S,
        MAX_MEASURE_S,
        &format!("the lengths a measurement takes, {MIN_RUN_S} to {MAX_MEASURE_S} s (an hour)"),
    )
}

/// Parses a timeout in seconds (`stream --timeout`, `serve --timeout`): [`MIN_TIMEOUT_S`] to
/// [`MAX_TIMEOUT_S`] (an hour).
pub(crate) fn timeout_arg(arg: &str) -> Result<Duration, String> {
    seconds_in(
        arg,
        MIN_TIMEOUT_S,
        MAX_TIMEOUT_S,
        &format!("the timeouts servobus takes, {MIN_TIMEOUT_S} to {MAX_TIMEOUT_S} s (an hour)"),
    )
}

/// Parses a control rate (`--rate`): a number of Hz within the range
/// servobus runs ([`limits::check_rate_hz`]).
pub(crate) fn rate_arg(arg: &str) -> Result<f64, String> {
    let rate: f64 = arg
        .trim()
        .parse()
        .map_err(|_| format!("`{arg}` is not a number of Hz"))?;
    limits::check_rate_hz(rate).map_err(|e| e.to_string())
}

/// Parses a live display's refresh rate (`monitor --rate`): within
/// [`REFRESH_RATE_HZ`].
pub(crate) fn refresh_rate_arg(arg: &str) -> Result<f64, String> {
    let hz = finite(arg, "refreshes per second")?;
    let (min, max) = REFRESH_RATE_HZ;
    if (min..=max).contains(&hz) {
        Ok(hz)
    } else {
        Err(format!(
            "{} refreshes per second is outside the rates a display takes, {min} to {max}",
            Rounded(hz)
        ))
    }
}

/// Parses a count (`--count`): a whole number from 1 to [`MAX_COUNT`].
pub(crate) fn count_arg(arg: &str) -> Result<u64, String> {
    let n: u64 = arg
        .trim()
        .parse()
        .map_err(|_| format!("`{arg}` is not a whole number from 1 to {MAX_COUNT}"))?;
    if (1..=MAX_COUNT).contains(&n) {
        Ok(n)
    } else {
        Err(format!("{n} is outside the counts taken, 1 to {MAX_COUNT}"))
    }
}

/// Parses an angle in the robot file's units (`--pitch`, `--roll`): any
/// finite number (the joints' limits are checked once the robot is read).
pub(crate) fn angle_arg(arg: &str) -> Result<f64, String> {
    finite(arg, "degrees or radians (the robot file's units)")
}

/// Parses a length in millimetres (`--xyz`'s coordinates): any finite
/// number (reach is checked against the robot).
pub(crate) fn mm_arg(arg: &str) -> Result<f64, String> {
    finite(arg, "millimetres")
}

/// Parses a tolerance in degrees (`teach --tolerance`): 0.001 to 90 (a
/// thousandth of a degree is far below what a servo resolves).
pub(crate) fn tolerance_deg_arg(arg: &str) -> Result<f64, String> {
    let deg = finite(arg, "degrees")?;
    if (0.001..=90.0).contains(&deg) {
        Ok(deg)
    } else {
        Err(format!(
            "{} degrees is outside the tolerances taken, 0.001 to 90",
            Rounded(deg)
        ))
    }
}

/// Parses a baud rate (`--baud`): one the servos can be set to
/// ([`limits::check_baud`]).
pub(crate) fn baud_arg(arg: &str) -> Result<u32, String> {
    let baud: u32 = arg
        .trim()
        .parse()
        .map_err(|_| format!("`{arg}` is not a baud rate"))?;
    limits::check_baud(baud).map_err(|e| e.to_string())
}

/// Parses an adapter latency (`--latency-us`), at most
/// [`limits::MAX_LATENCY`].
pub(crate) fn latency_us_arg(arg: &str) -> Result<u64, String> {
    let us: u64 = arg
        .trim()
        .parse()
        .map_err(|_| format!("`{arg}` is not a whole number of microseconds"))?;
    limits::check_latency_us(us)
        .map(|_| us)
        .map_err(|e| e.to_string())
}

/// Parses a duration: seconds (`2`, `0.5`), or with a unit (`2s`, `500ms`).
#[cfg(feature = "zenoh")]
pub(crate) fn duration_arg(arg: &str) -> Result<std::time::Duration, String> {
    let arg = arg.trim();
    let (num, scale) = if let Some(n) = arg.strip_suffix("ms") {
        (n, 1e-3)
    } else if let Some(n) = arg.strip_suffix('s') {
        (n, 1.0)
    } else {
        (arg, 1.0)
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("`{arg}` is not a duration: give e.g. 2s or 500ms"))?;
    let secs = v * scale;
    if !(0.0..=3600.0).contains(&secs) {
        return Err(format!("`{arg}`: give 0 to 3600 s"));
    }
    std::time::Duration::try_from_secs_f64(secs).map_err(|_| format!("`{arg}`: give 0 to 3600 s"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const HOSTILE: [&str; 7] = ["0", "-1", "NaN", "inf", "1e-300", "1e300", "x"];

    #[test]
    fn hostile_numbers_are_refused_with_the_range() {
        for v in HOSTILE {
            let e = run_seconds_arg(v).expect_err(v);
            assert!(e.contains("86400") || e.contains("not a"), "{v}: {e}");
            assert!(measure_seconds_arg(v).is_err(), "{v}");
            let e = timeout_arg(v).expect_err(v);
            assert!(e.contains("3600") || e.contains("not a"), "{v}: {e}");
            let e = refresh_rate_arg(v).expect_err(v);
            assert!(e.contains("1000") || e.contains("not a"), "{v}: {e}");
            assert!(rate_arg(v).is_err(), "{v}");
            assert!(count_arg(v).is_err(), "{v}");
            assert!(tolerance_deg_arg(v).is_err(), "{v}");
        }
        for v in ["NaN", "inf", "-inf", "1e400", "x"] {
            assert!(angle_arg(v).is_err(), "{v}");
            assert!(mm_arg(v).is_err(), "{v}");
        }
    }

    #[test]
    fn values_in_range_are_taken() {
        assert_eq!(run_seconds_arg("1.5"), Ok(Duration::from_millis(1500)));
        assert_eq!(run_seconds_arg("86400"), Ok(Duration::from_secs(86_400)));
        assert!(run_seconds_arg("86400.5").is_err());
        assert_eq!(timeout_arg("0.001"), Ok(Duration::from_millis(1)));
        assert_eq!(timeout_arg("3600"), Ok(Duration::from_secs(3600)));
        assert_eq!(refresh_rate_arg("0.1"), Ok(0.1));
        assert_eq!(count_arg("1"), Ok(1));
        assert_eq!(count_arg(&MAX_COUNT.to_string()), Ok(MAX_COUNT));
        assert!(count_arg(&(MAX_COUNT + 1).to_string()).is_err());
        assert_eq!(angle_arg("-30"), Ok(-30.0));
        assert_eq!(tolerance_deg_arg("90"), Ok(90.0));
        assert_eq!(rate_arg("200"), Ok(200.0));
    }
}
