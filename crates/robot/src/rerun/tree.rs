//! The robot's joints as a tree of frames, read off its geometry: each
//! joint's parent, its origin on the parent's link and its axis, and the
//! named frames on each link; with the entity path of every joint in the
//! recording (`robot/<joint>/<child joint>/...`).

use std::collections::HashSet;

use servobus_kinematics::{Geometry, Isometry3, Poses, UnitQuaternion, Vector3};

/// A joint's angle while its tree is read off the geometry, rad: turning
/// one joint by it moves exactly the joints it carries.
const PROBE_RAD: f64 = 1.0;

/// How far a probed pose must move to count as moved (mm, or rad of
/// turn): far above rounding, far below any joint's effect.
const MOVED: f64 = 1e-9;

/// One joint of the tree.
#[derive(Debug, Clone)]
pub(super) struct Joint {
    /// The joint's name.
    pub(super) name: String,
    /// The joint that carries it (robot order); `None`: the base.
    pub(super) parent: Option<usize>,
    /// Its frame on the parent's link at angle 0, mm.
    pub(super) origin: Isometry3<f64>,
    /// The axis it turns about, in its own frame: a unit vector.
    pub(super) axis: Vector3<f64>,
    /// The names from the tree's root to it: its ancestors, then itself.
    pub(super) chain: Vec<String>,
}

/// A named frame (`tool`, `foot_<leg>`) on a link.
#[derive(Debug, Clone)]
pub(super) struct Frame {
    /// The joint whose link carries it; `None`: the base.
    pub(super) parent: Option<usize>,
    /// Its pose on that link, mm.
    pub(super) origin: Isometry3<f64>,
}

/// The joints and named frames of a geometry as a tree (frames in the
/// geometry's order).
#[derive(Debug, Clone)]
pub(super) struct Tree {
    pub(super) joints: Vec<Joint>,
    pub(super) frames: Vec<Frame>,
}

impl Tree {
    /// The tree of `geometry`, found by turning one joint at a time: the
    /// joints a turn moves are those it carries, and each joint's parent
    /// is the deepest joint that moves it.
    pub(super) fn of(geometry: &Geometry) -> Tree {
        let n = geometry.joint_count();
        let mut poses = Poses::new(geometry);
        let mut q = vec![0.0; n];
        geometry.forward(&q, &mut poses);
        let zero: Vec<Isometry3<f64>> = (0..n).map(|i| pose(&poses, i)).collect();
        let frames_zero: Vec<Isometry3<f64>> = (0..geometry.frame_count())
            .map(|k| poses.frame(k).copied().unwrap_or_else(Isometry3::identity))
            .collect();
        // carries[i][j]: joint i's turn moves joint j.
        let mut carries = vec![vec![false; n]; n];
        let mut axes = Vec::with_capacity(n);
        for i in 0..n {
            q[i] = PROBE_RAD;
            geometry.forward(&q, &mut poses);
            q[i] = 0.0;
            for (j, moved) in carries[i].iter_mut().enumerate() {
                *moved = j != i && differs(&zero[j], &pose(&poses, j));
            }
            let turn = zero[i].rotation.inverse() * pose(&poses, i).rotation;
            let axis = turn.scaled_axis();
            let length = axis.norm();
            axes.push(if length > MOVED {
                axis / length
            } else {
                Vector3::z()
            });
        }
        let depth: Vec<usize> = (0..n)
            .map(|j| (0..n).filter(|&i| carries[i][j]).count())
            .collect();
        let parent_of = |j: usize| (0..n).filter(|&i| carries[i][j]).max_by_key(|&i| depth[i]);
        let mut joints: Vec<Joint> = (0..n)
            .map(|j| {
                let parent = parent_of(j);
                let base = parent.map_or_else(Isometry3::identity, |p| zero[p]);
                Joint {
                    name: geometry.joint_name(j).unwrap_or("?").to_owned(),
                    parent,
                    origin: base.inverse() * zero[j],
                    axis: axes[j],
                    chain: Vec::new(),
                }
            })
            .collect();
        for j in 0..n {
            joints[j].chain = chain(&joints, j);
        }
        let frames = (0..geometry.frame_count())
            .map(|k| {
                let parent = geometry.chain_to_frame(k).last().copied();
                let base = parent.map_or_else(Isometry3::identity, |p| zero[p]);
                Frame {
                    parent,
                    origin: base.inverse() * frames_zero[k],
                }
            })
            .collect();
        Tree { joints, frames }
    }

    /// Joint `i`'s frame on its parent's link at angle `q` (rad): its
    /// origin, then the turn about its axis.
    pub(super) fn local(&self, i: usize, q: f64) -> Isometry3<f64> {
        let j = &self.joints[i];
        j.origin * UnitQuaternion::from_scaled_axis(j.axis * q)
    }

