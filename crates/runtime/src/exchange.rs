//! What the lanes of a run (one per bus) share: the commands, each stamped
//! with the cycle it takes effect in on every bus, and the first fault.
//!
//! Stamps make a command's effect a property of the run, not of thread
//! timing: the first lane receives the user's commands, stamps them
//! [`COMMAND_DELAY_CYCLES`] ahead (or later, when asked) and forwards them,
//! so that every lane applies them in the same cycle, in virtual time and on
//! threads alike.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use crossbeam_channel::{bounded, Receiver, SendError, Sender, TryRecvError, TrySendError};

use crate::command::Command;
use crate::fault::Fault;
use crate::options::Reaction;
use crate::target::Checked;

/// How many cycles after the one that receives it a command takes effect:
/// time enough for every bus thread to have it before its cycle comes.
pub const COMMAND_DELAY_CYCLES: u64 = 2;

/// A command as sent: the cycle it should take effect in, if one was asked.
#[derive(Debug, Clone)]
pub(crate) struct Order {
    at: Option<u64>,
    command: Command,
}

/// What a lane carries out at a cycle.
#[derive(Debug, Clone)]
pub(crate) enum Op {
    Command(Command),
    /// A live target (see [`crate::target`]).
    Target(Arc<Checked>),
    /// Every command sender is gone: a run still waiting for
    /// [`Command::Play`] can never start.
    Abandon,
}

/// An operation and the cycle it takes effect in.
#[derive(Debug, Clone)]
pub(crate) struct Stamped {
    cycle: u64,
    op: Op,
}

/// A sender of commands to a run (cheap to clone).
#[derive(Debug, Clone)]
pub struct CommandSender {
    tx: Sender<Order>,
}

impl CommandSender {
    pub(crate) fn new(tx: Sender<Order>) -> Self {
        CommandSender { tx }
    }

    /// Sends `command`, waiting while the channel is full. It takes effect
    /// [`COMMAND_DELAY_CYCLES`] after the cycle that receives it.
    ///
    /// # Errors
    ///
    /// The command back when the run has ended.
    pub fn send(&self, command: Command) -> Result<(), SendError<Command>> {
        self.send_order(None, command)
    }

    /// Sends `command` if the channel has room.
    ///
    /// # Errors
    ///
    /// The command back when the channel is full or the run has ended.
    pub fn try_send(&self, command: Command) -> Result<(), TrySendError<Command>> {
        let order = Order { at: None, command };
        self.tx.try_send(order).map_err(|e| match e {
            TrySendError::Full(o) => TrySendError::Full(o.command),
            TrySendError::Disconnected(o) => TrySendError::Disconnected(o.command),
        })
    }

    /// Sends `command` to take effect in cycle `cycle` on every bus (or
    /// [`COMMAND_DELAY_CYCLES`] after the cycle that receives it, if that is
    /// later): what makes a scripted run repeatable.
    ///
    /// # Errors
    ///
    /// The command back when the run has ended.
    pub fn send_at(&self, cycle: u64, command: Command) -> Result<(), SendError<Command>> {
        self.send_order(Some(cycle), command)
    }

    fn send_order(&self, at: Option<u64>, command: Command) -> Result<(), SendError<Command>> {
        self.tx
            .send(Order { at, command })
            .map_err(|SendError(o)| SendError(o.command))
    }
}

/// Where a lane's operations come from.
#[derive(Debug)]
pub(crate) enum Inbox {
    /// The first lane: the user's orders, stamped here and forwarded.
    Leader {
        user: Receiver<Order>,
        /// Live targets: they take effect in the cycle that receives them
        /// on a single bus, [`COMMAND_DELAY_CYCLES`] later on several.
        targets: Receiver<Arc<Checked>>,
        forwards: Vec<Sender<Stamped>>,
        /// Whether a user sender may still exist.
        open: bool,
        /// The latest stamp given: the end of the senders comes after it.
        latest: u64,
    },
    /// The other lanes: what the first forwards.
    Follower(Receiver<Stamped>),
}

/// The user's sender of commands, the sender of live targets (holding
/// `targets` of them), and the inboxes of `lanes` lanes (the first one the
/// leader), holding `capacity` commands each.
pub(crate) fn inboxes(
    lanes: usize,
    capacity: usize,
    targets: usize,
) -> (CommandSender, Sender<Arc<Checked>>, Vec<Inbox>) {
    let capacity = capacity.max(1);
    let (user_tx, user) = bounded(capacity);
    let (target_tx, target_rx) = bounded(targets.max(1));
    let mut forwards = Vec::new();
    let mut followers = Vec::new();
    for _ in 1..lanes {
        // Twice the user's channels: a follower reading every cycle always
        // has room for what the leader forwards (sent without waiting).
        let (tx, rx) = bounded((capacity + targets.max(1)) * 2);
        forwards.push(tx);
        followers.push(Inbox::Follower(rx));
    }
    let leader = Inbox::Leader {
        user,
        targets: target_rx,
        forwards,
        open: true,
        latest: 0,
    };
    let all = std::iter::once(leader).chain(followers).collect();
    (CommandSender::new(user_tx), target_tx, all)
}

/// One lane's operations, received and waiting for their cycle.
#[derive(Debug)]
pub(crate) struct Mailbox {
    inbox: Inbox,
    pending: Vec<Stamped>,
}

impl Mailbox {
    pub fn new(inbox: Inbox) -> Self {
        Mailbox {
            inbox,
            pending: Vec::with_capacity(16),
        }
    }

