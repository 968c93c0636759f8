//! `<ns>/follow_joint_trajectory`, the action server MoveIt drives a
//! joint_trajectory_controller through, as rmw_zenoh maps an action:
//!
//! | key under `<action>/_action/` | Zenoh | what the node does |
//! |---|---|---|
//! | `send_goal` | queryable | checks the goal ([`super::trajectory`], tolerances), replies `accepted`, sends it as a timed chunk |
//! | `cancel_goal` | queryable | stops the goals named (jerk limited) and holds |
//! | `get_result` | queryable | replies once the goal has ended (the query is held until then, or until the run ends) |
//! | `feedback` | published at the state rate | desired (the path now), actual (measured), error |
//! | `status` | published on every change; the last one kept for late subscribers | every goal kept and its status |
//!
//! Every request carries rmw_zenoh's attachment (sequence number, source
//! time, client GID); the reply echoes the sequence number and the
//! client's GID with the reply's own time, as rmw_zenoh's service servers
//! do. A request without it, or whose payload is not the request, is
//! counted in `malformed`, said on stderr and answered with a Zenoh error
//! reply; it moves nothing.
//!
//! A refused goal (unknown joints, a point past a limit, a piece faster
//! than a joint can go, multi-DOF joints) is answered `accepted: false`;
//! the reason is said on stderr and kept as the goal's result, so a
//! `get_result` for its id answers `STATUS_UNKNOWN` with the error code
//! (`INVALID_JOINTS`, `INVALID_GOAL`, `OLD_HEADER_TIMESTAMP`) and the
//! reason. Goal life and tolerances: [`goals`].

use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, Mutex};

use servobus_robot::config::Units;
use zenoh::pubsub::Publisher;
use zenoh::query::{Query, Queryable};
use zenoh::Wait;

use super::topics::{plan_arrival, send_planned, Arrival, Context};
use super::view::View;
use crate::node::relay::stop_and_hold;
use crate::node::state::Done;
use crate::node::{lock, unix_ns, zerr, NodeError};
use crate::ros2::{
    ActionKeys, Attachment, CancelGoalRequest, CdrMessage, FeedbackMessage,
    FollowJointTrajectoryFeedback, FollowJointTrajectoryResult as Fjt, GetResultRequest, Header,
    JointTrajectoryPoint, RosDuration, RosTime, SendGoalRequest, SendGoalResponse, Uuid,
};

mod goals;

use goals::{tolerances, Change, Cycle, Goals, Track, DEFAULT_GOAL_TIME};

/// The most `get_result` queries held at once.
const MOST_WAITING: usize = 64;

/// A held `get_result` query.
struct Waiting {
    goal: Uuid,
    query: Query,
    attachment: Attachment,
}

/// What the server's queryables and the telemetry loop share.
struct Inner {
    cx: Arc<Context>,
    keys: ActionKeys,
    goals: Mutex<Goals>,
    waiting: Mutex<Vec<Waiting>>,
    feedback: Publisher<'static>,
    status: Publisher<'static>,
    /// The last status published (payload, attachment), for late subscribers.
    last_status: Mutex<Option<(Vec<u8>, Vec<u8>)>>,
    /// The GIDs of feedback and status.
    gids: [[u8; 16]; 2],
    /// The sequence numbers of feedback and status.
    seq: [AtomicI64; 2],
}

/// The action server; dropping it undeclares its keys.
pub(in crate::node) struct Server {
    inner: Arc<Inner>,
    _queryables: Vec<Queryable<()>>,
}

