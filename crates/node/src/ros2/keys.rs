//! The names rmw_zenoh gives ROS 2 entities on Zenoh: data key
//! expressions, liveliness tokens and the attachment of every sample.
//!
//! ```text
//! data key:   <domain>/<fully qualified name without its leading />/<DDS type>/<RIHS01 hash>
//! liveliness: @ros2_lv/<domain>/<zid>/<node id>/<entity id>/<kind>/<enclave>/<namespace>/<node>
//!             [/<name>/<DDS type>/<hash>/<qos>]          names mangled with / -> %, empty -> %
//! attachment: sequence (i64 LE) | source stamp, ns (i64 LE) | 16 (u8) | GID (16 bytes)
//! ```
//!
//! A service is keyed by its service type (for an action's services,
//! e.g. `control_msgs::action::dds_::FollowJointTrajectory_SendGoal_`) and
//! the service type's hash; a topic by its message type and hash. An action
//! server is three service servers and two publishers under
//! `<action>/_action/`.
//!
//! | kind | entity |
//! |---|---|
//! | `NN` | node |
//! | `MP` | publisher |
//! | `MS` | subscription |
//! | `SS` | service server |
//! | `SC` | service client |

use super::hash::TypeDescription;
use super::types;

/// The DDS type name rmw_zenoh uses for `sensor_msgs/msg/JointState`.
pub const JOINT_STATE_TYPE: &str = "sensor_msgs::msg::dds_::JointState_";

/// The QoS in rmw_zenoh's compact key form: reliable, volatile, keep the
/// last 10, no deadline, lifespan or liveliness lease (the defaults). Also
/// what ROS 2 services and action feedback use.
pub const QOS_KEEP_LAST_10: &str = "::,10:,:,:,,";

/// The QoS of an action's `_action/status` topic: reliable, transient
/// local, keep the last 1 (rcl_action's status default).
pub const QOS_ACTION_STATUS: &str = ":1:,1:,:,:,,";

/// The RIHS01 type hash of `sensor_msgs/msg/JointState`.
pub fn joint_state_type_hash() -> String {
    types::JOINT_STATE.rihs01()
}

/// The fully qualified topic of a robot's joint states: `/<robot>/joint_states`.
pub fn joint_states_topic(robot: &str) -> String {
    format!("/{}/joint_states", ros_name(robot))
}

/// `name` made a valid ROS name token: letters, digits and `_`, not
/// starting with a digit.
pub fn ros_name(name: &str) -> String {
    let mut out: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

/// A namespace made valid and absolute: `""` for the root, otherwise
/// `/a/b`, each token made a ROS name ([`ros_name`]), empty tokens dropped.
pub fn ros_namespace(namespace: &str) -> String {
    namespace
        .split('/')
        .filter(|t| !t.is_empty())
        .map(|t| format!("/{}", ros_name(t)))
        .collect()
}

/// The fully qualified name of `name` in `namespace`: `/<ns>/<name>`.
pub fn name_in(namespace: &str, name: &str) -> String {
    format!("{}/{name}", ros_namespace(namespace))
}

/// The data key expression of the topic or service `name` (fully
/// qualified) carrying `ty`, in `domain`.
pub fn data_key(domain: u32, name: &str, ty: &TypeDescription) -> String {
    format!(
        "{domain}/{}/{}/{}",
        name.trim_matches('/'),
        ty.dds_name(),
        ty.rihs01()
    )
}

/// The data key expression of a robot's joint states in `domain`.
pub fn joint_states_key(domain: u32, robot: &str) -> String {
    data_key(domain, &joint_states_topic(robot), &types::JOINT_STATE)
}

/// The key of `<ns>/joint_trajectory` (`trajectory_msgs/msg/JointTrajectory`).
pub fn joint_trajectory_key(domain: u32, namespace: &str) -> String {
    let topic = name_in(namespace, "joint_trajectory");
    data_key(domain, &topic, &types::JOINT_TRAJECTORY)
}

/// The keys of `<ns>/joint_commands`, one per type it takes:
/// `sensor_msgs/msg/JointState`, then `std_msgs/msg/Float64MultiArray`.
pub fn joint_commands_keys(domain: u32, namespace: &str) -> [String; 2] {
    let topic = name_in(namespace, "joint_commands");
    [
        data_key(domain, &topic, &types::JOINT_STATE),
        data_key(domain, &topic, &types::FLOAT64_MULTI_ARRAY),
    ]
}

/// The five Zenoh keys of an action server, as rmw_zenoh maps an action.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ActionKeys {
    /// `_action/send_goal`, a queryable.
    pub send_goal: String,
    /// `_action/cancel_goal`, a queryable.
    pub cancel_goal: String,
    /// `_action/get_result`, a queryable.
    pub get_result: String,
    /// `_action/feedback`, published.
    pub feedback: String,
    /// `_action/status`, published (transient local).
    pub status: String,
}

