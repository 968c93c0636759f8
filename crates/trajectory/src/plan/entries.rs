//! The keyframe list as the planner walks it: checked, then expanded over
//! the repetitions with the time origin of every `at`.

use super::{Keyframe, PlanOptions};
use crate::error::PlanError;
use crate::limits::{check_keyframe, validate_all};
use crate::spline::TimedShape;
use crate::JointLimits;

/// A keyframe of the expanded (repeated) list.
pub(super) struct Entry<'a> {
    /// The keyframe's positions.
    pub pos: &'a [f64],
    /// Its time from the latest rebase, if timed.
    pub at: Option<f64>,
    /// The shape of the timed segment arriving here.
    pub shape: TimedShape,
    /// Its index in the caller's keyframe list.
    pub index: usize,
    /// The repetition it belongs to.
    pub cycle: usize,
    /// This entry's arrival is the time origin of the following `at`s.
    pub rebase: bool,
    /// Untimed motion must stop here (a cycle start followed by timed
    /// keyframes: their times depend on this arrival).
    pub boundary: bool,
}

/// Refuses limits, keyframes or options [`plan`](super::plan) cannot use.
pub(super) fn validate(
    limits: &[JointLimits],
    keyframes: &[Keyframe],
    options: &PlanOptions,
) -> Result<(), PlanError> {
    validate_all(limits)?;
    if keyframes.is_empty() {
        return Err(PlanError::NoKeyframes);
    }
    if options.repeat == 0 {
        return Err(PlanError::ZeroRepeat);
    }
    for (k, kf) in keyframes.iter().enumerate() {
        if kf.positions.len() != limits.len() {
            return Err(PlanError::WrongJointCount {
                keyframe: k,
                expected: limits.len(),
                actual: kf.positions.len(),
            });
        }
        check_keyframe(k, &kf.positions, limits)?;
        if let Some(at) = kf.at {
            if !at.is_finite() {
                return Err(PlanError::NotFinite {
                    keyframe: k,
                    joint: 0,
                });
            }
        }
    }
    if let Some(at) = keyframes[0].at {
        if at != 0.0 {
            return Err(PlanError::FirstKeyframeTime { at });
        }
    }
    Ok(())
}

/// The keyframe list played `options.repeat` times, each entry marked with
/// where its times count from and where untimed motion must stop.
pub(super) fn expand<'a>(keyframes: &'a [Keyframe], options: &PlanOptions) -> Vec<Entry<'a>> {
    let timed_in_cycle = keyframes[1..].iter().any(|k| k.at.is_some());
    let closed =
        keyframes.len() > 1 && keyframes[0].positions == keyframes[keyframes.len() - 1].positions;
    let mut e = Vec::with_capacity(keyframes.len() * options.repeat as usize);
    for cycle in 0..options.repeat as usize {
        for (index, kf) in keyframes.iter().enumerate() {
            let shape = kf.shape.unwrap_or(options.shape);
            if index == 0 {
                if cycle == 0 {
                    e.push(Entry {
                        pos: &kf.positions,
                        at: Some(0.0),
                        shape,
                        index,
                        cycle,
                        rebase: true,
                        boundary: false,
                    });
                } else if closed {
                    // The previous cycle ended here: that arrival is this
                    // cycle's origin.
                    if let Some(last) = e.last_mut() {
                        last.rebase = true;
                        last.boundary |= timed_in_cycle && last.at.is_none();
                    }
                } else {
                    e.push(Entry {
                        pos: &kf.positions,
                        at: None,
                        shape,
                        index,
                        cycle,
                        rebase: true,
                        boundary: timed_in_cycle,
                    });
                }
            } else {
                e.push(Entry {
                    pos: &kf.positions,
                    at: kf.at,
                    shape,
                    index,
                    cycle,
                    rebase: false,
                    boundary: false,
                });
            }
        }
    }
    e
}
