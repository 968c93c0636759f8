//! The simulated robot's body, as files name it: how each servo horn is
//! mounted (`--mounting M.yaml`, or drawn at random with `--unit SEED`) and
//! the hand that moves the joints (`--hand H.yaml`).
//!
//! ```yaml
//! # mounting: the raw tick at each joint's physical zero, whether rising
//! # ticks turn it positive (1) or negative (-1), optional end stops (deg)
//! shoulder_pan: {zero_tick: 3900, direction: -1, stops: [-115, 115]}
//! ```
//!
//! ```yaml
//! # hand: physical angles (deg) at seconds from the simulator's start
//! keyframes:
//!   - {at: 0, pose: {shoulder_pan: 0}}
//!   - {at: 2, pose: {shoulder_pan: 90}}
//! # optional: an object in a joint's way, its surface at `at` deg, on the
//! # side away from where the joint starts; `stiffness` in % of full torque
//! # per degree of squeeze (default 20)
//! object: {joint: gripper, at: 25, stiffness: 20}
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use serde::Deserialize;
use servobus_sim::body::{HandObject, DEFAULT_STIFFNESS, MAX_STIFFNESS};
use servobus_sim::{HandPath, Mount};

use crate::config::limits::{Rounded, MAX_MOTION_DURATION_S};
use crate::config::seam::turn_ticks;
use crate::config::{ConfigError, FieldPath, JointConfig, JointMap, Robot, Source};

/// Every joint's mounting, in the robot's joint order.
#[derive(Debug, Clone, PartialEq)]
pub struct Mounting {
    mounts: Vec<Mount>,
}

/// Degrees beyond each joint limit where a random mounting puts its stops.
const RANDOM_STOP_MARGIN_DEG: f64 = 5.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "a joint's mounting: a mapping with `zero_tick:` and optional `direction:`, `stops:`"
)]
struct RawMount {
    zero_tick: f64,
    #[serde(default = "positive")]
    direction: i64,
    #[serde(default)]
    stops: Option<[f64; 2]>,
}

fn positive() -> i64 {
    1
}

impl Mounting {
    /// The mounting the robot file assumes: tick `resolution / 2` (2048 on
    /// an STS3215) plus the joint's `offset` at its zero, rising ticks
    /// positive unless `inverted`, no stops. A simulator with this mounting
    /// behaves exactly as one without a body.
    pub fn of_robot_file(robot: &Robot) -> Mounting {
        Mounting {
            mounts: robot.joints().map(|j| design_mount(robot, j)).collect(),
        }
    }

    /// The mounting of each joint, in the robot's joint order.
    pub fn mounts(&self) -> &[Mount] {
        &self.mounts
    }