/// The name of an action's part: `<action>/_action/<part>`.
fn action_part(action: &str, part: &str) -> String {
    format!("{action}/_action/{part}")
}

/// The services and topics of an action server, in the order the keys
/// and tokens list them: send_goal, cancel_goal, get_result (services),
/// feedback, status (topics).
fn action_parts() -> [(&'static str, &'static TypeDescription); 5] {
    [
        ("send_goal", &types::FJT_SEND_GOAL),
        ("cancel_goal", &types::CANCEL_GOAL),
        ("get_result", &types::FJT_GET_RESULT),
        ("feedback", &types::FJT_FEEDBACK_MESSAGE),
        ("status", &types::GOAL_STATUS_ARRAY),
    ]
}

/// The keys of `<ns>/follow_joint_trajectory`
/// (`control_msgs/action/FollowJointTrajectory`).
pub fn follow_joint_trajectory_keys(domain: u32, namespace: &str) -> ActionKeys {
    let action = name_in(namespace, "follow_joint_trajectory");
    let [send_goal, cancel_goal, get_result, feedback, status] =
        action_parts().map(|(part, ty)| data_key(domain, &action_part(&action, part), ty));
    ActionKeys {
        send_goal,
        cancel_goal,
        get_result,
        feedback,
        status,
    }
}

/// The node's name: `servobus_<robot>`.
pub fn node_name(robot: &str) -> String {
    format!("servobus_{}", ros_name(robot))
}

/// A name with every `/` replaced by `%` (an empty name is `%`).
fn mangle(name: &str) -> String {
    if name.is_empty() {
        "%".into()
    } else {
        name.replace('/', "%")
    }
}

/// What kind of entity a liveliness token announces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EntityKind {
    /// A publisher (`MP`).
    Publisher,
    /// A subscription (`MS`).
    Subscription,
    /// A service server (`SS`).
    ServiceServer,
    /// A service client (`SC`).
    ServiceClient,
}

impl EntityKind {
    /// The kind's two letters in a token.
    pub fn code(self) -> &'static str {
        match self {
            EntityKind::Publisher => "MP",
            EntityKind::Subscription => "MS",
            EntityKind::ServiceServer => "SS",
            EntityKind::ServiceClient => "SC",
        }
    }
}

/// A ROS 2 node as rmw_zenoh announces it: the Zenoh session, the node's
/// id in it (servobus has one node per session: 0), namespace and name.
#[derive(Debug, Clone, Copy)]
pub struct RosNode<'a> {
    /// The ROS domain.
    pub domain: u32,
    /// The Zenoh session's id, in hex as Zenoh prints it.
    pub session_id: &'a str,
    /// The node's namespace (`""` for the root).
    pub namespace: &'a str,
    /// The node's name.
    pub name: &'a str,
}

