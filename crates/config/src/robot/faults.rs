//! A joint's own fault policy (`faults:` of a joint in the robot file):
//! whether a stall or a following error of that joint ends the run, is held
//! and reported, or is not checked.
//!
//! Only those two are set per joint. Heat, over-current, the other status
//! flags and a servo that stops answering always end the run with the
//! run-wide reaction: a key for them is refused, saying so.

use std::fmt;

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};

use super::JointConfig;
use crate::error::{ConfigError, Source};
use crate::locate::FieldPath;

/// What a run does when tracking finds a joint stalled, or off its path by
/// more than the tolerance (a value of `faults:` in the robot file).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
#[serde(expecting = "`fault`, `hold` or `ignore`")]
pub enum FaultResponse {
    /// A fault, with the run-wide reaction (the default). In a live
    /// session a stall still holds the joint pressed, as it always has.
    #[default]
    Fault,
    /// The joint is held pressed where it stands (its goal kept close to
    /// it) and the stall is reported; the run goes on, played or live, and
    /// the joint follows again once its path comes back.
    Hold,
    /// Not checked for this joint.
    Ignore,
}

/// A joint's `faults:`: its reaction to a following error and to a stall,
/// and its own following-error tolerance. The default (no `faults:`) is the
/// run-wide policy for both.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointFaults {
    /// A following error of the joint (`following_error:`).
    pub following_error: FaultResponse,
    /// A stall of the joint (`stall:`).
    pub stall: FaultResponse,
    /// The largest tracking error tolerated before a following error, in
    /// the robot's units (`following_tolerance:`); `None`: the run's.
    pub following_tolerance: Option<f64>,
}

/// The keys `faults:` accepts.
const KEYS: &str = "`following_error`, `stall` and `following_tolerance`";

/// A joint's `faults:` as written.
#[derive(Default)]
pub(super) struct RawFaults {
    following_error: Option<FaultResponse>,
    stall: Option<FaultResponse>,
    following_tolerance: Option<f64>,
}

/// A key of `faults:`; any other is refused where it stands, naming the
/// accepted ones.
enum Key {
    FollowingError,
    Stall,
    FollowingTolerance,
}

impl<'de> Deserialize<'de> for Key {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Key;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "one of {KEYS}")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Key, E> {
                match v {
                    "following_error" => Ok(Key::FollowingError),
                    "stall" => Ok(Key::Stall),
                    "following_tolerance" => Ok(Key::FollowingTolerance),
                    _ => Err(E::custom(format!(
                        "unknown field `{v}`: a joint's `faults:` sets only {KEYS}; heat, \
                         over-current, the other status flags and a missing servo always \
                         end the run"
                    ))),
                }
            }
        }
        d.deserialize_identifier(V)
    }
}

impl<'de> Deserialize<'de> for RawFaults {
    // By hand rather than derived, so that an unknown key says which
    // faults are never set per joint.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawFaults;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "a joint's faults: a mapping with any of {KEYS}")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<RawFaults, A::Error> {
                let mut out = RawFaults::default();
                while let Some(key) = map.next_key::<Key>()? {
                    match key {
                        Key::FollowingError => {
                            once(&mut out.following_error, &mut map, "following_error")?;
                        }
                        Key::Stall => once(&mut out.stall, &mut map, "stall")?,
                        Key::FollowingTolerance => {
                            once(
                                &mut out.following_tolerance,
                                &mut map,
                                "following_tolerance",
                            )?;
                        }
                    }
                }
                Ok(out)
            }
        }
        d.deserialize_map(V)
    }
}

/// Reads the value of `key` into `slot`, refusing a second one.
fn once<'de, T: Deserialize<'de>, A: MapAccess<'de>>(
    slot: &mut Option<T>,
    map: &mut A,
    key: &'static str,
) -> Result<(), A::Error> {
    if slot.is_some() {
        return Err(de::Error::duplicate_field(key));
    }
    *slot = Some(map.next_value()?);
    Ok(())
}

/// The `faults:` of `joint` (at `jp` in the file), checked: a positive
/// tolerance, and none at all on a wheel, which follows no path.
pub(super) fn joint_faults(
    raw: Option<&RawFaults>,
    joint: &JointConfig,
    jp: &FieldPath,
    src: &Source,
) -> Result<JointFaults, ConfigError> {
    let Some(raw) = raw else {
        return Ok(JointFaults::default());
    };
    let at = jp.key("faults");
    if joint.is_wheel() {
        return Err(src.error(
            &at,
            format!(
                "joint `{}` is a wheel: it follows no path, so it has no stall or following \
                 error to set; remove `faults:`",
                joint.name
            ),
        ));
    }
    if let Some(t) = raw.following_tolerance {
        if !(t.is_finite() && t > 0.0) {
            return Err(src.error(
                &at.key("following_tolerance"),
                format!("must be a positive angle in the file's units, got {t}"),
            ));
        }
    }
    Ok(JointFaults {
        following_error: raw.following_error.unwrap_or_default(),
        stall: raw.stall.unwrap_or_default(),
        following_tolerance: raw.following_tolerance,
    })
}
