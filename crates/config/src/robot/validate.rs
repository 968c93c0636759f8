//! From a robot file's raw shape to a [`Robot`]: every field checked, every
//! problem reported at its place in the file.

use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::time::Duration;

use servobus_protocol::registers::{model_by_name, Model, MODELS};
use servobus_protocol::MAX_ID;

use super::raw::{LatencySpec, RawBus, RawJoint, RawRobot};
use super::{faults, servo, urdf, BusConfig, JointConfig, JointMode, Robot, RobotCalibration};
use crate::error::{ConfigError, Source};
use crate::limits::{check_baud, check_latency_us, check_rate_hz};
use crate::locate::FieldPath;
use crate::Units;

/// The largest lag-compensation lead a robot file may set, ms.
const MAX_LEAD_MS: f64 = 500.0;

/// The largest return delay register 7 can hold (255 x 2 us).
const MAX_RETURN_DELAY_US: u64 = 510;

/// Checks that `rate_hz` fits every bus of `robot`; the error points at `field`.
pub(crate) fn check_rate(
    robot: &Robot,
    source: &Source,
    rate_hz: f64,
    field: &FieldPath,
) -> Result<(), ConfigError> {
    if let Err(e) = check_rate_hz(rate_hz) {
        return Err(source.error(field, e.to_string()));
    }
    for bus in &robot.buses {
        if let Err(why) = bus.check_rate(rate_hz) {
            return Err(source.error(field, format!("bus `{}`: {}", bus.name, why.with_advice())));
        }
    }
    Ok(())
}

fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// The robot `raw` describes, checked field by field; a URDF its
/// `kinematics:` names is relative to `dir`.
pub(super) fn robot(mut raw: RawRobot, src: &Source, dir: &Path) -> Result<Robot, ConfigError> {
    let root = FieldPath::root();
    if raw.name.trim().is_empty() {
        return Err(src.error(&root.key("name"), "must not be empty"));
    }
    if let Err(e) = check_rate_hz(raw.rate) {
        return Err(src.error(&root.key("rate"), e.to_string()));
    }
    let lead = match raw.lead_ms {
        None => None,
        Some(ms) if ms.is_finite() && (0.0..=MAX_LEAD_MS).contains(&ms) => {
            Some(Duration::from_secs_f64(ms / 1e3))
        }
        Some(ms) => {
            return Err(src.error(
                &root.key("lead_ms"),
                format!("must be between 0 and {MAX_LEAD_MS} ms, got {ms}"),
            ))
        }
    };
    if raw.buses.is_empty() {
        return Err(src.error(&root.key("buses"), "a robot needs at least one bus"));
    }
    let pose = std::mem::take(&mut raw.calibration_pose);
    let given = std::mem::take(&mut raw.servo_defaults);
    let defaults = servo_defaults(&given, raw.units, src)?;
    for rb in &mut raw.buses {
        for rj in &mut rb.joints {
            let own = model_by_name(&rj.model).map(|m| m.number);
            if let Some(&(_, d)) = defaults.iter().find(|(n, _)| Some(*n) == own) {
                rj.servo = Some(rj.servo.as_ref().map_or_else(|| d.clone(), |s| s.or(d)));
            }
        }
    }
    let imported = urdf::import(&mut raw, dir, src)?;
    let mut bus_names = HashSet::new();
    let mut joint_names: HashMap<String, FieldPath> = HashMap::new();
    let mut buses = Vec::with_capacity(raw.buses.len());
    for (bi, rb) in raw.buses.into_iter().enumerate() {
        let bp = root.key("buses").index(bi);
        if !bus_names.insert(rb.name.clone()) {
            return Err(src.error(
                &bp.key("name"),
                format!("bus name `{}` is used twice", rb.name),
            ));
        }
        buses.push(bus(rb, &bp, raw.units, &mut joint_names, src)?);
    }
    let mut robot = Robot {
        name: raw.name,
        units: raw.units,
        rate_hz: raw.rate,
        lead,
        buses,
        path: src.path.clone(),
        calibration: RobotCalibration::None,
        calibration_pose: Vec::new(),
        kinematics: None,
        urdf: imported,
        base: None,
    };
    robot.calibration_pose = calibration_pose(&robot, &pose, src)?;
    if let Some(section) = &raw.kinematics {
        robot.kinematics = Some(urdf::kinematics(&robot, section, robot.urdf.as_ref(), src)?);
    }
    if let Some(spec) = &raw.base {
        robot.base = Some(base(&robot, spec, src)?);
    }
    Ok(robot)
}

