//! The grasps of one bus's joints (see [`crate::grasp`]): each grasping
//! servo's torque limit set to its effort and put back when the grasp
//! ends, its press's push set from the effort, and its load, temperature
//! and current read while it grasps, lowering the effort when warm or
//! drawing much current, and letting go near its temperature limit or at
//! its protection current.
//!
//! A write or read that fails (a servo that missed it) is tried again the
//! next cycle; only a lost port is an error. At most one joint's torque
//! limit is written and one joint's readings read (one READ of the
//! registers from its load to its current) in a cycle, so a grasp costs a
//! cycle two short exchanges at most.

use servobus_driver::{Bus, Transport};
use servobus_protocol::registers::{ByteOrder, Register, RegisterMap};

use super::tracking::Tracker;
use crate::config::BusConfig;
use crate::error::PortGone;
use crate::grasp::{
    full_effort_error, GraspCause, GraspEvent, CURRENT_LET_GO_SHARE, CURRENT_READINGS,
    CURRENT_WARNING_SHARE, DEFAULT_MAX_TEMPERATURE_C, FACTORY_P, HOLD_GAIN, HOLD_SHARE,
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
    /// Its protection current, mA: the robot file's, or what the servo
    /// held when the grasp began (`None`: not known, not watched).
    max_current: Option<f64>,
    /// How many readings in a row reached the let-go current.
    over_current: u8,
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

/// One reading of a grasping servo.
#[derive(Debug, Clone, Copy, Default)]
struct Reading {
    /// Its load, a share of the torque.
    load: Option<f64>,
    /// Its temperature, degrees C.
    temperature_c: Option<f64>,
    /// Its current, mA.
    current_ma: Option<f64>,
}

/// The registers a grasp reads, read in one READ from the first's address
/// to the end of the last.
#[derive(Debug)]
struct Readings {
    load: Option<&'static Register>,
    temperature: Option<&'static Register>,
    current: Option<&'static Register>,
    /// mA per step of `current` (`None`: its unit is not a current).
    current_step_ma: Option<f64>,
    order: ByteOrder,
    /// The span read: first address, length.
    span: Option<(u8, usize)>,
}

/// The grasps of one bus.
#[derive(Debug)]
pub(crate) struct GraspWatch {
    joints: Vec<Joint>,
    torque_limit: Option<&'static Register>,
    /// The protection current register, read when a grasp begins on a
    /// joint whose robot file gives none.
    protection: Option<&'static Register>,
    readings: Readings,
}

/// The mA of one step of `reg`, when it counts in mA (`6.5 mA`).
fn ma_per_step(reg: &Register) -> Option<f64> {
    let step = reg.unit.trim().strip_suffix("mA")?.trim();
    let step: f64 = step.parse().ok()?;
    (step > 0.0).then_some(step)
}

impl Readings {
    fn new(map: &RegisterMap, order: ByteOrder) -> Readings {
        let (load, temperature) = (map.get("present_load"), map.get("present_temperature"));
        let current = map.get("present_current");
        let current_step_ma = current.and_then(ma_per_step);
        let regs = [load, temperature, current];
        let first = regs.iter().flatten().map(|r| r.address).min();
        let end = regs.iter().flatten().map(|r| r.end()).max();
        let span = first
            .zip(end)
            .map(|(a, e)| (a, usize::from(e).saturating_sub(usize::from(a))));
        Readings {
            load,
            temperature,
            current,
            current_step_ma,
            order,
            span,
        }
    }

    /// Reads servo `id`'s load, temperature and current in one READ
    /// (`None`: the servo missed it).
    fn read<T: Transport>(&self, bus: &mut Bus<T>, id: u8) -> Result<Option<Reading>, PortGone> {
        let Some((first, len)) = self.span else {
            return Ok(None);
        };
        let mut bytes = [0u8; 32];
        let Some(bytes) = bytes.get_mut(..len) else {
            return Ok(None);
        };
        if PortGone::check(bus.read(id, first, bytes))?.is_none() {
            return Ok(None);
        }
        let value = |reg: Option<&'static Register>| {
            let reg = reg?;
            let at = usize::from(reg.address - first);
            let raw = bytes.get(at..at + usize::from(reg.size))?;
            reg.decode(raw, self.order).ok().map(f64::from)
        };
        Ok(Some(Reading {
            load: value(self.load).map(|raw| (raw / 1000.0).abs()),
            temperature_c: value(self.temperature),
            current_ma: value(self.current)
                .zip(self.current_step_ma)
                .map(|(raw, step)| raw.abs() * step),
        }))
    }
}

