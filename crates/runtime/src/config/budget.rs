//! Whether a control rate fits a bus, from servobus-timing's cycle plan.

use servobus_timing::{plan, Block, Plan, PlanError, Servo};

use super::BusConfig;

impl BusConfig {
    /// The servos of this bus as the timing planner sees them, in joint order.
    pub fn timing_servos(&self) -> Vec<Servo> {
        self.joints
            .iter()
            .map(|j| Servo::new(j.id, self.return_delay, j.model.series.has_sync_read()))
            .collect()
    }

    /// The plan of this bus's control cycle at `rate_hz`: goal positions
    /// written to every servo (SYNC WRITE), present positions read back (SYNC
    /// READ, or one READ per servo without it). When the full cycle does not
    /// fit, the plan reads a round-robin subset each cycle and lists what
    /// would make it fit.
    ///
    /// # Errors
    ///
    /// [`PlanError`] when not even the round-robin cycle fits (it names the
    /// cheapest change that would), or the rate is not positive.
    pub fn plan(&self, rate_hz: f64) -> Result<Plan, PlanError> {
        plan(
            &self.link(),
            &self.timing_servos(),
            Some(Block::GOAL_POSITION),
            Some(Block::PRESENT_POSITION),
            rate_hz,
        )
    }
}

/// `Ok` when `rate_hz` can run on `bus` (reading every servo each cycle, or
/// a round-robin subset the plan chose); else the planner's reason, which
/// names the cheapest change that would fit.
pub(crate) fn check_bus(bus: &BusConfig, rate_hz: f64) -> Result<(), PlanError> {
    bus.plan(rate_hz).map(|_| ())
}
