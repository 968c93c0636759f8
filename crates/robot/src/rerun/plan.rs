//! A planned motion recorded before anything moves: the robot posed by
//! the path in the path's own time, each joint's commanded angle and its
//! margin to the nearer limit, the tool's or the feet's paths and the
//! workspace.

use servobus_trajectory::{JointState, Trajectory};

use ::rerun::Scalars;

use super::{Recorder, MIN_PERIOD_S};

impl Recorder {
    /// Records `trajectory` (planned for this recorder's robot, every
    /// joint in its order) sampled at `rate_hz` (at most every
    /// [`MIN_PERIOD_S`]) from its start to its end: nothing is measured,
    /// so the robot's tree is posed by the plan and no ghost follows it;
    /// `joints/<joint>/margin` is the distance to the nearer limit. The
    /// workspace is logged once.
    pub fn plan(&mut self, trajectory: &Trajectory, rate_hz: f64) {
        if let Some(space) = &mut self.space {
            space.planned();
            let logged = super::scene::workspace(
                &self.output.stream,
                &space.geometry,
                &space.tree,
                &space.tracked,
            );
            self.note(logged);
        }
        let step = (1.0 / rate_hz).max(MIN_PERIOD_S);
        let duration = trajectory.duration();
        let samples = (duration / step).ceil() as usize;
        let mut state = vec![JointState::default(); trajectory.joints()];
        let all: Vec<usize> = (0..self.joints.len()).collect();
        for k in 0..=samples {
            let t = (k as f64 * step).min(duration);
            trajectory.sample(t, &mut state);
            for (slot, s) in self.commanded.iter_mut().zip(&state) {
                *slot = Some(self.units.from_rad(s.position));
            }
            self.set_time(t);
            self.log_margins(&state);
            self.log_state(&all, false, true);
        }
    }

    /// Each joint's distance to its nearer limit at `state` (rad in), in
    /// the recorder's units.
    fn log_margins(&mut self, state: &[JointState]) {
        let stream = &self.output.stream;
        let mut logged = Ok(());
        for (series, s) in self.joints.iter().zip(state) {
            let Some((lo, hi)) = series.limits else {
                continue;
            };
            let margin = self.units.from_rad((s.position - lo).min(hi - s.position));
            logged = logged.and(stream.log(series.margin.clone(), &Scalars::single(margin)));
        }
        self.note(logged);
    }
}