    /// Loads a mounting file for `robot`; joints it does not name keep the
    /// robot file's mounting ([`Mounting::of_robot_file`]).
    ///
    /// # Errors
    /// [`ConfigError`] naming the file, line, column and field of the first
    /// problem: an unknown joint, a tick outside the servo's range, a
    /// direction other than 1 or -1, stops not in order.
    pub fn load(path: &Path, robot: &Robot) -> Result<Mounting, ConfigError> {
        let src = Source::read(path)?;
        let raw: BTreeMap<String, RawMount> = src.parse()?;
        let mut m = Mounting::of_robot_file(robot);
        let root = FieldPath::root();
        let names: Vec<&str> = robot.joints().map(|j| j.name.as_str()).collect();
        for (name, r) in raw {
            let field = root.key(&name);
            let Some(i) = names.iter().position(|n| *n == name) else {
                return Err(src.key_error(
                    &field,
                    format!(
                        "no joint `{name}` in the robot (joints: {})",
                        names.join(", ")
                    ),
                ));
            };
            let Some(joint) = robot.joints().nth(i) else {
                continue;
            };
            let res = f64::from(joint.model.resolution);
            if !(0.0..res).contains(&r.zero_tick) {
                return Err(src.error(
                    &field.key("zero_tick"),
                    format!("must be a tick in 0..={}, got {}", res - 1.0, r.zero_tick),
                ));
            }
            let reversed = match r.direction {
                1 => false,
                -1 => true,
                d => {
                    return Err(src.error(
                        &field.key("direction"),
                        format!("must be 1 (rising ticks turn the joint positive) or -1, got {d}"),
                    ))
                }
            };
            let mut mount = Mount::new(r.zero_tick, reversed);
            if let Some([lo, hi]) = r.stops {
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    return Err(src.error(
                        &field.key("stops"),
                        format!("must be [min_deg, max_deg] with min < max, got [{lo}, {hi}]"),
                    ));
                }
                mount = mount.with_stops(lo, hi);
            }
            m.mounts[i] = mount;
        }
        Ok(m)
    }

    /// A robot as it comes off a careless assembly, drawn from `seed`: every
    /// horn at a random tick of the turn, random directions, stops a few
    /// degrees beyond each joint's limits. On full-turn servos at least one
    /// joint's range crosses the 4095 -> 0 seam and at least one direction
    /// is reversed (when the robot has two such joints). Same seed, same
    /// robot.
    pub fn random(robot: &Robot, seed: u64) -> Mounting {
        let mut rng = SmallRng::seed_from_u64(seed);
        let joints: Vec<&JointConfig> = robot.joints().collect();
        let full: Vec<usize> = (0..joints.len())
            .filter(|&i| turn_ticks(joints[i].model).is_some())
            .collect();
        let seam = (!full.is_empty()).then(|| full[rng.gen_range(0..full.len())]);
        let reversed = match full.len() {
            0 | 1 => None,
            n => {
                let k = rng.gen_range(1..n);
                let s = full.iter().position(|&i| Some(i) == seam).unwrap_or(0);
                Some(full[(s + k) % n])
            }
        };
        let mounts = joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let (lo, hi) = limits_deg(robot, j);
                let dir = if Some(i) == reversed || (Some(i) != seam && rng.gen_bool(0.5)) {
                    -1.0
                } else {
                    1.0
                };
                let res = f64::from(j.model.resolution);
                let tpd = res / j.model.range_deg;
                let zero = if Some(i) == seam {
                    // The seam between 25 % and 75 % of the range.
                    let at = lo + rng.gen_range(0.25..0.75) * (hi - lo);
                    (-dir * at * tpd).rem_euclid(res).round()
                } else if full.contains(&i) {
                    f64::from(rng.gen_range(0..j.model.resolution))
                } else {
                    // A partial-turn sensor: the whole range must stay on it.
                    let a = -dir * lo * tpd;
                    let b = -dir * hi * tpd;
                    let (min_zero, max_zero) = (a.max(b), res - 1.0 + a.min(b));
                    if min_zero < max_zero {
                        rng.gen_range(min_zero..max_zero).round()
                    } else {
                        design_mount(robot, j).zero_tick
                    }
                };
                Mount::new(zero, dir < 0.0)
                    .with_stops(lo - RANDOM_STOP_MARGIN_DEG, hi + RANDOM_STOP_MARGIN_DEG)
            })
            .collect();
        Mounting { mounts }
    }

    /// The mounting as a mounting file says it (to keep a random unit).
    pub fn to_yaml(&self, robot: &Robot) -> String {
        let mut out = String::new();
        for (j, m) in robot.joints().zip(&self.mounts) {
            out.push_str(&format!(
                "{}: {{zero_tick: {}, direction: {}",
                j.name, m.zero_tick, m.direction
            ));
            if let Some([lo, hi]) = m.stops {
                out.push_str(&format!(", stops: [{lo}, {hi}]"));
            }
            out.push_str("}\n");
        }
        out
    }
}

/// The robot file's own mounting of joint `j`.
fn design_mount(robot: &Robot, j: &JointConfig) -> Mount {
    let map = JointMap::new(j, robot.units);
    Mount::new(map.raw_ticks(0.0), j.inverted)
}

/// A joint's limits in degrees.
fn limits_deg(robot: &Robot, j: &JointConfig) -> (f64, f64) {
    let deg = |v: f64| robot.units.to_rad(v).to_degrees();
    (deg(j.min), deg(j.max))
}

/// The latest time a hand file's keyframe may be at, s: a day, as the
/// longest motion ([`MAX_MOTION_DURATION_S`]); a hand is a person's
/// moves during one session with the simulator.
pub const MAX_HAND_S: f64 = MAX_MOTION_DURATION_S;

/// A hand's path for every joint it names, in the robot's joint order,
/// with the object it puts in a joint's way.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Hand {
    paths: Vec<Option<HandPath>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(expecting = "a hand file: a mapping with `keyframes:` and optional `object:`")]
struct RawHand {
    #[serde(default)]
    keyframes: Vec<RawKey>,
    #[serde(default)]
    object: Option<RawObject>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "a hand's object: a mapping with `joint:`, `at:` (deg) and optional `stiffness:`"
)]
struct RawObject {
    joint: String,
    at: f64,
    #[serde(default = "default_stiffness")]
    stiffness: f64,
}

