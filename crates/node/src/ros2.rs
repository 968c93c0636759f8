//! ROS 2 `sensor_msgs/msg/JointState` the way rmw_zenoh publishes a topic:
//! the key expression, the CDR payload, the attachment and the liveliness
//! tokens that make the topic visible to `ros2 topic list`. No ROS
//! installation is needed: everything here is computed from the message
//! definition.
//!
//! The layout follows rmw_zenoh's design document:
//! - data key: `<domain>/<fully qualified topic>/<DDS type name>/<type hash>`,
//!   the topic without its leading `/`;
//! - payload: CDR, little endian, after the 4-byte encapsulation header
//!   `00 01 00 00`;
//! - attachment: sequence number (i64 LE), source timestamp (ns since the
//!   UNIX epoch, i64 LE), the GID's length (one byte, 16), the GID (16 bytes);
//! - liveliness: `@ros2_lv/<domain>/<session id>/<node id>/<entity id>/<kind>/
//!   <enclave>/<namespace>/<node>[/<topic>/<type>/<hash>/<qos>]`, names
//!   mangled with `/` → `%`.
//!
//! The type hash is REP-2016's RIHS01: SHA-256 over the JSON of the type's
//! description and its referenced types (sorted by name, default values
//! left out), written with Python's default separators.

use sha2::{Digest, Sha256};

/// The DDS type name rmw_zenoh uses for `sensor_msgs/msg/JointState`.
pub const JOINT_STATE_TYPE: &str = "sensor_msgs::msg::dds_::JointState_";

/// The QoS in rmw_zenoh's compact key form: reliable, volatile, keep the
/// last 10, no deadline, lifespan or liveliness lease (the defaults).
pub const QOS_KEEP_LAST_10: &str = "::,10:,:,:,,";

/// Field type ids of `type_description_interfaces/msg/FieldType`.
mod field_type {
    pub const NESTED: u8 = 1;
    pub const INT32: u8 = 6;
    pub const UINT32: u8 = 7;
    pub const DOUBLE: u8 = 11;
    pub const STRING: u8 = 17;
    /// Added to an element type for an unbounded sequence of it.
    pub const SEQUENCE: u8 = 144;
}

/// One field of a message type: name, type id, nested type.
struct Field {
    name: &'static str,
    type_id: u8,
    nested: &'static str,
}

/// One message type: its name and fields, in definition order.
struct TypeDesc {
    name: &'static str,
    fields: &'static [Field],
}

const fn field(name: &'static str, type_id: u8) -> Field {
    Field {
        name,
        type_id,
        nested: "",
    }
}

/// A field whose type is the message type `nested`.
const fn nested(name: &'static str, nested: &'static TypeDesc) -> Field {
    Field {
        name,
        type_id: field_type::NESTED,
        nested: nested.name,
    }
}

const TIME: TypeDesc = TypeDesc {
    name: "builtin_interfaces/msg/Time",
    fields: &[
        field("sec", field_type::INT32),
        field("nanosec", field_type::UINT32),
    ],
};

const HEADER: TypeDesc = TypeDesc {
    name: "std_msgs/msg/Header",
    fields: &[
        nested("stamp", &TIME),
        field("frame_id", field_type::STRING),
    ],
};

const JOINT_STATE: TypeDesc = TypeDesc {
    name: "sensor_msgs/msg/JointState",
    fields: &[
        nested("header", &HEADER),
        field("name", field_type::STRING + field_type::SEQUENCE),
        field("position", field_type::DOUBLE + field_type::SEQUENCE),
        field("velocity", field_type::DOUBLE + field_type::SEQUENCE),
        field("effort", field_type::DOUBLE + field_type::SEQUENCE),
    ],
};

