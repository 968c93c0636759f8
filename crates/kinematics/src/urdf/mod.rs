//! URDF import: a robot's geometry, joint limits and visual meshes from the
//! URDF file its makers publish, instead of typing them into the robot file.
//!
//! A robot file says `kinematics: {urdf: FILE, joints: {<joint>: <URDF
//! joint>}, zero: {...}, inverted: [...], frames: {...}, origin: {...}}`
//! ([`UrdfSpec`]); [`Urdf::load`] reads the file (roxmltree, every problem
//! placed at its line) and turns the chain into the same [`Spec`] a
//! hand-typed section gives, so forward and inverse kinematics, lines and
//! gaits work on it unchanged.
//!
//! | URDF | servobus |
//! | --- | --- |
//! | the root link | `base` (placed by `origin`, default: the same frame) |
//! | a mapped revolute or continuous joint | that joint: its origin, then a turn by `zero` about its axis |
//! | fixed joints between mapped joints | composed into the next joint's origin, or a frame's |
//! | a link named in `frames` | a named frame on the joint (or `base`) that carries it |
//! | metres, radians | millimetres, the file's angle unit |
//! | `<limit lower upper velocity>` | [`UrdfLimits`], in the servobus joint's angle |
//! | `<visual>` meshes, boxes, cylinders, spheres | [`LinkVisuals`], posed on the servobus frames |
//!
//! `zero` is the URDF angle at servobus's zero of the joint; a joint in
//! `inverted` turns the opposite way to its URDF joint. The URDF angle of
//! a joint is then `zero + angle` (or `zero - angle`). Refused, with the
//! file and line: malformed XML, a mapped joint the file lacks (naming the
//! joints it has), a link with two parents or a loop, a mapped joint that
//! is fixed, prismatic, planar or floating, a moving joint between mapped
//! ones that is not mapped, a `package://` mesh, a mesh that is not there.

mod chain;
mod error;
mod model;

use std::collections::BTreeMap;
use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

use nalgebra::Isometry3;
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};

pub use error::{UrdfError, UrdfPlace};

use crate::spec::Spec;

/// The largest URDF read, bytes: a robot description is text of some
/// hundred kilobytes; anything larger is not one.
pub const MAX_URDF_BYTES: u64 = 16 << 20;

/// The robot file's `kinematics:` section in its URDF form.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UrdfSpec {
    /// The URDF file, relative to the robot file's directory.
    pub urdf: PathBuf,
    /// Every servobus joint with geometry, and the URDF joint it is.
    pub joints: BTreeMap<String, String>,
    /// The URDF angle at servobus's zero of a joint, in the robot file's
    /// angle unit (default 0).
    #[serde(default)]
    pub zero: BTreeMap<String, f64>,
    /// Joints that turn the opposite way to their URDF joint.
    #[serde(default)]
    pub inverted: Vec<String>,
    /// Named frames (`tool`, `foot_<leg>`) on URDF links.
    #[serde(default)]
    pub frames: BTreeMap<String, UrdfFrame>,
    /// Where the URDF's root link sits in the robot's base frame (default:
    /// the base frame is the root link's).
    #[serde(default)]
    pub origin: Placement,
}

/// A pose: `xyz` in mm, `rpy` roll, pitch, yaw about fixed x, y, z in the
/// robot file's angle unit, as in a hand-typed `kinematics:` section.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Placement {
    /// Offset, mm.
    #[serde(default)]
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw, the file's angle unit.
    #[serde(default)]
    pub rpy: [f64; 3],
}

/// A named frame on a URDF link: the link's name alone
/// (`tool: gripper_frame_link`), or `{link, xyz, rpy}` for a frame placed
/// on the link.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfFrame {
    /// The URDF link.
    pub link: String,
    /// The frame on the link.
    pub at: Placement,
}

impl<'de> Deserialize<'de> for UrdfFrame {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct OnLink {
            link: String,
            #[serde(default)]
            xyz: [f64; 3],
            #[serde(default)]
            rpy: [f64; 3],
        }
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = UrdfFrame;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a URDF link's name, or {link, xyz, rpy}")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<UrdfFrame, E> {
                Ok(UrdfFrame {
                    link: v.to_owned(),
                    at: Placement::default(),
                })
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<UrdfFrame, A::Error> {
                let o = OnLink::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(UrdfFrame {
                    link: o.link,
                    at: Placement {
                        xyz: o.xyz,
                        rpy: o.rpy,
                    },
                })
            }
        }
        d.deserialize_any(V)
    }
}

