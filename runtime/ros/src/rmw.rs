//! How `rmw_zenoh` (ROS 2 Jazzy's Zenoh middleware) names and frames what it sends, so that ROS 2
//! tools see skillc's topics: key expressions, the 33-byte attachment every sample carries, the
//! liveliness tokens that announce nodes, publishers and subscriptions, and the entity GIDs.
//!
//! - A topic's key expression is `<domain>/<topic without its leading />/<type>/<hash>`, the type
//!   mangled as DDS names it (`sensor_msgs::msg::dds_::JointState_`) and the hash as REP 2011
//!   defines it ([`crate::hash`]).
//! - A sample's attachment is its publisher's sequence number (`i64`, from 1), its source
//!   timestamp (ns since the epoch, `i64`), then the GID's length (16) as one byte and the 16
//!   GID bytes, all little-endian.
//! - A liveliness token is `@ros2_lv/<domain>/<session id>/<node id>/<entity id>/<kind>/<enclave>/
//!   <namespace>/<node name>`, and for a topic's endpoints also `/<topic>/<type>/<hash>/<qos>`;
//!   the kinds are `NN` (node), `MP` (publisher) and `MS` (subscription); every `/` inside a name
//!   is written `%`, so the root namespace and an empty enclave are both `%`.
//! - QoS is written `<reliability>:<durability>:<history>,<depth>:<deadline>:<lifespan>:
//!   <liveliness>`, an empty field meaning the default (reliable, volatile, keep last): depth 10
//!   with every other setting default is `::,10:,:,:,,`.
//! - An entity's GID is the 128-bit XXH3 hash of its liveliness token, as little-endian bytes.

use crate::hash::type_hash;
use crate::msgs::MsgType;

/// Bytes in an attachment: sequence number, timestamp, GID length, GID.
pub const ATTACHMENT_BYTES: usize = 8 + 8 + 1 + GID_BYTES;
/// Bytes in a GID.
pub const GID_BYTES: usize = 16;
/// The QoS skillc's endpoints declare: reliable, volatile, keep last 10.
pub const DEFAULT_QOS: &str = "::,10:,:,:,,";

/// The DDS-mangled type name: `sensor_msgs/msg/JointState` → `sensor_msgs::msg::dds_::JointState_`.
pub fn mangled_type(ty: MsgType) -> String {
    let name = ty.schema_name();
    let (path, last) = name.rsplit_once('/').unwrap_or(("", name));
    format!("{}::dds_::{last}_", path.replace('/', "::"))
}

/// A topic's key expression on `domain`: `0/joint_states/sensor_msgs::msg::dds_::JointState_/RIHS01_…`.
pub fn topic_key(domain: u32, topic: &str, ty: MsgType) -> String {
    format!(
        "{domain}/{}/{}/{}",
        topic.trim_start_matches('/'),
        mangled_type(ty),
        type_hash(ty)
    )
}

/// A name inside a liveliness token: every `/` becomes `%`; empty becomes `%`.
fn token_part(name: &str) -> String {
    if name.is_empty() {
        "%".to_owned()
    } else {
        name.replace('/', "%")
    }
}

/// What a liveliness token announces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Entity<'a> {
    /// The node itself.
    Node,
    /// A publisher of `topic`.
    Publisher {
        /// The topic (`/joint_states`).
        topic: &'a str,
        /// Its type.
        ty: MsgType,
    },
    /// A subscription to `topic`.
    Subscription {
        /// The topic.
        topic: &'a str,
        /// Its type.
        ty: MsgType,
    },
}

/// A node as the liveliness tokens name it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeName {
    /// The ROS domain.
    pub domain: u32,
    /// The Zenoh session's id, in hex as Zenoh prints it.
    pub session_id: String,
    /// The node's id within the session.
    pub node_id: u32,
    /// Namespace (`/` for the root).
    pub namespace: String,
    /// Node name.
    pub name: String,
}

impl NodeName {
    /// The liveliness token of entity `entity_id` of this node (the node itself is entity 0 by
    /// rmw_zenoh's count, which numbers a node and its endpoints in one sequence per session).
    pub fn token(&self, entity_id: u32, entity: Entity<'_>) -> String {
        let namespace = if self.namespace == "/" {
            ""
        } else {
            self.namespace.as_str()
        };
        let kind = match entity {
            Entity::Node => "NN",
            Entity::Publisher { .. } => "MP",
            Entity::Subscription { .. } => "MS",
        };
        let mut token = format!(
            "@ros2_lv/{}/{}/{}/{}/{kind}/%/{}/{}",
            self.domain,
            self.session_id,
            self.node_id,
            entity_id,
            token_part(namespace),
            token_part(&self.name)
        );
        if let Entity::Publisher { topic, ty } | Entity::Subscription { topic, ty } = entity {
            token.push_str(&format!(
                "/{}/{}/{}/{DEFAULT_QOS}",
                token_part(topic),
                mangled_type(ty),
                type_hash(ty)
            ));
        }
        token
    }
}

