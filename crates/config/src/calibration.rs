//! Calibration files: where one physical robot's joints really are.
//!
//! A robot file describes a design; every robot built from it has its servo
//! horns fitted at their own angles. The calibration file belongs to one
//! physical robot and says, per joint, which servo tick the joint reads in
//! the calibration pose, which way the ticks run, and the range the joint
//! was measured to travel:
//!
//! ```yaml
//! robot: so101
//! taken: 2026-11-24T00:31:07Z
//! joints:
//!   - name: shoulder_pan
//!     id: 1
//!     model: STS3215
//!     firmware: "3.10"
//!     homing_offset: 0      # register 31 while calibrating (present = actual - offset)
//!     pose_deg: 0           # the joint's angle in the calibration pose
//!     pose_tick: 3990       # Present_Position in that pose
//!     direction: -1         # -1: rising ticks turn the joint negative
//!     range: [3700, 4380]   # measured, unwrapped: past 4095 it crossed the seam
//! ```
//!
//! Ticks are in the present-position frame of `homing_offset`. A range that
//! crosses the seam is played by moving the frame (see [`seam`](super::seam)):
//! [`JointCalibration::play_frame`] says how.

use std::path::Path;

use serde::{Deserialize, Serialize};
use servobus_protocol::registers::{model_by_name, Model};

use super::error::{ConfigError, Source};
use super::locate::FieldPath;
use super::seam::{centring_offset, turn_ticks, MAX_HOMING_OFFSET};

/// How far inside the measured range the joint limits are kept, degrees:
/// the ends were found by hand against the end stops, so a goal right at
/// one would press the servo into its stop.
pub const RANGE_MARGIN_DEG: f64 = 3.0;

/// One physical robot's calibration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(expecting = "a calibration file: a mapping with `robot:`, `taken:` and `joints:`")]
pub struct Calibration {
    /// The robot file's `name` it was taken for.
    pub robot: String,
    /// When it was taken (UTC, RFC 3339), or where it came from.
    pub taken: String,
    /// Every joint, in the robot's joint order.
    pub joints: Vec<JointCalibration>,
}

/// One joint's calibration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "a joint's calibration: a mapping with `name:`, `id:`, `model:`, `pose_deg:`, `pose_tick:`, `direction:` and `range:`"
)]
pub struct JointCalibration {
    /// The joint's name in the robot file.
    pub name: String,
    /// The servo's ID.
    pub id: u8,
    /// The servo's model, as it reported it (`STS3215`).
    pub model: String,
    /// The servo's firmware version, `major.minor` (absent when imported).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub firmware: Option<String>,
    /// The homing offset (register 31) the servo held: ticks below are
    /// `actual - homing_offset`.
    #[serde(default)]
    pub homing_offset: i32,
    /// The joint's angle in the calibration pose, degrees.
    pub pose_deg: f64,
    /// Present position in the calibration pose. Written as the integer
    /// it is (`2048`, not `2048.0`); read from either. A LeRobot import
    /// puts the pose at the middle of the range, half a tick when the
    /// range's ends add up to an odd number: that is written as it is.
    #[serde(serialize_with = "serialize_tick")]
    pub pose_tick: f64,
    /// +1 when rising ticks turn the joint positive, -1 otherwise.
    pub direction: i8,
    /// Lowest and highest present position measured, unwrapped: the
    /// minimum is in `[0, turn)`, the maximum may pass the turn when the
    /// range crosses the seam.
    pub range: [i64; 2],
}

/// Writes a tick as an integer when it is a whole number (every measured
/// one), else as the float it is.
fn serialize_tick<S: serde::Serializer>(tick: &f64, s: S) -> Result<S::Ok, S::Error> {
    // Every whole number below 2^53 converts to i64 exactly; a tick is far
    // below that.
    if tick.fract() == 0.0 && tick.abs() < 9_007_199_254_740_992.0 {
        s.serialize_i64(*tick as i64)
    } else {
        s.serialize_f64(*tick)
    }
}

/// The frame a joint is played in: the homing offset its servo must hold
/// and how far that frame is shifted from the calibration's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlayFrame {
    /// Homing offset the servo must hold while playing.
    pub homing_offset: i32,
    /// Present position while playing = calibration tick - `shift`.
    pub shift: i64,
}

