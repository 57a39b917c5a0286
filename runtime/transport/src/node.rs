//! A ROS 2 node on Zenoh as `rmw_zenoh` forms one: a peer-mode session that listens on or connects
//! to one endpoint (no router, no multicast scouting), the node's liveliness token, and publishers
//! and subscriptions that declare their own tokens and stamp each sample with the 33-byte
//! attachment ([`skill_ros::rmw`]).

use std::sync::atomic::{AtomicI64, Ordering};
use std::time::{SystemTime, UNIX_EPOCH};

use skill_ros::msgs::MsgType;
use skill_ros::rmw::{self, Attachment, Entity, NodeName};
use zenoh::bytes::ZBytes;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::sample::Sample;
use zenoh::{Session, Wait};

use crate::TransportError;

/// How a session reaches its peer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Accept peers on the endpoint (the plant).
    Listen,
    /// Connect to the endpoint (the run).
    Connect,
}

/// An endpoint as skillc takes it: `tcp/HOST:PORT`, read by Zenoh's own parser
/// ([`zenoh::config::EndPoint`]) and then held to what skillc serves on: the `tcp` protocol (the
/// only one built in), no metadata or configuration (`?…`, `#…`), a port from 1 to 65535 and a
/// host that is an IP address (IPv6 in brackets) or a DNS name (letters, digits, `-` and `.`).
/// What Zenoh is given is this value, never text spliced into a configuration.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Endpoint(zenoh::config::EndPoint);

impl Endpoint {
    /// The endpoint as Zenoh writes it (what a banner names).
    pub fn as_str(&self) -> &str {
        self.0.as_str()
    }

    /// Zenoh's endpoint.
    pub fn zenoh(&self) -> &zenoh::config::EndPoint {
        &self.0
    }
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Endpoint {
    type Err = TransportError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        parse_endpoint(text)
    }
}

/// Whether `host` is a DNS name: dot-separated labels of 1-63 letters, digits and `-`, none
/// starting or ending with `-`, 253 characters at most.
fn dns_name(host: &str) -> bool {
    host.len() <= 253
        && host.split('.').all(|label| {
            (1..=63).contains(&label.len())
                && label.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'-')
                && !label.starts_with('-')
                && !label.ends_with('-')
        })
}

/// Reads `text` as an [`Endpoint`], or says what is wrong with it.
pub fn parse_endpoint(text: &str) -> Result<Endpoint, TransportError> {
    let bad = |why: &str| TransportError::Endpoint {
        endpoint: text.to_owned(),
        reason: why.to_owned(),
    };
    let parsed: zenoh::config::EndPoint = text.parse().map_err(|err: zenoh::Error| TransportError::Endpoint {
        endpoint: text.to_owned(),
        reason: format!("Zenoh cannot read it ({err}); write it `tcp/HOST:PORT`"),
    })?;
    if parsed.protocol().as_str() != "tcp" {
        return Err(bad(
            "write it `tcp/HOST:PORT`, e.g. `tcp/127.0.0.1:7447` (only TCP is built in)",
        ));
    }
    if !parsed.metadata().as_str().is_empty() || !parsed.config().as_str().is_empty() || text.contains(['?', '#']) {
        return Err(bad(
            "skillc takes no metadata (`?…`) or configuration (`#…`) in an endpoint: `tcp/HOST:PORT`",
        ));
    }
    let address = parsed.address().as_str();
    let Some((host, port)) = address.rsplit_once(':') else {
        return Err(bad("it needs a port: `tcp/HOST:PORT`"));
    };
    if host.is_empty() {
        return Err(bad(
            "it needs a host: `tcp/HOST:PORT` (`0.0.0.0` listens on every interface)",
        ));
    }
    let host_ok = match host.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
        Some(v6) => v6.parse::<std::net::Ipv6Addr>().is_ok(),
        None => host.parse::<std::net::Ipv4Addr>().is_ok() || dns_name(host),
    };
    if !host_ok {
        return Err(bad(
            "its host is neither an IP address (IPv6 in brackets: `tcp/[::1]:7447`) nor a DNS name (letters, \
             digits, `-` and `.`)",
        ));
    }
    match port.parse::<u16>() {
        Ok(number) if number > 0 && port.bytes().all(|b| b.is_ascii_digit()) => Ok(Endpoint(parsed)),
        _ => Err(bad("its port must be a number from 1 to 65535")),
    }
}

/// Checks an endpoint as skillc takes it ([`parse_endpoint`]).
pub fn check_endpoint(endpoint: &str) -> Result<(), TransportError> {
    parse_endpoint(endpoint).map(|_| ())
}

