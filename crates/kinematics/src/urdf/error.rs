//! Why a URDF could not be imported: every error names the URDF file and,
//! where the problem is in it, the line.

use std::fmt;
use std::path::{Path, PathBuf};

use thiserror::Error;

/// A place in a URDF file: the file and the 1-based line, when the problem
/// is on one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UrdfPlace {
    /// The URDF file.
    pub file: PathBuf,
    /// 1-based line; `None` when the problem is with the file as a whole
    /// (a joint it does not have).
    pub line: Option<u32>,
}

impl fmt::Display for UrdfPlace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}", self.file.display()),
            None => write!(f, "{}", self.file.display()),
        }
    }
}

impl UrdfPlace {
    pub(crate) fn at(file: &Path, line: u32) -> Self {
        UrdfPlace {
            file: file.to_owned(),
            line: Some(line),
        }
    }

    pub(crate) fn file(file: &Path) -> Self {
        UrdfPlace {
            file: file.to_owned(),
            line: None,
        }
    }
}

/// A URDF that cannot give a servobus robot its geometry. Each prints as
/// `file:line: reason` ([`UrdfError::place`]).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum UrdfError {
    /// The file could not be read.
    #[error("{place}: cannot read: {reason}")]
    Read {
        /// The file.
        place: UrdfPlace,
        /// What the operating system said.
        reason: String,
    },
    /// The text is not well-formed XML.
    #[error("{place}:{column}: not well-formed XML: {reason}")]
    Xml {
        /// The file and line.
        place: UrdfPlace,
        /// 1-based column.
        column: u32,
        /// What the XML parser said.
        reason: String,
    },
    /// Well-formed XML that is not a URDF servobus can read: a missing
    /// attribute, a number that is not one, a link named twice, a joint
    /// naming a link the file lacks, more than one root link.
    #[error("{place}: {reason}")]
    Malformed {
        /// The file and line.
        place: UrdfPlace,
        /// What is wrong.
        reason: String,
    },
    /// The robot file maps a joint to a URDF joint the file does not have.
    #[error(
        "{place}: no joint `{urdf_joint}` (mapped from `{joint}`); the file's joints: {}",
        known.join(", ")
    )]
    MissingJoint {
        /// The file.
        place: UrdfPlace,
        /// The servobus joint.
        joint: String,
        /// The URDF joint it is mapped to.
        urdf_joint: String,
        /// The joints the file has, with their types.
        known: Vec<String>,
    },
    /// A named frame on a URDF link the file does not have.
    #[error("{place}: no link `{link}` (for frame `{frame}`); the file's links: {}", known.join(", "))]
    MissingLink {
        /// The file.
        place: UrdfPlace,
        /// The frame.
        frame: String,
        /// The link it names.
        link: String,
        /// The links the file has.
        known: Vec<String>,
    },
    /// A link that is the child of two joints: the joints close a loop,
    /// and a servobus robot is a tree.
    #[error(
        "{place}: link `{link}` has two parents, joint `{first}` (line {first_line}) and joint \
         `{second}`: the joints close a kinematic loop; servobus needs a tree"
    )]
    TwoParents {
        /// The file and the line of the second joint.
        place: UrdfPlace,
        /// The link.
        link: String,
        /// The first joint with it as its child.
        first: String,
        /// That joint's line.
        first_line: u32,
        /// The second.
        second: String,
    },
    /// Joints whose links lead back to themselves.
    #[error("{place}: joint `{joint}` is on a kinematic loop (its links lead back to themselves): servobus needs a tree")]
    Loop {
        /// The file and the joint's line.
        place: UrdfPlace,
        /// A joint on the loop.
        joint: String,
    },
    /// A mapped joint of a type no servo drives.
    #[error(
        "{place}: joint `{urdf_joint}` (mapped from `{joint}`) is {kind}: servobus drives \
         joints that turn (revolute and continuous); a prismatic, planar or floating joint \
         cannot be mapped to a servo"
    )]
    Undrivable {
        /// The file and the joint's line.
        place: UrdfPlace,
        /// The servobus joint.
        joint: String,
        /// The URDF joint.
        urdf_joint: String,
        /// Its type, as the file says.
        kind: String,
    },
    /// A mapped joint that is fixed.
    #[error("{place}: joint `{urdf_joint}` (mapped from `{joint}`) is fixed: it never moves, so no servo can drive it; map a revolute or continuous joint")]
    Fixed {
        /// The file and the joint's line.
        place: UrdfPlace,
        /// The servobus joint.
        joint: String,
        /// The URDF joint.
        urdf_joint: String,
    },
    /// Two servobus joints mapped to one URDF joint.
    #[error("{place}: joint `{urdf_joint}` is mapped from both `{first}` and `{second}`")]
    MappedTwice {
        /// The file and the joint's line.
        place: UrdfPlace,
        /// The URDF joint.
        urdf_joint: String,
        /// One servobus joint.
        first: String,
        /// The other.
        second: String,
    },
    /// A mapped joint (or a frame's link) whose chain reaches the nearest
    /// mapped joint above it, or the root, only through a joint that moves
    /// and is not mapped.
    #[error(
        "{place}: `{what}` does not reach its parent through fixed joints: URDF joint \
         `{between}` on the way is {kind} and no servobus joint is mapped to it; map it \
         (`joints: {{<joint>: {between}}}`) or make it fixed"
    )]
    Unmapped {
        /// The file and the line of the joint in between.
        place: UrdfPlace,
        /// The servobus joint or frame whose chain is broken.
        what: String,
        /// The URDF joint in between.
        between: String,
        /// Its type.
        kind: String,
    },
    /// `zero` or `inverted` names a joint that is not mapped.
    #[error("`{key}` names `{joint}`, which `joints` does not map to the URDF")]
    UnknownEntry {
        /// `zero` or `inverted`.
        key: &'static str,
        /// The joint named.
        joint: String,
    },
    /// A `zero` that is not a finite number.
    #[error("`zero` of `{joint}` must be a finite number, got {value}")]
    NotFinite {
        /// The joint.
        joint: String,
        /// The value given.
        value: f64,
    },
    /// A joint axis of length zero, or a number that is not finite.
    #[error("{place}: joint `{urdf_joint}`: its axis {axis:?} has no direction")]
    BadAxis {
        /// The file and the joint's line.
        place: UrdfPlace,
        /// The URDF joint.
        urdf_joint: String,
        /// The axis as given.
        axis: [f64; 3],
    },
    /// A mesh named by a ROS package.
    #[error(
        "{place}: mesh `{filename}`: `package://` names a ROS package, which servobus does not \
         look up; give the mesh's path relative to the URDF file (e.g. `meshes/part.stl`)"
    )]
    PackageUri {
        /// The file and the line of the mesh.
        place: UrdfPlace,
        /// The file name as written.
        filename: String,
    },
    /// A mesh file that does not exist where the URDF says.
    #[error("{place}: mesh `{filename}` not found (looked for {})", path.display())]
    MeshNotFound {
        /// The file and the line of the mesh.
        place: UrdfPlace,
        /// The file name as written.
        filename: String,
        /// Where it was looked for.
        path: PathBuf,
    },
}

impl UrdfError {
    /// The URDF file and line the error is about (`None` for the errors
    /// about the mapping alone: [`UrdfError::UnknownEntry`],
    /// [`UrdfError::NotFinite`]).
    pub fn place(&self) -> Option<&UrdfPlace> {
        match self {
            UrdfError::Read { place, .. }
            | UrdfError::Xml { place, .. }
            | UrdfError::Malformed { place, .. }
            | UrdfError::MissingJoint { place, .. }
            | UrdfError::MissingLink { place, .. }
            | UrdfError::TwoParents { place, .. }
            | UrdfError::Loop { place, .. }
            | UrdfError::Undrivable { place, .. }
            | UrdfError::Fixed { place, .. }
            | UrdfError::MappedTwice { place, .. }
            | UrdfError::Unmapped { place, .. }
            | UrdfError::BadAxis { place, .. }
            | UrdfError::PackageUri { place, .. }
            | UrdfError::MeshNotFound { place, .. } => Some(place),
            UrdfError::UnknownEntry { .. } | UrdfError::NotFinite { .. } => None,
        }
    }
}
