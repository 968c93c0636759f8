//! The grasps of one bus's joints (see [`crate::grasp`]): each grasping
//! servo's torque limit set to its effort and put back when the grasp
//! ends, its press's push set from the effort, and its temperature read
//! while it grasps, lowering the effort when warm and letting go near its
//! limit.
//!
//! A write or read that fails (a servo that missed it) is tried again the
//! next cycle; only a lost port is an error. At most one joint's torque
//! limit is written and one temperature read in a cycle, so a grasp costs
//! a cycle one short exchange at most.

use servobus_driver::{Bus, Transport};
use servobus_protocol::registers::Register;

use super::tracking::Tracker;
use crate::config::BusConfig;
use crate::error::PortGone;
use crate::grasp::{
    full_effort_error, GraspEvent, DEFAULT_MAX_TEMPERATURE_C, FACTORY_P, HOLD_GAIN, HOLD_SHARE,
    HOLD_TARGET, LET_GO_BELOW_LIMIT_C, LOWER_BY, LOWER_EVERY_S, LOWEST_EFFORT, READ_EVERY_S,
    WARNING_BELOW_LIMIT_C,
};

/// One joint's grasp state.
#[derive(Debug)]
struct Joint {
    robot_index: usize,
    id: u8,
    /// The position error of its servo's whole torque, rad.
    full_error: f64,
    /// Its torque limit outside a grasp, in the register's 0.1 %: the
    /// robot file's, or what the servo held when the grasp began.
    restore: i32,
    /// Its temperature limit, degrees C.
    max_temp: f64,
    /// The effort asked (a share of the torque), while it grasps.
    asked: Option<f64>,
    /// The effort in force (lowered when warm).
    effort: f64,
    /// How far beyond where it stands its goal is held, rad (set from
    /// the load read).
    push: f64,
    /// The last load read, a share of the torque.
    load: f64,
    /// When the effort may be lowered next, s.
    next_lower: f64,
    /// It let go (too warm): backed off from the object until the grasp
    /// ends.
    let_go: bool,
    /// The torque limit the servo should hold, and whether it was written.
    limit: (i32, bool),
    /// When its temperature is read next, s.
    next_read: f64,
}

/// How close to the effort's target the load must have settled before the
/// effort is lowered (a factor of the target).
const SETTLED: f64 = 1.1;

/// The grasps of one bus.
#[derive(Debug)]
pub(crate) struct GraspWatch {
    joints: Vec<Joint>,
    torque_limit: Option<&'static Register>,
    load: Option<&'static Register>,
    temperature: Option<&'static Register>,
}

