//! A checked geometry: the tree of joints and named frames, and forward
//! kinematics into a caller's buffer.

use std::collections::HashMap;

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::spec::{FrameSpec, JointSpec, Section, Spec, SpecError, BASE};

/// How far an axis's length may be from 1.
const AXIS_TOLERANCE: f64 = 1e-6;

/// One joint of a [`Geometry`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Joint {
    pub(crate) name: String,
    /// The parent joint (index in the robot's joint order); `None`: the base.
    pub(crate) parent: Option<usize>,
    /// translate(xyz) * rotate(rpy).
    pub(crate) origin: Isometry3<f64>,
    pub(crate) axis: Unit<Vector3<f64>>,
    /// Lowest and highest angle, radians.
    pub(crate) limits: (f64, f64),
}

/// One named frame of a [`Geometry`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Frame {
    pub(crate) name: String,
    pub(crate) parent: Option<usize>,
    pub(crate) origin: Isometry3<f64>,
}

/// A robot's geometry, checked: joints in the robot's joint order, each
/// with its parent, origin, axis and limits (radians; unlimited until
/// [`Geometry::set_limits`]), and the named frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    pub(crate) joints: Vec<Joint>,
    /// Joint indices, every parent before its children.
    order: Vec<usize>,
    pub(crate) frames: Vec<Frame>,
}

/// The pose of every joint frame and named frame (in the base frame, mm),
/// filled by [`Geometry::forward`] without allocating.
#[derive(Debug, Clone, PartialEq)]
pub struct Poses {
    joints: Vec<Isometry3<f64>>,
    frames: Vec<Isometry3<f64>>,
}

impl Poses {
    /// A buffer for `geometry`'s poses.
    pub fn new(geometry: &Geometry) -> Self {
        Poses {
            joints: vec![Isometry3::identity(); geometry.joints.len()],
            frames: vec![Isometry3::identity(); geometry.frames.len()],
        }
    }

    /// The frame of joint `i` (robot order): its link after it has turned.
    pub fn joint(&self, i: usize) -> Option<&Isometry3<f64>> {
        self.joints.get(i)
    }

    /// Named frame `i` ([`Geometry::frame_index`]).
    pub fn frame(&self, i: usize) -> Option<&Isometry3<f64>> {
        self.frames.get(i)
    }
}

