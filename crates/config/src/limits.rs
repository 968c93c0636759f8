//! Limits on what a file or a flag may ask for, each with the figure in
//! its message.
//!
//! A few bytes of YAML can ask for unbounded work: `repeat: 1000000000`
//! makes the planner allocate half a terabyte, `at: 1e12` makes `plan`
//! sample for ever, and a file nested 100,000 deep takes serde_yaml a
//! minute. Each limit here is far above anything a robot or a motion needs
//! and low enough that the work it allows finishes in seconds; every
//! refusal says the limit.

use std::fmt;
use std::io::Read;
use std::path::Path;
use std::time::Duration;

use servobus_protocol::registers::{baud_index, BAUD_RATES};

use super::ConfigError;

/// The largest robot, motion, calibration or simulator-body file read,
/// bytes. The shipped files are under 10 KB; a hexapod with every field
/// commented is under 30 KB. At 1 MiB serde_yaml still parses in well under
/// a second on a slow machine.
pub const MAX_FILE_BYTES: u64 = 1 << 20;

/// The largest recording (CSV) read, bytes. `play --log` writes about 60
/// bytes per joint and cycle: 64 MiB is ten minutes of a six-joint arm at
/// 200 Hz, more than [`MAX_TRACK_STEPS`] lets the filter follow anyway.
pub const MAX_RECORDING_BYTES: u64 = 64 << 20;

/// The deepest nesting of mappings and lists in a YAML file. A robot file
/// nests five levels (`buses[0].joints[2].min` and a flow map); 32 leaves
/// room for any layout, and serde_yaml gets slow (quadratic) on deep flow
/// mappings long before its own recursion limit stops it.
pub const MAX_NESTING: usize = 32;

/// The longest motion, s (every repetition together): a day. A motion
/// file is a choreography; anything longer is a loop outside servobus.
pub const MAX_MOTION_DURATION_S: f64 = 86_400.0;

/// The most control cycles one motion or recording may take (duration x
/// rate): a day at 200 Hz is 17.3 million. `plan` samples every cycle, so
/// this bounds its work to seconds.
pub const MAX_MOTION_CYCLES: f64 = 20e6;

/// The most joint segments a motion may plan: keyframes x `repeat` x
/// joints. A planned segment of one joint takes about 240 bytes, so this
/// is about 120 MB of trajectory (9 keyframes of a six-joint arm repeated
/// 9,000 times).
pub const MAX_PLANNED_SEGMENTS: f64 = 500_000.0;

/// The most rows a recording may have. At 16 bytes per joint and row kept
/// while reading, this bounds the memory to tens of megabytes.
pub const MAX_RECORDING_ROWS: usize = 2_000_000;

/// The most filter steps a recording may take to follow: control cycles
/// over its span x joints. The filter keeps about 1 KB per step and joint
/// (forward and backward pass), so this is about 1 GB at most; it is the
/// span of a six-joint arm's recording of 14 minutes at 200 Hz.
pub const MAX_TRACK_STEPS: f64 = 1_000_000.0;

/// The shortest step period of a walk, s. Walk samples come every 20 ms,
/// and a wave gait swings each leg for a sixth of the period: at 0.2 s a
/// swing still has a couple of samples (a servo of the SO-101 class needs
/// about that long for the 60 degrees a swing turns a coxa). Shorter
/// periods cannot be sampled, and `period: 1e-9` would ask for a billion
/// steps a second.
pub const MIN_STEP_PERIOD_S: f64 = 0.2;

/// The most velocity segments one walk may have. Planning the body's path
/// looks at every segment at each of its 2 ms grid points, so this bounds
/// that work (a walk is a few segments; a thousand is a long tour).
pub const MAX_WALK_SEGMENTS: usize = 1000;

/// The slowest control rate, Hz. Below it the servos reach each goal and
/// stop before the next one (the path becomes a staircase), and a servo
/// that stops answering (three missed cycles) is noticed only after
/// seconds.
pub const MIN_RATE_HZ: f64 = 10.0;

