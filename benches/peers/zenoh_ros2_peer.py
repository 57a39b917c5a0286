"""A running `skillc plant` seen and driven by an independent Zenoh client, the way ROS 2's
`rmw_zenoh` sees a node: Zenoh's own Python binding (eclipse-zenoh) for the session, rosbags'
CDR code for the messages and the xxhash package for the GIDs, none of it skillc's.

It checks, against the plant at ENDPOINT on DOMAIN:
  1. the liveliness tokens: the node `skillc_plant` (NN), its publishers of /joint_states, /wrench
     and /skillc/state (MP) and its subscription to /joint_effort_commands (MS), each parsed into
     rmw_zenoh's fields (domain, session id, node id, entity id, kind, enclave, namespace, node,
     then topic, type, type hash, QoS), the session id being the plant's Zenoh id;
  2. /joint_states on the key expression its token names (domain/topic/type/hash): CDR decoded
     by rosbags, the URDF's seven joints, every sample's 33-byte attachment (sequence number
     counting up by one, a source timestamp within a second of now, GID length 16 and the GID
     equal to XXH3-128 of the publisher's token, little-endian);
  3. a foreign controller: Float64MultiArray torque commands (serialized by rosbags) published on
     the subscription's key with an attachment of its own; in lockstep each one steps the plant
     once, so /joint_states' stamp advances by 1 ms per command.

Usage (in a venv with eclipse-zenoh, rosbags and xxhash; never needed by the build or the tests):
    skillc plant --scene examples/scenes/table.toml --listen tcp/127.0.0.1:7447 &
    python benches/peers/zenoh_ros2_peer.py tcp/127.0.0.1:7447 [DOMAIN]
Exits 0 when every check holds, 1 with the failed check otherwise.
"""

import struct
import sys
import threading
import time

import xxhash
import zenoh
from rosbags.typesys import Stores, get_typestore

TYPES = get_typestore(Stores.ROS2_JAZZY)
deserialize_cdr, serialize_cdr = TYPES.deserialize_cdr, TYPES.serialize_cdr
Float64MultiArray = TYPES.types["std_msgs/msg/Float64MultiArray"]
MultiArrayLayout = TYPES.types["std_msgs/msg/MultiArrayLayout"]

KINDS = {"NN": "node", "MP": "publisher", "MS": "subscription"}


def fail(why):
    print(f"FAILED: {why}")
    sys.exit(1)


def parse_token(key):
    """rmw_zenoh's fields of a liveliness token (names keep their `%` for `/`)."""
    parts = key.split("/")
    if parts[0] != "@ros2_lv" or len(parts) not in (9, 13):
        fail(f"`{key}` is not a liveliness token with 8 or 12 fields")
    token = dict(zip(["domain", "session", "node_id", "entity_id", "kind", "enclave", "namespace", "node"], parts[1:9]))
    if len(parts) == 13:
        token.update(zip(["topic", "type", "hash", "qos"], parts[9:]))
    return token


def attachment(sample):
    raw = bytes(sample.attachment.to_bytes()) if sample.attachment is not None else b""
    if len(raw) != 33 or raw[16] != 16:
        fail(f"an attachment of {len(raw)} bytes, not rmw_zenoh's 33 with a 16-byte GID")
    sequence, stamp_ns = struct.unpack_from("<qq", raw)
    return sequence, stamp_ns, raw[17:]


