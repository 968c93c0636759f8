//! The extremes of each joint over a whole trajectory, from its pieces.

use super::Trajectory;

/// Extremes of one joint over the whole trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSummary {
    /// Largest speed reached.
    pub peak_velocity: f64,
    /// Largest acceleration magnitude reached.
    pub peak_acceleration: f64,
    /// Largest jerk magnitude; `f64::INFINITY` when the acceleration jumps
    /// (trapezoidal profiles of a joint without a jerk limit).
    pub peak_jerk: f64,
    /// Lowest position reached.
    pub min_position: f64,
    /// Highest position reached.
    pub max_position: f64,
}

impl Trajectory {
    /// Extremes of joint `j` over the whole trajectory (exact: from the
    /// polynomial pieces, not from samples). `None` if there is no such
    /// joint.
    pub fn joint_summary(&self, j: usize) -> Option<JointSummary> {
        if j >= self.joints() {
            return None;
        }
        let ps = self.joint_pieces(j);
        let mut s = JointSummary {
            peak_velocity: 0.0,
            peak_acceleration: 0.0,
            peak_jerk: 0.0,
            min_position: f64::INFINITY,
            max_position: f64::NEG_INFINITY,
        };
        let mut prev_acc: Option<f64> = None;
        for p in ps {
            let (lo, hi) = p.range(0);
            s.min_position = s.min_position.min(lo);
            s.max_position = s.max_position.max(hi);
            s.peak_velocity = s.peak_velocity.max(p.peak(1));
            let acc = p.peak(2);
            s.peak_acceleration = s.peak_acceleration.max(acc);
            s.peak_jerk = s.peak_jerk.max(p.peak(3));
            let a0 = p.eval_local(0.0).2;
            if let Some(a) = prev_acc {
                if (a - a0).abs() > 1e-9 * (1.0 + acc) {
                    s.peak_jerk = f64::INFINITY;
                }
            }
            prev_acc = Some(p.eval_local(p.duration()).2);
        }
        Some(s)
    }

    /// [`joint_summary`](Self::joint_summary) of every joint.
    pub fn summaries(&self) -> Vec<JointSummary> {
        (0..self.joints())
            .filter_map(|j| self.joint_summary(j))
            .collect()
    }
}