/// The fastest control rate, Hz. Its period, 100 us, is about the wake-up
/// jitter of a real-time thread on Linux; no bus of the baud table carries
/// a full cycle that fast anyway (one servo at 1 Mbps needs about 300 us).
pub const MAX_RATE_HZ: f64 = 10_000.0;

/// The longest adapter latency per transaction: 255 ms, the largest
/// setting of an FTDI adapter's latency timer (the slowest USB serial
/// adapters there are; CDC adapters answer in about 1 ms).
pub const MAX_LATENCY: Duration = Duration::from_millis(255);

/// A value beyond one of the limits of this module.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LimitError {
    /// A baud rate the servos cannot be set to (register 6's table).
    #[error(
        "{baud} baud is not a rate the servos can be set to; use one of {}",
        baud_list()
    )]
    Baud {
        /// The rate asked for.
        baud: u32,
    },
    /// An adapter latency beyond [`MAX_LATENCY`].
    #[error(
        "{latency_us} us is not an adapter latency: give 0 to {} us (the largest FTDI \
         latency timer)",
        MAX_LATENCY.as_micros()
    )]
    Latency {
        /// The latency asked for, us.
        latency_us: u64,
    },
    /// A control rate outside [`MIN_RATE_HZ`]..=[`MAX_RATE_HZ`].
    #[error(
        "{} Hz is outside the control rates servobus runs, {MIN_RATE_HZ} to {MAX_RATE_HZ} Hz",
        Rounded(*rate_hz)
    )]
    Rate {
        /// The rate asked for.
        rate_hz: f64,
    },
    /// A motion or recording longer than [`MAX_MOTION_DURATION_S`].
    #[error(
        "{} s is longer than the limit of {MAX_MOTION_DURATION_S} s (a day) for one motion",
        Rounded(*duration_s)
    )]
    Duration {
        /// The length, s.
        duration_s: f64,
    },
    /// More control cycles than [`MAX_MOTION_CYCLES`].
    #[error(
        "{} s at {} Hz is {} control cycles, more than the limit of {}",
        Rounded(*duration_s),
        Rounded(*rate_hz),
        Rounded(duration_s * rate_hz),
        Rounded(MAX_MOTION_CYCLES)
    )]
    Cycles {
        /// The length, s.
        duration_s: f64,
        /// The control rate, Hz.
        rate_hz: f64,
    },
    /// More planned joint segments than [`MAX_PLANNED_SEGMENTS`].
    #[error(
        "{keyframes} keyframes x {repeat} repetitions x {joints} joints is {} joint segments \
         to plan, more than the limit of {}",
        Rounded(*keyframes as f64 * *repeat as f64 * *joints as f64),
        Rounded(MAX_PLANNED_SEGMENTS)
    )]
    Segments {
        /// Keyframes of one repetition.
        keyframes: usize,
        /// Repetitions.
        repeat: u64,
        /// Joints of the robot.
        joints: usize,
    },
    /// A generator (a walk, a body move, a straight line) that would add
    /// more keyframes than [`MAX_PLANNED_SEGMENTS`] leaves room for.
    #[error(
        "would make {} samples, and the motion has room for {allowed} more ({} joint \
         segments at most: keyframes x repetitions x joints)",
        Rounded(*samples),
        Rounded(MAX_PLANNED_SEGMENTS)
    )]
    Samples {
        /// The samples (whole robot poses) it would make.
        samples: f64,
        /// How many more the motion may have.
        allowed: usize,
    },
    /// A recording with more rows than [`MAX_RECORDING_ROWS`].
    #[error("more than {MAX_RECORDING_ROWS} rows, the limit for a recording")]
    Rows,
    /// A recording that would take more filter steps than [`MAX_TRACK_STEPS`].
    #[error(
        "{} s at {} Hz for {joints} joints is {} filter steps, more than the limit of {}",
        Rounded(*span_s),
        Rounded(*rate_hz),
        Rounded(span_s * rate_hz * *joints as f64),
        Rounded(MAX_TRACK_STEPS)
    )]
    TrackSteps {
        /// The recording's span, s.
        span_s: f64,
        /// The control rate, Hz.
        rate_hz: f64,
        /// Joints of the robot.
        joints: usize,
    },
}

