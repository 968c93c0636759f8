//! Robot geometry on nalgebra: forward and inverse kinematics.
//!
//! servobus plays motions written in joint angles; this crate gives a robot
//! its shape so that motions can also be written in space. A robot file's
//! `kinematics:` section ([`Spec`]) names, for every joint, its parent
//! (`base` or another joint), where its axis sits on the parent's link
//! (`xyz` in mm, `rpy` roll-pitch-yaw about fixed x, y, z) and the `axis`
//! it turns about; named frames (`tool`, `foot_<leg>`) are fixed to a
//! joint's link. A joint's frame is
//! `parent * translate(xyz) * rotate(rpy) * rotate(axis, angle)`, so the
//! geometry's zero pose is the robot file's zero.
//!
//! - [`Geometry`] checks a spec against the robot's joints (typed
//!   [`SpecError`]s that name the entry) and computes forward kinematics of
//!   every joint frame and named frame into a reused [`Poses`] buffer,
//!   allocating nothing.
//! - [`LegIk`] solves a 3-DOF leg (coxa yaw, femur and tibia pitch) in
//!   closed form, choosing the knee solution nearest the previous one.
//! - [`ArmIk`] solves an arm chain up to [`MAX_DOF`] joints by damped
//!   least squares inside the joint limits, from the previous solution (no
//!   elbow or wrist flips), restarting from poses spread over the joints'
//!   ranges when that leads nowhere: the position of a frame and, if
//!   asked, its pitch and roll (what a 5-DOF arm like the SO-101 can
//!   choose).
//!
//! - [`sample_line`] follows a straight tool move ([`PoseLine`]: the
//!   position along a segment, the orientation slerped) with arm angles,
//!   sampled until straight joint moves between samples keep the tool
//!   within a tolerance of the line, and refuses a line that comes near a
//!   singular pose ([`ArmIk::dexterity`]) or would flip the arm.
//! - [`Legs`] finds a legged robot's legs by their `foot_<leg>` frames and
//!   moves the body with the feet planted ([`Legs::body_move`]);
//!   [`plan_walk`] walks it with a tripod, ripple or wave [`Gait`] along
//!   segments of body velocity, stance feet fixed on the ground.
//! - [`Base`] checks a wheeled base's `base:` section ([`BaseSpec`]: three
//!   omni wheels or a differential pair) and maps a body velocity
//!   ([`Twist`], in m/s and rad/s) to wheel speeds and back, scaling all
//!   wheels together at their limits ([`Base::limited`]); [`Odometry`]
//!   integrates the measured velocity into a pose on the floor, exactly
//!   along arcs.
//!
//! - [`Urdf`] imports a robot's geometry from its URDF ([`UrdfSpec`]: the
//!   file and which URDF joint each servobus joint is), giving the same
//!   [`Spec`] a hand-typed section does, with the URDF's joint limits
//!   ([`UrdfLimits`]) and visual meshes ([`LinkVisuals`]); every refusal
//!   names the file and line ([`UrdfError`]).
//!
//! Angles are radians and lengths millimetres throughout (except a base's
//! velocities, in metres); the caller converts the robot file's angle unit.
//! Failures are typed ([`IkError`]): unreachable (with the distance
//! short), a joint limit (naming the joint), near a singularity.

mod arm;
mod base;
mod error;
mod gait;
mod geometry;
mod leg;
mod legs;
mod line;
mod spec;
mod support;
mod urdf;

pub use arm::{ArmIk, ArmTarget, MAX_DOF};
pub use base::{
    Base, BaseError, BaseKind, BaseSpec, DifferentialSpec, Odometry, Omni3Spec, OmniWheelSpec,
    Twist, MIN_SEPARATION_DEG,
};
pub use error::IkError;
pub use gait::{
    plan_walk, Gait, Walk, WalkError, WalkPlan, WalkSegment, LOW_MARGIN_MM, MAX_WALK_SAMPLES,
};
pub use geometry::{Geometry, Poses};
pub use leg::LegIk;
pub use legs::{LegError, Legs, PoseSample, FOOT_PREFIX};
pub use line::{
    sample_line, Held, LineError, LineOptions, LinePlan, LineSample, PoseLine, MAX_LINE_SAMPLES,
    TURN_WEIGHT_MM,
};
pub use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector2, Vector3};
pub use spec::{FrameSpec, JointSpec, Location, Section, Spec, SpecError, BASE};
pub use support::{move_on_feet, planar_motion, support_margin};
pub use urdf::{
    LinkVisuals, Placement, Urdf, UrdfError, UrdfFrame, UrdfLimits, UrdfPlace, UrdfSpec, Visual,
    VisualGeometry, MAX_URDF_BYTES,
};