/// An entity's GID: the XXH3-128 of its liveliness token, little-endian.
pub fn gid(token: &str) -> [u8; GID_BYTES] {
    xxhash_rust::xxh3::xxh3_128(token.as_bytes()).to_le_bytes()
}

/// A sample's attachment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Attachment {
    /// The publisher's sequence number (from 1).
    pub sequence: i64,
    /// When it was published, ns since the Unix epoch.
    pub timestamp_ns: i64,
    /// The publisher's GID.
    pub gid: [u8; GID_BYTES],
}

impl Attachment {
    /// Its bytes.
    pub fn encode(&self) -> [u8; ATTACHMENT_BYTES] {
        let mut out = [0u8; ATTACHMENT_BYTES];
        out[..8].copy_from_slice(&self.sequence.to_le_bytes());
        out[8..16].copy_from_slice(&self.timestamp_ns.to_le_bytes());
        out[16] = GID_BYTES as u8;
        out[17..].copy_from_slice(&self.gid);
        out
    }

    /// Reads an attachment; `None` unless it is exactly the 33 bytes with a 16-byte GID.
    pub fn decode(bytes: &[u8]) -> Option<Attachment> {
        if bytes.len() != ATTACHMENT_BYTES || bytes[16] as usize != GID_BYTES {
            return None;
        }
        let word = |at: usize| {
            let mut le = [0u8; 8];
            le.copy_from_slice(&bytes[at..at + 8]);
            i64::from_le_bytes(le)
        };
        let mut gid = [0u8; GID_BYTES];
        gid.copy_from_slice(&bytes[17..]);
        Some(Attachment {
            sequence: word(0),
            timestamp_ns: word(8),
            gid,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_expressions_are_rmw_zenohs() {
        assert_eq!(
            topic_key(0, "/joint_states", MsgType::JointState),
            "0/joint_states/sensor_msgs::msg::dds_::JointState_/\
             RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e"
        );
        assert_eq!(
            topic_key(7, "/skillc/observation", MsgType::Float64MultiArray),
            "7/skillc/observation/std_msgs::msg::dds_::Float64MultiArray_/\
             RIHS01_1025ddc6b9552d191f89ef1a8d2f60f3d373e28b283d8891ddcc974e8c55397f"
        );
    }

    /// A token and its GID as rmw_zenoh forms them (the GID checked with Python's `xxhash`).
    #[test]
    fn tokens_and_gids() {
        let node = NodeName {
            domain: 0,
            session_id: "aac3178e146ba6f1fc6e6a4085e77f21".into(),
            node_id: 0,
            namespace: "/".into(),
            name: "skillc_plant".into(),
        };
        assert_eq!(
            node.token(0, Entity::Node),
            "@ros2_lv/0/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/skillc_plant"
        );
        let publisher = node.token(
            1,
            Entity::Publisher {
                topic: "/joint_states",
                ty: MsgType::JointState,
            },
        );
        assert_eq!(
            publisher,
            "@ros2_lv/0/aac3178e146ba6f1fc6e6a4085e77f21/0/1/MP/%/%/skillc_plant/%joint_states/\
             sensor_msgs::msg::dds_::JointState_/\
             RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e/::,10:,:,:,,"
        );
        let hex: String = gid(&publisher).iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(hex, "7b5d7da813f6470b0f964f4444956077");
        let sub = node.token(
            2,
            Entity::Subscription {
                topic: "/skillc/x",
                ty: MsgType::Float64MultiArray,
            },
        );
        assert!(sub.contains("/0/2/MS/%/%/skillc_plant/%skillc%x/std_msgs::msg::dds_::Float64MultiArray_/"));
    }

    #[test]
    fn attachments_round_trip_and_refuse_other_lengths() {
        let attachment = Attachment {
            sequence: 42,
            timestamp_ns: 1_700_000_000_123_456_789,
            gid: [7; GID_BYTES],
        };
        let bytes = attachment.encode();
        assert_eq!(bytes.len(), 33);
        assert_eq!(&bytes[..8], &42i64.to_le_bytes());
        assert_eq!(bytes[16], 16);
        assert_eq!(Attachment::decode(&bytes), Some(attachment));
        assert_eq!(Attachment::decode(&bytes[..32]), None);
        let mut wrong = bytes;
        wrong[16] = 8;
        assert_eq!(Attachment::decode(&wrong), None);
    }
}