impl Server {
    /// Declares the server's keys on `session`: `gids` are the five
    /// entities' (send_goal, cancel_goal, get_result, feedback, status),
    /// `status_id` the status publisher's entity id.
    ///
    /// # Errors
    /// [`NodeError::Zenoh`] when a key cannot be declared.
    pub fn declare(
        session: &zenoh::Session,
        keys: &ActionKeys,
        (gids, status_id): ([[u8; 16]; 5], u32),
        cx: &Arc<Context>,
    ) -> Result<Self, NodeError> {
        let feedback = session
            .declare_publisher(keys.feedback.clone())
            .wait()
            .map_err(zerr)?;
        let status = session
            .declare_publisher(keys.status.clone())
            .wait()
            .map_err(zerr)?;
        let inner = Arc::new(Inner {
            cx: Arc::clone(cx),
            keys: keys.clone(),
            goals: Mutex::new(Goals::default()),
            waiting: Mutex::new(Vec::new()),
            feedback,
            status,
            last_status: Mutex::new(None),
            gids: [gids[3], gids[4]],
            seq: [AtomicI64::new(0), AtomicI64::new(0)],
        });
        type Answer = fn(&Inner, Query);
        let services: [(String, Answer); 3] = [
            (keys.send_goal.clone(), Inner::send_goal),
            (keys.cancel_goal.clone(), Inner::cancel_goal),
            (keys.get_result.clone(), Inner::get_result),
        ];
        let mut queryables = Vec::new();
        for (key, answer) in services {
            let inner = Arc::clone(&inner);
            queryables.push(
                session
                    .declare_queryable(key)
                    .complete(true)
                    .callback(move |query| answer(&inner, query))
                    .wait()
                    .map_err(zerr)?,
            );
        }
        queryables.push(keep_last_status(session, &inner, status_id)?);
        Ok(Server {
            inner,
            _queryables: queryables,
        })
    }

    /// Publishes the running goal's feedback from the cycle `done`.
    pub fn feedback(&self, done: &Done, units: Units) {
        let inner = &self.inner;
        let msg = {
            let goals = lock(&inner.goals);
            let Some(goal) = goals.running() else {
                return;
            };
            let Some(track) = &goal.track else {
                return;
            };
            let view = View::of(done, units);
            let now = inner.cx.shared.stream_now();
            feedback_of(goal.id, track, &view, now)
        };
        inner.put(0, msg.encode());
    }

    /// Checks the goals against the cycle `done`.
    pub fn cycle(&self, done: &Done, units: Units) {
        let inner = &self.inner;
        let view = View::of(done, units);
        let commanded_velocity = lock(&inner.cx.shared.latest).velocity.clone();
        let cycle = Cycle {
            now: inner.cx.shared.stream_now(),
            lead: done.lead,
            generation: inner.cx.shared.generation.load(Ordering::Relaxed),
            planned: &view.planned,
            measured: &view.measured,
            velocity: &view.velocity,
            commanded_velocity: &commanded_velocity,
        };
        let changes = lock(&inner.goals).cycle(&cycle, &inner.cx.robot.names);
        if changes.is_empty() {
            return;
        }
        for c in &changes {
            if let Change::Stop(_) = c {
                stop_and_hold(&inner.cx.to, &inner.cx.shared);
            }
        }
        inner.ended();
    }

    /// Ends every goal still running, answering its held queries.
    pub fn finish(&self, why: &str) {
        let ended = lock(&self.inner.goals).finish(why);
        if !ended.is_empty() {
            eprintln!(
                "follow_joint_trajectory: {} goal(s) aborted: {why}",
                ended.len()
            );
        }
        self.inner.answer(true);
    }
}

/// The feedback of the running goal `id` in the cycle `view`, at stream
/// time `now`.
fn feedback_of(id: Uuid, track: &Track, view: &View, now: f64) -> FeedbackMessage {
    let pick = |v: &[f64]| -> Vec<f64> { track.joints.iter().map(|&j| v[j]).collect() };
    let desired = pick(&view.planned);
    let actual: Vec<f64> = track
        .joints
        .iter()
        .map(|&j| view.measured[j].unwrap_or(view.commanded[j]))
        .collect();
    let error: Vec<f64> = desired.iter().zip(&actual).map(|(d, a)| d - a).collect();
    let since = RosDuration::from_secs_f64((now - track.start).max(0.0));
    let point = |positions: Vec<f64>, velocities: Vec<f64>| JointTrajectoryPoint {
        positions,
        velocities,
        time_from_start: since,
        ..Default::default()
    };
    FeedbackMessage {
        goal_id: id,
        feedback: FollowJointTrajectoryFeedback {
            header: Header {
                stamp: RosTime::from_ns(view.stamp_ns),
                frame_id: String::new(),
            },
            joint_names: track.names.clone(),
            desired: point(desired, Vec::new()),
            actual: point(actual, pick(&view.velocity)),
            error: point(error, Vec::new()),
            ..Default::default()
        },
    }
}

