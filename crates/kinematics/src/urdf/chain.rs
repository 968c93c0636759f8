//! From a URDF's links and joints to a servobus [`Spec`]: the tree checked,
//! the mapped joints found, fixed joints composed, zeros folded in.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Unit, UnitQuaternion, Vector3};

use super::error::{UrdfError, UrdfPlace};
use super::model::{Joint, Kind, Model, Shape};
use super::{LinkVisuals, Urdf, UrdfLimits, UrdfSpec, Visual, VisualGeometry};
use crate::geometry::origin;
use crate::spec::{FrameSpec, JointSpec, Spec, BASE};

/// The import of `model` (URDF `file`) as `spec` maps it.
pub(super) fn import(
    model: &Model,
    file: &Path,
    spec: &UrdfSpec,
    angle_to_rad: f64,
) -> Result<Urdf, UrdfError> {
    let parents = tree(model, file)?;
    let mapped = mapping(model, file, spec)?;
    let at = Walk {
        model,
        parents: &parents,
        mapped: &mapped,
        root: origin(spec.origin.xyz, spec.origin.rpy.map(|a| a * angle_to_rad)),
    };
    let blocked = |what: &str, j: usize| {
        let joint = &model.joints[j];
        UrdfError::Unmapped {
            place: UrdfPlace::at(file, joint.line),
            what: what.to_owned(),
            between: joint.name.clone(),
            kind: joint.kind.word().to_owned(),
        }
    };
    let mut out = Spec::default();
    let mut limits = BTreeMap::new();
    for (i, name) in mapped.iter().enumerate() {
        let Some(name) = name else { continue };
        let joint = &model.joints[i];
        let (parent, above) = at
            .anchor(joint.parent, false)
            .map_err(|j| blocked(name, j))?;
        let zero = spec.zero.get(name).copied().unwrap_or(0.0) * angle_to_rad;
        let sign = if spec.inverted.contains(name) {
            -1.0
        } else {
            1.0
        };
        let axis = unit_axis(joint, file)?;
        let local = above * joint.origin * UnitQuaternion::from_axis_angle(&axis, zero);
        let (xyz, rpy) = parts(&local, angle_to_rad);
        let axis = (axis.into_inner() * sign).into();
        out.joints.insert(
            name.clone(),
            JointSpec {
                parent,
                xyz,
                rpy,
                axis,
            },
        );
        limits.insert(name.clone(), joint_limits(joint, file, zero, sign));
    }
    for (name, frame) in &spec.frames {
        let Some(link) = model.links.iter().position(|l| l.name == frame.link) else {
            return Err(UrdfError::MissingLink {
                place: UrdfPlace::file(file),
                frame: name.clone(),
                link: frame.link.clone(),
                known: model.links.iter().map(|l| l.name.clone()).collect(),
            });
        };
        let (parent, above) = at.anchor(link, false).map_err(|j| blocked(name, j))?;
        let on_link = origin(frame.at.xyz, frame.at.rpy.map(|a| a * angle_to_rad));
        let (xyz, rpy) = parts(&(above * on_link), angle_to_rad);
        out.frames
            .insert(name.clone(), FrameSpec { parent, xyz, rpy });
    }
    Ok(Urdf {
        file: file.to_owned(),
        spec: out,
        limits,
        links: visuals(&at, file)?,
    })
}

/// `xyz` (mm) and `rpy` (in the file's unit) of a pose.
fn parts(pose: &Isometry3<f64>, angle_to_rad: f64) -> ([f64; 3], [f64; 3]) {
    let (r, p, y) = pose.rotation.euler_angles();
    let v = pose.translation.vector;
    ([v.x, v.y, v.z], [r, p, y].map(|a| a / angle_to_rad))
}

fn unit_axis(joint: &Joint, file: &Path) -> Result<Unit<Vector3<f64>>, UrdfError> {
    let norm = joint.axis.norm();
    if !(norm.is_finite() && norm > 1e-9) {
        return Err(UrdfError::BadAxis {
            place: UrdfPlace::at(file, joint.line),
            urdf_joint: joint.name.clone(),
            axis: joint.axis.into(),
        });
    }
    Ok(Unit::new_normalize(joint.axis))
}

