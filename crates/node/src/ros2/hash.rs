//! REP-2016 type hashes (RIHS01): SHA-256 over the JSON of a type's
//! description and of every type it refers to, directly or not, sorted by
//! name. The JSON is what Python's `json.dumps` writes with its default
//! separators (`", "`, `": "`), keys in the schema's order, default values
//! and comments left out. Constants are not part of a description, so they
//! never change a hash.
//!
//! A service `pkg/srv/S` is described as a type with the fields
//! `request_message`, `response_message` and `event_message`; its event
//! `S_Event` holds `info` (`service_msgs/msg/ServiceEventInfo`) and
//! `request`/`response` as sequences of at most one. An action `pkg/action/A`
//! is a type with `goal`, `result`, `feedback`, `send_goal_service`,
//! `get_result_service` and `feedback_message`. The tables of these
//! descriptions are in [`super::types`].

use sha2::{Digest, Sha256};

/// Field type ids of `type_description_interfaces/msg/FieldType`.
pub(crate) mod field_type {
    pub const NESTED: u8 = 1;
    pub const INT8: u8 = 2;
    pub const UINT8: u8 = 3;
    pub const UINT16: u8 = 5;
    pub const INT32: u8 = 6;
    pub const UINT32: u8 = 7;
    pub const INT64: u8 = 8;
    pub const DOUBLE: u8 = 11;
    pub const BOOLEAN: u8 = 15;
    pub const STRING: u8 = 17;
    /// Added to an element type for a fixed-size array of it.
    pub const ARRAY: u8 = 48;
    /// Added to an element type for a sequence of at most `capacity`.
    pub const BOUNDED_SEQUENCE: u8 = 96;
    /// Added to an element type for an unbounded sequence of it.
    pub const SEQUENCE: u8 = 144;
}

/// One field of a type description.
#[derive(Debug)]
pub(crate) struct Field {
    name: &'static str,
    type_id: u8,
    capacity: u32,
    nested: Option<&'static TypeDescription>,
}

/// A ROS 2 interface type as REP-2016 describes it: its name and fields.
/// Every message, service and action servobus speaks has one (see
/// [`super::types`]), from which its RIHS01 hash and its DDS type name
/// are computed.
#[derive(Debug)]
pub struct TypeDescription {
    name: &'static str,
    fields: &'static [Field],
}

/// A field of a primitive type (`type_id` from [`field_type`]).
pub(crate) const fn field(name: &'static str, type_id: u8) -> Field {
    Field {
        name,
        type_id,
        capacity: 0,
        nested: None,
    }
}

/// A fixed-size array of `len` primitives.
pub(crate) const fn array(name: &'static str, type_id: u8, len: u32) -> Field {
    Field {
        name,
        type_id: type_id + field_type::ARRAY,
        capacity: len,
        nested: None,
    }
}

/// A field holding one message of type `of`.
pub(crate) const fn nested(name: &'static str, of: &'static TypeDescription) -> Field {
    Field {
        name,
        type_id: field_type::NESTED,
        capacity: 0,
        nested: Some(of),
    }
}

/// An unbounded sequence of messages of type `of`.
pub(crate) const fn nested_seq(name: &'static str, of: &'static TypeDescription) -> Field {
    Field {
        name,
        type_id: field_type::NESTED + field_type::SEQUENCE,
        capacity: 0,
        nested: Some(of),
    }
}

/// A sequence of at most `max` messages of type `of`.
pub(crate) const fn nested_bounded(
    name: &'static str,
    of: &'static TypeDescription,
    max: u32,
) -> Field {
    Field {
        name,
        type_id: field_type::NESTED + field_type::BOUNDED_SEQUENCE,
        capacity: max,
        nested: Some(of),
    }
}

impl TypeDescription {
    /// A description from its name and fields.
    pub(crate) const fn new(name: &'static str, fields: &'static [Field]) -> Self {
        TypeDescription { name, fields }
    }

    /// The ROS name, e.g. `trajectory_msgs/msg/JointTrajectory`.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// The DDS type name rmw_zenoh puts in key expressions and liveliness
    /// tokens: `pkg/msg/Name` becomes `pkg::msg::dds_::Name_`. For a
    /// service this is what rmw_zenoh keys the service by (its response
    /// type's name without `Response_`), e.g.
    /// `action_msgs::srv::dds_::CancelGoal_`.
    pub fn dds_name(&self) -> String {
        match self.name.rsplit_once('/') {
            Some((namespace, name)) => {
                format!("{}::dds_::{name}_", namespace.replace('/', "::"))
            }
            None => format!("dds_::{}_", self.name),
        }
    }

    /// The RIHS01 hash, `RIHS01_` and 64 lowercase hex digits.
    pub fn rihs01(&self) -> String {
        let mut referenced: Vec<&TypeDescription> = Vec::new();
        self.collect(&mut referenced);
        referenced.sort_by_key(|t| t.name);
        referenced.dedup_by_key(|t| t.name);
        referenced.retain(|t| t.name != self.name);
        let refs: Vec<String> = referenced.iter().map(|t| t.hashable_json()).collect();
        let text = format!(
            "{{\"type_description\": {}, \"referenced_type_descriptions\": [{}]}}",
            self.hashable_json(),
            refs.join(", ")
        );
        let digest = Sha256::digest(text.as_bytes());
        let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
        format!("RIHS01_{hex}")
    }

    /// Every type this one refers to, directly or not (with repeats).
    fn collect(&self, out: &mut Vec<&'static TypeDescription>) {
        for f in self.fields {
            if let Some(t) = f.nested {
                if !out.iter().any(|seen| seen.name == t.name) {
                    out.push(t);
                    t.collect(out);
                }
            }
        }
    }

    /// The description alone, as REP-2016 writes it for hashing.
    fn hashable_json(&self) -> String {
        let fields: Vec<String> = self
            .fields
            .iter()
            .map(|f| {
                format!(
                    "{{\"name\": \"{}\", \"type\": {{\"type_id\": {}, \"capacity\": {}, \
                     \"string_capacity\": 0, \"nested_type_name\": \"{}\"}}}}",
                    f.name,
                    f.type_id,
                    f.capacity,
                    f.nested.map_or("", |t| t.name)
                )
            })
            .collect();
        format!(
            "{{\"type_name\": \"{}\", \"fields\": [{}]}}",
            self.name,
            fields.join(", ")
        )
    }
}