impl GraspWatch {
    /// The grasps `config`'s joints (the first is robot joint
    /// `first_joint`) may make, with the registers of the series' `map`
    /// (in byte order `order`): `torque_limit`, `protection_current`,
    /// `present_load`, `present_temperature` and `present_current` (one
    /// missing: that part is not done).
    pub fn new(
        config: &BusConfig,
        first_joint: usize,
        map: &RegisterMap,
        order: ByteOrder,
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
                    max_current: s.and_then(|s| s.protection_current),
                    over_current: 0,
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
            torque_limit: map.get("torque_limit"),
            protection: map.get("protection_current"),
            readings: Readings::new(map, order),
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
                        begin(bus, j, self.torque_limit, self.protection)?;
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
        let Some(reading) = self.readings.read(bus, j.id)? else {
            return Ok(());
        };
        let held = track.joints.get(i).is_some_and(|tj| tj.press.is_some());
        if let (Some(load), true) = (reading.load, held) {
            j.load = load;
            let wanted = HOLD_TARGET * j.effort;
            let most = j.effort * j.full_error;
            j.push = (j.push + HOLD_GAIN * (wanted - load) * j.full_error).clamp(-most, most);
            track.set_grasp(i, Some(j.push));
        }
        let temperature_c = reading.temperature_c.unwrap_or(0.0);
        let current_ma = reading.current_ma;
        let share = current_ma.zip(j.max_current).map(|(c, most)| c / most);
        // The current counts once the load has settled at the effort in
        // force (the first push of a contact strains at the torque limit
        // for a moment): a grasp whose effort itself draws too much.
        let settled = held && j.load <= HOLD_TARGET * j.effort * SETTLED;
        let over = settled && share.is_some_and(|s| s >= CURRENT_LET_GO_SHARE);
        j.over_current = if over { j.over_current + 1 } else { 0 };
        let hot = temperature_c >= j.max_temp - LET_GO_BELOW_LIMIT_C;
        if hot || j.over_current >= CURRENT_READINGS {
            j.let_go(track, i);
            let cause = cause_of(hot);
            publish(
                j.robot_index,
                GraspEvent::LetGo {
                    temperature_c,
                    current_ma,
                    cause,
                },
            );
            return Ok(());
        }
        let warm = temperature_c >= j.max_temp - WARNING_BELOW_LIMIT_C;
        let drawing = settled && share.is_some_and(|s| s >= CURRENT_WARNING_SHARE);
        if (warm || drawing)
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
            let cause = cause_of(warm);
            publish(
                j.robot_index,
                GraspEvent::Lowered {
                    effort_pct: 100.0 * j.effort,
                    temperature_c,
                    current_ma,
                    cause,
                },
            );
        }
        Ok(())
    }
}

/// The temperature when `by_temperature`, else the current.
fn cause_of(by_temperature: bool) -> GraspCause {
    if by_temperature {
        GraspCause::Temperature
    } else {
        GraspCause::Current
    }
}

/// What a grasp of joint `j` takes from its servo when it begins: the
/// torque limit it held (put back after), and its protection current when
/// the robot file gives none.
fn begin<T: Transport>(
    bus: &mut Bus<T>,
    j: &mut Joint,
    torque_limit: Option<&'static Register>,
    protection: Option<&'static Register>,
) -> Result<(), PortGone> {
    if let Some(reg) = torque_limit {
        if let Some((held, _)) = PortGone::check(bus.read_register(j.id, reg))? {
            j.restore = held;
            j.limit = (held, true);
        }
    }
    if let (None, Some(reg)) = (j.max_current, protection) {
        if let (Some((raw, _)), Some(step)) = (
            PortGone::check(bus.read_register(j.id, reg))?,
            ma_per_step(reg),
        ) {
            j.max_current = (raw > 0).then(|| f64::from(raw) * step);
        }
    }
    j.over_current = 0;
    Ok(())
}

impl Joint {
    /// Lets go: the goal backs off behind where the joint stands (the
    /// press bounds it from the furthest point it reached), so the jaws
    /// open from the object and the servo rests.
    fn let_go(&mut self, track: &mut Tracker, i: usize) {
        let depth = track
            .joints
            .get(i)
            .and_then(|tj| Some((tj.measured? - tj.press?.anchor).abs()))
            .unwrap_or(0.0);
        self.push = -(depth + self.effort * self.full_error);
        self.let_go = true;
        self.set_limit(track, i);
    }

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
