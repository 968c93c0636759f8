//! The calibration procedure: torque off, the calibration pose held, every
//! joint swept end to end, the calibration computed.

use std::time::Duration;

use servobus_driver::{Bus, Clock, Transport};

use crate::config::seam::{turn_ticks, turns_below, Unwrapper};
use crate::config::{Calibration, JointCalibration, JointConfig, Robot, Units};

use super::servos::{identify, present, torque_off, FoundServo};
use super::{CalibrateError, Operator, Step};

/// How the procedure watches the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcedureOptions {
    /// End each step on its own when the robot has moved and then been
    /// held still (besides on Enter): `--yes`, or stdin not a terminal.
    pub auto: bool,
    /// How long "held still" lasts.
    pub still_for: Duration,
    /// A joint within this of where it was is still, degrees.
    pub still_deg: f64,
    /// The robot has moved once a joint is this far from where the step
    /// began, degrees.
    pub moved_deg: f64,
    /// Time between two readings of every joint.
    pub period: Duration,
    /// A step that has not ended after this fails.
    pub timeout: Duration,
    /// When the calibration is taken, for the file.
    pub taken: String,
}

impl Default for ProcedureOptions {
    fn default() -> Self {
        ProcedureOptions {
            auto: false,
            still_for: Duration::from_secs(2),
            still_deg: 1.0,
            moved_deg: 5.0,
            period: Duration::from_millis(20),
            timeout: Duration::from_secs(600),
            taken: String::new(),
        }
    }
}

/// The smallest range a swept joint must show, degrees: less means the
/// person did not move it.
pub const MIN_RANGE_DEG: f64 = 10.0;

/// How long a servo may stay silent while the procedure watches: a hand
/// turns a joint well under half a turn in this time, so the unwrapping
/// still holds when it answers again.
const MAX_SILENCE: Duration = Duration::from_millis(1000);

/// A joint is first moved towards positive angles; it has left the pose
/// once this far from it, degrees.
const DEPARTURE_DEG: f64 = 4.0;

/// A calibration pose this close to the upper limit leaves only the
/// negative way to go first, degrees.
const AT_LIMIT_DEG: f64 = 1.0;

/// What the procedure sees of one joint while sweeping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveJoint {
    /// Lowest unwrapped tick seen.
    pub min: i64,
    /// Highest unwrapped tick seen.
    pub max: i64,
    /// Unwrapped tick now.
    pub now: i64,
}

struct Joint<'a> {
    bus: usize,
    config: &'a JointConfig,
    found: FoundServo,
    deg_per_tick: f64,
    unwrap: Unwrapper,
    live: LiveJoint,
    pose_tick: i64,
    departure: Option<i64>,
    /// When the servo last answered.
    heard: Duration,
}

/// Runs the calibration of `robot` on `buses` (in the robot's bus order)
/// with a person (or a script) as `operator`, and returns the calibration.
/// Servos are only read, and their torque switched off.
///
/// # Errors
/// [`CalibrateError`]: a servo that does not answer or is another model, a
/// step that does not end, a joint that was not swept, or swept a full turn.
pub fn calibrate<T: Transport>(
    robot: &Robot,
    buses: &mut [Bus<T>],
    operator: &mut dyn Operator,
    o: &ProcedureOptions,
) -> Result<Calibration, CalibrateError> {
    let mut joints = find_servos(robot, buses)?;
    for (bus, config) in buses.iter_mut().zip(&robot.buses) {
        torque_off(bus, config)?;
    }
    operator.step(Step::TorqueOff);
    operator.step(Step::HoldPose);
    wait_step(buses, &mut joints, operator, o, false)?;
    for j in &mut joints {
        let first = j.live.now;
        j.pose_tick = first;
        let reading = i32::try_from(first).unwrap_or(0);
        j.unwrap = Unwrapper::new(reading, turn_ticks(j.config.model));
        j.live = LiveJoint {
            min: first,
            max: first,
            now: first,
        };
    }
    operator.step(Step::Sweep);
    wait_step(buses, &mut joints, operator, o, true)?;
    operator.step(Step::Done);
    let units = robot.units;
    let out = joints
        .iter()
        .zip(&robot.calibration_pose)
        .map(|(j, &pose)| finish_joint(j, units.convert(pose, Units::Deg), units))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Calibration {
        robot: robot.name.clone(),
        taken: o.taken.clone(),
        joints: out,
    })
}

fn find_servos<'a, T: Transport>(
    robot: &'a Robot,
    buses: &mut [Bus<T>],
) -> Result<Vec<Joint<'a>>, CalibrateError> {
    let mut joints = Vec::new();
    for (b, (bus, config)) in buses.iter_mut().zip(&robot.buses).enumerate() {
        for joint in &config.joints {
            let found = identify(bus, joint).map_err(|e| CalibrateError::bus(joint, e))?;
            if found.model.number != joint.model.number {
                return Err(CalibrateError::Model {
                    joint: joint.name.clone(),
                    id: joint.id,
                    found: found.model.name,
                    expected: joint.model.name,
                });
            }
            let now = i64::from(present(bus, joint).map_err(|e| CalibrateError::bus(joint, e))?);
            joints.push(Joint {
                bus: b,
                config: joint,
                deg_per_tick: joint.model.deg_per_tick(),
                unwrap: Unwrapper::new(0, None),
                live: LiveJoint {
                    min: now,
                    max: now,
                    now,
                },
                pose_tick: now,
                departure: None,
                heard: bus.clock().now(),
                found,
            });
        }
    }
    Ok(joints)
}