/// Whether every number of `v` is finite.
fn finite(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// translate(xyz) * rotate(rpy), rpy already in radians.
pub(crate) fn origin(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

impl Geometry {
    /// Checks `spec` against the robot's joints (`joint_names`, in the
    /// robot's order) and builds the tree. `angle_to_rad` converts the
    /// file's angle unit (the `rpy` fields) to radians: 1 for radians,
    /// pi/180 for degrees.
    ///
    /// # Errors
    /// A [`SpecError`] naming the entry: an unknown parent, a cycle, an
    /// axis not of unit length, a frame without a parent, a number that is
    /// not finite, a name used twice, geometry for a joint the robot does
    /// not have, or a robot joint without geometry.
    pub fn new<'a>(
        spec: &Spec,
        joint_names: impl IntoIterator<Item = &'a str>,
        angle_to_rad: f64,
    ) -> Result<Self, SpecError> {
        let names: Vec<&str> = joint_names.into_iter().collect();
        let index: HashMap<&str, usize> = names.iter().enumerate().map(|(i, n)| (*n, i)).collect();
        check_joint_names(spec, &index)?;
        let mut joints = Vec::with_capacity(names.len());
        for name in &names {
            let Some(js) = spec.joints.get(*name) else {
                return Err(SpecError::MissingJoint {
                    joint: (*name).to_owned(),
                });
            };
            joints.push(checked_joint(name, js, &index, angle_to_rad)?);
        }
        let order = topological(&joints)?;
        let mut frames = Vec::with_capacity(spec.frames.len());
        for (name, fs) in &spec.frames {
            frames.push(checked_frame(name, fs, &index, angle_to_rad)?);
        }
        Ok(Geometry {
            joints,
            order,
            frames,
        })
    }

    /// Number of joints (the robot's).
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// Number of named frames.
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// The name of joint `i`.
    pub fn joint_name(&self, i: usize) -> Option<&str> {
        self.joints.get(i).map(|j| j.name.as_str())
    }

    /// The name of named frame `i`.
    pub fn frame_name(&self, i: usize) -> Option<&str> {
        self.frames.get(i).map(|f| f.name.as_str())
    }

    /// The index of the joint called `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// The index of the named frame called `name`.
    pub fn frame_index(&self, name: &str) -> Option<usize> {
        self.frames.iter().position(|f| f.name == name)
    }

    /// Sets joint `i`'s limits, radians (no effect for an unknown joint).
    pub fn set_limits(&mut self, i: usize, min: f64, max: f64) {
        if let Some(j) = self.joints.get_mut(i) {
            j.limits = (min, max);
        }
    }

    /// Joint `i`'s limits, radians.
    pub fn limits(&self, i: usize) -> Option<(f64, f64)> {
        self.joints.get(i).map(|j| j.limits)
    }

    /// The joint's frame from its parent's at angle `q`:
    /// translate(xyz) * rotate(rpy) * rotate(axis, q).
    pub(crate) fn local(&self, i: usize, q: f64) -> Isometry3<f64> {
        let j = &self.joints[i];
        j.origin * UnitQuaternion::from_axis_angle(&j.axis, q)
    }

    /// Forward kinematics: the pose of every joint frame and named frame at
    /// joint angles `q` (radians, robot order; missing angles count as 0),
    /// into `out` (from [`Poses::new`] for this geometry). Allocates nothing.
    pub fn forward(&self, q: &[f64], out: &mut Poses) {
        for &i in &self.order {
            let local = self.local(i, q.get(i).copied().unwrap_or(0.0));
            let pose = match self.joints[i].parent {
                Some(p) => out.joints[p] * local,
                None => local,
            };
            out.joints[i] = pose;
        }
        for (k, f) in self.frames.iter().enumerate() {
            out.frames[k] = match f.parent {
                Some(p) => out.joints[p] * f.origin,
                None => f.origin,
            };
        }
    }

    /// The joints from the base to `frame`'s link, base first.
    pub fn chain_to_frame(&self, frame: usize) -> Vec<usize> {
        let mut chain = Vec::new();
        let mut at = self.frames.get(frame).and_then(|f| f.parent);
        while let Some(i) = at {
            chain.push(i);
            at = self.joints[i].parent;
        }
        chain.reverse();
        chain
    }
}

/// Refuses geometry for a joint named `base` or one the robot (`index`)
/// does not have.
fn check_joint_names(spec: &Spec, index: &HashMap<&str, usize>) -> Result<(), SpecError> {
    for name in spec.joints.keys() {
        if name == BASE {
            return Err(SpecError::NameTaken {
                section: Section::Joints,
                name: name.clone(),
            });
        }
        if !index.contains_key(name.as_str()) {
            return Err(SpecError::UnknownJoint {
                joint: name.clone(),
            });
        }
    }
    Ok(())
}

/// Joint `name` from its entry `js`, checked: finite numbers, a unit axis,
/// a known parent (`index`: the robot's joints).
fn checked_joint(
    name: &str,
    js: &JointSpec,
    index: &HashMap<&str, usize>,
    angle_to_rad: f64,
) -> Result<Joint, SpecError> {
    for (field, v) in [("xyz", &js.xyz), ("rpy", &js.rpy), ("axis", &js.axis)] {
        if !finite(v) {
            return Err(SpecError::NotFinite {
                section: Section::Joints,
                name: name.to_owned(),
                field,
            });
        }
    }
    let axis = Vector3::from(js.axis);
    let length = axis.norm();
    if (length - 1.0).abs() > AXIS_TOLERANCE {
        return Err(SpecError::BadAxis {
            joint: name.to_owned(),
            axis: js.axis,
            length,
        });
    }
    let parent = parent_index(index, &js.parent, Section::Joints, name)?;
    let rpy = js.rpy.map(|a| a * angle_to_rad);
    Ok(Joint {
        name: name.to_owned(),
        parent,
        origin: origin(js.xyz, rpy),
        axis: Unit::new_normalize(axis),
        limits: (f64::NEG_INFINITY, f64::INFINITY),
    })
}

/// Named frame `name` from its entry `fs`, checked: a name no joint has,
/// a known parent, finite numbers.
fn checked_frame(
    name: &str,
    fs: &FrameSpec,
    index: &HashMap<&str, usize>,
    angle_to_rad: f64,
) -> Result<Frame, SpecError> {
    if name == BASE || index.contains_key(name) {
        return Err(SpecError::NameTaken {
            section: Section::Frames,
            name: name.to_owned(),
        });
    }
    if fs.parent.trim().is_empty() {
        return Err(SpecError::NoParent {
            frame: name.to_owned(),
        });
    }
    for (field, v) in [("xyz", &fs.xyz), ("rpy", &fs.rpy)] {
        if !finite(v) {
            return Err(SpecError::NotFinite {
                section: Section::Frames,
                name: name.to_owned(),
                field,
            });
        }
    }
    let parent = parent_index(index, &fs.parent, Section::Frames, name)?;
    Ok(Frame {
        name: name.to_owned(),
        parent,
        origin: origin(fs.xyz, fs.rpy.map(|a| a * angle_to_rad)),
    })
}

fn parent_index(
    index: &HashMap<&str, usize>,
    parent: &str,
    section: Section,
    name: &str,
) -> Result<Option<usize>, SpecError> {
    if parent == BASE {
        return Ok(None);
    }
    index
        .get(parent)
        .map(|&i| Some(i))
        .ok_or_else(|| SpecError::UnknownParent {
            section,
            name: name.to_owned(),
            parent: parent.to_owned(),
        })
}

/// Joint indices ordered parents first, or the cycle found.
fn topological(joints: &[Joint]) -> Result<Vec<usize>, SpecError> {
    let mut depth = vec![usize::MAX; joints.len()];
    for start in 0..joints.len() {
        let mut at = Some(start);
        let mut steps = 0usize;
        while let Some(i) = at {
            if steps > joints.len() {
                return Err(SpecError::Cycle {
                    joint: joints[start].name.clone(),
                });
            }
            steps += 1;
            at = joints[i].parent;
        }
        depth[start] = steps;
    }
    let mut order: Vec<usize> = (0..joints.len()).collect();
    order.sort_by_key(|&i| depth[i]);
    Ok(order)
}
