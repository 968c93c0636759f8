//! What travels on the node's keys, in JSON: the robot's state out, live
//! targets and commands in. Parsing never panics: a message that is not
//! one is a [`WireError`] saying why, and never moves the robot.

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::Serialize;

/// Why a message on `target` or `command` was not taken.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum WireError {
    /// The payload is not UTF-8 text.
    #[error("the payload is not UTF-8 text")]
    NotText,
    /// The payload is not the JSON expected.
    #[error("not a target: {0}; give {{\"joints\": {{\"<name>\": angle}}}}")]
    Target(String),
    /// The command is not one the node knows.
    #[error("unknown command `{0}`: give play <motion> [at <UTC time>], stop, pause, resume or torque_off")]
    UnknownCommand(String),
    /// `play` names no motion.
    #[error("`play` needs a motion: its name, a file, or YAML text")]
    NoMotion,
    /// The start time of `play ... at` is not a UTC time.
    #[error("`{0}` is not a UTC time: give e.g. 2026-11-25T20:00:00.250Z or UNIX seconds")]
    BadTime(String),
}

/// A live target from the `target` key: its stamp (seconds on the
/// sender's clock), if given, and angles by joint name in the robot file's
/// units.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetMessage {
    /// `t`, when the sender stamped the target.
    pub t: Option<f64>,
    /// Angles by joint name, in the robot file's units.
    pub joints: Vec<(String, f64)>,
    /// `sent_ns`, when the sender says when it published the target (ns
    /// since the UNIX epoch): the target's latency is then counted from
    /// there, network included (on machines whose clocks agree).
    pub sent_ns: Option<i64>,
}

/// Parses `{"t": <s, optional>, "joints": {"<name>": <angle>, ...}}`.
/// Whether the names are joints and the angles finite is the target
/// stream's to check (it counts and refuses, with the reason).
pub fn parse_target(payload: &[u8]) -> Result<TargetMessage, WireError> {
    let text = std::str::from_utf8(payload).map_err(|_| WireError::NotText)?;
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| WireError::Target(format!("not JSON ({e})")))?;
    let obj = value
        .as_object()
        .ok_or_else(|| WireError::Target("not a JSON object".into()))?;
    let t = match obj.get("t") {
        None | Some(serde_json::Value::Null) => None,
        Some(t) => Some(
            t.as_f64()
                .ok_or_else(|| WireError::Target("`t` is not a number".into()))?,
        ),
    };
    let sent_ns = match obj.get("sent_ns") {
        None | Some(serde_json::Value::Null) => None,
        Some(v) => Some(
            v.as_i64()
                .ok_or_else(|| WireError::Target("`sent_ns` is not an integer".into()))?,
        ),
    };
    let joints = obj
        .get("joints")
        .and_then(|j| j.as_object())
        .ok_or_else(|| WireError::Target("no `joints` object".into()))?;
    let mut out = Vec::with_capacity(joints.len());
    for (name, angle) in joints {
        let a = angle.as_f64().ok_or_else(|| {
            WireError::Target(format!("joint `{name}`: the angle is not a number"))
        })?;
        out.push((name.clone(), a));
    }
    Ok(TargetMessage {
        t,
        joints: out,
        sent_ns,
    })
}

/// A command from the `command` key.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeCommand {
    /// Play a motion (a shipped motion's name, a file, or YAML text), now
    /// or on the first control cycle at or after `at`.
    Play {
        /// The motion: name, path or YAML.
        motion: String,
        /// When to start, on this machine's clock.
        at: Option<SystemTime>,
    },
    /// Stop every joint (jerk limited) and hold.
    Stop,
    /// Pause the motion along its path.
    Pause,
    /// Resume a paused motion.
    Resume,
    /// Disable torque now.
    TorqueOff,
}

/// Parses a command: `play <motion> [at <UTC time>]`, `stop`, `pause`,
/// `resume`, `torque_off`. The time is RFC 3339 in UTC
/// (`2026-11-25T20:00:00.250Z`) or UNIX seconds.
pub fn parse_command(payload: &[u8]) -> Result<NodeCommand, WireError> {
    let text = std::str::from_utf8(payload).map_err(|_| WireError::NotText)?;
    let text = text.trim();
    let (word, rest) = match text.split_once(char::is_whitespace) {
        Some((w, r)) => (w, r.trim()),
        None => (text, ""),
    };
    let simple = |c: NodeCommand| {
        if rest.is_empty() {
            Ok(c)
        } else {
            Err(WireError::UnknownCommand(text.chars().take(80).collect()))
        }
    };
    match word {
        "stop" => simple(NodeCommand::Stop),
        "pause" => simple(NodeCommand::Pause),
        "resume" => simple(NodeCommand::Resume),
        "torque_off" => simple(NodeCommand::TorqueOff),
        "play" => {
            // `at <time>` ends a one-line motion; YAML text spans lines.
            let (motion, at) = match rest.rsplit_once(" at ") {
                Some((m, t)) if !t.contains('\n') && !m.trim().is_empty() => {
                    (m.trim(), Some(parse_utc(t.trim())?))
                }
                _ => (rest, None),
            };
            if motion.is_empty() {
                return Err(WireError::NoMotion);
            }
            Ok(NodeCommand::Play {
                motion: motion.to_string(),
                at,
            })
        }
        _ => Err(WireError::UnknownCommand(text.chars().take(80).collect())),
    }
}