/// A type description as REP-2016 hashes it: Python's `json.dumps` with
/// its default separators (`", "`, `": "`), keys in schema order.
fn hashable_json(t: &TypeDesc) -> String {
    let fields: Vec<String> = t
        .fields
        .iter()
        .map(|f| {
            format!(
                "{{\"name\": \"{}\", \"type\": {{\"type_id\": {}, \"capacity\": 0, \
                 \"string_capacity\": 0, \"nested_type_name\": \"{}\"}}}}",
                f.name, f.type_id, f.nested
            )
        })
        .collect();
    format!(
        "{{\"type_name\": \"{}\", \"fields\": [{}]}}",
        t.name,
        fields.join(", ")
    )
}

/// `RIHS01_<sha256>` of a type and the types it refers to (given sorted by
/// name, as the standard requires).
fn rihs01(main: &TypeDesc, referenced: &[&TypeDesc]) -> String {
    let refs: Vec<String> = referenced.iter().map(|t| hashable_json(t)).collect();
    let text = format!(
        "{{\"type_description\": {}, \"referenced_type_descriptions\": [{}]}}",
        hashable_json(main),
        refs.join(", ")
    );
    let digest = Sha256::digest(text.as_bytes());
    let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
    format!("RIHS01_{hex}")
}

/// The RIHS01 type hash of `sensor_msgs/msg/JointState`.
pub fn joint_state_type_hash() -> String {
    rihs01(&JOINT_STATE, &[&TIME, &HEADER])
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

/// The data key expression of a robot's joint states in `domain`.
pub fn joint_states_key(domain: u32, robot: &str) -> String {
    let topic = joint_states_topic(robot);
    format!(
        "{domain}/{}/{JOINT_STATE_TYPE}/{}",
        topic.trim_start_matches('/'),
        joint_state_type_hash()
    )
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

/// The liveliness tokens of the node and of its JointState publisher, for
/// the Zenoh session `session_id` (hex, as Zenoh prints it).
pub fn liveliness_tokens(domain: u32, session_id: &str, robot: &str) -> [String; 2] {
    let node = node_name(robot);
    let namespace = mangle("");
    let nodekey = format!("@ros2_lv/{domain}/{session_id}/0/0/NN/%/{namespace}/{node}");
    let publisher = format!(
        "@ros2_lv/{domain}/{session_id}/0/10/MP/%/{namespace}/{node}/{}/{JOINT_STATE_TYPE}/{}/{QOS_KEEP_LAST_10}",
        mangle(&joint_states_topic(robot)),
        joint_state_type_hash()
    );
    [nodekey, publisher]
}

/// The attachment rmw_zenoh subscribers require with every sample.
pub fn attachment(sequence: i64, stamp_ns: i64, gid: &[u8; 16]) -> Vec<u8> {
    let mut out = Vec::with_capacity(33);
    out.extend_from_slice(&sequence.to_le_bytes());
    out.extend_from_slice(&stamp_ns.to_le_bytes());
    out.push(16);
    out.extend_from_slice(gid);
    out
}

/// A CDR (little endian) writer; alignment counts from after the
/// encapsulation header.
struct Cdr {
    buf: Vec<u8>,
}

impl Cdr {
    fn new() -> Self {
        Cdr {
            buf: vec![0x00, 0x01, 0x00, 0x00],
        }
    }

    fn align(&mut self, n: usize) {
        while !(self.buf.len() - 4).is_multiple_of(n) {
            self.buf.push(0);
        }
    }

    fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    fn string(&mut self, s: &str) {
        // The length counts the terminating NUL.
        self.u32(u32::try_from(s.len() + 1).unwrap_or(u32::MAX));
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    fn len(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }

    fn doubles(&mut self, v: &[f64]) {
        self.len(v.len());
        if !v.is_empty() {
            self.align(8);
        }
        for x in v {
            self.buf.extend_from_slice(&x.to_le_bytes());
        }
    }
}

/// One `sensor_msgs/msg/JointState`: positions in rad, velocities in rad/s
/// (either may be empty), stamped in ns since the UNIX epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct JointState<'a> {
    /// Time of the measurement, ns since the UNIX epoch.
    pub stamp_ns: i64,
    /// The header's frame (empty for joint states, as is usual).
    pub frame_id: &'a str,
    /// Joint names.
    pub names: &'a [String],
    /// Positions, rad.
    pub position: &'a [f64],
    /// Velocities, rad/s.
    pub velocity: &'a [f64],
    /// Efforts (servobus publishes none).
    pub effort: &'a [f64],
}

impl JointState<'_> {
    /// The CDR payload, encapsulation header first.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Cdr::new();
        let sec = self.stamp_ns.div_euclid(1_000_000_000);
        let nanosec = self.stamp_ns.rem_euclid(1_000_000_000);
        w.i32(i32::try_from(sec).unwrap_or(i32::MAX));
        w.u32(u32::try_from(nanosec).unwrap_or(0));
        w.string(self.frame_id);
        w.len(self.names.len());
        for n in self.names {
            w.string(n);
        }
        w.doubles(self.position);
        w.doubles(self.velocity);
        w.doubles(self.effort);
        w.buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_joint_state_type_hash_is_the_one_ros_2_publishes() {
        // As `ros2 topic info -v /joint_states` prints it on Jazzy.
        assert_eq!(
            joint_state_type_hash(),
            "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e"
        );
    }

    #[test]
    fn the_key_follows_the_domain_topic_type_hash_layout() {
        let key = joint_states_key(7, "so101");
        assert!(
            key.starts_with(
                "7/so101/joint_states/sensor_msgs::msg::dds_::JointState_/RIHS01_a13ee3"
            ),
            "{key}"
        );
        assert_eq!(
            joint_states_key(0, "my-arm").split('/').nth(1),
            Some("my_arm")
        );
    }

    #[test]
    fn liveliness_tokens_name_the_node_and_its_publisher() {
        let [node, publisher] = liveliness_tokens(0, "abc", "so101");
        assert_eq!(node, "@ros2_lv/0/abc/0/0/NN/%/%/servobus_so101");
        assert!(publisher.starts_with(
            "@ros2_lv/0/abc/0/10/MP/%/%/servobus_so101/%so101%joint_states/sensor_msgs::msg::dds_::JointState_/RIHS01_"
        ));
        assert!(publisher.ends_with("/::,10:,:,:,,"), "{publisher}");
    }

    #[test]
    fn the_attachment_is_sequence_stamp_and_gid() {
        let gid = [9u8; 16];
        let a = attachment(3, 0x0102, &gid);
        assert_eq!(a.len(), 33);
        assert_eq!(&a[..8], &[3, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(&a[8..16], &[2, 1, 0, 0, 0, 0, 0, 0]);
        assert_eq!(a[16], 16);
        assert_eq!(&a[17..], &gid);
    }

    #[test]
    fn a_joint_state_encodes_as_cdr_by_hand() {
        let names = vec!["a".to_string()];
        let msg = JointState {
            stamp_ns: 1_500_000_000,
            frame_id: "",
            names: &names,
            position: &[1.0],
            velocity: &[],
            effort: &[],
        };
        let bytes = msg.encode();
        let expected: Vec<u8> = [
            &[0x00, 0x01, 0x00, 0x00][..],   // encapsulation: CDR little endian
            &[1, 0, 0, 0],                   // sec
            &[0x00, 0x65, 0xcd, 0x1d],       // nanosec 500_000_000
            &[1, 0, 0, 0, 0, 0, 0, 0],       // frame_id: length 1, NUL, pad
            &[1, 0, 0, 0],                   // one name
            &[2, 0, 0, 0, b'a', 0, 0, 0],    // "a", NUL, pad to 4
            &[1, 0, 0, 0],                   // one position (offset 28)
            &[0, 0, 0, 0, 0, 0, 0xf0, 0x3f], // 1.0 at offset 32
            &[0, 0, 0, 0],                   // no velocities
            &[0, 0, 0, 0],                   // no efforts
        ]
        .concat();
        assert_eq!(bytes, expected);
    }
}
