//! Writing goals: each joint's angle clamped to its limits and rounded to a
//! tick inside them, encoded once into a SYNC WRITE block that is reused
//! every cycle.
//!
//! Wheel joints get no goal position: their entry here only keeps the
//! bus's joints in step with tracking (see `wheels` for their goal
//! speeds), and the block carries the position joints alone. A bus of
//! wheels alone sends no goal position frame.

use servobus_driver::{Bus, BusError, Transport};
use servobus_protocol::registers::{addr, ByteOrder, Register};
use servobus_trajectory::JointState;

use super::tracking::Press;
use crate::config::{BusConfig, JointConfig, JointMap, Units};
use crate::error::PortGone;

/// One joint's goal.
#[derive(Debug, Clone)]
pub(crate) struct JointGoal {
    /// Index in the robot's joint order.
    pub robot_index: usize,
    map: JointMap,
    /// The joint limits as ticks, rounded inwards: every goal sent lies in
    /// `lo_tick..=hi_tick`.
    lo_tick: i32,
    hi_tick: i32,
    tick: i32,
    /// The commanded angle (inside the limits), before the tick rounding:
    /// what telemetry reports and holds fall back to.
    pub rad: f64,
    /// Whether the last goal was clamped to the limits.
    pub clamped: bool,
    /// Goals clamped so far (a clamp means the plan was wrong).
    pub clamps: u64,
    /// A wheel joint: no goal position is sent (see `wheels`).
    pub wheel: bool,
}

/// The ticks inside a joint's limits: lowest and highest.
fn tick_range(map: &JointMap, joint: &JointConfig) -> (i32, i32) {
    let a = map.raw_ticks(map.min_rad);
    let b = map.raw_ticks(map.max_rad);
    let max = i32::try_from(joint.model.max_position()).unwrap_or(i32::MAX);
    // A small epsilon keeps a limit that falls exactly on a tick (up to
    // rounding) on that tick.
    let lo = (a.min(b) - 1e-6).ceil().clamp(0.0, f64::from(max)) as i32;
    let hi = (a.max(b) + 1e-6).floor().clamp(0.0, f64::from(max)) as i32;
    (lo, hi)
}

/// The joint positions (rad) a goal can be sent at as they are: the limits
/// narrowed to the ticks inside them (a position between those ticks rounds
/// to one of them or one between).
pub(crate) fn reachable(joint: &JointConfig, units: Units) -> (f64, f64) {
    let map = JointMap::new(joint, units);
    let (lo, hi) = tick_range(&map, joint);
    let (a, b) = (map.from_ticks(lo), map.from_ticks(hi));
    (a.min(b), a.max(b))
}

impl JointGoal {
    fn new(robot_index: usize, joint: &JointConfig, units: Units) -> Self {
        let map = JointMap::new(joint, units);
        let (lo, hi) = tick_range(&map, joint);
        JointGoal {
            robot_index,
            map,
            lo_tick: lo.min(hi),
            hi_tick: hi,
            tick: lo,
            rad: map.from_ticks(lo),
            clamped: false,
            clamps: 0,
            wheel: joint.is_wheel(),
        }
    }

    /// The goal for `rad`: clamped to the joint limits at the very last
    /// step, in ticks. Counts a clamp.
    fn set(&mut self, rad: f64) {
        if self.wheel {
            return;
        }
        let c = self.map.goal(rad);
        // Rounding to a tick can land half a tick beyond a limit: keep the
        // tick inside too.
        let tick = c.value.clamp(self.lo_tick, self.hi_tick);
        self.clamped = c.clamped;
        if c.clamped {
            self.clamps += 1;
        }
        self.tick = tick;
        self.rad = if c.value == tick {
            self.map.clamp(rad).value
        } else {
            self.map.from_ticks(tick)
        };
    }
}

/// The goals of one bus and the SYNC WRITE block that carries them.
#[derive(Debug)]
pub(crate) struct GoalWriter {
    reg: &'static Register,
    order: ByteOrder,
    /// Every servo of the bus (torque, profiles).
    ids: Vec<u8>,
    /// The servos of position joints: the goals' SYNC WRITE.
    position_ids: Vec<u8>,
    /// The encoded goals, one block per position joint: allocated once.
    data: Vec<u8>,
    /// Torque-enable blocks, off and on: a fault turns torque off without
    /// allocating.
    torque: [Vec<u8>; 2],
    pub joints: Vec<JointGoal>,
}