/// Reads every joint each period until the step ends: on Enter, or (with
/// `auto`) once the robot has moved and then been still for `still_for`.
/// While sweeping, readings are unwrapped and the range kept.
fn wait_step<T: Transport>(
    buses: &mut [Bus<T>],
    joints: &mut [Joint<'_>],
    operator: &mut dyn Operator,
    o: &ProcedureOptions,
    sweeping: bool,
) -> Result<(), CalibrateError> {
    let start = now(buses);
    let origin: Vec<i64> = joints.iter().map(|j| j.live.now).collect();
    let mut anchor = origin.clone();
    let mut still_since = start;
    let mut moved = false;
    let mut next = start;
    loop {
        next += o.period;
        for bus in buses.iter() {
            bus.clock().sleep_until(next);
        }
        for j in joints.iter_mut() {
            let bus = &mut buses[j.bus];
            let tick = match present(bus, j.config) {
                Ok(tick) => {
                    j.heard = next;
                    tick
                }
                // A lost reply costs one reading; a servo silent for long
                // ends the calibration (the joint may have turned too far
                // to unwrap its next reading).
                Err(_) if next.saturating_sub(j.heard) < MAX_SILENCE => continue,
                Err(e) => return Err(CalibrateError::bus(j.config, e)),
            };
            j.live.now = if sweeping {
                j.unwrap.push(tick)
            } else {
                i64::from(tick)
            };
            if sweeping {
                j.live.min = j.live.min.min(j.live.now);
                j.live.max = j.live.max.max(j.live.now);
                let away = j.live.now - j.pose_tick;
                if j.departure.is_none() && (away as f64 * j.deg_per_tick).abs() > DEPARTURE_DEG {
                    j.departure = Some(away.signum());
                }
            }
        }
        let t = now(buses);
        let live: Vec<LiveJoint> = joints.iter().map(|j| j.live).collect();
        operator.watch(t, &live);
        if operator.confirmed() {
            return Ok(());
        }
        let far = |from: &[i64], limit: f64| {
            joints
                .iter()
                .zip(from)
                .any(|(j, &f)| ((j.live.now - f) as f64 * j.deg_per_tick).abs() > limit)
        };
        moved |= far(&origin, o.moved_deg);
        if far(&anchor, o.still_deg) {
            anchor = joints.iter().map(|j| j.live.now).collect();
            still_since = t;
        } else if o.auto && moved && t.saturating_sub(still_since) >= o.still_for {
            return Ok(());
        }
        if t.saturating_sub(start) > o.timeout {
            return Err(CalibrateError::Timeout {
                waited: o.timeout,
                moved,
            });
        }
    }
}

/// The time on the first bus's clock (every bus's clock agrees, or is
/// moved in step by the sleeps above).
fn now<T: Transport>(buses: &[Bus<T>]) -> Duration {
    buses.first().map_or(Duration::ZERO, |b| b.clock().now())
}

/// The calibration of one swept joint, whose pose angle is `pose_deg`.
fn finish_joint(
    j: &Joint<'_>,
    pose_deg: f64,
    units: Units,
) -> Result<JointCalibration, CalibrateError> {
    let span = j.live.max - j.live.min;
    let span_deg = span as f64 * j.deg_per_tick;
    if span_deg < MIN_RANGE_DEG {
        return Err(CalibrateError::NoRange {
            joint: j.config.name.clone(),
            span_deg,
        });
    }
    let turn = turn_ticks(j.config.model);
    if let Some(turn) = turn {
        if span >= i64::from(turn) {
            return Err(CalibrateError::FullTurn {
                joint: j.config.name.clone(),
            });
        }
    }
    // Whole turns off so that the minimum lies in [0, turn).
    let down = turn.map_or(0, |turn| turns_below(j.live.min, turn) * i64::from(turn));
    let upper = units.convert(j.config.max, Units::Deg) - pose_deg < AT_LIMIT_DEG;
    let first = j.departure.unwrap_or(1);
    let direction = if upper { -first } else { first };
    Ok(JointCalibration {
        name: j.config.name.clone(),
        id: j.config.id,
        model: j.found.model.name.to_owned(),
        firmware: Some(j.found.firmware.clone()),
        homing_offset: j.found.homing_offset,
        pose_deg,
        pose_tick: (j.pose_tick - down) as f64,
        direction: if direction < 0 { -1 } else { 1 },
        range: [j.live.min - down, j.live.max - down],
    })
}