/// A joint's limits in the servobus angle: `zero` (rad) subtracted, the
/// direction `sign`.
fn joint_limits(joint: &Joint, file: &Path, zero: f64, sign: f64) -> UrdfLimits {
    let position = match (joint.kind, joint.lower, joint.upper) {
        (Kind::Continuous, _, _) => None,
        (_, Some(lo), Some(hi)) => {
            let (a, b) = (sign * (lo - zero), sign * (hi - zero));
            Some((a.min(b), a.max(b)))
        }
        _ => None,
    };
    UrdfLimits {
        urdf_joint: joint.name.clone(),
        place: UrdfPlace::at(file, joint.line),
        position,
        velocity: joint.velocity,
    }
}

/// Each link's parent joint, once the links are checked to form one tree.
fn tree(model: &Model, file: &Path) -> Result<Vec<Option<usize>>, UrdfError> {
    let mut parent: Vec<Option<usize>> = vec![None; model.links.len()];
    for (i, j) in model.joints.iter().enumerate() {
        if let Some(first) = parent[j.child] {
            let first = &model.joints[first];
            return Err(UrdfError::TwoParents {
                place: UrdfPlace::at(file, j.line),
                link: model.links[j.child].name.clone(),
                first: first.name.clone(),
                first_line: first.line,
                second: j.name.clone(),
            });
        }
        parent[j.child] = Some(i);
    }
    for start in 0..model.links.len() {
        let mut at = start;
        let mut steps = 0;
        while let Some(j) = parent[at] {
            if steps > model.joints.len() {
                let joint = &model.joints[j];
                return Err(UrdfError::Loop {
                    place: UrdfPlace::at(file, joint.line),
                    joint: joint.name.clone(),
                });
            }
            steps += 1;
            at = model.joints[j].parent;
        }
    }
    let roots: Vec<usize> = (0..model.links.len())
        .filter(|&l| parent[l].is_none())
        .collect();
    if let [_, second, ..] = roots.as_slice() {
        let names: Vec<&str> = roots
            .iter()
            .map(|&l| model.links[l].name.as_str())
            .collect();
        return Err(UrdfError::Malformed {
            place: UrdfPlace::at(file, model.links[*second].line),
            reason: format!(
                "{} links have no parent joint ({}): a robot has one root link",
                roots.len(),
                names.join(", ")
            ),
        });
    }
    if roots.is_empty() {
        return Err(UrdfError::Malformed {
            place: UrdfPlace::file(file),
            reason: "the file has no links".into(),
        });
    }
    Ok(parent)
}

/// The servobus joint each URDF joint is mapped to, checked: every mapped
/// joint exists, once, and turns; `zero` and `inverted` name mapped joints.
fn mapping(model: &Model, file: &Path, spec: &UrdfSpec) -> Result<Vec<Option<String>>, UrdfError> {
    let mut mapped: Vec<Option<String>> = vec![None; model.joints.len()];
    for (name, urdf) in &spec.joints {
        let Some(i) = model.joints.iter().position(|j| &j.name == urdf) else {
            let known = model.joints.iter();
            return Err(UrdfError::MissingJoint {
                place: UrdfPlace::file(file),
                joint: name.clone(),
                urdf_joint: urdf.clone(),
                known: known
                    .map(|j| format!("{} ({})", j.name, j.kind.word()))
                    .collect(),
            });
        };
        let j = &model.joints[i];
        let place = UrdfPlace::at(file, j.line);
        let (joint, urdf_joint) = (name.clone(), urdf.clone());
        match j.kind {
            Kind::Revolute | Kind::Continuous => {}
            Kind::Fixed => {
                return Err(UrdfError::Fixed {
                    place,
                    joint,
                    urdf_joint,
                })
            }
            kind => {
                let kind = kind.word().to_owned();
                return Err(UrdfError::Undrivable {
                    place,
                    joint,
                    urdf_joint,
                    kind,
                });
            }
        }
        if let Some(first) = &mapped[i] {
            let (first, second) = (first.clone(), name.clone());
            return Err(UrdfError::MappedTwice {
                place,
                urdf_joint,
                first,
                second,
            });
        }
        mapped[i] = Some(name.clone());
    }
    for (key, names) in [
        ("zero", spec.zero.keys().collect::<Vec<_>>()),
        ("inverted", spec.inverted.iter().collect()),
    ] {
        if let Some(joint) = names.into_iter().find(|n| !spec.joints.contains_key(*n)) {
            return Err(UrdfError::UnknownEntry {
                key,
                joint: joint.clone(),
            });
        }
    }
    if let Some((joint, &value)) = spec.zero.iter().find(|(_, v)| !v.is_finite()) {
        return Err(UrdfError::NotFinite {
            joint: joint.clone(),
            value,
        });
    }
    Ok(mapped)
}