impl GoalWriter {
    /// The goals of `config`'s joints, whose first is robot joint
    /// `first_joint`; `units` is the robot file's.
    pub fn new(
        config: &BusConfig,
        first_joint: usize,
        units: Units,
        reg: &'static Register,
        order: ByteOrder,
    ) -> Self {
        let joints: Vec<JointGoal> = config
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| JointGoal::new(first_joint + i, j, units))
            .collect();
        let positions = joints.iter().filter(|j| !j.wheel).count();
        GoalWriter {
            reg,
            order,
            ids: config.joints.iter().map(|j| j.id).collect(),
            position_ids: config
                .joints
                .iter()
                .filter(|j| !j.is_wheel())
                .map(|j| j.id)
                .collect(),
            data: vec![0; positions * usize::from(reg.size)],
            torque: [vec![0; joints.len()], vec![1; joints.len()]],
            joints,
        }
    }

    /// Aims every joint at `cmd` (robot order, rad), each passed through
    /// `bound(i)` (joint `i` of the bus) first: a pressed joint's goal is
    /// kept near where it stands ([`Press::limit`]). The joint limits apply
    /// after it, as always.
    pub fn aim_within(&mut self, cmd: &[JointState], bound: impl Fn(usize) -> Option<Press>) {
        for (i, j) in self.joints.iter_mut().enumerate() {
            let rad = cmd.get(j.robot_index).map_or(f64::NAN, |s| s.position);
            j.set(bound(i).map_or(rad, |p| p.limit(rad)));
        }
    }

    /// Aims every joint at `positions` (robot order, rad); a joint missing
    /// there keeps its goal.
    pub fn aim_at(&mut self, positions: &[f64]) {
        for j in &mut self.joints {
            let rad = positions.get(j.robot_index).copied().unwrap_or(j.rad);
            j.set(rad);
        }
    }

    /// Aims joint `i` of the bus at `rad` without counting a clamp: where
    /// it stands at start-up, which may be outside its limits.
    pub fn start_at(&mut self, i: usize, rad: f64) {
        if let Some(j) = self.joints.get_mut(i) {
            j.set(rad);
            j.clamps = 0;
        }
    }

    fn encode(&mut self) {
        let size = usize::from(self.reg.size);
        let positions = self.joints.iter().filter(|j| !j.wheel);
        for (j, out) in positions.zip(self.data.chunks_exact_mut(size)) {
            // The tick is inside the servo's range, so it always encodes.
            let _ = self.reg.encode(j.tick, self.order, out);
        }
    }

    /// Sends the goals, patiently: start-up, where any failure is an error.
    pub fn send_checked<T: Transport>(&mut self, bus: &mut Bus<T>) -> Result<(), BusError> {
        self.encode();
        if self.position_ids.is_empty() {
            return Ok(());
        }
        bus.sync_write(self.reg.address, &self.position_ids, &self.data)
    }

    /// Sends the goals in a cycle. Only a lost port is an error: a servo
    /// that missed its goal gets the next one a period later.
    pub fn send<T: Transport>(&mut self, bus: &mut Bus<T>) -> Result<(), PortGone> {
        PortGone::check(self.send_checked(bus)).map(|_| ())
    }

    /// Turns off every servo's own motion profile (its acceleration ramp,
    /// and the move time and speed that cap a goal): the run's path is
    /// already within the joints' limits, and a ramp in the firmware on
    /// top of it would only make the servo trail the path. These are RAM
    /// registers (no EEPROM write); a power cycle clears them too. The goal
    /// speed is among them: a wheel's is 0 (at rest) from here until the
    /// loop commands one.
    pub fn release_profiles<T: Transport>(&self, bus: &mut Bus<T>) -> Result<(), BusError> {
        // Zeroes: one byte per servo for the ramp, four for time and speed.
        let ramp = &self.torque[0];
        bus.sync_write(addr::ACCELERATION, &self.ids, ramp)?;
        let none = vec![0u8; self.ids.len() * 4];
        bus.sync_write(addr::GOAL_TIME, &self.ids, &none)
    }

    /// Enables or disables torque on every servo of the bus.
    pub fn torque<T: Transport>(&self, bus: &mut Bus<T>, on: bool) -> Result<(), BusError> {
        let flags = &self.torque[usize::from(on)];
        bus.sync_write(addr::TORQUE_ENABLE, &self.ids, flags)
    }
}
