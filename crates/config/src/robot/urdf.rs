//! A robot file's `kinematics:` section in either of its forms: typed by
//! hand (`joints: {<joint>: {parent, xyz, rpy, axis}}`) or imported from a
//! URDF (`urdf: FILE, joints: {<joint>: <URDF joint>}, zero, inverted,
//! frames, origin`; see [`servobus_kinematics::UrdfSpec`]). With a URDF,
//! a position joint without `min` or `max` takes the URDF's limit, and
//! limits the file gives must lie within the URDF's.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use servobus_kinematics::{
    FrameSpec, Geometry, JointSpec, Placement, Spec, Urdf, UrdfError, UrdfFrame, UrdfSpec,
};

use super::raw::{RawBus, RawRobot};
use super::{JointMode, Robot};
use crate::error::{ConfigError, Source};
use crate::locate::FieldPath;
use crate::Units;

/// How far (degrees) a robot file's limit may pass the URDF's: URDF files
/// round their radians (110 deg is written 1.91986).
const LIMIT_SLACK_DEG: f64 = 0.01;

/// The `kinematics:` section as written, in either form.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "a kinematics section: `joints:` and `frames:`, typed by hand or with `urdf: FILE`"
)]
pub(super) struct RawKinematics {
    #[serde(default)]
    urdf: Option<PathBuf>,
    joints: BTreeMap<String, RawJointEntry>,
    #[serde(default)]
    frames: BTreeMap<String, RawFrameEntry>,
    #[serde(default)]
    zero: Option<BTreeMap<String, f64>>,
    #[serde(default)]
    inverted: Option<Vec<String>>,
    #[serde(default)]
    origin: Option<Placement>,
}

/// A joint's entry: its geometry, or (with `urdf:`) its URDF joint's name.
enum RawJointEntry {
    Urdf(String),
    Spec(JointSpec),
}