    /// Takes in what arrived by cycle `k`.
    pub fn collect(&mut self, k: u64) {
        match &mut self.inbox {
            Inbox::Leader {
                user,
                targets,
                forwards,
                open,
                latest,
            } => {
                let delay = if forwards.is_empty() {
                    0
                } else {
                    COMMAND_DELAY_CYCLES
                };
                while let Ok(t) = targets.try_recv() {
                    let op = Stamped {
                        cycle: k + delay,
                        op: Op::Target(t),
                    };
                    for f in forwards.iter() {
                        let _ = f.try_send(op.clone());
                    }
                    self.pending.push(op);
                }
                loop {
                    let soonest = k + COMMAND_DELAY_CYCLES;
                    let op = match user.try_recv() {
                        Ok(order) => Stamped {
                            cycle: order.at.unwrap_or(0).max(soonest),
                            op: Op::Command(order.command),
                        },
                        // Only once every command sent has taken effect can the
                        // run know it will never play.
                        Err(TryRecvError::Disconnected) if *open => {
                            *open = false;
                            Stamped {
                                cycle: soonest.max(*latest),
                                op: Op::Abandon,
                            }
                        }
                        Err(_) => break,
                    };
                    *latest = (*latest).max(op.cycle);
                    for f in forwards.iter() {
                        // A follower that stopped reading has ended its run.
                        let _ = f.try_send(op.clone());
                    }
                    self.pending.push(op);
                }
            }
            Inbox::Follower(rx) => {
                while let Ok(op) = rx.try_recv() {
                    self.pending.push(op);
                }
            }
        }
    }

    /// The next operation due by cycle `k`: the earliest stamp first, in
    /// the order sent among equal stamps.
    pub fn next_due(&mut self, k: u64) -> Option<Op> {
        let (i, _) = self
            .pending
            .iter()
            .enumerate()
            .filter(|(_, s)| s.cycle <= k)
            .min_by_key(|(i, s)| (s.cycle, *i))?;
        Some(self.pending.remove(i).op)
    }
}

/// The first fault of the run, which every lane reacts to.
#[derive(Debug, Default)]
pub(crate) struct FaultBoard {
    /// Set once `first` holds a fault: checked every cycle without a lock.
    raised: AtomicBool,
    first: Mutex<Option<Fault>>,
}

impl FaultBoard {
    /// Posts `f`. Returns whether it is the run's first fault, and the
    /// reaction every lane carries out: the first fault's.
    pub fn raise(&self, f: &Fault) -> (bool, Reaction) {
        let mut slot = self.first.lock().unwrap_or_else(|e| e.into_inner());
        match &*slot {
            Some(first) => (false, first.reaction),
            None => {
                *slot = Some(f.clone());
                self.raised.store(true, Ordering::Release);
                (true, f.reaction)
            }
        }
    }

    /// The reaction to the first fault, if it was detected before cycle
    /// `k`: the other lanes react from the cycle after detection, in
    /// virtual time as on threads.
    pub fn before(&self, k: u64) -> Option<Reaction> {
        if !self.raised.load(Ordering::Acquire) {
            return None;
        }
        let slot = self.first.lock().unwrap_or_else(|e| e.into_inner());
        slot.as_ref().filter(|f| f.cycle < k).map(|f| f.reaction)
    }

    /// The first fault.
    pub fn first(&self) -> Option<Fault> {
        if !self.raised.load(Ordering::Acquire) {
            return None;
        }
        self.first.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(mail: &mut Mailbox, k: u64) -> Vec<&'static str> {
        std::iter::from_fn(|| mail.next_due(k))
            .map(|op| match op {
                Op::Command(Command::Play) => "play",
                Op::Command(Command::Stop) => "stop",
                Op::Command(_) | Op::Target(_) => "other",
                Op::Abandon => "abandon",
            })
            .collect()
    }

    #[test]
    fn every_lane_gets_each_command_at_its_stamp_and_the_end_after_the_last() {
        let (tx, _targets, inboxes) = inboxes(2, 4, 4);
        let mut lanes: Vec<Mailbox> = inboxes.into_iter().map(Mailbox::new).collect();
        tx.send_at(50, Command::Stop).expect("room");
        tx.send_at(10, Command::Play).expect("room");
        tx.send(Command::Pause).expect("room");
        drop(tx);
        // The leader receives at cycle 5: Pause is due at 5 + 2, and the
        // end of the senders only after the Stop at 50.
        lanes[0].collect(5);
        lanes[1].collect(6);
        for mail in &mut lanes {
            assert_eq!(names(mail, 6), Vec::<&str>::new());
            assert_eq!(names(mail, 7), ["other"]);
            assert_eq!(names(mail, 49), ["play"]);
            assert_eq!(names(mail, 50), ["stop", "abandon"]);
        }
    }

    #[test]
    fn the_first_fault_wins_and_reaches_the_others_from_the_next_cycle() {
        let board = FaultBoard::default();
        let fault = |cycle, reaction| Fault {
            kind: crate::FaultKind::PortGone {
                message: "gone".into(),
            },
            bus: "b".into(),
            joint: None,
            servo_id: None,
            time_s: 0.0,
            cycle,
            reaction,
            units: "deg",
        };
        assert_eq!(board.before(100), None);
        assert_eq!(
            board.raise(&fault(7, Reaction::Hold)),
            (true, Reaction::Hold)
        );
        assert_eq!(
            board.raise(&fault(7, Reaction::Stop)),
            (false, Reaction::Hold)
        );
        assert_eq!(board.before(7), None);
        assert_eq!(board.before(8), Some(Reaction::Hold));
        assert_eq!(board.first().map(|f| f.reaction), Some(Reaction::Hold));
    }
}
