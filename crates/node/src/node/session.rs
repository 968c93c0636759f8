//! Opening a node's Zenoh session (loopback, no multicast scouting unless
//! a config file turns it on) and the keys robots started together share.

use std::path::PathBuf;

use zenoh::Wait;

/// Where the node listens by default: loopback only, Zenoh's usual port.
pub const DEFAULT_LISTEN: &str = "tcp/127.0.0.1:7447";

/// How a node joins the network.
#[derive(Debug, Clone, Default)]
pub struct NodeConfig {
    /// A Zenoh configuration file (JSON5), for authentication, TLS or
    /// scouting. Its settings stand unless `listen`/`connect` override.
    pub zenoh_config: Option<PathBuf>,
    /// Endpoints to listen on; none: [`DEFAULT_LISTEN`] (unless the
    /// config file names some).
    pub listen: Vec<String>,
    /// Peers to connect to.
    pub connect: Vec<String>,
    /// ROS 2 in this ROS domain, if wanted: JointState out; trajectories,
    /// joint commands and the FollowJointTrajectory action in.
    pub ros2_domain: Option<u32>,
    /// The ROS 2 namespace of the node's topics and action (`None`: the
    /// robot's name, `/<robot>/joint_states`; `"/"`: the root).
    pub ros_namespace: Option<String>,
    /// How often `state` is published, Hz.
    pub state_hz: f64,
    /// A group whose commands this robot also takes, from
    /// `servobus/group/<group>/command` (robots started together).
    pub group: Option<String>,
}

/// Why a node could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NodeError {
    /// The Zenoh configuration could not be read or set.
    #[error("zenoh configuration: {0}")]
    Config(String),
    /// The session or one of its keys could not be declared.
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// The run could not be joined.
    #[error(transparent)]
    Run(#[from] servobus_robot::Error),
}

pub(super) fn zerr(e: impl std::fmt::Display) -> NodeError {
    NodeError::Zenoh(e.to_string())
}

/// Opens a Zenoh session per `config`: peer mode; loopback listening and
/// multicast scouting off unless the configuration file says otherwise.
pub fn open_session(config: &NodeConfig) -> Result<zenoh::Session, NodeError> {
    let cerr = |e: zenoh::Error| NodeError::Config(e.to_string());
    let (mut z, from_file) = match &config.zenoh_config {
        Some(path) => (
            zenoh::Config::from_file(path)
                .map_err(|e| NodeError::Config(format!("{}: {e}", path.display())))?,
            true,
        ),
        None => (zenoh::Config::default(), false),
    };
    if !from_file {
        z.insert_json5("mode", "\"peer\"").map_err(cerr)?;
        z.insert_json5("scouting/multicast/enabled", "false")
            .map_err(cerr)?;
    }
    let listen = if config.listen.is_empty() && !from_file {
        vec![DEFAULT_LISTEN.to_string()]
    } else {
        config.listen.clone()
    };
    if !listen.is_empty() {
        let json = serde_json::to_string(&listen).map_err(|e| NodeError::Config(e.to_string()))?;
        z.insert_json5("listen/endpoints", &json).map_err(cerr)?;
    }
    if !config.connect.is_empty() {
        let json =
            serde_json::to_string(&config.connect).map_err(|e| NodeError::Config(e.to_string()))?;
        z.insert_json5("connect/endpoints", &json).map_err(cerr)?;
    }
    zenoh::open(z).wait().map_err(zerr)
}

/// The key a group's commands travel on: `servobus/group/<group>/command`.
pub fn group_command_key(group: &str) -> String {
    format!("servobus/group/{}/command", crate::key_chunk(group))
}

/// The liveliness token of a group member: `servobus/group/<group>/members/<robot>`.
pub fn group_member_key(group: &str, robot: &str) -> String {
    let robot = if robot == "*" {
        "*".to_string()
    } else {
        crate::key_chunk(robot)
    };
    format!("servobus/group/{}/members/{robot}", crate::key_chunk(group))
}

/// Opens a session for a program that talks to nodes without being one:
/// peer mode, no multicast, listening only where `config.listen` says
/// (nowhere by default), connected to `config.connect`.
///
/// # Errors
/// [`NodeError::Config`] or [`NodeError::Zenoh`] as [`open_session`].
pub fn open_peer(config: &NodeConfig) -> Result<zenoh::Session, NodeError> {
    let cerr = |e: zenoh::Error| NodeError::Config(e.to_string());
    let mut z = zenoh::Config::default();
    z.insert_json5("mode", "\"peer\"").map_err(cerr)?;
    z.insert_json5("scouting/multicast/enabled", "false")
        .map_err(cerr)?;
    let json =
        |v: &[String]| serde_json::to_string(v).map_err(|e| NodeError::Config(e.to_string()));
    z.insert_json5("listen/endpoints", &json(&config.listen)?)
        .map_err(cerr)?;
    z.insert_json5("connect/endpoints", &json(&config.connect)?)
        .map_err(cerr)?;
    zenoh::open(z).wait().map_err(zerr)
}
