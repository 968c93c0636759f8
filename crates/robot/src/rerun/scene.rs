//! What a recording holds that never moves: the view's up axis, the
//! robot's links on their joints (the URDF's visuals, or shapes drawn
//! from the kinematics), the ghost's bones, and a plan's workspace.

use std::f64::consts::PI;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use servobus_kinematics::{
    Geometry, Isometry3, LinkVisuals, Point3, Poses, UnitQuaternion, Urdf, Vector3, VisualGeometry,
};

use ::rerun::{
    AsComponents, Asset3D, Boxes3D, Cylinders3D, Ellipsoids3D, EntityPath, EntityPathPart,
    FillMode, LineStrips3D, Points3D, Quaternion, RecordingStream, Rgba32, Scale3D, TextLog,
    Transform3D, ViewCoordinates,
};

use super::tree::{mm_to_m, to_rerun, Tree};

/// The root of the robot's tree, posed by the measured angles.
pub(super) const ROBOT: &str = "robot";

/// The root of the ghost's tree, posed by the commanded angles.
pub(super) const GHOST: &str = "ghost";

/// The colour of links without one of their own, and of the shapes drawn
/// from the kinematics.
const LINK_COLOUR: [u8; 4] = [200, 205, 215, 255];

/// The ghost's colour: translucent orange.
const GHOST_COLOUR: [u8; 4] = [255, 140, 0, 150];

/// Drawn from the kinematics: a joint's cylinder along its axis (radius,
/// length) and the radius of the bones to its children, mm.
const JOINT_RADIUS_MM: f64 = 12.0;
const JOINT_LENGTH_MM: f64 = 30.0;
const BONE_RADIUS_MM: f64 = 4.0;

/// How many random poses within the limits a plan's workspace shows.
pub(super) const WORKSPACE_POSES: usize = 1500;

/// Every entity path of the recording that belongs to a joint.
#[derive(Debug, Clone)]
pub(super) struct Paths {
    /// Per joint, its entity in the robot's tree.
    pub(super) robot: Vec<EntityPath>,
    /// Per joint, its entity in the ghost's tree.
    pub(super) ghost: Vec<EntityPath>,
}

/// The entity `root/<names...>`.
pub(super) fn path<'a>(root: &'a str, names: impl IntoIterator<Item = &'a str>) -> EntityPath {
    let parts = std::iter::once(root)
        .chain(names)
        .map(EntityPathPart::new)
        .collect();
    EntityPath::new(parts)
}

impl Paths {
    /// The paths of `tree`'s joints under [`ROBOT`] and [`GHOST`].
    pub(super) fn of(tree: &Tree) -> Paths {
        let under = |root: &str| {
            tree.joints
                .iter()
                .map(|j| path(root, j.chain.iter().map(String::as_str)))
                .collect()
        };
        Paths {
            robot: under(ROBOT),
            ghost: under(GHOST),
        }
    }

    /// The entity of joint `parent` (`None`: the root) in the robot's
    /// (`ghost`: the ghost's) tree, with `child` under it.
    fn under(&self, parent: Option<usize>, ghost: bool, child: &str) -> EntityPath {
        let (root, joints) = if ghost {
            (GHOST, &self.ghost)
        } else {
            (ROBOT, &self.robot)
        };
        let base = parent
            .and_then(|p| joints.get(p).cloned())
            .unwrap_or_else(|| path(root, []));
        base.join(&EntityPath::new(vec![EntityPathPart::new(child)]))
    }
}

/// A colour from RGBA.
fn colour([r, g, b, a]: [u8; 4]) -> Rgba32 {
    Rgba32::from_unmultiplied_rgba(r, g, b, a)
}

/// A pose as Rerun's transform, with a `scale` applied first.
fn transform(pose: &Isometry3<f64>, scale: [f64; 3]) -> Transform3D {
    let (t, q) = to_rerun(pose);
    Transform3D::from_translation_rotation_scale(
        t,
        Quaternion::from_xyzw(q),
        Scale3D::from(scale.map(|s| s as f32)),
    )
}