/// Days from 1970-01-01 to a civil date (proleptic Gregorian).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// A UTC time: RFC 3339 with `Z` (fractional seconds allowed), or UNIX
/// seconds.
pub fn parse_utc(s: &str) -> Result<SystemTime, WireError> {
    let bad = || WireError::BadTime(s.chars().take(40).collect());
    if let Ok(secs) = s.parse::<f64>() {
        if (0.0..1e11).contains(&secs) {
            return Ok(UNIX_EPOCH + Duration::from_secs_f64(secs));
        }
        return Err(bad());
    }
    let s2 = s
        .strip_suffix('Z')
        .or_else(|| s.strip_suffix('z'))
        .ok_or_else(bad)?;
    let (date, time) = s2.split_once(['T', 't', ' ']).ok_or_else(bad)?;
    let num = |p: &str| p.parse::<i64>().map_err(|_| bad());
    let mut d = date.split('-');
    let (Some(y), Some(mo), Some(da), None) = (d.next(), d.next(), d.next(), d.next()) else {
        return Err(bad());
    };
    let (y, mo, da) = (num(y)?, num(mo)?, num(da)?);
    let mut t = time.split(':');
    let (Some(h), Some(mi), Some(sec), None) = (t.next(), t.next(), t.next(), t.next()) else {
        return Err(bad());
    };
    let (h, mi) = (num(h)?, num(mi)?);
    let sec: f64 = sec.parse().map_err(|_| bad())?;
    let ok = (1970..=9999).contains(&y)
        && (1..=12).contains(&mo)
        && (1..=31).contains(&da)
        && (0..24).contains(&h)
        && (0..60).contains(&mi)
        && (0.0..61.0).contains(&sec);
    if !ok {
        return Err(bad());
    }
    let whole = days_from_civil(y, mo, da) * 86_400 + h * 3600 + mi * 60;
    let whole = u64::try_from(whole).map_err(|_| bad())?;
    Ok(UNIX_EPOCH + Duration::from_secs(whole) + Duration::from_secs_f64(sec))
}

/// The robot's state, published on `state`: what one control cycle saw.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StateMessage {
    /// Time since the start of the run, s.
    pub t: f64,
    /// Wall-clock time of the sample, ns since the UNIX epoch.
    pub stamp_ns: i64,
    /// The control cycle.
    pub cycle: u64,
    /// The angle unit of every angle here.
    pub units: &'static str,
    /// Joint names, in the robot's order; every array follows it.
    pub joints: Vec<String>,
    /// Measured angles (null before a joint's first reading).
    pub measured: Vec<Option<f64>>,
    /// Commanded angles (the goals sent).
    pub commanded: Vec<f64>,
    /// Measured velocities, units/s.
    pub velocity: Vec<f64>,
    /// Faults so far, as text (empty while healthy).
    pub faults: Vec<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_target_names_joints() {
        let m = parse_target(br#"{"t": 1.5, "joints": {"elbow_flex": 30, "gripper": 2.5}}"#)
            .expect("a target");
        assert_eq!(m.t, Some(1.5));
        assert_eq!(m.sent_ns, None);
        assert_eq!(
            m.joints,
            vec![
                ("elbow_flex".to_string(), 30.0),
                ("gripper".to_string(), 2.5)
            ]
        );
        let m = parse_target(br#"{"sent_ns": 17, "joints": {}}"#).expect("a target");
        assert_eq!(m.sent_ns, Some(17));
    }

    #[test]
    fn malformed_targets_say_why() {
        for bad in [
            &b"\xff\xfe"[..],
            b"not json",
            b"[1, 2]",
            br#"{"t": 1}"#,
            br#"{"joints": {"elbow_flex": "far"}}"#,
            br#"{"t": "soon", "joints": {}}"#,
            br#"{"sent_ns": 1.5, "joints": {}}"#,
        ] {
            assert!(
                parse_target(bad).is_err(),
                "{:?}",
                String::from_utf8_lossy(bad)
            );
        }
    }

    #[test]
    fn commands_parse() {
        assert_eq!(parse_command(b" stop\n"), Ok(NodeCommand::Stop));
        assert_eq!(parse_command(b"torque_off"), Ok(NodeCommand::TorqueOff));
        assert_eq!(
            parse_command(b"play arm-wave"),
            Ok(NodeCommand::Play {
                motion: "arm-wave".into(),
                at: None
            })
        );
        let at = UNIX_EPOCH + Duration::from_millis(1_764_100_800_250);
        assert_eq!(
            parse_command(b"play arm-wave at 2025-11-25T20:00:00.250Z"),
            Ok(NodeCommand::Play {
                motion: "arm-wave".into(),
                at: Some(at)
            })
        );
        assert!(matches!(parse_command(b"play"), Err(WireError::NoMotion)));
        assert!(matches!(
            parse_command(b"stop now"),
            Err(WireError::UnknownCommand(_))
        ));
        assert!(matches!(
            parse_command(b"dance"),
            Err(WireError::UnknownCommand(_))
        ));
        assert!(matches!(
            parse_command(b"play arm-wave at tomorrow"),
            Err(WireError::BadTime(_))
        ));
    }

    #[test]
    fn utc_times_by_hand() {
        // 2000-03-01T00:00:00Z is 951868800 s after the epoch.
        assert_eq!(
            parse_utc("2000-03-01T00:00:00Z"),
            Ok(UNIX_EPOCH + Duration::from_secs(951_868_800))
        );
        assert_eq!(
            parse_utc("12.5"),
            Ok(UNIX_EPOCH + Duration::from_millis(12_500))
        );
        for bad in [
            "2000-13-01T00:00:00Z",
            "2000-01-01T00:00:00",
            "-3",
            "NaN",
            "",
        ] {
            assert!(parse_utc(bad).is_err(), "{bad}");
        }
    }
}