/// The `servo_defaults:` section: per servo model (by any of its names),
/// its `servo:` settings checked against the model's registers; a problem
/// is reported at the model's entry, naming its field. Each with its
/// model's number.
fn servo_defaults<'r>(
    raw: &'r std::collections::BTreeMap<String, super::raw::RawServo>,
    units: Units,
    src: &Source,
) -> Result<Vec<(u16, &'r super::raw::RawServo)>, ConfigError> {
    let at = FieldPath::root().key("servo_defaults");
    let mut out: Vec<(u16, &super::raw::RawServo)> = Vec::with_capacity(raw.len());
    for (name, settings) in raw {
        let Some(model) = model_by_name(name) else {
            let known: Vec<&str> = MODELS.iter().map(|m| m.name).collect();
            return Err(src.key_error(
                &at.key(name),
                format!("unknown model `{name}` (known: {})", known.join(", ")),
            ));
        };
        if out.iter().any(|(n, _)| *n == model.number) {
            return Err(src.key_error(
                &at.key(name),
                format!("model `{}` is given twice, by two of its names", model.name),
            ));
        }
        servo::settings(settings, model, units).map_err(|r| {
            let reason = format!("model `{}`: {}", model.name, r.reason);
            src.error(&at.key(name).key(r.setting), reason)
        })?;
        out.push((model.number, settings));
    }
    Ok(out)
}

/// The `base:` section checked against the robot's joints: each wheel a
/// joint of the robot in `mode: wheel`; a problem is reported at `base`,
/// naming its field.
fn base(
    robot: &Robot,
    spec: &servobus_kinematics::BaseSpec,
    src: &Source,
) -> Result<servobus_kinematics::Base, ConfigError> {
    let at = FieldPath::root().key("base");
    let base = servobus_kinematics::Base::new(spec, |name| robot.joint_index(name))
        .map_err(|e| src.error(&at, e.to_string()))?;
    let joints: Vec<&JointConfig> = robot.joints().collect();
    for &w in base.wheels() {
        let Some(joint) = joints.get(w) else { continue };
        if !joint.is_wheel() {
            return Err(src.error(
                &at,
                format!(
                    "`{}` drives a wheel of the base but is a position joint: give it `mode: wheel`",
                    joint.name
                ),
            ));
        }
    }
    Ok(base)
}

/// One bus of the robot at `bp` (angles in `units`), its joints' names
/// also checked against every other bus's (`joint_names`: where each name
/// was first used).
fn bus(
    rb: RawBus,
    bp: &FieldPath,
    units: Units,
    joint_names: &mut HashMap<String, FieldPath>,
    src: &Source,
) -> Result<BusConfig, ConfigError> {
    if let Err(e) = check_baud(rb.baud) {
        return Err(src.error(&bp.key("baud"), e.to_string()));
    }
    if rb.return_delay_us > MAX_RETURN_DELAY_US || !rb.return_delay_us.is_multiple_of(2) {
        return Err(src.error(
            &bp.key("return_delay_us"),
            format!(
                "must be an even number of microseconds from 0 to {MAX_RETURN_DELAY_US} \
                 (register 7 counts 2 us), got {}",
                rb.return_delay_us
            ),
        ));
    }
    if rb.joints.is_empty() {
        return Err(src.error(&bp.key("joints"), "a bus needs at least one joint"));
    }
    let mut ids: HashMap<u8, usize> = HashMap::new();
    let mut joints = Vec::with_capacity(rb.joints.len());
    for (ji, rj) in rb.joints.into_iter().enumerate() {
        let jp = bp.key("joints").index(ji);
        let joint = validate_joint(rj, &jp, units, src)?;
        if let Some(first) = ids.insert(joint.id, ji) {
            return Err(src.error(
                &jp.key("id"),
                format!(
                    "ID {} is already used on bus `{}` by joint {}",
                    joint.id, rb.name, first
                ),
            ));
        }
        if let Some(prev) = joint_names.insert(joint.name.clone(), jp.clone()) {
            return Err(src.error(
                &jp.key("name"),
                format!("joint name `{}` is already used at {prev}", joint.name),
            ));
        }
        joints.push(joint);
    }
    let (latency, latency_auto) = match rb.latency_us {
        LatencySpec::Micros(us) => match check_latency_us(us) {
            Ok(latency) => (latency, false),
            Err(e) => return Err(src.error(&bp.key("latency_us"), e.to_string())),
        },
        LatencySpec::Auto => (Duration::ZERO, true),
        LatencySpec::Word(w) if w == "auto" => (Duration::ZERO, true),
        LatencySpec::Word(w) => {
            return Err(src.error(
                &bp.key("latency_us"),
                format!("must be a number of microseconds or `auto`, got `{w}`"),
            ))
        }
    };
    Ok(BusConfig {
        name: rb.name,
        port: rb.port,
        baud: rb.baud,
        latency,
        latency_auto,
        return_delay: Duration::from_micros(rb.return_delay_us),
        busy_poll: rb.busy_poll,
        round_robin: rb.round_robin,
        joints,
    })
}