/// Logs what never moves: the world's up axis (+z) and the robot's links
/// (the URDF's visuals when it has one, else shapes from its kinematics).
/// Visual files that cannot be read are said as events. The ghost's bones
/// come with its first pose ([`ghost`]): a plan has none.
pub(super) fn log(
    stream: &RecordingStream,
    tree: &Tree,
    urdf: Option<&Urdf>,
    paths: &Paths,
) -> ::rerun::RecordingStreamResult<()> {
    stream.log_static("/", &ViewCoordinates::RIGHT_HAND_Z_UP())?;
    match urdf {
        Some(urdf) => {
            for link in &urdf.links {
                link_visuals(stream, tree, paths, link)?;
            }
        }
        None => shapes(stream, tree, paths, false)?,
    }
    Ok(())
}

/// Logs the ghost's bones, translucent, on its tree.
pub(super) fn ghost(
    stream: &RecordingStream,
    tree: &Tree,
    paths: &Paths,
) -> ::rerun::RecordingStreamResult<()> {
    shapes(stream, tree, paths, true)
}

/// One URDF link's visuals, on the joint that carries it.
fn link_visuals(
    stream: &RecordingStream,
    tree: &Tree,
    paths: &Paths,
    link: &LinkVisuals,
) -> ::rerun::RecordingStreamResult<()> {
    let parent = tree.joints.iter().position(|j| j.name == link.parent);
    let at = paths.under(parent, false, &tree.free_name(&link.link));
    stream.log_static(at.clone(), &transform(&link.origin, [1.0; 3]))?;
    for (k, visual) in link.visuals.iter().enumerate() {
        let entity = at.join(&EntityPath::new(vec![EntityPathPart::new(format!(
            "visual_{k}"
        ))]));
        let tint = colour(visual.color.map_or(LINK_COLOUR, |c| {
            c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
        }));
        let (scale, shape): ([f64; 3], Box<dyn AsComponents>) = match &visual.geometry {
            VisualGeometry::Mesh { path, scale } => match Asset3D::from_file_path(path) {
                Ok(asset) => (*scale, Box::new(asset.with_albedo_factor(tint))),
                Err(e) => {
                    let text = format!("the mesh {} of link `{}`: {e}", path.display(), link.link);
                    stream.log_static(entity, &TextLog::new(text).with_level("WARN"))?;
                    continue;
                }
            },
            VisualGeometry::Box { size } => (
                [1.0; 3],
                Box::new(
                    Boxes3D::from_sizes([size.map(mm_to_m)])
                        .with_colors([tint])
                        .with_fill_mode(FillMode::Solid),
                ),
            ),
            VisualGeometry::Cylinder { radius, length } => (
                [1.0; 3],
                Box::new(
                    Cylinders3D::from_lengths_and_radii([mm_to_m(*length)], [mm_to_m(*radius)])
                        .with_colors([tint])
                        .with_fill_mode(FillMode::Solid),
                ),
            ),
            VisualGeometry::Sphere { radius } => (
                [1.0; 3],
                Box::new(
                    Ellipsoids3D::from_radii([mm_to_m(*radius)])
                        .with_colors([tint])
                        .with_fill_mode(FillMode::Solid),
                ),
            ),
        };
        stream.log_static(entity.clone(), &transform(&visual.origin, scale))?;
        stream.log_static(entity, shape.as_ref())?;
    }
    Ok(())
}