/// Opens a peer-mode session on `endpoint`. The configuration is built from typed values
/// serialised as JSON (the endpoint Zenoh parsed, as one JSON string): nothing given by a user
/// is spliced into configuration text.
pub fn open(endpoint: &str, role: Role) -> Result<Session, TransportError> {
    let endpoint = parse_endpoint(endpoint)?;
    let zenoh_err = |err: zenoh::Error| TransportError::Zenoh {
        what: format!("opening a session on `{endpoint}`"),
        reason: err.to_string(),
    };
    let json = |value: serde_json::Value| value.to_string();
    let endpoints = json(serde_json::json!([endpoint.as_str()]));
    let none = json(serde_json::json!([]));
    let (listen, connect) = match role {
        Role::Listen => (endpoints, none),
        Role::Connect => (none, endpoints),
    };
    let mut config = zenoh::Config::default();
    for (key, value) in [
        ("mode", json(serde_json::json!("peer"))),
        ("listen/endpoints", listen),
        ("connect/endpoints", connect),
        ("scouting/multicast/enabled", json(serde_json::json!(false))),
    ] {
        config.insert_json5(key, &value).map_err(zenoh_err)?;
    }
    if role == Role::Connect {
        // Keep trying while the plant starts, rather than failing on the first refusal.
        config
            .insert_json5("connect/timeout_ms", &json(serde_json::json!(-1)))
            .map_err(zenoh_err)?;
    }
    zenoh::open(config).wait().map_err(zenoh_err)
}

/// The SCHED_FIFO priority `skillc plant` and `skillc run --realtime` ask for (what ROS 2's
/// `ros2_control` controller manager asks for by default): above every normal thread, below the
/// kernel's own real-time threads (priority 99).
pub const FIFO_PRIORITY: u8 = 50;

/// Puts the calling thread, and every thread it starts from now on, under SCHED_FIFO at
/// [`FIFO_PRIORITY`], so that a 1 ms loop is not preempted by the machine's other work. Call it
/// before [`open`]: Zenoh's threads inherit it, and the loop's messages pass through them. It
/// needs root, `CAP_SYS_NICE` or an `rtprio` limit (`ulimit -r`) of 50; otherwise it changes
/// nothing and returns the system's words. On a 2-core VM it took the late commands of a
/// realtime slide from 0.3-2.1 % of ticks to 0.00-0.09 % (`docs/split.md`).
pub fn realtime_scheduling() -> Result<(), String> {
    use thread_priority::{
        set_thread_priority_and_policy, thread_native_id, RealtimeThreadSchedulePolicy, ThreadPriority,
        ThreadPriorityValue, ThreadSchedulePolicy,
    };
    let priority = ThreadPriorityValue::try_from(FIFO_PRIORITY).map_err(|err| err.to_string())?;
    set_thread_priority_and_policy(
        thread_native_id(),
        ThreadPriority::Crossplatform(priority),
        ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
    )
    .map_err(|err| match err {
        thread_priority::Error::OS(code) => std::io::Error::from_raw_os_error(code).to_string(),
        other => format!("{other:?}"),
    })
}

/// What [`realtime_scheduling`] did, in words for a run's or a plant's output.
pub fn scheduling_words(result: &Result<(), String>) -> String {
    match result {
        Ok(()) => format!("SCHED_FIFO priority {FIFO_PRIORITY}"),
        Err(why) => format!(
            "normal, not SCHED_FIFO ({why}: run as root, or grant CAP_SYS_NICE or `ulimit -r {FIFO_PRIORITY}`, for \
             fewer late commands)"
        ),
    }
}

/// Nanoseconds since the Unix epoch (0 if the clock is before it).
pub fn now_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |since| i64::try_from(since.as_nanos()).unwrap_or(i64::MAX))
}

/// A ROS 2 node: its name and token, and the count its endpoints take their ids from.
pub struct Node {
    name: NodeName,
    next_entity: u32,
    tokens: Vec<LivelinessToken>,
}

impl std::fmt::Debug for Node {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Node").field("name", &self.name).finish()
    }
}

impl Node {
    /// Declares node `name` (root namespace) on `domain` in `session`.
    pub fn new(session: &Session, domain: u32, name: &str) -> Result<Self, TransportError> {
        let mut node = Node {
            name: NodeName {
                domain,
                session_id: session.zid().to_string(),
                node_id: 0,
                namespace: "/".to_owned(),
                name: name.to_owned(),
            },
            next_entity: 0,
            tokens: Vec::new(),
        };
        node.announce(session, Entity::Node)?;
        Ok(node)
    }

    /// The node's name as its tokens write it.
    pub fn name(&self) -> &NodeName {
        &self.name
    }

    fn announce(&mut self, session: &Session, entity: Entity<'_>) -> Result<String, TransportError> {
        let token = self.name.token(self.next_entity, entity);
        self.next_entity += 1;
        let declared = session
            .liveliness()
            .declare_token(token.clone())
            .wait()
            .map_err(|err| TransportError::Zenoh {
                what: format!("declaring the liveliness token `{token}`"),
                reason: err.to_string(),
            })?;
        self.tokens.push(declared);
        Ok(token)
    }

