//! A bus's telemetry: one sample per cycle (several for a bus of more than
//! [`SAMPLE_JOINTS`] joints), sent without blocking or allocating; a full
//! channel drops the sample and counts it.
//!
//! A wheel joint's sample is of speeds (units/s): commanded, measured and
//! velocity are its commanded and present speed, and its error is
//! commanded - measured (see [`JointSample`]).

use std::time::Duration;

use crossbeam_channel::Sender;

use super::goals::JointGoal;
use super::tracking::{JointTrack, Tracker};
use super::wheels::{WheelGoal, WheelWriter};
use crate::config::Units;
use crate::telemetry::{CycleSample, JointSample, Telemetry, SAMPLE_JOINTS};

/// See the module documentation.
#[derive(Debug)]
pub(crate) struct Publisher {
    tx: Option<Sender<Telemetry>>,
    /// The bus's sample, filled anew every cycle (no allocation).
    sample: CycleSample,
    /// Messages dropped because the channel was full.
    pub dropped: u64,
}

/// The cycle a sample describes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SampleTiming {
    pub cycle: u64,
    pub time_s: f64,
    pub lateness: Duration,
    pub busy: Duration,
    pub skipped: u64,
    /// The lead in use, s.
    pub lead: f64,
    /// The time of the sample, on the bus's clock.
    pub now: Duration,
}

impl Publisher {
    /// The publisher of bus `index` (silent without a channel).
    pub fn new(index: usize, tx: Option<Sender<Telemetry>>) -> Self {
        Publisher {
            tx,
            sample: CycleSample::new(index, 0, 0.0),
            dropped: 0,
        }
    }

    /// Sends a message that is not a cycle sample (fault, rejection).
    pub fn publish(&mut self, message: Telemetry) {
        if let Some(tx) = &self.tx {
            if tx.try_send(message).is_err() {
                self.dropped += 1;
            }
        }
    }

    /// Sends the cycle's samples of `goals` and `track`, angles in `units`.
    pub fn cycle(
        &mut self,
        s: SampleTiming,
        goals: &[JointGoal],
        wheels: &WheelWriter,
        track: &Tracker,
        u: Units,
    ) {
        let Some(tx) = &self.tx else { return };
        let mut sample = self.sample;
        sample.cycle = s.cycle;
        sample.time_s = s.time_s;
        sample.lateness = s.lateness;
        sample.busy = s.busy;
        sample.skipped = s.skipped;
        sample.lead = Duration::from_secs_f64(s.lead.max(0.0));
        let joints = goals.iter().zip(&track.joints);
        for start in (0..goals.len()).step_by(SAMPLE_JOINTS) {
            sample.clear_joints();
            for (i, (g, j)) in joints.clone().enumerate().skip(start).take(SAMPLE_JOINTS) {
                let age = s.now.saturating_sub(j.measured_at);
                if let Some(w) = wheels.of_joint(i) {
                    sample.push(wheel_sample(w, j, age, track, u));
                    continue;
                }
                sample.push(JointSample {
                    joint: j.robot_index,
                    commanded: u.from_rad(g.rad),
                    planned: u.from_rad(j.planned),
                    measured: j.measured.map(|m| u.from_rad(m)),
                    error: u.from_rad(j.error),
                    velocity: u.from_rad(j.velocity),
                    feedback_age: age,
                    measured_at: j.measured_at,
                    stale: age > track.stale_after,
                    clamped: g.clamped,
                    flags: j.flags,
                    missing_reads: j.missing,
                    stalled: j.held,
                });
            }
            if tx.try_send(Telemetry::Cycle(sample)).is_err() {
                self.dropped += 1;
            }
        }
    }
}

/// A wheel's sample: speeds, units/s.
fn wheel_sample(
    w: &WheelGoal,
    j: &JointTrack,
    age: Duration,
    track: &Tracker,
    u: Units,
) -> JointSample {
    let measured = j.speed;
    JointSample {
        joint: j.robot_index,
        commanded: u.from_rad(w.speed),
        planned: u.from_rad(w.target),
        measured: measured.map(|m| u.from_rad(m)),
        error: measured.map_or(0.0, |m| u.from_rad(w.speed - m)),
        velocity: u.from_rad(measured.unwrap_or(0.0)),
        feedback_age: age,
        measured_at: j.measured_at,
        stale: age > track.stale_after,
        clamped: false,
        flags: j.flags,
        missing_reads: j.missing,
        stalled: false,
    }
}