fn baud_list() -> String {
    let rates: Vec<String> = BAUD_RATES.iter().map(u32::to_string).collect();
    rates.join(", ")
}

/// Checks that the servos can be set to `baud` (the protocol's table).
///
/// # Errors
/// [`LimitError::Baud`], which lists the rates there are.
pub fn check_baud(baud: u32) -> Result<u32, LimitError> {
    baud_index(baud)
        .map(|_| baud)
        .ok_or(LimitError::Baud { baud })
}

/// The adapter latency of `latency_us` microseconds, if at most [`MAX_LATENCY`].
///
/// # Errors
/// [`LimitError::Latency`].
pub fn check_latency_us(latency_us: u64) -> Result<Duration, LimitError> {
    let latency = Duration::from_micros(latency_us);
    if latency <= MAX_LATENCY {
        Ok(latency)
    } else {
        Err(LimitError::Latency { latency_us })
    }
}

/// Checks that `rate_hz` is a control rate servobus runs
/// ([`MIN_RATE_HZ`]..=[`MAX_RATE_HZ`]; NaN is not).
///
/// # Errors
/// [`LimitError::Rate`].
pub fn check_rate_hz(rate_hz: f64) -> Result<f64, LimitError> {
    if (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz) {
        Ok(rate_hz)
    } else {
        Err(LimitError::Rate { rate_hz })
    }
}

/// Checks that a motion or recording of `duration_s` is within
/// [`MAX_MOTION_DURATION_S`] (NaN is not).
///
/// # Errors
/// [`LimitError::Duration`].
pub fn check_duration(duration_s: f64) -> Result<(), LimitError> {
    if duration_s <= MAX_MOTION_DURATION_S {
        Ok(())
    } else {
        Err(LimitError::Duration { duration_s })
    }
}

/// Checks that a motion or recording of `duration_s` played at `rate_hz`
/// is within [`MAX_MOTION_DURATION_S`] and [`MAX_MOTION_CYCLES`].
///
/// # Errors
/// [`LimitError::Duration`] or [`LimitError::Cycles`].
pub fn check_length(duration_s: f64, rate_hz: f64) -> Result<(), LimitError> {
    check_duration(duration_s)?;
    // NaN fails the test, so it is refused.
    if duration_s * rate_hz <= MAX_MOTION_CYCLES {
        Ok(())
    } else {
        Err(LimitError::Cycles {
            duration_s,
            rate_hz,
        })
    }
}

/// Checks that planning `keyframes` keyframes `repeat` times for `joints`
/// joints stays within [`MAX_PLANNED_SEGMENTS`].
///
/// # Errors
/// [`LimitError::Segments`].
pub fn check_segments(keyframes: usize, repeat: u64, joints: usize) -> Result<(), LimitError> {
    let segments = keyframes as f64 * repeat as f64 * joints as f64;
    if segments <= MAX_PLANNED_SEGMENTS {
        Ok(())
    } else {
        Err(LimitError::Segments {
            keyframes,
            repeat,
            joints,
        })
    }
}

/// How many joint keyframes (whole robot poses) a generator may still add
/// to a motion that has `keyframes` of them so far, repeated `repeat`
/// times for `joints` joints, within [`MAX_PLANNED_SEGMENTS`]: a walk, a
/// body move or a straight line checks its sample count against this
/// before it allocates them.
pub fn samples_left(keyframes: usize, repeat: u64, joints: usize) -> usize {
    let per_keyframe = (repeat.max(1) as f64) * (joints.max(1) as f64);
    let allowed = (MAX_PLANNED_SEGMENTS / per_keyframe).floor();
    // Both are far below 2^53: the conversions are exact.
    (allowed as usize).saturating_sub(keyframes)
}

/// Checks that a generator making `samples` whole robot poses fits a
/// motion of `keyframes` so far, repeated `repeat` times, for `joints`
/// joints ([`samples_left`]); NaN does not.
///
/// # Errors
/// [`LimitError::Samples`].
pub fn check_samples(
    samples: f64,
    keyframes: usize,
    repeat: u64,
    joints: usize,
) -> Result<(), LimitError> {
    let allowed = samples_left(keyframes, repeat, joints);
    if samples <= allowed as f64 {
        Ok(())
    } else {
        Err(LimitError::Samples { samples, allowed })
    }
}

