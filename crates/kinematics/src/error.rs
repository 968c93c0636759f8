//! Why inverse kinematics found no angles.

use thiserror::Error;

/// An inverse kinematics problem with no acceptable answer, or a chain the
/// solver cannot handle.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum IkError {
    /// The target is out of reach.
    #[error("unreachable: the target is {short:.2} mm out of reach")]
    Unreachable {
        /// How far the closest pose the chain can take is from the target, mm.
        short: f64,
    },
    /// The only answers put a joint beyond one of its limits.
    #[error("joint `{joint}` would have to go to {angle:.4} rad, outside [{min:.4}, {max:.4}]")]
    JointLimit {
        /// The joint.
        joint: String,
        /// The angle it would need, radians.
        angle: f64,
        /// Its lowest angle, radians.
        min: f64,
        /// Its highest angle, radians.
        max: f64,
    },
    /// The target is at or near a singular pose (a leg stretched straight
    /// or folded flat, a foot on its coxa axis, an orientation the wrist
    /// cannot take there).
    #[error("near a singularity: {what}")]
    Singular {
        /// Which singularity.
        what: &'static str,
    },
    /// A sampled path (a straight line) would need more samples than its
    /// limit to keep to its tolerance; refused before they are made.
    #[error("the path needs more than {limit} samples to keep to its tolerance")]
    TooManySamples {
        /// The most samples allowed.
        limit: usize,
    },
    /// No named frame of that name.
    #[error("no frame `{frame}`")]
    UnknownFrame {
        /// The name asked for.
        frame: String,
    },
    /// The chain to the frame is not of a shape this solver handles.
    #[error("frame `{frame}`: {why}")]
    Unsupported {
        /// The frame.
        frame: String,
        /// What is wrong with its chain.
        why: &'static str,
    },
}