impl JointCalibration {
    /// The servo model named, if known.
    pub fn servo_model(&self) -> Option<&'static Model> {
        model_by_name(&self.model)
    }

    /// Whether the measured range crosses the seam in the calibration's frame.
    pub fn crosses_seam(&self) -> bool {
        self.servo_model()
            .and_then(turn_ticks)
            .is_some_and(|turn| self.range[1] >= i64::from(turn))
    }

    /// The frame to play in: the calibration's own when the range stays on
    /// one side of the seam, else one whose homing offset centres the range.
    pub fn play_frame(&self) -> PlayFrame {
        let turn = self.servo_model().and_then(turn_ticks);
        match turn {
            Some(turn) if self.crosses_seam() => {
                let (homing_offset, shift) = centring_offset(self.range, self.homing_offset, turn);
                PlayFrame {
                    homing_offset,
                    shift,
                }
            }
            _ => PlayFrame {
                homing_offset: self.homing_offset,
                shift: 0,
            },
        }
    }

    /// The same calibration moved to `frame`: ticks shifted, offset replaced
    /// (what `--write-servos` records after writing the offset).
    pub fn in_frame(&self, frame: PlayFrame) -> JointCalibration {
        JointCalibration {
            homing_offset: frame.homing_offset,
            pose_tick: self.pose_tick - frame.shift as f64,
            range: [self.range[0] - frame.shift, self.range[1] - frame.shift],
            ..self.clone()
        }
    }

    /// Joint angle, degrees, of an unwrapped tick in this calibration's frame.
    pub fn degrees_at(&self, model: &Model, tick: f64) -> f64 {
        self.pose_deg + f64::from(self.direction) * (tick - self.pose_tick) * model.deg_per_tick()
    }

    /// The joint angles, degrees, at the two ends of the measured range;
    /// lowest first.
    pub fn range_deg(&self, model: &Model) -> (f64, f64) {
        let a = self.degrees_at(model, self.range[0] as f64);
        let b = self.degrees_at(model, self.range[1] as f64);
        (a.min(b), a.max(b))
    }

    /// The joint angles, degrees, at the two ends of the measured range,
    /// each brought [`RANGE_MARGIN_DEG`] inwards; lowest first. The
    /// calibration pose stays reachable: where it lies within the margin of
    /// an end (a gripper held closed against its stop), that side's limit is
    /// the pose itself.
    pub fn limits_deg(&self, model: &Model) -> (f64, f64) {
        let (lo, hi) = self.range_deg(model);
        let pose = self.pose_deg.clamp(lo, hi);
        (
            (lo + RANGE_MARGIN_DEG).min(pose),
            (hi - RANGE_MARGIN_DEG).max(pose),
        )
    }
}

/// Loads a calibration file.
///
/// # Errors
/// [`ConfigError::Read`] when it cannot be read, [`ConfigError::Invalid`]
/// pointing at the first wrong field: an unknown model, a direction other
/// than +-1, an offset beyond +-2047, a range the wrong way round, wider
/// than a turn, or not holding its own pose.
pub fn load_calibration(path: &Path) -> Result<Calibration, ConfigError> {
    load_source(path).map(|(cal, _)| cal)
}

/// Loads and validates a calibration file, and keeps its text for errors.
pub(crate) fn load_source(path: &Path) -> Result<(Calibration, Source), ConfigError> {
    let src = Source::read(path)?;
    let cal: Calibration = src.parse()?;
    validate(&cal, &src)?;
    Ok((cal, src))
}

/// Why a calibration could not be saved.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationSaveError {
    /// The calibration could not be put in YAML (a value YAML cannot hold).
    #[error("cannot write the calibration of `{robot}` as YAML: {source}")]
    Yaml {
        /// The robot it is the calibration of.
        robot: String,
        /// The serialiser's error.
        #[source]
        source: serde_yaml::Error,
    },
    /// The file could not be written; an earlier file at the path is as it
    /// was.
    #[error(transparent)]
    Output(#[from] servobus_io::OutputError),
}

/// Writes `cal` to `path` as YAML, with a header saying what it is. The file
/// is replaced whole or not at all ([`servobus_io::write_atomic`]): a
/// failure leaves an earlier calibration at `path` untouched.
///
/// # Errors
/// [`CalibrationSaveError::Yaml`] when the calibration cannot be put in
/// YAML, [`CalibrationSaveError::Output`] (naming the file) when it cannot
/// be written.
pub fn save_calibration(cal: &Calibration, path: &Path) -> Result<(), CalibrationSaveError> {
    let body = serde_yaml::to_string(cal).map_err(|source| CalibrationSaveError::Yaml {
        robot: cal.robot.clone(),
        source,
    })?;
    let text = format!(
        "# servobus calibration of one physical `{}` robot: ticks of the calibration\n\
         # pose, directions and measured ranges (servobus calibrate). Angles in the\n\
         # robot's files mean physical angles through this file.\n{body}",
        cal.robot
    );
    servobus_io::write_atomic(path, text.as_bytes())?;
    Ok(())
}