fn default_stiffness() -> f64 {
    DEFAULT_STIFFNESS
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(expecting = "a hand keyframe: a mapping with `at:` and `pose:`")]
struct RawKey {
    at: f64,
    pose: BTreeMap<String, f64>,
}

impl Hand {
    /// A hand from `(time_s, [(joint index, angle_deg)])` keyframes, for
    /// tests and tools that script it in code.
    pub fn from_keyframes(robot: &Robot, keyframes: &[(f64, Vec<(usize, f64)>)]) -> Hand {
        let mut keys: Vec<Vec<(f64, f64)>> = vec![Vec::new(); robot.joint_count()];
        for (t, pose) in keyframes {
            for &(j, a) in pose {
                if let Some(k) = keys.get_mut(j) {
                    k.push((*t, a));
                }
            }
        }
        Hand {
            paths: keys
                .into_iter()
                .map(|k| (!k.is_empty()).then(|| HandPath::new(k)))
                .collect(),
        }
    }

    /// The same hand with `object` in the way of joint `index` (robot
    /// joint order; ignored past the last joint), in place of any object
    /// the hand had there.
    #[must_use]
    pub fn with_object(mut self, index: usize, object: HandObject) -> Hand {
        if let Some(p) = self.paths.get_mut(index) {
            *p = Some(p.take().unwrap_or_default().with_object(object));
        }
        self
    }

    /// Loads a hand file for `robot`.
    ///
    /// # Errors
    /// [`ConfigError`] naming the file, line, column and field of the first
    /// problem: an unknown joint, a time outside 0 to a day or not
    /// after the previous keyframe's, an angle that is not a number, an
    /// object on an unknown joint, at an angle that is not a number, or
    /// with a stiffness not above 0 and at most [`MAX_STIFFNESS`].
    pub fn load(path: &Path, robot: &Robot) -> Result<Hand, ConfigError> {
        let src = Source::read(path)?;
        let raw: RawHand = src.parse()?;
        let names: Vec<&str> = robot.joints().map(|j| j.name.as_str()).collect();
        let keyframes = keyframes(&src, &raw.keyframes, &names)?;
        let mut hand = Hand::from_keyframes(robot, &keyframes);
        if let Some(o) = &raw.object {
            let (index, object) = object(&src, o, &names)?;
            hand = hand.with_object(index, object);
        }
        Ok(hand)
    }

    /// The path of joint `index` (robot joint order), if the hand names it.
    pub fn path(&self, index: usize) -> Option<&HandPath> {
        self.paths.get(index).and_then(Option::as_ref)
    }

    /// The object in the way of joint `index` (robot joint order), if any.
    pub fn object(&self, index: usize) -> Option<HandObject> {
        self.path(index).and_then(HandPath::object)
    }
}

/// A hand file's keyframes, checked, as `(time_s, [(joint index, deg)])`.
type Keyframes = Vec<(f64, Vec<(usize, f64)>)>;

/// Checks a hand file's keyframes against the robot's joint `names`.
fn keyframes(src: &Source, raw: &[RawKey], names: &[&str]) -> Result<Keyframes, ConfigError> {
    let root = FieldPath::root().key("keyframes");
    let mut keyframes = Vec::with_capacity(raw.len());
    let mut last = f64::NEG_INFINITY;
    for (k, key) in raw.iter().enumerate() {
        let field = root.index(k);
        if !(0.0..=MAX_HAND_S).contains(&key.at) {
            return Err(src.error(
                &field.key("at"),
                format!(
                    "must be a time from 0 to {MAX_HAND_S} s (a day) from the simulator's \
                         start, got {}",
                    Rounded(key.at)
                ),
            ));
        }
        if key.at <= last {
            return Err(src.error(
                &field.key("at"),
                format!("{} s is not after the previous keyframe's {last} s", key.at),
            ));
        }
        last = key.at;
        let mut pose = Vec::with_capacity(key.pose.len());
        for (name, &deg) in &key.pose {
            let f = field.key("pose").key(name);
            let Some(i) = names.iter().position(|n| n == name) else {
                return Err(src.key_error(
                    &f,
                    format!(
                        "no joint `{name}` in the robot (joints: {})",
                        names.join(", ")
                    ),
                ));
            };
            if !deg.is_finite() {
                return Err(src.error(&f, "must be an angle in degrees"));
            }
            pose.push((i, deg));
        }
        keyframes.push((key.at, pose));
    }
    Ok(keyframes)
}

