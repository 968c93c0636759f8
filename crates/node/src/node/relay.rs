//! From the network to the loop: targets and chunks on `target`, commands
//! on `command`, and what `stop` means for a node that goes on serving.
//!
//! | command | sent to the loop | the node afterwards |
//! |---|---|---|
//! | `play M [at T]` | [`Command::Replace`] (at cycle T's) | serving; the motion plays |
//! | `stop` | a switch to live following (when a motion may be playing), then [`Command::Pause`] | serving, *stopped*: the joints stop (jerk limited) and hold |
//! | a target or chunk while stopped | the target, then [`Command::Resume`] | following again |
//! | `resume` while stopped | nothing (logged) | still stopped: the stopped motion never resumes |
//! | `pause`, `resume` | [`Command::Pause`], [`Command::Resume`] | serving |
//! | `torque_off` | [`Command::TorqueOff`] | the run ends, then the node |
//! | `shutdown` | [`Command::Stop`] (as Ctrl-C) | the run ends, then the node |
//!
//! The loop's [`Command::Stop`] ends its run, so `stop` is made of what a
//! live run already does: a target switches whatever path is running to
//! live following from the commanded state (which, with no target joint
//! given, stops every joint within its limits and holds), and a pause of
//! live following stops and holds until it is resumed.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant, SystemTime};

use servobus_robot::config::{Robot, Units};
use servobus_robot::{Chunk, Command, CommandSender, LiveTarget, TargetError, TargetSender};

use super::{lock, unix_ns, Planner, Shared};
use crate::wire::{parse_command, parse_live, LiveMessage, NodeCommand, TargetMessage};

/// The stamp of the joint-less target that switches a running path to
/// live following on `stop`: far before any sender's stamp, so that the
/// live follower's estimate of the senders' clock offset (the smallest
/// arrival minus stamp seen) never takes it for a sender's.
const SWITCH_STAMP: f64 = -1.0e12;

/// What the node last set the loop doing.
#[derive(Debug, Default)]
pub(super) struct Motion {
    /// `stop` was carried out and nothing has moved the robot since.
    stopped: bool,
    /// A `play` was sent after the last target: a path may be playing
    /// (live following is not running).
    playing: bool,
}

/// The loop's two inputs, as the node's callbacks hold them.
#[derive(Clone)]
pub(super) struct Inputs {
    pub(super) targets: TargetSender,
    pub(super) commands: CommandSender,
}

/// A target (its grasps with it) or chunk from the network into the
/// stream; a malformed one is counted and logged, never sent. The first
/// one after `stop` resumes the following.
pub(super) fn take_target(
    payload: &[u8],
    to: &Inputs,
    robot: (Units, Option<&Robot>),
    started: Instant,
    shared: &Shared,
) {
    let (units, config) = robot;
    let malformed = |why: &dyn std::fmt::Display| {
        shared.counts.malformed.fetch_add(1, Ordering::Relaxed);
        eprintln!("target: {why}; ignored");
    };
    let msg = match parse_live(payload) {
        Ok(m) => m,
        Err(why) => return malformed(&why),
    };
    // A base velocity becomes its wheels' speeds (rad/s) before anything is
    // sent: one the robot cannot take moves nothing.
    let wheels = match wheel_speeds(&msg, config) {
        Ok(w) => w,
        Err(why) => return malformed(&why),
    };
    let (sent, what) = match msg {
        LiveMessage::Target(m) => {
            let mut joints: Vec<(String, f64)> = m
                .joints
                .into_iter()
                .map(|(n, a)| (n, units.to_rad(a)))
                .collect();
            joints.extend(wheels);
            let stamp = m.t.unwrap_or_else(|| started.elapsed().as_secs_f64());
            let target = LiveTarget::named(stamp, joints)
                .with_grasps(m.grasps)
                .taken_at(taken_at(m.sent_ns));
            (deliver(to, shared, "target", |t| t.send(target)), "target")
        }
        LiveMessage::Chunk(m) => {
            let joints = m
                .joints
                .into_iter()
                .map(|(n, a)| (n, a.into_iter().map(|a| units.to_rad(a)).collect()))
                .collect();
            let chunk = Chunk::named(m.t0, m.dt, joints).taken_at(taken_at(m.sent_ns));
            (
                deliver(to, shared, "chunk", |t| t.send_chunk(chunk)),
                "chunk",
            )
        }
    };
    match sent {
        Ok(_) => {
            let count = match what {
                "chunk" => &shared.counts.chunks,
                _ => &shared.counts.targets,
            };
            count.fetch_add(1, Ordering::Relaxed);
        }
        // The stream counts its refusals for the report.
        Err(why) => eprintln!("{what}: {why}; refused"),
    }
}