fn validate_joint(
    rj: RawJoint,
    jp: &FieldPath,
    units: Units,
    src: &Source,
) -> Result<JointConfig, ConfigError> {
    if rj.name.trim().is_empty() {
        return Err(src.error(&jp.key("name"), "must not be empty"));
    }
    let id = match u8::try_from(rj.id) {
        Ok(id) if id <= MAX_ID => id,
        _ => {
            return Err(src.error(
                &jp.key("id"),
                format!("servo IDs go from 0 to {MAX_ID}, got {}", rj.id),
            ))
        }
    };
    let Some(model) = model_by_name(&rj.model) else {
        let known: Vec<&str> = MODELS.iter().map(|m| m.name).collect();
        return Err(src.error(
            &jp.key("model"),
            format!("unknown model `{}` (known: {})", rj.model, known.join(", ")),
        ));
    };
    let (min, max) = match rj.mode {
        JointMode::Position => position_limits(&rj, jp, src)?,
        JointMode::Wheel => wheel_fields(&rj, model, jp, src)?,
    };
    for (field, v) in [
        ("max_velocity", Some(rj.max_velocity)),
        ("max_acceleration", Some(rj.max_acceleration)),
        ("max_jerk", rj.max_jerk),
    ] {
        if let Some(v) = v {
            if !positive(v) {
                return Err(src.error(&jp.key(field), format!("must be positive, got {v}")));
            }
        }
    }
    if rj.mode == JointMode::Wheel {
        wheel_speed(&rj, model, units, jp, src)?;
    }
    let servo = match &rj.servo {
        None => None,
        Some(raw) => Some(servo::settings(raw, model, units).map_err(|r| {
            let reason = format!("joint `{}`: {}", rj.name, r.reason);
            src.error(&jp.key("servo").key(r.setting), reason)
        })?),
    };
    let mut joint = JointConfig {
        name: rj.name,
        id,
        model,
        mode: rj.mode,
        min,
        max,
        max_velocity: rj.max_velocity,
        max_acceleration: rj.max_acceleration,
        max_jerk: rj.max_jerk,
        offset: rj.offset.unwrap_or(0.0),
        inverted: rj.inverted,
        home: rj.home,
        calibration: None,
        servo,
        faults: Default::default(),
    };
    joint.faults = faults::joint_faults(rj.faults.as_ref(), &joint, jp, src)?;
    if let Some(home) = joint.home {
        if !(home >= joint.min && home <= joint.max) {
            return Err(src.error(
                &jp.key("home"),
                format!("home {home} is outside [{}, {}]", joint.min, joint.max),
            ));
        }
    }
    Ok(joint)
}

/// A position joint's `min` and `max`: both given, finite and in order
/// (and its `offset` finite).
fn position_limits(rj: &RawJoint, jp: &FieldPath, src: &Source) -> Result<(f64, f64), ConfigError> {
    let (Some(min), Some(max)) = (rj.min, rj.max) else {
        // Where serde reports a missing field: the joint's mapping.
        let (field, what) = if rj.min.is_none() {
            ("min", "lowest")
        } else {
            ("max", "highest")
        };
        return Err(src.error(
            jp,
            format!(
                "missing field `{field}`: joint `{}` is a position joint and needs its {what} \
                 position, in the file's units (a wheel says `mode: wheel`)",
                rj.name
            ),
        ));
    };
    let offset = rj.offset.unwrap_or(0.0);
    for (field, v) in [("min", min), ("max", max), ("offset", offset)] {
        if !v.is_finite() {
            return Err(src.error(&jp.key(field), "must be a finite number"));
        }
    }
    if min >= max {
        return Err(src.error(
            &jp.key("max"),
            format!("max ({max}) must be greater than min ({min})"),
        ));
    }
    Ok((min, max))
}

