//! A lane: one bus's share of a run, with its own copy of the robot-wide
//! path. [`Lane::cycle`] is the one cycle function of servobus: commands,
//! the fault reaction, hold, stop and pause all happen here, whether the
//! lanes are stepped one after the other in virtual time
//! ([`VirtualRun`](crate::VirtualRun)) or each on its own thread on the
//! real clock ([`spawn`](crate::spawn)). Only the clock and the pacing
//! differ between the two.
//!
//! Lanes keep in step through what they share ([`crate::exchange`]):
//! commands take effect in the cycle they are stamped with on every lane,
//! and the first fault of any bus is carried out by every other bus from the
//! cycle after its detection.
//!
//! Wheels take their target speeds from the timeline each cycle (0 but
//! while live targets are followed): a stop, a pause, a hold of a fault
//! reaction and a live timeout all ramp them to 0 in the bus loop, and a
//! run whose path is over ends only once they are at rest. Torque off
//! (the command, the fault reaction) sets their speed to 0 at once; a lost
//! port sends nothing.

use std::sync::Arc;
use std::time::Duration;

use servobus_driver::Transport;
use servobus_trajectory::JointState;

use crate::busloop::{BusLoop, CycleTiming};
use crate::command::Command;
use crate::error::RunError;
use crate::exchange::{FaultBoard, Mailbox, Op};
use crate::fault::Fault;
use crate::live::LiveEvent;
use crate::options::Reaction;
use crate::pacer::Tick;
use crate::target::{Count, TargetCounts};
use crate::telemetry::{Finish, Telemetry};
use crate::timeline::{Kind, Timeline};

/// See the module documentation.
pub(crate) struct Lane<T: Transport> {
    pub bus: BusLoop<T>,
    /// This lane's copy of the path. Only its own joints are sent from it;
    /// every copy sees the same commands at the same cycles.
    timeline: Timeline,
    mail: Mailbox,
    board: Arc<FaultBoard>,
    /// The counts of live targets (this lane adds the followed, timed out
    /// and resumed ones when it is the first).
    counters: Arc<TargetCounts>,
    cmd: Vec<JointState>,
    /// The wheels' target speeds this cycle, rad/s (robot order).
    speeds: Vec<f64>,
    /// The grasps' efforts this cycle (robot order).
    grasps: Vec<Option<f64>>,
    reference: Vec<JointState>,
    hold: Vec<f64>,
    /// The fault reaction this lane has carried out (one per run).
    reacted: Option<Reaction>,
    /// How long the end of a completed path is held, s.
    settle: f64,
    period: Duration,
    /// Why this lane's run ended, once it has.
    pub finish: Option<Finish>,
    /// When the oldest target applied this cycle was taken (for the
    /// latency to the goals on the wire).
    taken: Option<std::time::Instant>,
}

impl<T: Transport> Lane<T> {
    /// The lane of `bus` on `timeline` (every lane gets a clone).
    #[allow(clippy::too_many_arguments)] // what a lane shares with the others
    pub fn new(
        bus: BusLoop<T>,
        timeline: Timeline,
        mail: Mailbox,
        board: Arc<FaultBoard>,
        counters: Arc<TargetCounts>,
        joints: usize,
        settle: Duration,
        period: Duration,
    ) -> Self {
        Lane {
            bus,
            timeline,
            mail,
            board,
            counters,
            cmd: vec![JointState::default(); joints],
            speeds: vec![0.0; joints],
            grasps: vec![None; joints],
            reference: vec![JointState::default(); joints],
            hold: vec![0.0; joints],
            reacted: None,
            settle: settle.as_secs_f64(),
            period,
            finish: None,
            taken: None,
        }
    }

    /// Runs the cycle `tick` is due for. Returns why the lane's run ended,
    /// once it has; later calls do nothing.
    pub fn cycle(&mut self, tick: Tick) -> Option<Finish> {
        if self.finish.is_none() {
            self.finish = self.run_cycle(tick);
        }
        self.finish
    }

    fn run_cycle(&mut self, tick: Tick) -> Option<Finish> {
        let k = tick.index;
        let t = k as f64 * self.period.as_secs_f64();
        self.timeline.begin_cycle(t);
        if let Some(end) = self.take_commands(k) {
            return Some(end);
        }
        if self.reacted.is_none() {
            if let Some(reaction) = self.board.before(k) {
                if let Some(end) = self.react(reaction) {
                    return Some(end);
                }
            }
        }
        let timing = CycleTiming {
            index: k,
            deadline: tick.deadline,
            woke: tick.woke,
            skipped: 0,
        };
        let (lead, found) = self.bus_cycle(timing, t);
        if let Some(event) = self.timeline.take_event() {
            self.live_event(event, t);
        }
        if self.bus.index == 0 {
            self.timeline.envelopes(&self.counters);
        }
        let end = found.and_then(|f| self.raise(&f));
        self.bus.finish_cycle(lead);
        if end.is_some() {
            return end;
        }
        self.timeline.prune(t);
        // A path that is over ends the run once the wheels are at rest too:
        // the last goal speed sent is 0.
        let over = self.timeline.finished(t, self.settle);
        (over && self.bus.wheels_at_rest()).then(|| self.finish_of())
    }