/// Sends what `send` gives the stream (a target, a chunk, a trajectory's
/// targets), the way every input reaches it: under the motion's lock (a
/// `stop` never comes between a target and the resume it needs), clamping
/// said on stderr as `what`, and, the first time after `stop`, followed by
/// the resume. Returns what `send` returned.
pub(super) fn deliver(
    to: &Inputs,
    shared: &Shared,
    what: &str,
    send: impl FnOnce(&TargetSender) -> Result<usize, TargetError>,
) -> Result<usize, TargetError> {
    let mut motion = lock(&shared.motion);
    let clamped = send(&to.targets)?;
    shared.generation.fetch_add(1, Ordering::Relaxed);
    if clamped > 0 {
        eprintln!("{what}: {clamped} angle(s) beyond the joint limits, clamped");
    }
    motion.playing = false;
    if motion.stopped {
        // The target reached the paused follower first (it was sent
        // first): following resumes towards it.
        if to.commands.send(Command::Resume).is_ok() {
            motion.stopped = false;
        }
    }
    Ok(clamped)
}

/// The wheel speeds (rad/s) a message's base velocity asks for: none
/// without one; an error when the robot cannot take it.
fn wheel_speeds(msg: &LiveMessage, config: Option<&Robot>) -> Result<Vec<(String, f64)>, String> {
    match msg {
        LiveMessage::Target(TargetMessage {
            base: Some(base), ..
        }) => match config.map(|r| r.wheel_targets(base)) {
            Some(Ok(w)) => Ok(w.wheels),
            Some(Err(why)) => Err(why.to_string()),
            None => Err("a `base` target needs the robot's base".into()),
        },
        _ => Ok(Vec::new()),
    }
}

/// When a message was taken: counted from its publishing when the sender
/// says when that was (`sent_ns`, Unix nanoseconds), else now.
fn taken_at(sent_ns: Option<i64>) -> Instant {
    let now = Instant::now();
    sent_ns
        .and_then(|sent| {
            let ago = unix_ns(SystemTime::now()).checked_sub(sent)?;
            now.checked_sub(Duration::from_nanos(u64::try_from(ago).ok()?))
        })
        .unwrap_or(now)
}

/// A command from the network to the loop; a malformed one is counted and
/// logged, never acted on.
pub(super) fn take_command(
    payload: &[u8],
    to: &Inputs,
    planner: &Planner,
    period: f64,
    shared: &Shared,
) {
    let cmd = match parse_command(payload) {
        Ok(c) => c,
        Err(why) => {
            shared.counts.malformed.fetch_add(1, Ordering::Relaxed);
            eprintln!("command: {why}; ignored");
            return;
        }
    };
    let mut motion = lock(&shared.motion);
    let (command, at) = match cmd {
        NodeCommand::Stop => {
            let done = halt(to, &mut motion);
            count(shared, done);
            return;
        }
        NodeCommand::Resume if motion.stopped => {
            eprintln!(
                "command: resume: the motion was stopped, not paused; \
                 send a target or a chunk, or play a motion"
            );
            return;
        }
        NodeCommand::Shutdown => (Command::Stop, None),
        NodeCommand::Pause => (Command::Pause, None),
        NodeCommand::Resume => (Command::Resume, None),
        NodeCommand::TorqueOff => (Command::TorqueOff, None),
        NodeCommand::Play { motion: m, at } => match planner(&m) {
            Ok(c) => (c, at),
            Err(why) => {
                eprintln!("command: play: {why}; ignored");
                return;
            }
        },
    };
    let play = matches!(command, Command::Replace(_));
    let sent = match (at, *lock(&shared.start)) {
        (Some(at), Some(start)) => {
            let since = at.duration_since(start).map_or(0.0, |d| d.as_secs_f64());
            let cycle = (since / period - 1e-9).ceil().max(0.0) as u64;
            lock(&shared.timed).push((cycle, at));
            to.commands.send_at(cycle, command)
        }
        _ => to.commands.send(command),
    };
    if sent.is_ok() && play {
        *motion = Motion {
            stopped: false,
            playing: true,
        };
    }
    count(shared, sent.is_ok());
}

/// `stop` for the node's own reasons (a goal canceled or aborted): the
/// joints stop (jerk limited) and hold until the next target, chunk or
/// motion. Returns whether the loop took it.
pub(super) fn stop_and_hold(to: &Inputs, shared: &Shared) -> bool {
    let mut motion = lock(&shared.motion);
    shared.generation.fetch_add(1, Ordering::Relaxed);
    halt(to, &mut motion)
}

/// `stop`: the joints stop (jerk limited) and hold, and the run goes on.
/// Returns whether the loop took it.
fn halt(to: &Inputs, motion: &mut Motion) -> bool {
    if motion.playing {
        // A joint-less target: the path running (a motion, its approach,
        // its end's hold) gives way to live following from the commanded
        // state, which stops every joint within its limits.
        match to.targets.send(LiveTarget::named(SWITCH_STAMP, Vec::new())) {
            Ok(_) => motion.playing = false,
            Err(TargetError::Ended) => return false,
            // Not expected of a target naming no joint; the pause below
            // still stops a live run, and slows a motion to a standstill
            // along its path.
            Err(why) => eprintln!("command: stop: {why}"),
        }
    }
    if to.commands.send(Command::Pause).is_err() {
        return false;
    }
    motion.stopped = true;
    true
}

fn count(shared: &Shared, taken: bool) {
    if taken {
        shared.generation.fetch_add(1, Ordering::Relaxed);
        shared.counts.commands.fetch_add(1, Ordering::Relaxed);
    } else {
        eprintln!("command: the run has ended; ignored");
    }
}

#[cfg(test)]
mod tests;