/// A mapped joint's limits from its URDF joint, in the servobus joint's
/// angle (after `zero` and `inverted`).
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfLimits {
    /// The URDF joint.
    pub urdf_joint: String,
    /// Where it is in the file.
    pub place: UrdfPlace,
    /// Lowest and highest angle, radians; `None` for a continuous joint
    /// (or a revolute one without `<limit>`).
    pub position: Option<(f64, f64)>,
    /// Speed limit, rad/s, when the file gives a positive one.
    pub velocity: Option<f64>,
}

/// What a visual draws. Lengths in mm; a mesh's vertices are in the
/// URDF's unit, metres, times `scale`.
#[derive(Debug, Clone, PartialEq)]
pub enum VisualGeometry {
    /// A mesh file (STL, DAE, OBJ), its path resolved.
    Mesh {
        /// The file, relative to the URDF's directory resolved.
        path: PathBuf,
        /// Scale per axis, as the URDF gives it (default 1).
        scale: [f64; 3],
    },
    /// A box centred on the visual's origin: size, mm.
    Box {
        /// Edge lengths along x, y, z, mm.
        size: [f64; 3],
    },
    /// A cylinder along the visual's z axis.
    Cylinder {
        /// Radius, mm.
        radius: f64,
        /// Length, mm.
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius, mm.
        radius: f64,
    },
}

/// One `<visual>` of a link.
#[derive(Debug, Clone, PartialEq)]
pub struct Visual {
    /// The shape.
    pub geometry: VisualGeometry,
    /// The shape's frame in the link's, mm.
    pub origin: Isometry3<f64>,
    /// RGBA from 0 to 1, when the URDF gives a colour.
    pub color: Option<[f64; 4]>,
}

/// A link's visuals, posed on a servobus frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkVisuals {
    /// The URDF link.
    pub link: String,
    /// The servobus joint whose frame carries the link, or `base`.
    pub parent: String,
    /// The link's frame in the parent's, mm (URDF joints no servobus joint
    /// drives count at angle 0).
    pub origin: Isometry3<f64>,
    /// What it draws.
    pub visuals: Vec<Visual>,
}

/// An imported URDF.
#[derive(Debug, Clone, PartialEq)]
pub struct Urdf {
    /// The URDF file.
    pub file: PathBuf,
    /// The geometry, as a hand-typed `kinematics:` section would give it
    /// (`rpy` in the robot file's angle unit).
    pub spec: Spec,
    /// Each mapped joint's limits, by servobus joint.
    pub limits: BTreeMap<String, UrdfLimits>,
    /// Every link with something to draw.
    pub links: Vec<LinkVisuals>,
}

impl Urdf {
    /// Reads the URDF `spec` names (relative to `dir`, the robot file's
    /// directory) and imports it; `angle_to_rad` converts the robot file's
    /// angle unit (`zero`, the `rpy` fields) to radians.
    ///
    /// # Errors
    /// [`UrdfError::Read`] when the file cannot be read (or is larger than
    /// [`MAX_URDF_BYTES`]); the errors of [`Urdf::from_text`].
    pub fn load(spec: &UrdfSpec, dir: &Path, angle_to_rad: f64) -> Result<Urdf, UrdfError> {
        let file = dir.join(&spec.urdf);
        let read_error = |reason: String| UrdfError::Read {
            place: UrdfPlace::file(&file),
            reason,
        };
        let f = std::fs::File::open(&file).map_err(|e| read_error(io_reason(&e)))?;
        let mut bytes = Vec::new();
        f.take(MAX_URDF_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| read_error(io_reason(&e)))?;
        if bytes.len() as u64 > MAX_URDF_BYTES {
            return Err(read_error(format!(
                "larger than {} MiB: not a robot description",
                MAX_URDF_BYTES >> 20
            )));
        }
        let text = String::from_utf8(bytes).map_err(|_| read_error("not UTF-8 text".into()))?;
        Urdf::from_text(&text, &file, spec, angle_to_rad)
    }

    /// Imports the URDF text of `file` (meshes are relative to `file`'s
    /// directory; `spec.urdf` is not read).
    ///
    /// # Errors
    /// A [`UrdfError`] naming the file and line: the XML, a malformed
    /// element, the tree (two parents, a loop, several roots), the mapping
    /// (a joint the file lacks, one that no servo can drive, one mapped
    /// twice, a moving joint in between that is not mapped, a frame on a
    /// link the file lacks, `zero` or `inverted` for an unmapped joint),
    /// a `package://` mesh or a mesh that is not there.
    pub fn from_text(
        text: &str,
        file: &Path,
        spec: &UrdfSpec,
        angle_to_rad: f64,
    ) -> Result<Urdf, UrdfError> {
        let model = model::parse(text, file)?;
        chain::import(&model, file, spec, angle_to_rad)
    }
}

/// The operating system's reason, without `(os error N)`.
fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => {
            let text = e.to_string();
            text.find(" (os error")
                .map_or(text.clone(), |i| text[..i].to_owned())
        }
    }
}