    /// A publisher of `topic` (express: each sample is sent at once, not batched; it blocks
    /// rather than drops when the link is congested, as a control loop needs every tick).
    pub fn publisher(&mut self, session: &Session, topic: &str, ty: MsgType) -> Result<RosPublisher, TransportError> {
        let token = self.announce(session, Entity::Publisher { topic, ty })?;
        let key = rmw::topic_key(self.name.domain, topic, ty);
        let publisher = session
            .declare_publisher(key.clone())
            .congestion_control(CongestionControl::Block)
            .express(true)
            .wait()
            .map_err(|err| TransportError::Zenoh {
                what: format!("declaring a publisher on `{key}`"),
                reason: err.to_string(),
            })?;
        Ok(RosPublisher {
            publisher,
            gid: rmw::gid(&token),
            sequence: AtomicI64::new(0),
        })
    }

    /// A subscription to `topic`; `callback` gets each sample on Zenoh's thread.
    pub fn subscription(
        &mut self,
        session: &Session,
        topic: &str,
        ty: MsgType,
        callback: impl Fn(Sample) + Send + Sync + 'static,
    ) -> Result<Subscriber<()>, TransportError> {
        self.announce(session, Entity::Subscription { topic, ty })?;
        let key = rmw::topic_key(self.name.domain, topic, ty);
        session
            .declare_subscriber(key.clone())
            .callback(callback)
            .wait()
            .map_err(|err| TransportError::Zenoh {
                what: format!("subscribing to `{key}`"),
                reason: err.to_string(),
            })
    }
}

/// A publisher that stamps each sample with rmw_zenoh's attachment.
pub struct RosPublisher {
    publisher: Publisher<'static>,
    gid: [u8; rmw::GID_BYTES],
    sequence: AtomicI64,
}

impl std::fmt::Debug for RosPublisher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RosPublisher")
            .field("key", &self.publisher.key_expr().as_str())
            .finish()
    }
}

impl RosPublisher {
    /// The GID its samples carry in their attachment.
    pub fn gid(&self) -> [u8; rmw::GID_BYTES] {
        self.gid
    }

    /// Publishes `payload` with the next sequence number.
    pub fn put(&self, payload: Vec<u8>) -> Result<(), TransportError> {
        let sequence = self.sequence.fetch_add(1, Ordering::Relaxed) + 1;
        self.put_numbered(payload, sequence)
    }

    /// Publishes `payload` under a sequence number the caller chooses (a command names the tick
    /// of the state it answers this way).
    pub fn put_numbered(&self, payload: Vec<u8>, sequence: i64) -> Result<(), TransportError> {
        let attachment = Attachment {
            sequence,
            timestamp_ns: now_ns(),
            gid: self.gid,
        };
        self.publisher
            .put(payload)
            .attachment(ZBytes::from(attachment.encode().to_vec()))
            .wait()
            .map_err(|err| TransportError::Zenoh {
                what: format!("publishing on `{}`", self.publisher.key_expr().as_str()),
                reason: err.to_string(),
            })
    }
}

/// A sample's payload bytes and its attachment, if it has rmw_zenoh's.
pub fn sample_parts(sample: &Sample) -> (Vec<u8>, Option<Attachment>) {
    let payload = sample.payload().to_bytes().into_owned();
    let attachment = sample
        .attachment()
        .and_then(|bytes| Attachment::decode(&bytes.to_bytes()));
    (payload, attachment)
}

/// Closes `session`: its liveliness tokens go at once, so ROS 2 tools see the node leave.
pub fn close(session: &Session) {
    let _ = session.close().wait();
}

/// Waits for a message from `rx` until `deadline`: blocked until `spin_from`, then polling with
/// the core yielded between polls. A blocked thread wakes late on a loaded or virtual machine
/// (a 0.5 ms sleep overshot by a median 116 µs, p99 3.4 ms, on the 2-core VM this was built on);
/// polling near a deadline keeps a 1 ms loop on time at the cost of the polling core.
pub fn recv_until<T>(
    rx: &std::sync::mpsc::Receiver<T>,
    spin_from: std::time::Instant,
    deadline: std::time::Instant,
) -> Result<T, std::sync::mpsc::RecvTimeoutError> {
    use std::sync::mpsc::{RecvTimeoutError, TryRecvError};
    let now = std::time::Instant::now();
    if now < spin_from.min(deadline) {
        match rx.recv_timeout(spin_from.min(deadline) - now) {
            Err(RecvTimeoutError::Timeout) => {}
            other => return other,
        }
    }
    loop {
        match rx.try_recv() {
            Ok(value) => return Ok(value),
            Err(TryRecvError::Disconnected) => return Err(RecvTimeoutError::Disconnected),
            Err(TryRecvError::Empty) if std::time::Instant::now() >= deadline => return Err(RecvTimeoutError::Timeout),
            Err(TryRecvError::Empty) => std::thread::yield_now(),
        }
    }
}
