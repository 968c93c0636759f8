//! The keys a serving robot declares, held for as long as it serves: its
//! liveliness, `state`, `target`, `command`, `report` and, with ROS 2 on,
//! its ROS 2 entities ([`super::ros`]).

use std::sync::Arc;

use servobus_robot::Run;
use zenoh::bytes::Encoding;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::query::Queryable;
use zenoh::Wait;

use super::relay::{take_command, take_target, Inputs};
use super::ros::Ros2;
use super::{
    group_command_key, group_member_key, lock, zerr, NodeConfig, NodeError, Planner, RobotInfo,
    Shared,
};
use crate::prefix;

/// The robot's declared keys; dropping them undeclares them.
pub(super) struct Keys {
    // Fields drop in the order they are written: the reverse of the order
    // they are declared in.
    /// The ROS 2 side, with ROS 2 on.
    pub(super) ros: Option<Ros2>,
    _report: Queryable<()>,
    _commands: Vec<Subscriber<()>>,
    _targets: Subscriber<()>,
    /// The `state` publisher.
    pub(super) state: Publisher<'static>,
    _member: Option<LivelinessToken>,
    _alive: LivelinessToken,
}

impl Keys {
    /// Declares every key of `robot` on `session`, its callbacks feeding
    /// `runner` and sharing `shared`.
    ///
    /// # Errors
    /// [`NodeError::Zenoh`] when a key cannot be declared.
    pub(super) fn declare(
        session: &zenoh::Session,
        robot: &RobotInfo,
        runner: &Run,
        planner: Box<Planner>,
        config: &NodeConfig,
        shared: &Arc<Shared>,
    ) -> Result<Keys, NodeError> {
        let base = prefix(&robot.name);
        let alive = session
            .liveliness()
            .declare_token(format!("{base}/alive"))
            .wait()
            .map_err(zerr)?;
        let member = match &config.group {
            Some(g) => Some(
                session
                    .liveliness()
                    .declare_token(group_member_key(g, &robot.name))
                    .wait()
                    .map_err(zerr)?,
            ),
            None => None,
        };
        let state = session
            .declare_publisher(format!("{base}/state"))
            .encoding(Encoding::APPLICATION_JSON)
            .wait()
            .map_err(zerr)?;
        let targets = subscribe_targets(session, &base, robot, runner, shared)?;
        let commands = subscribe_commands(session, &base, robot, runner, planner, config, shared)?;
        let report = answer_reports(session, &base, shared)?;
        let ros = match config.ros2_domain {
            Some(domain) => Some(Ros2::declare(
                session,
                domain,
                robot,
                config,
                inputs(runner),
                shared,
            )?),
            None => None,
        };
        Ok(Keys {
            ros,
            _report: report,
            _commands: commands,
            _targets: targets,
            state,
            _member: member,
            _alive: alive,
        })
    }
}

/// The loop's two inputs, for one more callback.
fn inputs(runner: &Run) -> Inputs {
    Inputs {
        targets: runner.targets(),
        commands: runner.commands(),
    }
}

/// Subscribes `base/target`: targets and chunks into the stream.
fn subscribe_targets(
    session: &zenoh::Session,
    base: &str,
    robot: &RobotInfo,
    runner: &Run,
    shared: &Arc<Shared>,
) -> Result<Subscriber<()>, NodeError> {
    let to = inputs(runner);
    let shared = Arc::clone(shared);
    let units = robot.units;
    let config = robot.config.clone();
    let started = shared.started;
    session
        .declare_subscriber(format!("{base}/target"))
        .callback(move |sample| {
            let robot = (units, config.as_ref());
            take_target(&sample.payload().to_bytes(), &to, robot, started, &shared);
        })
        .wait()
        .map_err(zerr)
}

/// Subscribes `base/command` and, in a group, the group's command key.
fn subscribe_commands(
    session: &zenoh::Session,
    base: &str,
    robot: &RobotInfo,
    runner: &Run,
    planner: Box<Planner>,
    config: &NodeConfig,
    shared: &Arc<Shared>,
) -> Result<Vec<Subscriber<()>>, NodeError> {
    let period = 1.0 / robot.rate_hz;
    let planner: Arc<Planner> = Arc::from(planner);
    let mut command_keys = vec![format!("{base}/command")];
    if let Some(g) = &config.group {
        command_keys.push(group_command_key(g));
    }
    let mut commands = Vec::new();
    for key in command_keys {
        let to = inputs(runner);
        let shared = Arc::clone(shared);
        let planner = Arc::clone(&planner);
        commands.push(
            session
                .declare_subscriber(key)
                .callback(move |sample| {
                    take_command(
                        &sample.payload().to_bytes(),
                        &to,
                        &*planner,
                        period,
                        &shared,
                    );
                })
                .wait()
                .map_err(zerr)?,
        );
    }
    Ok(commands)
}

/// Declares `base/report`, which answers with what `shared` holds.
fn answer_reports(
    session: &zenoh::Session,
    base: &str,
    shared: &Arc<Shared>,
) -> Result<Queryable<()>, NodeError> {
    let shared = Arc::clone(shared);
    session
        .declare_queryable(format!("{base}/report"))
        .callback(move |query| {
            let text = lock(&shared.report).clone();
            let key = query.key_expr().clone();
            if let Err(e) = query
                .reply(key, text)
                .encoding(Encoding::APPLICATION_JSON)
                .wait()
            {
                eprintln!("report: the reply could not be sent: {e}");
            }
        })
        .wait()
        .map_err(zerr)
}