/// Checks that following a recording spanning `span_s` at `rate_hz` for
/// `joints` joints stays within [`MAX_MOTION_DURATION_S`] and
/// [`MAX_TRACK_STEPS`].
///
/// # Errors
/// [`LimitError::Duration`] or [`LimitError::TrackSteps`].
pub fn check_recording(span_s: f64, rate_hz: f64, joints: usize) -> Result<(), LimitError> {
    check_duration(span_s)?;
    if span_s * rate_hz * joints as f64 <= MAX_TRACK_STEPS {
        Ok(())
    } else {
        Err(LimitError::TrackSteps {
            span_s,
            rate_hz,
            joints,
        })
    }
}

/// The bytes of `path`, reading at most `limit + 1` of them: a larger file
/// (or a device such as `/dev/zero`) is refused after that many.
///
/// # Errors
/// [`ConfigError::Read`] with the operating system's reason, or
/// [`ConfigError::TooLarge`].
pub fn read_capped(path: &Path, limit: u64) -> Result<Vec<u8>, ConfigError> {
    let read = |error| ConfigError::Read {
        path: path.to_owned(),
        error,
    };
    let file = std::fs::File::open(path).map_err(read)?;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(read)?;
    if bytes.len() as u64 > limit {
        return Err(ConfigError::TooLarge {
            path: path.to_owned(),
            limit,
        });
    }
    Ok(bytes)
}

/// A number as a message echoes it: at most 9 significant digits, and in
/// exponent form when very large or small, so that a 309-digit number
/// prints as `1e308`, `0.1 + 0.2` as `0.3` and `120.0` as `120`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rounded(pub f64);

/// A number with a fixed count of decimals (`Fixed(v, 2)` prints as
/// `{v:.2}` does), except that a value that rounds to zero prints without
/// a sign: `0.00`, never `-0.00`. For the angles of logs, taught files and
/// live views, where a joint resting at 0 reads -0.0001 as often as 0.0001.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fixed(pub f64, pub usize);

impl fmt::Display for Fixed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = format!("{:.*}", self.1, self.0);
        match text.strip_prefix('-') {
            Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => f.write_str(rest),
            _ => f.write_str(&text),
        }
    }
}

impl fmt::Display for Rounded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        let a = v.abs();
        if !v.is_finite() || v == 0.0 {
            // `inf`, `NaN`, `0` (and `-0` as `0`).
            return if v == 0.0 {
                f.write_str("0")
            } else {
                write!(f, "{v}")
            };
        }
        if !(1e-6..1e9).contains(&a) {
            let text = format!("{v:.8e}");
            let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
            return write!(f, "{}e{exponent}", trim_zeros(mantissa));
        }
        // Digits after the point for 9 significant ones.
        let magnitude = a.log10().floor() as i32;
        let decimals = (8 - magnitude).clamp(0, 17) as usize;
        let text = format!("{v:.decimals$}");
        f.write_str(trim_zeros(&text))
    }
}