/// Checks a hand file's `object:`: the joint's index and the object.
fn object(
    src: &Source,
    raw: &RawObject,
    names: &[&str],
) -> Result<(usize, HandObject), ConfigError> {
    let field = FieldPath::root().key("object");
    let Some(index) = names.iter().position(|n| *n == raw.joint) else {
        return Err(src.error(
            &field.key("joint"),
            format!(
                "no joint `{}` in the robot (joints: {})",
                raw.joint,
                names.join(", ")
            ),
        ));
    };
    if !raw.at.is_finite() {
        return Err(src.error(
            &field.key("at"),
            "must be the angle in degrees of the object's surface",
        ));
    }
    HandObject::new(raw.at, raw.stiffness)
        .map(|o| (index, o))
        .ok_or_else(|| {
            src.error(
                &field.key("stiffness"),
                format!(
                    "must be above 0 and at most {MAX_STIFFNESS} (% of full torque per degree of \
                     squeeze; {DEFAULT_STIFFNESS} if left out), got {}",
                    raw.stiffness
                ),
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{load_robot, RobotOptions, RobotSource};

    fn so101() -> Robot {
        load_robot(RobotSource::Builtin("so101"), &RobotOptions::default()).expect("the arm")
    }

    /// Loads `yaml` as a hand file of the so101 (a file of its own per case).
    fn load(name: &str, yaml: &str) -> Result<Hand, ConfigError> {
        let dir = std::env::temp_dir().join(format!("servobus-hand-object-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let file = dir.join(format!("{name}.yaml"));
        std::fs::write(&file, yaml).expect("writes");
        Hand::load(&file, &so101())
    }

    fn gripper() -> usize {
        so101()
            .joints()
            .position(|j| j.name == "gripper")
            .expect("a gripper")
    }

    #[test]
    fn a_hand_file_puts_an_object_in_a_joint_s_way() {
        let yaml = "keyframes:\n  - {at: 0, pose: {shoulder_pan: 5}}\n\
                    object: {joint: gripper, at: 25, stiffness: 40}\n";
        let hand = load("full", yaml).expect("loads");
        let o = hand.object(gripper()).expect("an object on the gripper");
        assert_eq!((o.at_deg(), o.stiffness()), (25.0, 40.0));
        assert_eq!(hand.object(0), None);
        assert_eq!(hand.path(0).map(|p| p.keys().len()), Some(1));
        // The gripper has no keyframes: the hand never holds it.
        assert!(hand.path(gripper()).is_some_and(|p| p.keys().is_empty()));

        let hand = load("bare", "object: {joint: gripper, at: -3}\n").expect("loads");
        let o = hand.object(gripper()).expect("an object");
        assert_eq!((o.at_deg(), o.stiffness()), (-3.0, DEFAULT_STIFFNESS));
    }

    #[test]
    fn a_hand_file_without_an_object_has_none() {
        let hand = load("none", "keyframes:\n  - {at: 0, pose: {gripper: 5}}\n").expect("loads");
        assert!((0..6).all(|i| hand.object(i).is_none()));
        let scripted = Hand::from_keyframes(&so101(), &[(0.0, vec![(gripper(), 5.0)])]);
        assert_eq!(hand, scripted);
    }

    #[test]
    fn a_bad_object_is_refused_naming_its_field() {
        let cases = [
            (
                "joint",
                "object: {joint: grip, at: 25}\n",
                "object.joint",
                "grip",
            ),
            (
                "negative",
                "object: {joint: gripper, at: 25, stiffness: -5}\n",
                "object.stiffness",
                "above 0",
            ),
            (
                "zero",
                "keyframes: []\nobject: {joint: gripper, at: 25, stiffness: 0}\n",
                "object.stiffness",
                "got 0",
            ),
            (
                "nan",
                "object: {joint: gripper, at: .nan}\n",
                "object.at",
                "degrees",
            ),
            (
                "key",
                "object: {joint: gripper, at: 25, stifness: 5}\n",
                "object",
                "stifness",
            ),
            ("missing", "object: {joint: gripper}\n", "object", "at"),
        ];
        for (name, yaml, field, says) in cases {
            let e = load(name, yaml).expect_err("refused");
            assert_eq!(e.field(), Some(field), "{name}: {e}");
            assert!(e.to_string().contains(says), "{name}: {e}");
        }
    }
}