/// A queryable that answers late subscribers of `_action/status` with the
/// last status (what a transient-local publisher with a cache of 1 does,
/// on the key Zenoh's advanced subscribers ask for history under).
fn keep_last_status(
    session: &zenoh::Session,
    inner: &Arc<Inner>,
    status_id: u32,
) -> Result<Queryable<()>, NodeError> {
    let key = format!(
        "{}/@adv/pub/{}/{status_id}/_",
        inner.keys.status,
        session.zid()
    );
    let inner = Arc::clone(inner);
    let source: zenoh::time::TimestampId = session.zid().into();
    session
        .declare_queryable(key)
        .callback(move |query| {
            let Some((payload, attachment)) = lock(&inner.last_status).clone() else {
                return;
            };
            let sent = query
                .reply(inner.keys.status.clone(), payload)
                .attachment(attachment)
                .timestamp(timestamp(source))
                .wait();
            if let Err(e) = sent {
                eprintln!("follow_joint_trajectory: status: the reply could not be sent: {e}");
            }
        })
        .wait()
        .map_err(zerr)
}

/// Now, as the timestamp of a sample from `source`.
fn timestamp(source: zenoh::time::TimestampId) -> zenoh::time::Timestamp {
    let since = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    zenoh::time::Timestamp::new(since.into(), source)
}

impl Inner {
    /// Publishes `payload` on feedback (0) or status (1), with its
    /// attachment.
    fn put(&self, which: usize, payload: Vec<u8>) {
        let seq = self.seq[which].fetch_add(1, Ordering::Relaxed) + 1;
        let now = unix_ns(std::time::SystemTime::now());
        let attachment = crate::ros2::attachment(seq, now, &self.gids[which]);
        let publisher = if which == 0 {
            &self.feedback
        } else {
            &self.status
        };
        if which == 1 {
            *lock(&self.last_status) = Some((payload.clone(), attachment.clone()));
        }
        if let Err(e) = publisher.put(payload).attachment(attachment).wait() {
            eprintln!("follow_joint_trajectory: could not publish: {e}");
        }
    }

    /// Publishes the status, and answers the held `get_result` queries of
    /// goals that have ended (every one held when `all`).
    fn ended(&self) {
        self.answer(false);
    }

    fn answer(&self, all: bool) {
        // Goals, then the queries held: the order get_result locks them in.
        let goals = lock(&self.goals);
        let status = goals.status();
        let mut waiting = lock(&self.waiting);
        let mut due = Vec::new();
        let mut still = Vec::new();
        for w in waiting.drain(..) {
            match goals.result(w.goal) {
                Some(r) => due.push((w, r)),
                None if all => {
                    let r = crate::ros2::GetResultResponse {
                        status: crate::ros2::GoalStatus::STATUS_ABORTED,
                        result: Fjt {
                            error_code: Fjt::INVALID_GOAL,
                            error_string: "the node stopped".into(),
                        },
                    };
                    due.push((w, r));
                }
                None => still.push(w),
            }
        }
        *waiting = still;
        drop(waiting);
        drop(goals);
        self.put(1, status.encode());
        for (w, r) in due {
            self.reply(&w.query, &self.keys.get_result, r.encode(), &w.attachment);
        }
    }

    /// Replies `payload` to `query` on `key`, the attachment echoing the
    /// request's sequence number and GID.
    fn reply(&self, query: &Query, key: &str, payload: Vec<u8>, request: &Attachment) {
        let attachment = Attachment {
            sequence: request.sequence,
            stamp_ns: unix_ns(std::time::SystemTime::now()),
            gid: request.gid,
        };
        if let Err(e) = query
            .reply(key.to_string(), payload)
            .attachment(attachment.encode())
            .wait()
        {
            eprintln!("follow_joint_trajectory: the reply could not be sent: {e}");
        }
    }

    /// The request of `query`: its payload decoded and its attachment; on
    /// failure counted, said and answered with an error.
    fn request<T: CdrMessage>(&self, query: &Query, service: &str) -> Option<(T, Attachment)> {
        let attachment = query
            .attachment()
            .map(|a| a.to_bytes())
            .ok_or_else(|| "the request has no rmw_zenoh attachment".to_string())
            .and_then(|a| Attachment::decode(&a).map_err(|e| e.to_string()));
        let payload = query.payload().map(|p| p.to_bytes()).unwrap_or_default();
        let decoded = attachment.and_then(|a| {
            T::decode(&payload)
                .map(|t| (t, a))
                .map_err(|e| e.to_string())
        });
        match decoded {
            Ok(d) => Some(d),
            Err(why) => {
                self.cx
                    .malformed(&format!("follow_joint_trajectory {service}"), &why);
                if let Err(e) = query.reply_err(why).wait() {
                    eprintln!("follow_joint_trajectory: the error reply could not be sent: {e}");
                }
                None
            }
        }
    }