/// A frame's entry: a URDF link's name, or a mapping (`parent`, `xyz`,
/// `rpy` typed by hand; `link`, `xyz`, `rpy` on a URDF link).
enum RawFrameEntry {
    Link(String),
    Map(RawFrameMap),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFrameMap {
    #[serde(default)]
    parent: Option<String>,
    #[serde(default)]
    link: Option<String>,
    #[serde(default)]
    xyz: Option<[f64; 3]>,
    #[serde(default)]
    rpy: Option<[f64; 3]>,
}

// By hand rather than `untagged`, which loses the place of a problem
// inside a joint's mapping (see `LatencySpec`).
impl<'de> Deserialize<'de> for RawJointEntry {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawJointEntry;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(
                    "a joint's {parent, xyz, rpy, axis}, or with `urdf:` a URDF joint's name",
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawJointEntry, E> {
                Ok(RawJointEntry::Urdf(v.to_owned()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<RawJointEntry, A::Error> {
                let d = de::value::MapAccessDeserializer::new(map);
                JointSpec::deserialize(d).map(RawJointEntry::Spec)
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for RawFrameEntry {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawFrameEntry;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a frame's {parent, xyz, rpy}, or with `urdf:` a URDF link's name or {link, xyz, rpy}")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawFrameEntry, E> {
                Ok(RawFrameEntry::Link(v.to_owned()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<RawFrameEntry, A::Error> {
                let d = de::value::MapAccessDeserializer::new(map);
                RawFrameMap::deserialize(d).map(RawFrameEntry::Map)
            }
        }
        d.deserialize_any(V)
    }
}

fn section() -> FieldPath {
    FieldPath::root().key("kinematics")
}

/// The URDF the robot file's `kinematics:` section names (relative to
/// `dir`, the robot file's directory), imported, with every position joint
/// that lacks `min` or `max` given the URDF's limit; `None` for a
/// hand-typed section or none.
pub(super) fn import(
    raw: &mut RawRobot,
    dir: &Path,
    src: &Source,
) -> Result<Option<Urdf>, ConfigError> {
    let imported = load(raw.kinematics.as_ref(), dir, raw.units, src)?;
    fill_limits(&mut raw.buses, imported.as_ref(), raw.units);
    Ok(imported)
}

/// The URDF a `kinematics:` section names, imported; see [`import`].
fn load(
    raw: Option<&RawKinematics>,
    dir: &Path,
    units: Units,
    src: &Source,
) -> Result<Option<Urdf>, ConfigError> {
    let Some(
        raw @ RawKinematics {
            urdf: Some(file), ..
        },
    ) = raw
    else {
        return Ok(None);
    };
    let at = section();
    let mut joints = BTreeMap::new();
    for (name, entry) in &raw.joints {
        match entry {
            RawJointEntry::Urdf(urdf_joint) => joints.insert(name.clone(), urdf_joint.clone()),
            RawJointEntry::Spec(_) => {
                return Err(src.error(
                    &at.key("joints").key(name),
                    format!(
                        "with `urdf:`, a joint is the name of its URDF joint \
                         (`{name}: <URDF joint>`); its geometry comes from the URDF"
                    ),
                ))
            }
        };
    }
    let mut frames = BTreeMap::new();
    for (name, entry) in &raw.frames {
        let frame = match entry {
            RawFrameEntry::Link(link) => UrdfFrame {
                link: link.clone(),
                at: Placement::default(),
            },
            RawFrameEntry::Map(RawFrameMap {
                link: Some(link),
                parent: None,
                xyz,
                rpy,
            }) => UrdfFrame {
                link: link.clone(),
                at: Placement {
                    xyz: xyz.unwrap_or_default(),
                    rpy: rpy.unwrap_or_default(),
                },
            },
            RawFrameEntry::Map(_) => {
                return Err(src.error(
                    &at.key("frames").key(name),
                    "with `urdf:`, a frame is on a URDF link: `<frame>: <link>` or \
                     `{link: <link>, xyz: [...], rpy: [...]}` (no `parent:`)",
                ))
            }
        };
        frames.insert(name.clone(), frame);
    }
    let spec = UrdfSpec {
        urdf: file.clone(),
        joints,
        zero: raw.zero.clone().unwrap_or_default(),
        inverted: raw.inverted.clone().unwrap_or_default(),
        frames,
        origin: raw.origin.unwrap_or_default(),
    };
    Urdf::load(&spec, dir, units.to_rad(1.0))
        .map(Some)
        .map_err(|e| urdf_error(&e, raw, src))
}

/// A URDF's refusal at the robot file's entry it is about, naming the URDF
/// file and line in the reason.
fn urdf_error(e: &UrdfError, raw: &RawKinematics, src: &Source) -> ConfigError {
    let at = section();
    let entry = |key: &str, name: &str| at.key(key).key(name);
    let path = match e {
        UrdfError::MissingJoint { joint, .. }
        | UrdfError::Undrivable { joint, .. }
        | UrdfError::Fixed { joint, .. } => entry("joints", joint),
        UrdfError::MappedTwice { second, .. } => entry("joints", second),
        UrdfError::MissingLink { frame, .. } => entry("frames", frame),
        UrdfError::Unmapped { what, .. } if raw.joints.contains_key(what) => entry("joints", what),
        UrdfError::Unmapped { what, .. } => entry("frames", what),
        UrdfError::UnknownEntry { key, joint } => {
            return src.key_error(&entry(key, joint), e.to_string());
        }
        UrdfError::NotFinite { joint, .. } => entry("zero", joint),
        _ => at.key("urdf"),
    };
    src.error(&path, e.to_string())
}

/// Gives every position joint of `buses` that lacks `min` or `max` the
/// URDF's limit, in `units`.
fn fill_limits(buses: &mut [RawBus], urdf: Option<&Urdf>, units: Units) {
    let Some(urdf) = urdf else { return };
    for joint in buses.iter_mut().flat_map(|b| b.joints.iter_mut()) {
        let limit = urdf.limits.get(&joint.name).and_then(|l| l.position);
        let (Some((lo, hi)), JointMode::Position) = (limit, joint.mode) else {
            continue;
        };
        joint.min.get_or_insert(units.from_rad(lo));
        joint.max.get_or_insert(units.from_rad(hi));
    }
}

/// The `kinematics:` section checked against the robot's joints, from the
/// imported `urdf` when it names one; a problem is reported at its entry
/// and field.
pub(super) fn kinematics(
    robot: &Robot,
    raw: &RawKinematics,
    urdf: Option<&Urdf>,
    src: &Source,
) -> Result<Geometry, ConfigError> {
    let spec = match urdf {
        Some(urdf) => {
            check_limits(robot, urdf, src)?;
            urdf.spec.clone()
        }
        None => hand_typed(raw, src)?,
    };
    let names = robot.joints().map(|j| j.name.as_str());
    Geometry::new(&spec, names, robot.units.to_rad(1.0)).map_err(|e| {
        let (part, entry, field) = e.location();
        let mut at = section().key(part.key());
        let Some(entry) = entry else {
            return src.error(&at, e.to_string());
        };
        at = at.key(entry);
        match field {
            Some(field) => src.error(&at.key(field), e.to_string()),
            None => src.key_error(&at, e.to_string()),
        }
    })
}

/// A section without `urdf:` as a [`Spec`]: every entry typed by hand.
fn hand_typed(raw: &RawKinematics, src: &Source) -> Result<Spec, ConfigError> {
    let at = section();
    let needs_urdf = |path: &FieldPath, what: &str| {
        src.error(path, format!("{what} needs `urdf: FILE` in this section"))
    };
    for (key, given) in [
        ("zero", raw.zero.is_some()),
        ("inverted", raw.inverted.is_some()),
        ("origin", raw.origin.is_some()),
    ] {
        if given {
            return Err(needs_urdf(&at.key(key), &format!("`{key}:`")));
        }
    }
    let mut spec = Spec::default();
    for (name, entry) in &raw.joints {
        let RawJointEntry::Spec(js) = entry else {
            let what = "a URDF joint's name (typed by hand: {parent, xyz, rpy, axis})";
            return Err(needs_urdf(&at.key("joints").key(name), what));
        };
        spec.joints.insert(name.clone(), js.clone());
    }
    for (name, entry) in &raw.frames {
        let fp = at.key("frames").key(name);
        let m = match entry {
            RawFrameEntry::Map(m) if m.link.is_none() => m,
            _ => return Err(needs_urdf(&fp, "a frame on a URDF link")),
        };
        let (Some(parent), Some(xyz)) = (&m.parent, m.xyz) else {
            let field = if m.parent.is_none() { "parent" } else { "xyz" };
            return Err(src.error(&fp, format!("missing field `{field}`")));
        };
        let rpy = m.rpy.unwrap_or_default();
        let parent = parent.clone();
        spec.frames
            .insert(name.clone(), FrameSpec { parent, xyz, rpy });
    }
    Ok(spec)
}

/// Refuses a position joint whose limits go beyond its URDF joint's.
fn check_limits(robot: &Robot, urdf: &Urdf, src: &Source) -> Result<(), ConfigError> {
    let units = robot.units;
    let slack = units.from_rad(LIMIT_SLACK_DEG.to_radians());
    for (bi, bus) in robot.buses.iter().enumerate() {
        for (ji, joint) in bus.joints.iter().enumerate() {
            let limits = urdf.limits.get(&joint.name);
            let Some((l, (lo, hi))) = limits.and_then(|l| Some((l, l.position?))) else {
                continue;
            };
            if joint.is_wheel() {
                continue;
            }
            let (lo, hi) = (units.from_rad(lo), units.from_rad(hi));
            let jp = FieldPath::root()
                .key("buses")
                .index(bi)
                .key("joints")
                .index(ji);
            let (field, v, side, limit) = if joint.min < lo - slack {
                ("min", joint.min, "below the URDF's lower", lo)
            } else if joint.max > hi + slack {
                ("max", joint.max, "above the URDF's upper", hi)
            } else {
                continue;
            };
            return Err(src.error(
                &jp.key(field),
                format!(
                    "joint `{}`: {field} {v} {units} is {side} limit {limit:.2} {units} \
                     (joint `{}`, {}); keep within [{lo:.2}, {hi:.2}] or leave `{field}` out \
                     to take the URDF's",
                    joint.name, l.urdf_joint, l.place
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod kept {
    use std::path::Path;

    use crate::{load_robot, RobotOptions, RobotSource};

    #[test]
    fn a_robot_keeps_the_urdf_it_imports_for_its_meshes_and_none_typed_by_hand() {
        let file =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/urdf/so101_urdf.yaml");
        let robot = load_robot(&file, &RobotOptions::default()).expect("loads");
        let urdf = robot.urdf.as_ref().expect("the imported URDF");
        assert!(urdf.file.ends_with("so101/so101_new_calib.urdf"));
        let meshes = urdf
            .links
            .iter()
            .flat_map(|l| &l.visuals)
            .filter(|v| matches!(v.geometry, servobus_kinematics::VisualGeometry::Mesh { .. }))
            .count();
        assert!(meshes > 10, "{meshes} meshes");
        // Every link hangs on a joint of the robot, or on its base.
        for link in &urdf.links {
            assert!(
                link.parent == "base" || robot.joint(&link.parent).is_some(),
                "{}: {}",
                link.link,
                link.parent
            );
        }
        let hand =
            load_robot(RobotSource::Builtin("so101"), &RobotOptions::default()).expect("so101");
        assert!(hand.kinematics.is_some() && hand.urdf.is_none());
    }
}