/// A wheel's position limits (0, 0, unused) once it is checked to give no
/// position fields and its model to have a constant-speed mode.
fn wheel_fields(
    rj: &RawJoint,
    model: &Model,
    jp: &FieldPath,
    src: &Source,
) -> Result<(f64, f64), ConfigError> {
    for (field, given) in [
        ("min", rj.min.is_some()),
        ("max", rj.max.is_some()),
        ("home", rj.home.is_some()),
        ("offset", rj.offset.is_some()),
    ] {
        if given {
            return Err(src.error(
                &jp.key(field),
                format!(
                    "joint `{}` is a wheel: a wheel turns without end and its target is a \
                     speed, so it takes no `{field}:`; remove it",
                    rj.name
                ),
            ));
        }
    }
    let has_mode = |m: &Model| m.map().get("mode").is_some();
    if !has_mode(model) {
        let wheels: Vec<&str> = MODELS
            .iter()
            .filter(|m| has_mode(m))
            .map(|m| m.name)
            .collect();
        return Err(src.error(
            &jp.key("mode"),
            format!(
                "joint `{}` is a wheel, but the {} has no `mode` register to turn at a \
                 constant speed; use a model that has one ({})",
                rj.name,
                model.name,
                wheels.join(", ")
            ),
        ));
    }
    Ok((0.0, 0.0))
}

/// Refuses a wheel whose `max_velocity` is above its model's top speed
/// ([`Model::fastest_profile`]), converted to `units`.
fn wheel_speed(
    rj: &RawJoint,
    model: &Model,
    units: Units,
    jp: &FieldPath,
    src: &Source,
) -> Result<(), ConfigError> {
    let Some((top_deg_s, _)) = model.fastest_profile() else {
        return Ok(());
    };
    let top = units.from_rad(top_deg_s.to_radians());
    // Room for the rounding of the conversion: a top speed computed from
    // the same figures passes.
    if rj.max_velocity <= top * (1.0 + 1e-9) {
        return Ok(());
    }
    Err(src.error(
        &jp.key("max_velocity"),
        format!(
            "joint `{}` is a wheel whose max_velocity {} {units}/s is above what the {} can \
             turn at, {top:.1} {units}/s ({} steps/s)",
            rj.name, rj.max_velocity, model.name, model.max_speed
        ),
    ))
}

/// The calibration pose in joint order: every joint named exists and its
/// angle is inside its limits; unnamed joints are at 0.
fn calibration_pose(
    robot: &Robot,
    pose: &HashMap<String, f64>,
    src: &Source,
) -> Result<Vec<f64>, ConfigError> {
    let field = FieldPath::root().key("calibration_pose");
    for (name, &v) in pose {
        let Some(joint) = robot.joint(name) else {
            return Err(src.key_error(&field.key(name), format!("no joint `{name}`")));
        };
        if joint.is_wheel() {
            return Err(src.key_error(
                &field.key(name),
                format!("joint `{name}` is a wheel: it turns without end and has no pose"),
            ));
        }
        if !(v >= joint.min && v <= joint.max) {
            return Err(src.error(
                &field.key(name),
                format!("{v} is outside [{}, {}]", joint.min, joint.max),
            ));
        }
    }
    Ok(robot
        .joints()
        .map(|j| pose.get(&j.name).copied().unwrap_or(0.0))
        .collect())
}

/// Checks that both limits of every joint land inside the servo's tick range
/// (needs the robot's units, so it runs after the joint is built).
pub(crate) fn check_servo_range(robot: &Robot, src: &Source) -> Result<(), ConfigError> {
    let root = FieldPath::root();
    for (bi, bus) in robot.buses.iter().enumerate() {
        // A wheel's limits are no positions (see `JointConfig::min`).
        let positions = bus.joints.iter().enumerate().filter(|(_, j)| !j.is_wheel());
        for (ji, joint) in positions {
            let map = crate::JointMap::new(joint, robot.units);
            let jp = root.key("buses").index(bi).key("joints").index(ji);
            for (field, v) in [("min", joint.min), ("max", joint.max)] {
                let t = map.raw_ticks(robot.units.to_rad(v));
                if t < 0.0 || t > f64::from(joint.model.max_position()) {
                    let (lo, hi) = map.servo_range(robot.units);
                    return Err(src.error(
                        &jp.key(field),
                        format!(
                            "{v} {} is beyond what the {} can reach here: with offset {} \
                             and inverted {}, positions go from {lo:.1} to {hi:.1}",
                            robot.units, joint.model.name, joint.offset, joint.inverted
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}