    fn send_goal(&self, query: Query) {
        let Some((req, att)) = self.request::<SendGoalRequest>(&query, "send_goal") else {
            return;
        };
        let at = Arrival::now(&self.cx.shared);
        let stamp = RosTime::from_ns(at.unix_ns);
        let accepted = match self.start(&req, &at) {
            Ok(()) => true,
            Err((code, why)) => {
                eprintln!("follow_joint_trajectory: goal refused: {why}");
                lock(&self.goals).refuse(req.goal_id, stamp, code, why);
                false
            }
        };
        let response = SendGoalResponse { accepted, stamp };
        self.reply(&query, &self.keys.send_goal, response.encode(), &att);
        if accepted {
            self.ended();
        }
    }

    /// Checks the goal of `req`, then sends it and records it running.
    fn start(&self, req: &SendGoalRequest, at: &Arrival) -> Result<(), (i32, String)> {
        let goal = &req.goal;
        if goal.has_multi_dof() {
            let why = "multi-DOF trajectories and component tolerances are not supported".into();
            return Err((Fjt::INVALID_JOINTS, why));
        }
        let robot = &self.cx.robot.names;
        let names = &goal.trajectory.joint_names;
        let invalid = |why| (Fjt::INVALID_JOINTS, why);
        let path = tolerances(&goal.path_tolerance, names, robot, false).map_err(invalid)?;
        let ends = tolerances(&goal.goal_tolerance, names, robot, true).map_err(invalid)?;
        let planned = plan_arrival(&goal.trajectory, at, &self.cx).map_err(|r| (r.code, r.why))?;
        let goal_time = match goal.goal_time_tolerance.as_secs_f64() {
            t if t > 0.0 => t,
            _ => DEFAULT_GOAL_TIME,
        };
        // A goal running gives way first: its own checks end now.
        let preempted = lock(&self.goals).preempt();
        if preempted.is_some() {
            self.ended();
        }
        let into = (&self.cx.to, &*self.cx.shared, &self.cx.robot);
        let sent = send_planned(&planned, at.stream, at.instant, into)
            .map_err(|e| (Fjt::INVALID_GOAL, format!("the stream refused it: {e}")))?;
        if sent > 0 {
            eprintln!("follow_joint_trajectory: {sent} angle(s) clamped to the joint limits");
        }
        let track = Track {
            names: planned.joints.iter().map(|&j| robot[j].clone()).collect(),
            joints: planned.joints,
            path,
            goal: ends,
            goal_time,
            start: planned.start,
            end: planned.end,
            last: planned.last,
            generation: self.cx.shared.generation.load(Ordering::Relaxed),
        };
        lock(&self.goals).accept(req.goal_id, RosTime::from_ns(at.unix_ns), track);
        self.cx.shared.counts.goals.fetch_add(1, Ordering::Relaxed);
        Ok(())
    }

    fn cancel_goal(&self, query: Query) {
        let Some((req, att)) = self.request::<CancelGoalRequest>(&query, "cancel_goal") else {
            return;
        };
        let now = self.cx.shared.stream_now();
        let (response, stop) = lock(&self.goals).cancel(&req, now);
        if stop {
            stop_and_hold(&self.cx.to, &self.cx.shared);
        }
        self.reply(&query, &self.keys.cancel_goal, response.encode(), &att);
        if stop {
            self.ended();
        }
    }

    fn get_result(&self, query: Query) {
        let Some((req, att)) = self.request::<GetResultRequest>(&query, "get_result") else {
            return;
        };
        let goals = lock(&self.goals);
        if let Some(r) = goals.result(req.goal_id) {
            drop(goals);
            return self.reply(&query, &self.keys.get_result, r.encode(), &att);
        }
        let mut waiting = lock(&self.waiting);
        if waiting.len() < MOST_WAITING {
            waiting.push(Waiting {
                goal: req.goal_id,
                query,
                attachment: att,
            });
            return;
        }
        drop(waiting);
        drop(goals);
        let why = "too many get_result requests are waiting; ask again later";
        if let Err(e) = query.reply_err(why).wait() {
            eprintln!("follow_joint_trajectory: the error reply could not be sent: {e}");
        }
    }
}