/// Finds the servobus frame that carries a link.
struct Walk<'m> {
    model: &'m Model,
    parents: &'m [Option<usize>],
    mapped: &'m [Option<String>],
    /// The root link in the base frame.
    root: Isometry3<f64>,
}

impl Walk<'_> {
    /// The servobus joint (or `base`) whose frame carries `link`, and the
    /// link's frame in it: the joints between composed at angle 0. Only
    /// fixed joints may be passed unless `lenient`; otherwise the first
    /// other joint is the error.
    fn anchor(&self, link: usize, lenient: bool) -> Result<(String, Isometry3<f64>), usize> {
        let mut pose = Isometry3::identity();
        let mut at = link;
        loop {
            let Some(j) = self.parents[at] else {
                return Ok((BASE.to_owned(), self.root * pose));
            };
            if let Some(name) = &self.mapped[j] {
                return Ok((name.clone(), pose));
            }
            let joint = &self.model.joints[j];
            if joint.kind != Kind::Fixed && !lenient {
                return Err(j);
            }
            pose = joint.origin * pose;
            at = joint.parent;
        }
    }
}

/// Every link with visuals, posed on its servobus frame; mesh files
/// resolved relative to `file`'s directory.
fn visuals(at: &Walk<'_>, file: &Path) -> Result<Vec<LinkVisuals>, UrdfError> {
    let dir = file.parent().unwrap_or(Path::new(""));
    let mut out = Vec::new();
    for (i, link) in at.model.links.iter().enumerate() {
        if link.visuals.is_empty() {
            continue;
        }
        let Ok((parent, pose)) = at.anchor(i, true) else {
            continue;
        };
        let mut visuals = Vec::with_capacity(link.visuals.len());
        for v in &link.visuals {
            let geometry = match &v.shape {
                Shape::Mesh { filename, scale } => VisualGeometry::Mesh {
                    path: mesh_path(filename, dir, &UrdfPlace::at(file, v.line))?,
                    scale: *scale,
                },
                Shape::Box(size) => VisualGeometry::Box { size: *size },
                Shape::Cylinder { radius, length } => VisualGeometry::Cylinder {
                    radius: *radius,
                    length: *length,
                },
                Shape::Sphere(radius) => VisualGeometry::Sphere { radius: *radius },
            };
            visuals.push(Visual {
                geometry,
                origin: v.origin,
                color: v.color,
            });
        }
        out.push(LinkVisuals {
            link: link.name.clone(),
            parent,
            origin: pose,
            visuals,
        });
    }
    Ok(out)
}

/// A mesh's file: relative to `dir` (or absolute, or `file://`), refused
/// when it names a ROS package or is not there.
fn mesh_path(filename: &str, dir: &Path, place: &UrdfPlace) -> Result<PathBuf, UrdfError> {
    if filename.starts_with("package://") {
        return Err(UrdfError::PackageUri {
            place: place.clone(),
            filename: filename.to_owned(),
        });
    }
    let path = dir.join(filename.strip_prefix("file://").unwrap_or(filename));
    if !path.is_file() {
        return Err(UrdfError::MeshNotFound {
            place: place.clone(),
            filename: filename.to_owned(),
            path,
        });
    }
    Ok(path)
}
