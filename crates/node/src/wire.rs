//! What travels on the node's keys, in JSON: the robot's state out, live
//! targets, action chunks and commands in. Parsing never panics: a
//! message that is not one is a [`WireError`] saying why, and never moves
//! the robot.
//!
//! | key | payload | parsed by |
//! |---|---|---|
//! | `target` | `{"t": s?, "joints": {"<name>": angle}, "sent_ns": ns?}` | [`parse_live`] ([`parse_target`]) |
//! | `target` | `{"t": s?, "grasp": {"<name>": effort %}, "joints"?: ..., "base"?: ...}` | [`parse_live`] ([`parse_target`]) |
//! | `target` | `{"chunk": {"t0": s?, "dt": s, "joints": {"<name>": [angle, ...]}}, "sent_ns": ns?}` | [`parse_live`] ([`parse_chunk`]) |
//! | `command` | `play <motion> [at <UTC>]`, `stop`, `pause`, `resume`, `torque_off`, `shutdown` | [`parse_command`] |
//! | `state` | [`StateMessage`] | (published) |

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
    /// The payload is a chunk, but not a well-formed one.
    #[error("not a chunk: {0}; give {{\"chunk\": {{\"t0\": s (optional), \"dt\": s, \"joints\": {{\"<name>\": [angle, ...]}}}}}}")]
    Chunk(String),
    /// The command is not one the node knows.
    #[error("unknown command `{0}`: give play <motion> [at <UTC time>], stop, pause, resume, torque_off or shutdown")]
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
    /// Angles by joint name, in the robot file's units (a wheel joint's:
    /// its speed, units/s).
    pub joints: Vec<(String, f64)>,
    /// `base`, a mobile base's velocity: `{"x": m/s, "y": m/s, "theta":
    /// units/s}` (each optional, 0 when absent); its wheels' speeds are the
    /// robot's to work out ([`Robot::wheel_targets`](servobus_robot::config::Robot::wheel_targets)).
    pub base: Option<servobus_robot::config::BaseTarget>,
    /// `grasp`: joints told to grasp, by name, with their effort in
    /// percent of the servo's torque (see
    /// [`LiveTarget::with_grasps`](servobus_robot::LiveTarget::with_grasps));
    /// empty when none. None of them is in `joints`; whether each effort is
    /// one the joint can make is the target stream's to check.
    pub grasps: Vec<(String, f64)>,
    /// `sent_ns`, when the sender says when it published the target (ns
    /// since the UNIX epoch): the target's latency is then counted from
    /// there, network included (on machines whose clocks agree).
    pub sent_ns: Option<i64>,
}

/// An action chunk from the `target` key: points `dt` s apart, the first
/// at `t0` (seconds on the sender's clock; on arrival when absent), angles
/// by joint name in the robot file's units, one per point.
#[derive(Debug, Clone, PartialEq)]
pub struct ChunkMessage {
    /// `t0`, the sender's stamp of the first point, if given.
    pub t0: Option<f64>,
    /// `dt`, the time between points, s (positive).
    pub dt: f64,
    /// Per joint by name, its angles, one per point (every joint the same
    /// number, at least one).
    pub joints: Vec<(String, Vec<f64>)>,
    /// `sent_ns`, when the sender published the chunk (see
    /// [`TargetMessage::sent_ns`]).
    pub sent_ns: Option<i64>,
}

/// What the `target` key carries: a target or an action chunk.
#[derive(Debug, Clone, PartialEq)]
pub enum LiveMessage {
    /// `{"t", "joints"}`: go there.
    Target(TargetMessage),
    /// `{"chunk": {...}}`: follow the timed path through its points.
    Chunk(ChunkMessage),
}

type Object = serde_json::Map<String, serde_json::Value>;

/// The payload as a JSON object.
fn object(payload: &[u8]) -> Result<Object, WireError> {
    let text = std::str::from_utf8(payload).map_err(|_| WireError::NotText)?;
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| WireError::Target(format!("not JSON ({e})")))?;
    match value {
        serde_json::Value::Object(o) => Ok(o),
        _ => Err(WireError::Target("not a JSON object".into())),
    }
}

/// `obj[key]` as a number when present and not null.
fn number(obj: &Object, key: &str) -> Result<Option<f64>, String> {
    match obj.get(key) {
        None | Some(serde_json::Value::Null) => Ok(None),
        Some(v) => v
            .as_f64()
            .map(Some)
            .ok_or_else(|| format!("`{key}` is not a number")),
    }
}