def main():
    endpoint = sys.argv[1]
    domain = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    config = zenoh.Config()
    config.insert_json5("mode", '"peer"')
    config.insert_json5("connect/endpoints", f'["{endpoint}"]')
    config.insert_json5("scouting/multicast/enabled", "false")
    session = zenoh.open(config)
    time.sleep(0.5)

    # 1. Liveliness tokens.
    tokens = {}
    for reply in session.liveliness().get(f"@ros2_lv/{domain}/**", timeout=3.0):
        if reply.ok is not None:
            key = str(reply.ok.key_expr)
            tokens[key] = parse_token(key)
    plant = [t for t in tokens.values() if t["node"] == "skillc_plant"]
    if not plant:
        fail(f"no token of node skillc_plant among {len(tokens)} tokens on domain {domain}")
    wanted = {
        ("NN", None),
        ("MP", "%joint_states"),
        ("MP", "%wrench"),
        ("MP", "%skillc%state"),
        ("MS", "%joint_effort_commands"),
    }
    found = {(t["kind"], t.get("topic")) for t in plant}
    if not wanted <= found:
        fail(f"the plant's tokens are {sorted(found, key=str)}, missing {sorted(wanted - found, key=str)}")
    sessions = {t["session"] for t in plant}
    if len(sessions) != 1 or any(t["enclave"] != "%" or t["namespace"] != "%" for t in plant):
        fail(f"tokens with several sessions, or not in the root namespace and empty enclave: {plant}")
    peers = {str(zid) for zid in session.info.peers_zid()}
    if not sessions <= peers:
        fail(f"the tokens' session {sessions} is not the Zenoh id of a connected peer ({peers})")
    print(f"liveliness: {len(plant)} tokens of skillc_plant (session {sessions.pop()}):")
    for t in sorted(plant, key=lambda t: int(t["entity_id"])):
        print(f"  entity {t['entity_id']:>2} {KINDS[t['kind']]:<12} {t.get('topic', '').replace('%', '/')} {t.get('type', '')}")

    def topic_key(kind, topic):
        (t,) = [t for t in plant if t["kind"] == kind and t.get("topic") == topic]
        key = f"{domain}/{topic.replace('%', '/').lstrip('/')}/{t['type']}/{t['hash']}"
        token = next(k for k, v in tokens.items() if v is t)
        return key, token

    # 2. /joint_states: CDR, attachment, GID.
    js_key, js_token = topic_key("MP", "%joint_states")
    gid = xxhash.xxh3_128(js_token.encode()).intdigest().to_bytes(16, "little")
    got = []
    lock = threading.Lock()

    def on_sample(sample):
        with lock:
            got.append((bytes(sample.payload.to_bytes()), attachment(sample)))

    subscriber = session.declare_subscriber(js_key, on_sample)
    deadline = time.time() + 3.0
    while time.time() < deadline and len(got) < 3:
        time.sleep(0.05)
    if len(got) < 3:
        fail(f"{len(got)} samples on `{js_key}` in 3 s (the plant repeats its state every 100 ms)")
    for payload, (sequence, stamp_ns, sample_gid) in got:
        msg = deserialize_cdr(payload, "sensor_msgs/msg/JointState")
        if len(msg.name) != 7 or len(msg.position) != 7 or len(msg.velocity) != 7 or len(msg.effort) != 7:
            fail(f"a JointState of {len(msg.name)} names and {len(msg.position)} positions, not 7")
        if sample_gid != gid:
            fail("the attachment's GID is not XXH3-128 of the publisher's token")
        if abs(stamp_ns - time.time_ns()) > 1e9:
            fail(f"a source timestamp {stamp_ns} ns, more than 1 s from now")
    sequences = [a[0] for _, a in got]
    if any(b != a + 1 for a, b in zip(sequences, sequences[1:])):
        fail(f"sequence numbers {sequences} do not count up by one")
    first = deserialize_cdr(got[0][0], "sensor_msgs/msg/JointState")
    print(f"/joint_states on `{js_key}`: {len(got)} samples decoded by rosbags; joints {list(first.name)}; "
          f"sequence {sequences[0]}..{sequences[-1]}, GID = XXH3-128 of its token")

    # 3. Drive the plant as a foreign controller: each command steps it once (lockstep).
    cmd_key, _ = topic_key("MS", "%joint_effort_commands")
    publisher = session.declare_publisher(cmd_key)
    own_gid = xxhash.xxh3_128(b"zenoh_ros2_peer").intdigest().to_bytes(16, "little")
    with lock:
        got.clear()
    stamp0 = None
    steps = 20
    for k in range(steps):
        with lock:
            before = len(got)
        command = Float64MultiArray(layout=MultiArrayLayout(dim=[], data_offset=0), data=first.effort.copy())
        bits = struct.pack("<qqB", k + 1, time.time_ns(), 16) + own_gid
        publisher.put(bytes(serialize_cdr(command, "std_msgs/msg/Float64MultiArray")), attachment=bits)
        wait = time.time() + 1.0
        while time.time() < wait:
            with lock:
                if len(got) > before:
                    break
            time.sleep(0.001)
        with lock:
            if len(got) == before:
                fail(f"no state after command {k + 1}")
            msg = deserialize_cdr(got[-1][0], "sensor_msgs/msg/JointState")
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        if stamp0 is None:
            stamp0 = stamp - 1e-3
    stepped = round((stamp - stamp0) / 1e-3)
    if stepped != steps:
        fail(f"{steps} commands stepped the plant {stepped} ms")
    print(f"/joint_effort_commands on `{cmd_key}`: {steps} commands (rosbags CDR) stepped the plant "
          f"{stepped} ms, one tick each (holding the arm's own torques)")
    subscriber.undeclare()
    session.close()
    print("all checks hold")


if __name__ == "__main__":
    main()