impl GraspWatch {
    /// The grasps `config`'s joints (the first is robot joint
    /// `first_joint`) may make, with the series' `torque_limit`,
    /// `present_load` and `present_temperature` registers (`None`: that
    /// part is not done).
    pub fn new(
        config: &BusConfig,
        first_joint: usize,
        torque_limit: Option<&'static Register>,
        load: Option<&'static Register>,
        temperature: Option<&'static Register>,
    ) -> Self {
        let joints = config
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let s = j.servo.as_ref();
                let p = s.and_then(|s| s.p).map_or(FACTORY_P, f64::from);
                let restore = s
                    .and_then(|s| s.torque_limit)
                    .map_or(1000, |pct| (pct * 10.0).round() as i32);
                Joint {
                    robot_index: first_joint + i,
                    id: j.id,
                    full_error: full_effort_error(p),
                    restore,
                    max_temp: s
                        .and_then(|s| s.max_temperature)
                        .map_or(DEFAULT_MAX_TEMPERATURE_C, f64::from),
                    asked: None,
                    effort: 0.0,
                    push: 0.0,
                    load: 0.0,
                    next_lower: 0.0,
                    let_go: false,
                    limit: (restore, true),
                    next_read: 0.0,
                }
            })
            .collect();
        GraspWatch {
            joints,
            torque_limit,
            load,
            temperature,
        }
    }

    /// One cycle at `t` s: takes in the efforts asked (`asked`, robot
    /// order), sets the presses' pushes in `track`, writes a torque limit
    /// that is due, reads a temperature that is due, and hands each event
    /// to `publish` (the joint in the robot's order).
    ///
    /// # Errors
    ///
    /// [`PortGone`] when the port is lost.
    pub fn update<T: Transport>(
        &mut self,
        bus: &mut Bus<T>,
        asked: &[Option<f64>],
        t: f64,
        track: &mut Tracker,
        mut publish: impl FnMut(usize, GraspEvent),
    ) -> Result<(), PortGone> {
        for (i, j) in self.joints.iter_mut().enumerate() {
            let now = asked.get(j.robot_index).copied().flatten();
            if now == j.asked {
                continue;
            }
            match now {
                Some(effort) => {
                    if j.asked.is_none() {
                        // What the servo held before: put back after.
                        if let Some(reg) = self.torque_limit {
                            if let Some((held, _)) = PortGone::check(bus.read_register(j.id, reg))?
                            {
                                j.restore = held;
                                j.limit = (held, true);
                            }
                        }
                    }
                    j.effort = effort;
                    j.push = HOLD_SHARE * effort * j.full_error;
                    j.let_go = false;
                    j.next_read = t + READ_EVERY_S;
                    publish(
                        j.robot_index,
                        GraspEvent::Closing {
                            effort_pct: 100.0 * effort,
                        },
                    );
                }
                None => publish(j.robot_index, GraspEvent::Released),
            }
            j.asked = now;
            j.set_limit(track, i);
        }
        self.write_limit(bus)?;
        self.watch(bus, t, track, &mut publish)
    }

    /// Writes the first torque limit that is due.
    fn write_limit<T: Transport>(&mut self, bus: &mut Bus<T>) -> Result<(), PortGone> {
        let Some(reg) = self.torque_limit else {
            return Ok(());
        };
        if let Some(j) = self.joints.iter_mut().find(|j| !j.limit.1) {
            if PortGone::check(bus.write_register(j.id, reg, j.limit.0))?.is_some() {
                j.limit.1 = true;
            }
        }
        Ok(())
    }

    /// Reads the load and temperature of the first grasping joint whose
    /// reading is due: a held joint's push follows its load towards
    /// [`HOLD_TARGET`] of the effort; a warm one's effort is lowered, a hot
    /// one lets go.
    fn watch<T: Transport>(
        &mut self,
        bus: &mut Bus<T>,
        t: f64,
        track: &mut Tracker,
        publish: &mut impl FnMut(usize, GraspEvent),
    ) -> Result<(), PortGone> {
        let due = self
            .joints
            .iter()
            .position(|j| j.asked.is_some() && !j.let_go && t >= j.next_read);
        let Some(i) = due else { return Ok(()) };
        let j = &mut self.joints[i];
        j.next_read = t + READ_EVERY_S;
        let held = track.joints.get(i).is_some_and(|tj| tj.press.is_some());
        if let (Some(reg), true) = (self.load, held) {
            if let Some((raw, _)) = PortGone::check(bus.read_register(j.id, reg))? {
                let load = (f64::from(raw) / 1000.0).abs();
                j.load = load;
                let wanted = HOLD_TARGET * j.effort;
                let most = j.effort * j.full_error;
                j.push = (j.push + HOLD_GAIN * (wanted - load) * j.full_error).clamp(-most, most);
                track.set_grasp(i, Some(j.push));
            }
        }
        let Some(reg) = self.temperature else {
            return Ok(());
        };
        let Some((raw, _)) = PortGone::check(bus.read_register(j.id, reg))? else {
            return Ok(());
        };
        let temperature_c = f64::from(raw);
        if temperature_c >= j.max_temp - LET_GO_BELOW_LIMIT_C {
            // Let go: the goal backs off behind where the joint stands (the
            // press bounds it from the furthest point it reached), so the
            // jaws open from the object and the servo rests.
            let depth = track
                .joints
                .get(i)
                .and_then(|tj| Some((tj.measured? - tj.press?.anchor).abs()))
                .unwrap_or(0.0);
            j.push = -(depth + j.effort * j.full_error);
            j.let_go = true;
            j.set_limit(track, i);
            publish(j.robot_index, GraspEvent::LetGo { temperature_c });
        } else if temperature_c >= j.max_temp - WARNING_BELOW_LIMIT_C
            && j.effort > LOWEST_EFFORT
            && t >= j.next_lower
            && j.load <= HOLD_TARGET * j.effort * SETTLED
        {
            // Lowered once the load has settled at the effort in force:
            // a torque limit under what the servo pushes would strain it.
            j.next_lower = t + LOWER_EVERY_S;
            j.effort = (j.effort * LOWER_BY).max(LOWEST_EFFORT);
            j.push = j.push.min(j.effort * j.full_error);
            j.set_limit(track, i);
            publish(
                j.robot_index,
                GraspEvent::Lowered {
                    effort_pct: 100.0 * j.effort,
                    temperature_c,
                },
            );
        }
        Ok(())
    }
}

impl Joint {
    /// The torque limit and the press's push for the grasp's state, `i`
    /// the joint's index in the bus.
    fn set_limit(&mut self, track: &mut Tracker, i: usize) {
        let (limit, push) = match self.asked {
            None => (self.restore, None),
            Some(_) => ((self.effort * 1000.0).round() as i32, Some(self.push)),
        };
        if limit != self.limit.0 {
            self.limit = (limit, false);
        }
        track.set_grasp(i, push);
    }
}
