//! The live stream's line format, read in one place for every front end
//! (`servobus stream`, the Zenoh `target` key, Python): one JSON object a
//! line, angles in the robot file's units.
//!
//! | line | meaning |
//! |---|---|
//! | `{"t": s, "joints": {"<name>": angle}}` | a target; `t` (the sender's clock, s) optional |
//! | `{"chunk": {"t0": s, "dt": s, "joints": {"<name>": [angle, ...]}}}` | an action chunk: points `dt` apart from `t0` (optional: on arrival) |
//! | `{"t": s, "base": {"x": m/s, "y": m/s, "theta": units/s}}` | a mobile base's velocity ([`parse_line_for`]): its wheels' speeds, with `joints` or alone |
//! | `{"t": s, "grasp": {"<name>": effort %}}` | grippers told to grasp ([`LiveTarget::with_grasps`]): close until they meet something, then hold with `effort` percent of the servo's torque; with `joints` and `base` or alone |
//!
//! A target names some joints or all (the others keep theirs); a chunk's
//! joints each give one angle per point; a wheel joint's value is a speed
//! (units/s). A joint grasps or has a position in one target, not both.
//! What a line means is checked against the robot when it is sent
//! ([`TargetSender`]): an unknown joint, an effort not above 0 and at most
//! 100, a grasp for a wheel.

use servobus_config::{BaseTarget, Robot, Units};
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
/// s), with its grasps if it has any, or a chunk.
///
/// # Errors
/// [`LineError`] saying what is wrong with the line (a joint given both a
/// position and a grasp, a grasp beside a chunk among them).
pub fn parse_line(line: &str, units: Units, arrival: f64) -> Result<Input, LineError> {
    parse(line, units, None, arrival)
}

/// [`parse_line`] for `robot`, whose base (if it has one) a `base` velocity
/// drives: its wheel joints' speeds ([`Robot::wheel_targets`], all scaled
/// together within their limits), joined to the line's `joints`.
///
/// # Errors
/// [`LineError`] saying what is wrong with the line, or why the base
/// cannot move so (no base, a differential base sideways), or a wheel
/// given both in `joints` and by the base.
pub fn parse_line_for(line: &str, robot: &Robot, arrival: f64) -> Result<Input, LineError> {
    parse(line, robot.units, Some(robot), arrival)
}

/// Reads one line for [`parse_line`] and [`parse_line_for`].
fn parse(
    line: &str,
    units: Units,
    robot: Option<&Robot>,
    arrival: f64,
) -> Result<Input, LineError> {
    const SHAPE: &str = "give {\"joints\": {\"<name>\": angle}}";
    let value: serde_json::Value =
        serde_json::from_str(line).map_err(|e| err(format!("not JSON: {e}")))?;
    let obj = value
        .as_object()
        .ok_or_else(|| err(format!("not a JSON object: {SHAPE}")))?;
    if let Some(chunk) = obj.get("chunk") {
        if obj.contains_key("grasp") {
            return Err(err(
                "a `grasp` goes in a target line, not beside a `chunk`: send it on its own line",
            ));
        }
        return parse_chunk(chunk, units).map(Input::Chunk);
    }
    let t = number_or_null(obj.get("t"), "t")?;
    let base = obj.get("base");
    let grasp = obj.get("grasp").filter(|g| !g.is_null());
    let grasps = grasps(grasp)?;
    let joints = match obj.get("joints") {
        Some(j) => j
            .as_object()
            .ok_or_else(|| err(format!("`joints` is not an object: {SHAPE}")))?,
        None if base.is_some() || grasp.is_some() => &serde_json::Map::new(),
        None => return Err(err(format!("no `joints` object: {SHAPE}"))),
    };
    let mut out = Vec::with_capacity(joints.len());
    for (name, angle) in joints {
        let a = angle
            .as_f64()
            .ok_or_else(|| err(format!("joint `{name}`: the angle is not a number")))?;
        out.push((name.clone(), units.to_rad(a)));
    }
    if let Some(base) = base {
        let robot = robot.ok_or_else(|| err("a `base` target needs the robot's base"))?;
        for (wheel, speed) in wheel_speeds(base, robot)? {
            if out.iter().any(|(n, _)| *n == wheel) {
                return Err(err(format!(
                    "wheel `{wheel}` is driven by the `base` target: give its speed in `joints` or the base's velocity, not both"
                )));
            }
            out.push((wheel, speed));
        }
    }
    if let Some((name, _)) = grasps.iter().find(|(g, _)| out.iter().any(|(n, _)| n == g)) {
        return Err(err(format!(
            "joint `{name}` is given a position and a `grasp`: a joint grasps or goes to a position, not both"
        )));
    }
    let target = LiveTarget::named(t.unwrap_or(arrival), out).with_grasps(grasps);
    Ok(Input::Target(target))
}

