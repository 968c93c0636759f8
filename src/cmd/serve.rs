//! `servobus serve`: the robot's loop in live mode as a Zenoh node
//! (`servobus_node`): state out, targets and commands in, the report as a
//! queryable, a liveliness token, and optionally ROS 2 JointState the way
//! rmw_zenoh publishes it. Built with `--features zenoh`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use servobus_config::{
    load_motion_calibrated, load_motion_text, load_robot, plan_motion, RobotOptions,
};
use servobus_node::node::{
    group_command_key, group_member_key, open_session, serve, NodeConfig, RobotInfo,
};
use servobus_node::wire::NodeCommand;
use servobus_node::zenoh::Wait;
use servobus_robot::{live_options, Command, RunOptions};

use crate::shared::out::{errln, outln};

/// Arguments of `servobus serve`.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Keys, under servobus/<name>/: state (published), target (subscribed: \
{\"t\": s, \"joints\": {\"<joint>\": angle}} or an action chunk \
{\"chunk\": {\"t0\": s, \"dt\": s, \"joints\": {\"<joint>\": [angle, ...]}}}), \
command (subscribed), report (queryable), alive (liveliness).

With --ros2 (rmw_zenoh's layout, ROS domain --ros-domain), under the namespace \
--ros-namespace (default /<name>): joint_states (published), joint_trajectory \
(trajectory_msgs/JointTrajectory), joint_commands (sensor_msgs/JointState or \
std_msgs/Float64MultiArray, rad) and the follow_joint_trajectory action \
(control_msgs/action/FollowJointTrajectory).

Commands: play <motion> [at <UTC time>]; stop (the joints stop, jerk limited, \
and hold: the node goes on serving, and the next target, chunk or play moves \
the robot again); pause; resume; torque_off; shutdown (stop, hold and end the \
node, as Ctrl-C and SIGTERM do). Once the run has ended the node answers \
report for --linger seconds, then exits.")]
pub struct Args {
    /// The robot file, or a built-in robot's name, and its port and
    /// calibration.
    #[command(flatten)]
    pub robot: crate::shared::flags::RobotArgs,
    /// `--write-servos`: store what the robot file asks of the servos'
    /// EEPROM before the run.
    #[command(flatten)]
    pub store: crate::shared::flags::WriteServosArg,
    /// A Zenoh configuration file (JSON5): authentication, TLS, scouting.
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
    /// Listen on this endpoint (repeatable; default tcp/127.0.0.1:7447,
    /// loopback only).
    #[arg(long, value_name = "ENDPOINT")]
    pub listen: Vec<String>,
    /// Connect to this peer (repeatable), e.g. tcp/192.168.1.20:7447.
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Vec<String>,
    /// The robot's name on the network, `servobus/<name>/...` (default:
    /// the robot file's name).
    #[arg(long)]
    pub name: Option<String>,
    /// Also take commands sent to this group (`play --zenoh-group`).
    #[arg(long)]
    pub group: Option<String>,
    /// How often `state` is published, Hz.
    #[arg(long, default_value = "50", value_parser = crate::shared::args::refresh_rate_arg)]
    pub state_hz: f64,
    /// ROS 2 over rmw_zenoh: publish <ns>/joint_states; take
    /// <ns>/joint_trajectory, <ns>/joint_commands and the
    /// <ns>/follow_joint_trajectory action.
    #[arg(long)]
    pub ros2: bool,
    /// The ROS domain of the ROS 2 topics and action.
    #[arg(long, default_value_t = 0, requires = "ros2")]
    pub ros_domain: u32,
    /// The ROS 2 namespace of the topics and action (default: the robot's
    /// name; `/` for the root, as a controller manager's topics are).
    #[arg(long, value_name = "NS", requires = "ros2")]
    pub ros_namespace: Option<String>,
    /// Control rate in Hz (default: the robot's).
    #[arg(long, value_parser = crate::shared::args::rate_arg)]
    pub rate: Option<f64>,
    /// Seconds without a target after which the joints stop (jerk
    /// limited) and hold until targets come back.
    #[arg(long, default_value = "0.25", value_parser = crate::shared::args::timeout_arg)]
    pub timeout: Duration,
    /// Seconds the node keeps answering `report` after the run ends.
    #[arg(long, default_value_t = 2.0)]
    pub linger: f64,
    /// Print the report and the node's counts as one JSON line on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Runs `servobus serve`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if !(args.linger.is_finite() && args.linger >= 0.0 && args.linger <= 3600.0) {
        return Err(crate::shared::exit::input(format!(
            "--linger {}: give 0 to 3600 seconds",
            args.linger
        )));
    }
    let calibration = args.robot.hardware.calibration.clone();
    let robot = load_robot(
        &args.robot.path,
        &RobotOptions::default().calibration(calibration.as_deref()),
    )?;
    let config = NodeConfig {
        zenoh_config: args.zenoh_config.clone(),
        listen: args.listen.clone(),
        connect: args.connect.clone(),
        ros2_domain: args.ros2.then_some(args.ros_domain),
        ros_namespace: args.ros_namespace.clone(),
        state_hz: args.state_hz,
        group: args.group.clone(),
    };
    // The network first: a node that cannot join never moves the robot.
    let session = open_session(&config).map_err(|e| crate::shared::exit::input(e.to_string()))?;
    let options = RunOptions {
        rate_hz: args.rate,
        target_timeout: args.timeout,
        ..live_options(&robot)
    };
    let rate_hz = args.rate.unwrap_or(robot.rate_hz);
    let runner = crate::shared::ports::start_live(
        &robot,
        args.robot.hardware.port.as_deref(),
        options,
        args.store.write_servos,
    )?;
    crate::shared::install_ctrl_c(runner.commands());
    let info = RobotInfo {
        name: args.name.clone().unwrap_or_else(|| robot.name.clone()),
        joints: robot.joints().map(|j| j.name.clone()).collect(),
        units: robot.units,
        rate_hz,
        config: Some(robot.clone()),
    };
    let robot_path = robot.path.clone();
    let planner =
        Box::new(move |motion: &str| plan_command(motion, &robot_path, calibration.as_deref()));
    errln!(
        "serving {} on servobus/{}/ (state at {} Hz); `shutdown` or Ctrl-C ends the node",
        robot.name,
        servobus_node::key_chunk(&info.name),
        args.state_hz
    );
    let served = serve(
        &session,
        &info,
        runner,
        planner,
        &config,
        Duration::try_from_secs_f64(args.linger).unwrap_or_default(),
    )?;
    print_served(&served, args.json)?;
    Ok(crate::shared::exit::of_finish(served.report.finish))
}

/// The end of `serve`: the report and the node's counts, as one JSON line
/// on stdout with `--json`, else as text on stderr.
fn print_served(served: &servobus_node::node::Served, json: bool) -> anyhow::Result<()> {
    if json {
        outln!(
            "{}",
            serde_json::json!({
                "report": served.report,
                "node": served.counts(),
            })
        )?;
        return Ok(());
    }
    let mut err = std::io::stderr().lock();
    crate::shared::write_report(&mut err, &served.report, false)?;
    errln!(
        "  node: {} targets, {} malformed, {} commands, {} trajectories, {} goals, \
         {} states published",
        served.targets,
        served.malformed,
        served.commands,
        served.trajectories,
        served.goals,
        served.states
    );
    for o in &served.start_offsets {
        errln!("  timed start: {:+.2} ms from the agreed instant", o * 1e3);
    }
    Ok(())
}

/// The command that plays `motion` (a built-in motion's name, a file, or
/// YAML text) on this robot.
fn plan_command(motion: &str, robot: &Path, calibration: Option<&Path>) -> Result<Command, String> {
    let (m, r) = if motion.contains('\n') || motion.trim_start().starts_with('{') {
        // YAML text: the same checks as a file's, errors pointing at its
        // lines.
        load_motion_text(Path::new("<motion text>"), motion, Some(robot), calibration)
    } else {
        let path = servobus::builtin::motion_path_or_name(Path::new(motion.trim()));
        load_motion_calibrated(&path, Some(robot), calibration)
    }
    .map_err(|e| e.to_string())?;
    let trajectory = plan_motion(&m, &r).map_err(|e| e.to_string())?;
    Ok(Command::replace(trajectory))
}

/// `play MOTION --zenoh-group NAME`: tells every robot serving in the
/// group to play the motion `start_in` from now, on the same control
/// cycle. A shipped motion goes by name; a file goes as its text (each
/// robot plans it for itself).
pub(crate) fn announce(
    motion: &Path,
    group: &str,
    start_in: Duration,
    connect: &[String],
) -> anyhow::Result<ExitCode> {
    let what = match servobus::builtin::builtin_name(motion) {
        Some(name) => name.to_string(),
        None => std::fs::read_to_string(motion)
            .map_err(|e| crate::shared::exit::input(format!("{}: {e}", motion.display())))?,
    };
    let config = NodeConfig {
        connect: connect.to_vec(),
        // A conductor listens nowhere: it only reaches the robots named.
        listen: vec![],
        ..NodeConfig::default()
    };
    let session = open_conductor(&config)?;
    // Who serves the group (each robot declares itself while serving).
    let members: Vec<String> = session
        .liveliness()
        .get(group_member_key(group, "*"))
        .timeout(Duration::from_secs(2))
        .wait()
        .map_err(|e| crate::shared::exit::input(format!("zenoh: {e}")))?
        .iter()
        .filter_map(|r| {
            r.result().ok().map(|s| {
                s.key_expr()
                    .as_str()
                    .rsplit('/')
                    .next()
                    .unwrap_or("")
                    .to_string()
            })
        })
        .collect();
    if members.is_empty() {
        errln!("no robot serves group `{group}` at the given endpoints (--connect); nothing sent");
        return Ok(ExitCode::from(1));
    }
    let at = std::time::SystemTime::now() + start_in;
    let at_s = at
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64());
    let command = NodeCommand::Play {
        motion: what,
        at: Some(at),
    };
    session
        .put(group_command_key(group), command.to_string())
        .wait()
        .map_err(|e| crate::shared::exit::input(format!("zenoh: {e}")))?;
    // Let the put leave before the session closes.
    std::thread::sleep(Duration::from_millis(300));
    outln!(
        "group {group}: {} robot(s) ({}) start {} at UNIX {at_s:.3}",
        members.len(),
        members.join(", "),
        servobus::builtin::argument(motion)
    )?;
    Ok(ExitCode::SUCCESS)
}

/// A session for a program that only talks to robots: no listening, no
/// multicast, connected to `config.connect`.
fn open_conductor(config: &NodeConfig) -> anyhow::Result<servobus_node::zenoh::Session> {
    if config.connect.is_empty() {
        return Err(crate::shared::exit::input(
            "--zenoh-group needs --connect ENDPOINT for each robot (or a router)".to_string(),
        ));
    }
    servobus_node::node::open_peer(config).map_err(|e| crate::shared::exit::input(e.to_string()))
}
