//! The robot file's `kinematics:` section as serde reads it, and the typed
//! errors of checking it.

use std::collections::BTreeMap;

use serde::Deserialize;
use thiserror::Error;

/// The name of the root frame: the robot's base (an arm's foot, a
/// hexapod's body).
pub const BASE: &str = "base";

/// The geometry of a robot: one entry per joint and per named frame.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// Every joint of the robot, by name.
    pub joints: BTreeMap<String, JointSpec>,
    /// Named frames fixed to a joint's link (or to the base): `tool`,
    /// `foot_<leg>`.
    #[serde(default)]
    pub frames: BTreeMap<String, FrameSpec>,
}

/// One joint: where its axis sits on its parent's link.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSpec {
    /// `base` or another joint.
    pub parent: String,
    /// Offset from the parent's frame, mm.
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw about the fixed x, y, z axes (applied in that
    /// order), in the file's angle unit.
    #[serde(default)]
    pub rpy: [f64; 3],
    /// The axis the joint turns about, a unit vector in the joint's frame.
    pub axis: [f64; 3],
}

/// A named frame fixed to a joint's link.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameSpec {
    /// `base` or a joint.
    pub parent: String,
    /// Offset from the parent's frame, mm.
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw as for a joint, in the file's angle unit.
    #[serde(default)]
    pub rpy: [f64; 3],
}

/// Which part of the section an error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    /// `kinematics.joints`.
    Joints,
    /// `kinematics.frames`.
    Frames,
}

impl Section {
    /// The key of the section in the robot file.
    pub fn key(self) -> &'static str {
        match self {
            Section::Joints => "joints",
            Section::Frames => "frames",
        }
    }
}

/// A problem with a geometry: every variant names the entry it is about
/// ([`SpecError::location`]).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SpecError {
    /// A parent that is neither `base` nor a joint.
    #[error("unknown parent `{parent}` (use `base` or a joint)")]
    UnknownParent {
        /// Joint or frame.
        section: Section,
        /// The entry.
        name: String,
        /// The parent it names.
        parent: String,
    },
    /// A joint that is, through its parents, its own ancestor.
    #[error("joint `{joint}` is its own ancestor (a cycle of parents)")]
    Cycle {
        /// A joint on the cycle.
        joint: String,
    },
    /// An axis that is zero or not of unit length.
    #[error("axis {axis:?} must be a unit vector (length {length:.6})")]
    BadAxis {
        /// The joint.
        joint: String,
        /// The axis as given.
        axis: [f64; 3],
        /// Its length.
        length: f64,
    },
    /// A frame whose parent is empty.
    #[error("frame `{frame}` has no parent")]
    NoParent {
        /// The frame.
        frame: String,
    },
    /// A number that is not finite.
    #[error("`{field}` must be finite numbers")]
    NotFinite {
        /// Joint or frame.
        section: Section,
        /// The entry.
        name: String,
        /// `xyz`, `rpy` or `axis`.
        field: &'static str,
    },
    /// A name used by a joint and a frame, or the reserved name `base`.
    #[error("the name `{name}` is taken (by `base` or a joint)")]
    NameTaken {
        /// Joint or frame.
        section: Section,
        /// The name.
        name: String,
    },
    /// Geometry for a joint the robot does not have.
    #[error("the robot has no joint `{joint}`")]
    UnknownJoint {
        /// The joint.
        joint: String,
    },
    /// A joint of the robot without geometry.
    #[error("joint `{joint}` has no geometry here (every joint of the robot needs one)")]
    MissingJoint {
        /// The joint.
        joint: String,
    },
}

/// Where in the `kinematics:` section an error is: the section, the entry
/// (`None`: the section itself) and the field (`None`: the entry's key).
pub type Location<'a> = (Section, Option<&'a str>, Option<&'static str>);

impl SpecError {
    /// The place of the problem in the section, for error messages that
    /// point into the file.
    pub fn location(&self) -> Location<'_> {
        match self {
            SpecError::UnknownParent { section, name, .. } => {
                (*section, Some(name), Some("parent"))
            }
            SpecError::Cycle { joint } => (Section::Joints, Some(joint), Some("parent")),
            SpecError::BadAxis { joint, .. } => (Section::Joints, Some(joint), Some("axis")),
            SpecError::NoParent { frame } => (Section::Frames, Some(frame), Some("parent")),
            SpecError::NotFinite {
                section,
                name,
                field,
            } => (*section, Some(name), Some(field)),
            SpecError::NameTaken { section, name } => (*section, Some(name), None),
            SpecError::UnknownJoint { joint } => (Section::Joints, Some(joint), None),
            SpecError::MissingJoint { .. } => (Section::Joints, None, None),
        }
    }
}