/// Shapes from the kinematics on every joint of the robot's tree (a
/// cylinder along the axis, bones to the joints and frames it carries,
/// the body's outline on the base), or the ghost's bones and outline.
fn shapes(
    stream: &RecordingStream,
    tree: &Tree,
    paths: &Paths,
    ghost: bool,
) -> ::rerun::RecordingStreamResult<()> {
    let (tint, name) = if ghost {
        (colour(GHOST_COLOUR), tree.free_name("bones"))
    } else {
        (colour(LINK_COLOUR), tree.free_name("shape"))
    };
    let bones = |parent: Option<usize>| {
        let strips: Vec<Vec<[f32; 3]>> = tree
            .children(parent)
            .iter()
            .map(|c| vec![[0.0; 3], [c.x, c.y, c.z].map(mm_to_m)])
            .collect();
        LineStrips3D::new(strips)
            .with_colors([tint])
            .with_radii([mm_to_m(BONE_RADIUS_MM)])
    };
    for (i, joint) in tree.joints.iter().enumerate() {
        let at = paths.under(Some(i), ghost, &name);
        stream.log_static(at.clone(), &bones(Some(i)))?;
        if !ghost {
            // A cylinder stands along z; an axis along -z turns it over.
            let turn = UnitQuaternion::rotation_between(&Vector3::z(), &joint.axis)
                .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI));
            let (_, q) = to_rerun(&Isometry3::from_parts(Default::default(), turn));
            let cylinder = Cylinders3D::from_lengths_and_radii(
                [mm_to_m(JOINT_LENGTH_MM)],
                [mm_to_m(JOINT_RADIUS_MM)],
            )
            .with_quaternions([Quaternion::from_xyzw(q)])
            .with_colors([tint])
            .with_fill_mode(FillMode::Solid);
            stream.log_static(at, &cylinder)?;
        }
    }
    let body = paths.under(None, ghost, &tree.free_name("body"));
    stream.log_static(body.clone(), &bones(None))?;
    let mut outline: Vec<Vector3<f64>> = tree.children(None);
    if outline.len() >= 3 {
        let centre = outline.iter().sum::<Vector3<f64>>() / outline.len() as f64;
        outline.sort_by(|a, b| {
            let angle = |v: &Vector3<f64>| (v.y - centre.y).atan2(v.x - centre.x);
            angle(a).total_cmp(&angle(b))
        });
        outline.push(outline[0]);
        let line: Vec<[f32; 3]> = outline
            .iter()
            .map(|v| [v.x, v.y, v.z].map(mm_to_m))
            .collect();
        let strip = LineStrips3D::new([line])
            .with_colors([tint])
            .with_radii([mm_to_m(BONE_RADIUS_MM)]);
        stream.log_static(body.join(&path("outline", [])), &strip)?;
    }
    Ok(())
}

/// Logs a plan's workspace under the robot's base (so that it walks with
/// a legged body): where the tool (or each foot) gets to over
/// [`WORKSPACE_POSES`] random poses within the joint limits, as points.
pub(super) fn workspace(
    stream: &RecordingStream,
    geometry: &Geometry,
    tree: &Tree,
    tracked: &[usize],
) -> ::rerun::RecordingStreamResult<()> {
    if tracked.is_empty() {
        return Ok(());
    }
    // A fixed seed: the same plan shows the same points.
    let mut rng = SmallRng::seed_from_u64(0x5e7b_0b05);
    let mut poses = Poses::new(geometry);
    let mut q = vec![0.0; geometry.joint_count()];
    let mut points: Vec<[f32; 3]> = Vec::with_capacity(WORKSPACE_POSES * tracked.len());
    for _ in 0..WORKSPACE_POSES {
        for (i, v) in q.iter_mut().enumerate() {
            let (lo, hi) = geometry.limits(i).unwrap_or((0.0, 0.0));
            let (lo, hi) = (lo.max(-std::f64::consts::PI), hi.min(std::f64::consts::PI));
            *v = if hi > lo { rng.gen_range(lo..=hi) } else { lo };
        }
        geometry.forward(&q, &mut poses);
        for &f in tracked {
            let p = poses
                .frame(f)
                .map_or_else(Point3::origin, |p| Point3::from(p.translation.vector));
            points.push([p.x, p.y, p.z].map(mm_to_m));
        }
    }
    let at = path(ROBOT, [tree.free_name("workspace").as_str()]);
    let cloud = Points3D::new(points)
        .with_radii([0.0015f32])
        .with_colors([colour([90, 160, 255, 60])]);
    stream.log_static(at, &cloud)
}