impl RosNode<'_> {
    /// The token's part up to the node's name, for entity `id` of `kind`.
    fn prefix(&self, id: u32, kind: &str) -> String {
        format!(
            "@ros2_lv/{}/{}/0/{id}/{kind}/%/{}/{}",
            self.domain,
            self.session_id,
            mangle(&ros_namespace(self.namespace)),
            mangle(self.name)
        )
    }

    /// The node's own token.
    pub fn token(&self) -> String {
        self.prefix(0, "NN")
    }

    /// The token of entity `id` (unique in the session, not 0) of `kind`
    /// on the topic or service `name` (fully qualified) carrying `ty`.
    pub fn entity_token(
        &self,
        id: u32,
        kind: EntityKind,
        name: &str,
        ty: &TypeDescription,
        qos: &str,
    ) -> String {
        format!(
            "{}/{}/{}/{}/{qos}",
            self.prefix(id, kind.code()),
            mangle(name),
            mangle(&ty.dds_name()),
            ty.rihs01()
        )
    }

    /// The token of a subscription to `topic`, QoS keep-last-10.
    pub fn subscription_token(&self, id: u32, topic: &str, ty: &TypeDescription) -> String {
        self.entity_token(id, EntityKind::Subscription, topic, ty, QOS_KEEP_LAST_10)
    }

    /// The token of a server of the service `service` of type `ty`.
    pub fn service_token(&self, id: u32, service: &str, ty: &TypeDescription) -> String {
        self.entity_token(id, EntityKind::ServiceServer, service, ty, QOS_KEEP_LAST_10)
    }

    /// The five tokens of a `FollowJointTrajectory` server on `action`
    /// (fully qualified), entity ids `first_id..first_id + 5`: send_goal,
    /// cancel_goal, get_result (service servers), feedback, status
    /// (publishers).
    pub fn action_server_tokens(&self, first_id: u32, action: &str) -> [String; 5] {
        let mut id = first_id;
        action_parts().map(|(part, ty)| {
            let name = action_part(action, part);
            let token = match part {
                "feedback" => {
                    self.entity_token(id, EntityKind::Publisher, &name, ty, QOS_KEEP_LAST_10)
                }
                "status" => {
                    self.entity_token(id, EntityKind::Publisher, &name, ty, QOS_ACTION_STATUS)
                }
                _ => self.service_token(id, &name, ty),
            };
            id += 1;
            token
        })
    }
}

/// The liveliness tokens of the node and of its JointState publisher, for
/// the Zenoh session `session_id` (hex, as Zenoh prints it).
pub fn liveliness_tokens(domain: u32, session_id: &str, robot: &str) -> [String; 2] {
    let name = node_name(robot);
    let node = RosNode {
        domain,
        session_id,
        namespace: "",
        name: &name,
    };
    let publisher = node.entity_token(
        10,
        EntityKind::Publisher,
        &joint_states_topic(robot),
        &types::JOINT_STATE,
        QOS_KEEP_LAST_10,
    );
    [node.token(), publisher]
}

/// The attachment rmw_zenoh subscribers require with every sample.
pub fn attachment(sequence: i64, stamp_ns: i64, gid: &[u8; 16]) -> Vec<u8> {
    Attachment {
        sequence,
        stamp_ns,
        gid: *gid,
    }
    .encode()
}

/// An rmw_zenoh attachment: what a service request carries and its reply
/// must echo (the sequence number and the client's GID).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Attachment {
    /// The sample's (or request's) sequence number.
    pub sequence: i64,
    /// When it was sent, ns since the UNIX epoch.
    pub stamp_ns: i64,
    /// The sender's GID.
    pub gid: [u8; 16],
}

/// Why bytes are not an rmw_zenoh attachment.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum AttachmentError {
    /// Not the 33 bytes of one.
    #[error("an rmw_zenoh attachment has 33 bytes, not {found}")]
    Length {
        /// The bytes found.
        found: usize,
    },
    /// The GID's length byte is not 16.
    #[error("the attachment's GID length is {found}, not 16")]
    GidLength {
        /// The length byte found.
        found: u8,
    },
}

impl Attachment {
    /// The 33 bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(33);
        out.extend_from_slice(&self.sequence.to_le_bytes());
        out.extend_from_slice(&self.stamp_ns.to_le_bytes());
        out.push(16);
        out.extend_from_slice(&self.gid);
        out
    }

    /// An attachment from its bytes.
    ///
    /// # Errors
    /// [`AttachmentError`] when the bytes are not 33 or the GID's length
    /// is not 16.
    pub fn decode(bytes: &[u8]) -> Result<Self, AttachmentError> {
        let bytes: &[u8; 33] = bytes
            .try_into()
            .map_err(|_| AttachmentError::Length { found: bytes.len() })?;
        let (head, rest) = bytes.split_at(16);
        let (len, gid) = rest.split_at(1);
        if len[0] != 16 {
            return Err(AttachmentError::GidLength { found: len[0] });
        }
        let mut seq = [0u8; 8];
        let mut stamp = [0u8; 8];
        seq.copy_from_slice(&head[..8]);
        stamp.copy_from_slice(&head[8..]);
        let mut out = [0u8; 16];
        out.copy_from_slice(gid);
        Ok(Attachment {
            sequence: i64::from_le_bytes(seq),
            stamp_ns: i64::from_le_bytes(stamp),
            gid: out,
        })
    }
}