/// `sent_ns` when present and not null.
fn sent_ns(obj: &Object) -> Result<Option<i64>, String> {
    match obj.get("sent_ns") {
        None | Some(serde_json::Value::Null) => Ok(None),
        Some(v) => v
            .as_i64()
            .map(Some)
            .ok_or_else(|| "`sent_ns` is not an integer".to_string()),
    }
}

/// Parses what the `target` key carries: a target
/// `{"t": <s, optional>, "joints": {"<name>": <angle>, ...}}` (with a
/// `base` velocity and `grasp` efforts, or either alone) or an action
/// chunk `{"chunk": {"t0": <s, optional>, "dt": <s>, "joints": {"<name>":
/// [<angle>, ...], ...}}}`, either with an optional `sent_ns`.
pub fn parse_live(payload: &[u8]) -> Result<LiveMessage, WireError> {
    let obj = object(payload)?;
    if obj.contains_key("chunk") {
        chunk_of(&obj).map(LiveMessage::Chunk)
    } else {
        target_of(&obj).map(LiveMessage::Target)
    }
}

/// Parses `{"t": <s, optional>, "joints": {"<name>": <angle>, ...}}`.
/// Whether the names are joints and the angles finite is the target
/// stream's to check (it counts and refuses, with the reason).
pub fn parse_target(payload: &[u8]) -> Result<TargetMessage, WireError> {
    target_of(&object(payload)?)
}

fn target_of(obj: &Object) -> Result<TargetMessage, WireError> {
    let t = number(obj, "t").map_err(WireError::Target)?;
    let sent_ns = sent_ns(obj).map_err(WireError::Target)?;
    let base = match obj.get("base") {
        None | Some(serde_json::Value::Null) => None,
        Some(b) => Some(base_of(b)?),
    };
    let grasps = match obj.get("grasp") {
        None | Some(serde_json::Value::Null) => None,
        Some(g) => Some(grasps_of(g)?),
    };
    let none = Object::new();
    let joints = match obj.get("joints") {
        Some(j) => j
            .as_object()
            .ok_or_else(|| WireError::Target("`joints` is not an object".into()))?,
        None if base.is_some() || grasps.is_some() => &none,
        None => return Err(WireError::Target("no `joints` object".into())),
    };
    let grasps = grasps.unwrap_or_default();
    let mut out = Vec::with_capacity(joints.len());
    for (name, angle) in joints {
        let a = angle.as_f64().ok_or_else(|| {
            WireError::Target(format!("joint `{name}`: the angle is not a number"))
        })?;
        if grasps.iter().any(|(g, _)| g == name) {
            return Err(WireError::Target(format!(
                "joint `{name}` is given an angle and a `grasp`: a joint grasps or goes to an angle, not both"
            )));
        }
        out.push((name.clone(), a));
    }
    Ok(TargetMessage {
        t,
        joints: out,
        base,
        grasps,
        sent_ns,
    })
}

/// A target's `grasp`: `{"<name>": effort %, ...}`.
fn grasps_of(value: &serde_json::Value) -> Result<Vec<(String, f64)>, WireError> {
    let obj = value.as_object().ok_or_else(|| {
        WireError::Target("grasp: not an object: give {\"<name>\": effort %}".into())
    })?;
    obj.iter()
        .map(|(name, effort)| {
            effort.as_f64().map(|e| (name.clone(), e)).ok_or_else(|| {
                WireError::Target(format!(
                    "grasp `{name}`: the effort is not a number (percent of the servo's torque)"
                ))
            })
        })
        .collect()
}

/// A target's `base`: `{"x": m/s, "y": m/s, "theta": units/s}`, each
/// optional (0), nothing else.
fn base_of(value: &serde_json::Value) -> Result<servobus_robot::config::BaseTarget, WireError> {
    let bad = |why: String| WireError::Target(format!("base: {why}"));
    let obj = value.as_object().ok_or_else(|| {
        bad("not an object: give {\"x\": m/s, \"y\": m/s, \"theta\": units/s}".into())
    })?;
    if let Some(key) = obj
        .keys()
        .find(|k| !["x", "y", "theta"].contains(&k.as_str()))
    {
        return Err(bad(format!("no field `{key}` (x, y and theta are)")));
    }
    let field = |k: &str| number(obj, k).map(|v| v.unwrap_or(0.0)).map_err(bad);
    Ok(servobus_robot::config::BaseTarget {
        x: field("x")?,
        y: field("y")?,
        theta: field("theta")?,
    })
}