    /// The joints and frames carried by joint `parent` (`None`: the base),
    /// each with its origin on that link, mm.
    pub(super) fn children(&self, parent: Option<usize>) -> Vec<Vector3<f64>> {
        let joints = self.joints.iter().filter(|j| j.parent == parent);
        let frames = self.frames.iter().filter(|f| f.parent == parent);
        joints
            .map(|j| j.origin.translation.vector)
            .chain(frames.map(|f| f.origin.translation.vector))
            .collect()
    }

    /// A name for something drawn beside the joints (`want`, else `want`
    /// with underscores after it) that no joint has: an entity of its own
    /// that no joint's can be.
    pub(super) fn free_name(&self, want: &str) -> String {
        let taken: HashSet<&str> = self.joints.iter().map(|j| j.name.as_str()).collect();
        let mut name = want.to_owned();
        while taken.contains(name.as_str()) {
            name.push('_');
        }
        name
    }
}

/// Joint `i`'s pose in `poses` (identity for a joint it lacks).
fn pose(poses: &Poses, i: usize) -> Isometry3<f64> {
    poses.joint(i).copied().unwrap_or_else(Isometry3::identity)
}

/// Whether `a` and `b` are different poses.
fn differs(a: &Isometry3<f64>, b: &Isometry3<f64>) -> bool {
    (a.translation.vector - b.translation.vector).norm() > MOVED
        || a.rotation.angle_to(&b.rotation) > MOVED
}

/// The names from the root to joint `i`: its ancestors, then itself.
fn chain(joints: &[Joint], i: usize) -> Vec<String> {
    let mut names = Vec::new();
    let mut at = Some(i);
    // A tree has no cycle; the count bounds a walk all the same.
    while let (Some(j), true) = (at, names.len() <= joints.len()) {
        names.push(joints[j].name.clone());
        at = joints[j].parent;
    }
    names.reverse();
    names
}

/// An isometry in metres, single precision, as Rerun takes it: the
/// translation (mm in) and the rotation as x, y, z, w.
pub(super) fn to_rerun(pose: &Isometry3<f64>) -> ([f32; 3], [f32; 4]) {
    let t = pose.translation.vector;
    let q = pose.rotation.quaternion();
    (
        [mm_to_m(t.x), mm_to_m(t.y), mm_to_m(t.z)],
        [q.i as f32, q.j as f32, q.k as f32, q.w as f32],
    )
}

/// A length in mm as metres, single precision.
pub(super) fn mm_to_m(mm: f64) -> f32 {
    (mm / 1000.0) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn so101_tree() -> (Geometry, Tree) {
        let robot = crate::Robot::open("so101").expect("built-in robot");
        let geometry = robot.config().geometry().expect("geometry");
        let tree = Tree::of(&geometry);
        (geometry, tree)
    }

    #[test]
    fn the_tree_composed_along_each_chain_is_the_geometry_s_forward_kinematics() {
        let (geometry, tree) = so101_tree();
        let q = [0.3, -1.1, 0.9, 0.4, -2.0, 0.2];
        let mut poses = Poses::new(&geometry);
        geometry.forward(&q, &mut poses);
        for (i, joint) in tree.joints.iter().enumerate() {
            let mut composed = Isometry3::identity();
            let mut at = Some(i);
            while let Some(j) = at {
                composed = tree.local(j, q[j]) * composed;
                at = tree.joints[j].parent;
            }
            let fk = pose(&poses, i);
            let gap = (composed.translation.vector - fk.translation.vector).norm();
            assert!(gap < 1e-9, "{}: {gap} mm", joint.name);
            assert!(composed.rotation.angle_to(&fk.rotation) < 1e-9);
        }
    }

    #[test]
    fn an_arm_is_one_chain_from_the_base() {
        let (geometry, tree) = so101_tree();
        let names: Vec<&str> = tree.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(tree.joints[0].parent, None);
        for (i, joint) in tree.joints.iter().enumerate().skip(1) {
            assert_eq!(joint.parent, Some(i - 1), "{}", joint.name);
        }
        assert_eq!(tree.joints[5].chain, names);
        let tool = &tree.frames[geometry.frame_index("tool").expect("tool")];
        assert_eq!(tool.parent, Some(4), "the tool is on the wrist roll's link");
    }

    #[test]
    fn a_hexapod_has_six_legs_of_three() {
        let robot = crate::Robot::open("hexapod").expect("built-in robot");
        let tree = Tree::of(&robot.config().geometry().expect("geometry"));
        let roots = tree.joints.iter().filter(|j| j.parent.is_none()).count();
        assert_eq!(roots, 6);
        assert!(tree.joints.iter().all(|j| j.chain.len() <= 3));
        assert_eq!(tree.children(None).len(), 6);
    }

    #[test]
    fn names_beside_the_joints_are_none_of_theirs() {
        let (_, tree) = so101_tree();
        assert_eq!(tree.free_name("shape"), "shape");
        assert_eq!(tree.free_name("gripper"), "gripper_");
    }
}