/// A line's `grasp`: `{"<name>": effort %, ...}` (none when absent).
/// Whether each effort is one the joint can make is the sender's to check.
fn grasps(grasp: Option<&serde_json::Value>) -> Result<Vec<(String, f64)>, LineError> {
    const SHAPE: &str = "give {\"grasp\": {\"<name>\": effort %}}";
    let obj = match grasp {
        None => return Ok(Vec::new()),
        Some(g) => g
            .as_object()
            .ok_or_else(|| err(format!("`grasp` is not an object: {SHAPE}")))?,
    };
    obj.iter()
        .map(|(name, effort)| {
            effort.as_f64().map(|e| (name.clone(), e)).ok_or_else(|| {
                err(format!(
                    "grasp `{name}`: the effort is not a number (percent of the servo's torque)"
                ))
            })
        })
        .collect()
}

/// The wheel speeds (rad/s) of a line's `base` velocity on `robot`.
fn wheel_speeds(base: &serde_json::Value, robot: &Robot) -> Result<Vec<(String, f64)>, LineError> {
    const SHAPE: &str = "give {\"base\": {\"x\": m/s, \"y\": m/s, \"theta\": units/s}}";
    let obj = base
        .as_object()
        .ok_or_else(|| err(format!("`base` is not an object: {SHAPE}")))?;
    if let Some(key) = obj
        .keys()
        .find(|k| !["x", "y", "theta"].contains(&k.as_str()))
    {
        return Err(err(format!("`base.{key}`: no such field: {SHAPE}")));
    }
    let field =
        |k: &str| number_or_null(obj.get(k), &format!("base.{k}")).map(|v| v.unwrap_or(0.0));
    let target = BaseTarget {
        x: field("x")?,
        y: field("y")?,
        theta: field("theta")?,
    };
    robot
        .wheel_targets(&target)
        .map(|w| w.wheels)
        .map_err(|e| err(e.to_string()))
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

    /// A cart: an arm joint and a differential base of 50 mm wheels 200 mm
    /// apart, at 180 deg/s at most.
    fn cart() -> Robot {
        let text = "name: cart\nunits: deg\nbuses:\n  - name: b\n    joints:\n      \
             - {name: arm, id: 1, model: sts3215, min: -90, max: 90, max_velocity: 100, max_acceleration: 400}\n      \
             - {name: l, id: 2, model: sts3215, mode: wheel, max_velocity: 180, max_acceleration: 900}\n      \
             - {name: r, id: 3, model: sts3215, mode: wheel, max_velocity: 180, max_acceleration: 900}\n\
             base:\n  differential: {wheel_radius_mm: 50, track_mm: 200, left: l, right: r}\n";
        let source = servobus_config::RobotSource::Text {
            name: std::path::Path::new("<text>"),
            text,
        };
        servobus_config::load_robot(source, &servobus_config::RobotOptions::default())
            .expect("the cart loads")
    }

    #[test]
    fn a_base_velocity_is_its_wheels_speeds_with_the_lines_joints() {
        let cart = cart();
        let Ok(Input::Target(t)) = parse_line_for(
            r#"{"t": 2, "joints": {"arm": 10}, "base": {"x": 0.1}}"#,
            &cart,
            9.0,
        ) else {
            panic!("a target");
        };
        assert_eq!(
            t,
            LiveTarget::named(
                2.0,
                vec![
                    ("arm".into(), 10f64.to_radians()),
                    ("l".into(), 2.0),
                    ("r".into(), 2.0),
                ]
            )
        );
        let Ok(Input::Target(t)) = parse_line_for(r#"{"base": {"theta": 0}}"#, &cart, 9.0) else {
            panic!("a base alone is a target");
        };
        assert_eq!(
            t,
            LiveTarget::named(9.0, vec![("l".into(), 0.0), ("r".into(), 0.0)])
        );
        let why = |line: &str| match parse_line_for(line, &cart, 0.0) {
            Err(e) => e.to_string(),
            Ok(i) => panic!("{line} parsed: {i:?}"),
        };
        assert!(why(r#"{"base": {"y": 0.1}}"#).contains("sideways"));
        assert!(why(r#"{"base": {"z": 1}}"#).contains("`base.z`"));
        assert!(why(r#"{"base": {"x": "fast"}}"#).contains("`base.x` is not a number"));
        assert!(why(r#"{"joints": {"l": 1}, "base": {"x": 0.1}}"#).contains("not both"));
        assert!(why(r#"{"base": 3}"#).contains("not an object"));
        // Without the robot, or on a robot without a base: refused.
        assert!(parse_line(r#"{"base": {"x": 0.1}}"#, Units::Deg, 0.0).is_err());
    }

    #[test]
    fn a_grasp_is_carried_alone_or_beside_joints_and_a_base() {
        let t = parse_line(r#"{"t": 3, "grasp": {"gripper": 40}}"#, Units::Deg, 9.0);
        let want = LiveTarget::named(3.0, Vec::new()).with_grasps(vec![("gripper".into(), 40.0)]);
        assert_eq!(t, Ok(Input::Target(want)));
        // The effort is a percentage, never converted as an angle.
        let t = parse_line(
            r#"{"joints": {"wrist": 90}, "grasp": {"gripper": 12.5, "thumb": 100}}"#,
            Units::Deg,
            9.0,
        );
        let want = LiveTarget::named(9.0, vec![("wrist".into(), std::f64::consts::FRAC_PI_2)])
            .with_grasps(vec![("gripper".into(), 12.5), ("thumb".into(), 100.0)]);
        assert_eq!(t, Ok(Input::Target(want)));
        // A null grasp is none: the line is a plain target.
        let t = parse_line(r#"{"joints": {"a": 1}, "grasp": null}"#, Units::Rad, 0.0);
        assert_eq!(
            t,
            Ok(Input::Target(LiveTarget::named(
                0.0,
                vec![("a".into(), 1.0)]
            )))
        );
        let cart = cart();
        let Ok(Input::Target(t)) = parse_line_for(
            r#"{"t": 2, "base": {"x": 0.1}, "grasp": {"arm": 30}}"#,
            &cart,
            9.0,
        ) else {
            panic!("a target");
        };
        let want = LiveTarget::named(2.0, vec![("l".into(), 2.0), ("r".into(), 2.0)])
            .with_grasps(vec![("arm".into(), 30.0)]);
        assert_eq!(t, want);
    }

    #[test]
    fn a_bad_grasp_says_what_is_wrong() {
        let why = |l: &str| match parse_line_for(l, &cart(), 0.0) {
            Err(e) => e.to_string(),
            Ok(i) => panic!("{l} read as {i:?}"),
        };
        let both = why(r#"{"joints": {"arm": 10}, "grasp": {"arm": 40}}"#);
        assert!(
            both.contains("joint `arm`") && both.contains("not both"),
            "{both}"
        );
        // A wheel the base drives is a position (a speed) too.
        let wheel = why(r#"{"base": {"x": 0.1}, "grasp": {"l": 40}}"#);
        assert!(wheel.contains("joint `l`"), "{wheel}");
        let hard = why(r#"{"grasp": {"arm": "hard"}}"#);
        assert!(
            hard.contains("grasp `arm`: the effort is not a number"),
            "{hard}"
        );
        assert!(why(r#"{"grasp": [40]}"#).contains("`grasp` is not an object"));
        assert!(why(r#"{"grasp": 40}"#).contains("`grasp` is not an object"));
        assert!(
            why(r#"{"chunk": {"dt": 0.1, "joints": {}}, "grasp": {"arm": 40}}"#)
                .contains("not beside a `chunk`")
        );
        // The line is well formed; the run refuses efforts it cannot make.
        assert!(parse_line_for(r#"{"grasp": {"arm": 150}}"#, &cart(), 0.0).is_ok());
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