fn validate(cal: &Calibration, src: &Source) -> Result<(), ConfigError> {
    let root = FieldPath::root();
    for (i, j) in cal.joints.iter().enumerate() {
        let jp = root.key("joints").index(i);
        let Some(model) = j.servo_model() else {
            return Err(src.error(&jp.key("model"), format!("unknown model `{}`", j.model)));
        };
        if j.direction != 1 && j.direction != -1 {
            return Err(src.error(&jp.key("direction"), "must be 1 or -1"));
        }
        if j.homing_offset.abs() > MAX_HOMING_OFFSET {
            return Err(src.error(
                &jp.key("homing_offset"),
                format!("the register holds -2047..=2047, got {}", j.homing_offset),
            ));
        }
        let [lo, hi] = j.range;
        let top = i64::from(model.max_position());
        let ok = match turn_ticks(model) {
            Some(turn) => {
                (0..i64::from(turn)).contains(&lo) && lo < hi && hi - lo < i64::from(turn)
            }
            None => 0 <= lo && lo < hi && hi <= top,
        };
        if !ok {
            return Err(src.error(
                &jp.key("range"),
                format!(
                    "[{lo}, {hi}] is not a range of the {}: the minimum goes from 0 to {top}, \
                     the maximum above it by less than a turn",
                    model.name
                ),
            ));
        }
        if !(j.pose_tick >= lo as f64 && j.pose_tick <= hi as f64 && j.pose_deg.is_finite()) {
            return Err(src.error(
                &jp.key("pose_tick"),
                format!("{} is outside the range [{lo}, {hi}]", j.pose_tick),
            ));
        }
    }
    Ok(())
}

/// The current UTC time as RFC 3339 (`2026-11-24T00:31:07Z`), for
/// [`Calibration::taken`].
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_string(secs)
}

/// Seconds since 1970 as an RFC 3339 UTC date and time.
fn utc_string(secs: u64) -> String {
    let days = i64::try_from(secs / 86_400).unwrap_or(0);
    let rem = secs % 86_400;
    // Days to civil date (proleptic Gregorian), eras of 400 years.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A calibration of one STS3215 joint whose pose reads `pose_tick`.
    fn one_joint(pose_tick: f64) -> Calibration {
        Calibration {
            robot: "arm".to_owned(),
            taken: "2026-11-24T00:31:07Z".to_owned(),
            joints: vec![JointCalibration {
                name: "pan".to_owned(),
                id: 1,
                model: "STS3215".to_owned(),
                firmware: None,
                homing_offset: 0,
                pose_deg: 0.0,
                pose_tick,
                direction: 1,
                range: [1000, 3000],
            }],
        }
    }

    #[test]
    fn a_pose_tick_is_written_as_an_integer_and_read_from_either_form() {
        let path = std::env::temp_dir().join(format!(
            "servobus-config-pose-tick-{}.calibration.yaml",
            std::process::id()
        ));
        let cal = one_joint(2048.0);
        save_calibration(&cal, &path).expect("saves");
        let text = std::fs::read_to_string(&path).expect("reads");
        assert!(text.contains("pose_tick: 2048\n"), "{text}");
        assert_eq!(load_calibration(&path).expect("loads"), cal);
        // A file written before, with the tick as a float, still loads.
        std::fs::write(
            &path,
            text.replace("pose_tick: 2048\n", "pose_tick: 2048.0\n"),
        )
        .expect("writes");
        assert_eq!(load_calibration(&path).expect("loads the float"), cal);
        // Half a tick (a LeRobot range's middle) is kept as it is.
        let half = one_joint(2655.5);
        save_calibration(&half, &path).expect("saves");
        let text = std::fs::read_to_string(&path).expect("reads");
        assert!(text.contains("pose_tick: 2655.5\n"), "{text}");
        assert_eq!(load_calibration(&path).expect("loads"), half);
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn dates_are_civil_utc() {
        assert_eq!(utc_string(0), "1970-01-01T00:00:00Z");
        // 2000-02-29 12:34:56 UTC, a leap day.
        assert_eq!(utc_string(951_827_696), "2000-02-29T12:34:56Z");
    }
}