    /// The bus's work of cycle `timing.index` at path time `t`: command the
    /// path at `t + lead`, read the feedback back, and track it against the
    /// path at the time of the reading. Returns the lead used and the fault
    /// this cycle raised: a lost port, or what tracking found.
    fn bus_cycle(&mut self, timing: CycleTiming, t: f64) -> (f64, Option<Fault>) {
        let l = &mut self.bus;
        l.begin(timing);
        let lead = l.lead_at(t);
        self.timeline.sample_cmd(t + lead, &mut self.cmd);
        self.timeline.wheel_targets(t + lead, &mut self.speeds);
        self.timeline.grasp_efforts(t + lead, &mut self.grasps);
        let mut gone = l.write(&self.cmd, &self.speeds, &self.grasps).err();
        if let Some(taken) = self.taken.take() {
            // A target taken before the first cycle waited for the loop to
            // start (the start gap, 50 ms at least on the real clock): that
            // is not the loop's latency, and is left out of its figures.
            if timing.index > 0 {
                self.counters.latency(taken.elapsed());
            }
        }
        let x = match l.read() {
            Ok(x) => x,
            Err(e) => {
                gone.get_or_insert(e);
                t
            }
        };
        self.timeline.sample_ref(x, &mut self.reference);
        let kind = self.timeline.kind_at(x);
        if kind == Some(Kind::Live) {
            // A live session: a joint pressed against a stop is held, not
            // a fault.
            l.live_session();
        }
        let main = matches!(kind, Some(Kind::Main | Kind::Approach | Kind::Live));
        let found = match gone {
            Some(e) => Some(l.port_gone(&e)),
            None => l.track(&self.reference, main, t),
        };
        (lead, found)
    }

    /// Counts and publishes (on the first lane) what the live following
    /// did in the cycle at `t`.
    fn live_event(&mut self, event: LiveEvent, t: f64) {
        if self.bus.index != 0 {
            return;
        }
        self.counters.add(match event {
            LiveEvent::TimedOut => Count::Timeout,
            LiveEvent::Resumed => Count::Resume,
        });
        self.bus.publish(Telemetry::Live { event, time_s: t });
    }

    /// Carries out the operations due at cycle `k`.
    fn take_commands(&mut self, k: u64) -> Option<Finish> {
        self.mail.collect(k);
        while let Some(op) = self.mail.next_due(k) {
            let command = match op {
                Op::Abandon if self.waiting_for_play() => return Some(Finish::Abandoned),
                Op::Abandon => continue,
                Op::Target(target) => {
                    if self.timeline.target(&target) && self.bus.index == 0 {
                        self.counters.add(Count::Followed);
                        if let Some(taken) = target.taken {
                            self.taken = Some(self.taken.map_or(taken, |o| o.min(taken)));
                        }
                    }
                    continue;
                }
                Op::Command(c) => c,
            };
            match self.apply(command) {
                Ok(Some(end)) => {
                    self.bus.torque_off();
                    return Some(end);
                }
                Ok(None) => {}
                // Every lane rejects it alike; the first one says so.
                Err(why) if self.bus.index == 0 => {
                    self.bus.publish(Telemetry::Rejected(why.into()));
                }
                Err(_) => {}
            }
        }
        None
    }

    /// What a command asks of the path; `Some` when it ends the run.
    fn apply(&mut self, command: Command) -> Result<Option<Finish>, RunError> {
        let tl = &mut self.timeline;
        match command {
            Command::Play | Command::Resume => tl.play(),
            Command::Pause => tl.set_speed(0.0),
            Command::Stop => tl.stop()?,
            Command::TorqueOff => return Ok(Some(Finish::TorqueOff)),
            Command::Replace(t) => tl.replace(t)?,
        }
        Ok(None)
    }

    fn waiting_for_play(&self) -> bool {
        self.timeline.last_kind() == Some(Kind::Hold { last: false })
    }

    /// Posts a fault this lane found and starts the run's reaction (the
    /// first fault's, should another bus have been first).
    fn raise(&mut self, f: &Fault) -> Option<Finish> {
        let (first, reaction) = self.board.raise(f);
        if first {
            self.bus.publish(Telemetry::Fault(f.clone()));
        }
        self.react(reaction)
    }

    /// The fault reaction, carried out once.
    fn react(&mut self, reaction: Reaction) -> Option<Finish> {
        if self.reacted.is_some() {
            return None;
        }
        self.reacted = Some(reaction);
        match reaction {
            Reaction::Stop => {
                // A stop that cannot be planned still must not move on.
                if self.timeline.stop().is_err() {
                    self.hold_here();
                }
                None
            }
            Reaction::Hold => {
                self.hold_here();
                None
            }
            Reaction::TorqueOff => {
                self.bus.torque_off();
                Some(Finish::Fault)
            }
        }
    }

    /// Holds this bus's joints where they stand (fresh reading, else last
    /// goal) from now on, and sends that at once.
    fn hold_here(&mut self) {
        // Other buses' joints keep their commanded position in this copy of
        // the path; they are never sent from this lane.
        let x = self.timeline.horizon();
        self.timeline.sample_ref(x, &mut self.cmd);
        for (h, c) in self.hold.iter_mut().zip(&self.cmd) {
            *h = c.position;
        }
        self.bus.hold_positions(&mut self.hold);
        self.timeline.hold(self.hold.clone());
        // A lost port was already reported; the hold stands in the path.
        let _ = self.bus.send_hold(&self.hold);
    }

    /// Why the path ended, once it has.
    fn finish_of(&self) -> Finish {
        if self.reacted.is_some() {
            return Finish::Fault;
        }
        match self.timeline.last_kind() {
            Some(Kind::Stop) => Finish::Stopped,
            _ => Finish::Completed,
        }
    }
}

/// Why a run of several lanes ended: a fault on any bus, else the first
/// bus's reason (commands end every lane alike).
pub(crate) fn overall(finishes: impl IntoIterator<Item = Finish>) -> Finish {
    let mut first = None;
    for f in finishes {
        if f == Finish::Fault {
            return f;
        }
        first.get_or_insert(f);
    }
    first.unwrap_or(Finish::Completed)
}