/// Parses an action chunk,
/// `{"chunk": {"t0": <s, optional>, "dt": <s>, "joints": {"<name>": [<angle>, ...]}}}`.
/// Its shape is checked here: `dt` a positive number, `t0` a number, at
/// least one joint, every joint the same number of angles (1 to
/// [`MAX_CHUNK_POINTS`](servobus_robot::MAX_CHUNK_POINTS)); whether the
/// names are joints is the target stream's to check.
pub fn parse_chunk(payload: &[u8]) -> Result<ChunkMessage, WireError> {
    chunk_of(&object(payload)?)
}

fn chunk_of(obj: &Object) -> Result<ChunkMessage, WireError> {
    let bad = WireError::Chunk;
    if ["joints", "t", "grasp"]
        .iter()
        .any(|k| obj.contains_key(*k))
    {
        return Err(bad(
            "give either a target (`t`, `joints`, `grasp`) or a `chunk`, not both".into(),
        ));
    }
    let sent_ns = sent_ns(obj).map_err(bad)?;
    let chunk = obj
        .get("chunk")
        .and_then(|c| c.as_object())
        .ok_or_else(|| bad("`chunk` is not a JSON object".into()))?;
    let t0 = number(chunk, "t0").map_err(bad)?;
    let dt = number(chunk, "dt")
        .map_err(bad)?
        .ok_or_else(|| bad("no `dt`, the seconds between points".into()))?;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(bad(format!(
            "`dt` {dt} is not a positive number of seconds"
        )));
    }
    let joints = chunk
        .get("joints")
        .and_then(|j| j.as_object())
        .ok_or_else(|| bad("no `joints` object".into()))?;
    if joints.is_empty() {
        return Err(bad("`joints` names no joint".into()));
    }
    let most = servobus_robot::MAX_CHUNK_POINTS;
    let mut out = Vec::with_capacity(joints.len());
    let mut points = None;
    for (name, angles) in joints {
        let angles = angles
            .as_array()
            .ok_or_else(|| bad(format!("joint `{name}`: not a list of angles")))?;
        let n = *points.get_or_insert(angles.len());
        if n == 0 || n > most {
            return Err(bad(format!(
                "joint `{name}`: {n} angles; a chunk holds 1 to {most} points"
            )));
        }
        if angles.len() != n {
            return Err(bad(format!(
                "joint `{name}`: {} angles, the chunk's other joints {n}",
                angles.len()
            )));
        }
        let angles = angles
            .iter()
            .map(serde_json::Value::as_f64)
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(|| bad(format!("joint `{name}`: an angle is not a number")))?;
        out.push((name.clone(), angles));
    }
    Ok(ChunkMessage {
        t0,
        dt,
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
    /// Stop the motion: every joint comes to a jerk-limited stop and
    /// holds; the node goes on serving (a later target, chunk or `play`
    /// moves the robot again).
    Stop,
    /// Pause the motion along its path.
    Pause,
    /// Resume a paused motion.
    Resume,
    /// Disable torque now (the run ends).
    TorqueOff,
    /// Stop every joint (jerk limited), hold, end the run and the node
    /// (after its linger for `report`): what Ctrl-C does.
    Shutdown,
}

impl std::fmt::Display for NodeCommand {
    /// The command as [`parse_command`] reads it (a start time as UNIX
    /// seconds to the microsecond): what a conductor sends.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NodeCommand::Play { motion, at: None } => write!(f, "play {motion}"),
            NodeCommand::Play {
                motion,
                at: Some(at),
            } => {
                let secs = at
                    .duration_since(UNIX_EPOCH)
                    .map_or(0.0, |d| d.as_secs_f64());
                write!(f, "play {motion} at {secs:.6}")
            }
            NodeCommand::Stop => f.write_str("stop"),
            NodeCommand::Pause => f.write_str("pause"),
            NodeCommand::Resume => f.write_str("resume"),
            NodeCommand::TorqueOff => f.write_str("torque_off"),
            NodeCommand::Shutdown => f.write_str("shutdown"),
        }
    }
}

/// Parses a command: `play <motion> [at <UTC time>]`, `stop`, `pause`,
/// `resume`, `torque_off`, `shutdown`. The time is RFC 3339 in UTC
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
        "shutdown" => simple(NodeCommand::Shutdown),
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
    /// A mobile base's odometry (from its wheels' measured speeds, since
    /// the start): x along the floor where it started, m; left of that, m;
    /// its heading, deg counter-clockwise. Left out for a robot without a
    /// base.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base_x_m: Option<f64>,
    /// See [`base_x_m`](Self::base_x_m).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base_y_m: Option<f64>,
    /// See [`base_x_m`](Self::base_x_m).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base_theta_deg: Option<f64>,
}

#[cfg(test)]
mod tests;
