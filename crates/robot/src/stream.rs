//! The live stream's line format, read in one place for every front end
//! (`servobus stream`, the Zenoh `target` key, Python): one JSON object a
//! line, angles in the robot file's units.
//!
//! | line | meaning |
//! |---|---|
//! | `{"t": s, "joints": {"<name>": angle}}` | a target; `t` (the sender's clock, s) optional |
//! | `{"chunk": {"t0": s, "dt": s, "joints": {"<name>": [angle, ...]}}}` | an action chunk: points `dt` apart from `t0` (optional: on arrival) |
//!
//! A target names some joints or all (the others keep theirs); a chunk's
//! joints each give one angle per point. What a line means is checked
//! against the robot when it is sent ([`TargetSender`]).

use servobus_config::Units;
use servobus_runtime::{Chunk, LiveTarget, TargetError, TargetSender};

/// The longest line taken, bytes (as the longest file servobus reads).
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// What one line asks for.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// A target.
    Target(LiveTarget),
    /// An action chunk.
    Chunk(Chunk),
}

impl Input {
    /// Sends it to a run; returns how many angles were clamped to their
    /// limits.
    ///
    /// # Errors
    /// [`TargetError`] when the run refuses it or has ended.
    pub fn send(self, to: &TargetSender) -> Result<usize, TargetError> {
        match self {
            Input::Target(t) => to.send(t),
            Input::Chunk(c) => to.send_chunk(c),
        }
    }
}

/// Why a line is not a target or a chunk.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct LineError(String);

fn err(why: impl Into<String>) -> LineError {
    LineError(why.into())
}

/// Reads one line: a target (stamped `t`, or `arrival` when it has none,
/// s) or a chunk.
///
/// # Errors
/// [`LineError`] saying what is wrong with the line.
pub fn parse_line(line: &str, units: Units, arrival: f64) -> Result<Input, LineError> {
    let value: serde_json::Value =
        serde_json::from_str(line).map_err(|e| err(format!("not JSON: {e}")))?;
    let obj = value
        .as_object()
        .ok_or_else(|| err("not a JSON object: give {\"joints\": {\"<name>\": angle}}"))?;
    if let Some(chunk) = obj.get("chunk") {
        return parse_chunk(chunk, units).map(Input::Chunk);
    }
    let t = number_or_null(obj.get("t"), "t")?;
    let joints = obj
        .get("joints")
        .and_then(|j| j.as_object())
        .ok_or_else(|| err("no `joints` object: give {\"joints\": {\"<name>\": angle}}"))?;
    let mut out = Vec::with_capacity(joints.len());
    for (name, angle) in joints {
        let a = angle
            .as_f64()
            .ok_or_else(|| err(format!("joint `{name}`: the angle is not a number")))?;
        out.push((name.clone(), units.to_rad(a)));
    }
    Ok(Input::Target(LiveTarget::named(t.unwrap_or(arrival), out)))
}

/// A number, absent, or null.
fn number_or_null(v: Option<&serde_json::Value>, what: &str) -> Result<Option<f64>, LineError> {
    match v {
        None | Some(serde_json::Value::Null) => Ok(None),
        Some(t) => t
            .as_f64()
            .map(Some)
            .ok_or_else(|| err(format!("`{what}` is not a number"))),
    }
}

fn parse_chunk(chunk: &serde_json::Value, units: Units) -> Result<Chunk, LineError> {
    const SHAPE: &str =
        "give {\"chunk\": {\"t0\": s, \"dt\": s, \"joints\": {\"<name>\": [angle, ...]}}}";
    let obj = chunk
        .as_object()
        .ok_or_else(|| err(format!("`chunk` is not an object: {SHAPE}")))?;
    let t0 = number_or_null(obj.get("t0"), "chunk.t0")?;
    let dt = number_or_null(obj.get("dt"), "chunk.dt")?
        .ok_or_else(|| err(format!("the chunk has no `dt`: {SHAPE}")))?;
    let joints = obj
        .get("joints")
        .and_then(|j| j.as_object())
        .ok_or_else(|| err(format!("the chunk has no `joints` object: {SHAPE}")))?;
    let mut out = Vec::with_capacity(joints.len());
    for (name, angles) in joints {
        let list = angles
            .as_array()
            .ok_or_else(|| err(format!("chunk joint `{name}`: not a list of angles")))?;
        let angles = list
            .iter()
            .map(|a| a.as_f64().map(|a| units.to_rad(a)))
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(|| err(format!("chunk joint `{name}`: an angle is not a number")))?;
        out.push((name.clone(), angles));
    }
    Ok(Chunk::named(t0, dt, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_and_chunks_are_read_in_the_files_units() {
        let t = parse_line(r#"{"t": 1.5, "joints": {"a": 90}}"#, Units::Deg, 9.0);
        let want = LiveTarget::named(1.5, vec![("a".into(), std::f64::consts::FRAC_PI_2)]);
        assert_eq!(t, Ok(Input::Target(want)));
        let t = parse_line(r#"{"joints": {"a": 1}}"#, Units::Rad, 9.0);
        assert_eq!(
            t,
            Ok(Input::Target(LiveTarget::named(
                9.0,
                vec![("a".into(), 1.0)]
            )))
        );
        let c = parse_line(
            r#"{"chunk": {"dt": 0.02, "joints": {"a": [0, 1]}}}"#,
            Units::Rad,
            0.0,
        );
        let want = Chunk::named(None, 0.02, vec![("a".into(), vec![0.0, 1.0])]);
        assert_eq!(c, Ok(Input::Chunk(want)));
    }

    #[test]
    fn a_bad_line_says_what_is_wrong() {
        let why = |l: &str| match parse_line(l, Units::Deg, 0.0) {
            Err(e) => e.to_string(),
            Ok(i) => panic!("{l} read as {i:?}"),
        };
        assert!(why("{").starts_with("not JSON"));
        assert!(why("[1]").starts_with("not a JSON object"));
        assert!(why(r#"{"t": "x", "joints": {}}"#).contains("`t` is not a number"));
        assert!(why(r#"{"chunk": {"joints": {"a": [1]}}}"#).contains("no `dt`"));
        assert!(why(r#"{"chunk": {"dt": 0.1, "joints": {"a": 1}}}"#).contains("not a list"));
        assert!(why(r#"{"chunk": {"dt": 0.1, "joints": {"a": ["x"]}}}"#).contains("not a number"));
    }
}