/// `1.2300` as `1.23`, `5.000` as `5`; text without a point is kept.
fn trim_zeros(text: &str) -> &str {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_echoed_rounded() {
        assert_eq!(Rounded(120.0).to_string(), "120");
        assert_eq!(Rounded(-100.0).to_string(), "-100");
        assert_eq!(Rounded(0.1 + 0.2).to_string(), "0.3");
        assert_eq!(Rounded(1.000_000_1).to_string(), "1.0000001");
        assert_eq!(Rounded(1e308).to_string(), "1e308");
        assert_eq!(Rounded(-2.5e-9).to_string(), "-2.5e-9");
        assert_eq!(Rounded(1e9).to_string(), "1e9");
        assert_eq!(Rounded(999_999_999.0).to_string(), "999999999");
        assert_eq!(Rounded(5.4e10).to_string(), "5.4e10");
        assert_eq!(Rounded(f64::INFINITY).to_string(), "inf");
        assert_eq!(Rounded(-0.0).to_string(), "0");
        assert_eq!(Fixed(-0.0, 2).to_string(), "0.00");
        assert_eq!(Fixed(-0.004, 2).to_string(), "0.00");
        assert_eq!(Fixed(-0.005_1, 2).to_string(), "-0.01");
        assert_eq!(Fixed(-12.5, 1).to_string(), "-12.5");
        assert_eq!(Fixed(-0.3, 0).to_string(), "0");
        assert_eq!(Fixed(f64::NAN, 1).to_string(), "NaN");
        assert_eq!(Fixed(f64::NEG_INFINITY, 1).to_string(), "-inf");
    }

    #[test]
    fn baud_rates_come_from_the_servos_table() {
        assert_eq!(check_baud(115_200), Ok(115_200));
        for bad in [0, 1, 12_345, 2_000_000] {
            let e = check_baud(bad).expect_err("not in the table");
            let text = e.to_string();
            assert!(text.starts_with(&format!("{bad} baud is not")), "{text}");
            assert!(text.contains("1000000, 500000, 250000"), "{text}");
        }
    }

    #[test]
    fn latency_and_rate_have_a_range() {
        assert_eq!(check_latency_us(0), Ok(Duration::ZERO));
        assert_eq!(check_latency_us(255_000), Ok(Duration::from_millis(255)));
        let e = check_latency_us(999_999_999).expect_err("too long");
        assert!(e.to_string().contains("give 0 to 255000 us"), "{e}");
        assert_eq!(check_rate_hz(10.0), Ok(10.0));
        assert_eq!(check_rate_hz(10_000.0), Ok(10_000.0));
        for bad in [0.001, 9.99, 10_000.5, f64::NAN, -1.0] {
            let e = check_rate_hz(bad).expect_err("outside");
            assert!(e.to_string().contains("10 to 10000 Hz"), "{e}");
        }
    }

    #[test]
    fn generators_fit_what_is_left_of_the_plan() {
        // 500000 segments / (2 repetitions x 18 joints) = 13888 keyframes.
        assert_eq!(samples_left(0, 2, 18), 13_888);
        assert_eq!(samples_left(13_000, 2, 18), 888);
        assert_eq!(samples_left(20_000, 2, 18), 0);
        assert_eq!(check_samples(888.0, 13_000, 2, 18), Ok(()));
        let e = check_samples(889.0, 13_000, 2, 18).expect_err("one too many");
        assert_eq!(
            e.to_string(),
            "would make 889 samples, and the motion has room for 888 more (500000 joint \
             segments at most: keyframes x repetitions x joints)"
        );
        assert!(check_samples(f64::NAN, 0, 1, 1).is_err());
        assert!(check_samples(f64::INFINITY, 0, 1, 1).is_err());
    }

    #[test]
    fn lengths_and_segments_are_capped() {
        assert_eq!(check_length(86_400.0, 200.0), Ok(()));
        let e = check_length(1e12, 200.0).expect_err("too long");
        assert_eq!(
            e.to_string(),
            "1e12 s is longer than the limit of 86400 s (a day) for one motion"
        );
        let e = check_length(86_400.0, 1000.0).expect_err("too many cycles");
        assert!(e.to_string().contains("86400000 control cycles"), "{e}");
        assert!(check_length(f64::NAN, 200.0).is_err());
        assert_eq!(check_segments(9, 9_000, 6), Ok(()));
        let e = check_segments(9, 1_000_000_000, 6).expect_err("too many");
        assert!(e.to_string().contains("5.4e10 joint segments"), "{e}");
        assert!(e.to_string().contains("limit of 500000"), "{e}");
        assert_eq!(check_recording(100.0, 200.0, 6), Ok(()));
        assert!(matches!(
            check_recording(1e9, 200.0, 6),
            Err(LimitError::Duration { .. })
        ));
        assert!(matches!(
            check_recording(3600.0, 200.0, 6),
            Err(LimitError::TrackSteps { .. })
        ));
    }
}
