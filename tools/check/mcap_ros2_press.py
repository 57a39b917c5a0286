#!/usr/bin/env python3
"""Writes a small ROS 2 bag (MCAP) of a synthetic press with another tool than skillc.

The file is tests/data/press_ros2.mcap, which tests/mcap.rs reads with skillc's own reader: it
must not depend on skillc's writer, so it is made here with Foxglove's Python packages
`mcap` and `mcap-ros2-support` (zstd-compressed chunks, their default). Run it from a venv
outside the repository:

    python3 -m venv /tmp/venv-mcap && /tmp/venv-mcap/bin/pip install mcap mcap-ros2-support
    /tmp/venv-mcap/bin/python tools/check/mcap_ros2_press.py tests/data/press_ros2.mcap

What it holds, stamped from 1 700 000 000 s (a wall-clock epoch, as a real bag has):
- /ee_pose    geometry_msgs/msg/PoseStamped at 250 Hz, frame `base_link`: the flange moves
  down 4 cm (minimum jerk, 1 s), presses for 1.2 s, and goes back up (1 s), pointing down;
- /ft_sensor  geometry_msgs/msg/WrenchStamped at 500 Hz, frame `base_link`, stamped 1 ms after
  the pose samples so that the reader must interpolate: the force the surface exerts on the
  tool, +z, ramping to 10 N and back, with a 0.2 N ripple;
- /tf         tf2_msgs/msg/TFMessage at 250 Hz: `base_link` -> `tool0`, the same pose;
- /tf_static  tf2_msgs/msg/TFMessage once: `world` -> `base_link`.
"""

import math
import sys

from mcap_ros2.writer import Writer

SEP = "=" * 80
TIME = "int32 sec\nuint32 nanosec\n"
HEADER = "builtin_interfaces/Time stamp\nstring frame_id\n"
XYZ = "float64 x\nfloat64 y\nfloat64 z\n"
QUAT = XYZ + "float64 w\n"


def definition(own, deps):
    text = own
    for name, fields in deps:
        text += f"{SEP}\nMSG: {name}\n{fields}"
    return text


POSE_DEF = definition(
    "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
    [
        ("std_msgs/Header", HEADER),
        ("builtin_interfaces/Time", TIME),
        ("geometry_msgs/Pose", "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n"),
        ("geometry_msgs/Point", XYZ),
        ("geometry_msgs/Quaternion", QUAT),
    ],
)
WRENCH_DEF = definition(
    "std_msgs/Header header\ngeometry_msgs/Wrench wrench\n",
    [
        ("std_msgs/Header", HEADER),
        ("builtin_interfaces/Time", TIME),
        ("geometry_msgs/Wrench", "geometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque\n"),
        ("geometry_msgs/Vector3", XYZ),
    ],
)
TF_DEF = definition(
    "geometry_msgs/TransformStamped[] transforms\n",
    [
        ("geometry_msgs/TransformStamped", "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n"),
        ("std_msgs/Header", HEADER),
        ("builtin_interfaces/Time", TIME),
        ("geometry_msgs/Transform", "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n"),
        ("geometry_msgs/Vector3", XYZ),
        ("geometry_msgs/Quaternion", QUAT),
    ],
)

EPOCH_NS = 1_700_000_000 * 10**9
POSE_HZ = 250
WRENCH_HZ = 500
DOWN_S, PRESS_S, UP_S = 1.0, 1.2, 1.0
DURATION_S = DOWN_S + PRESS_S + UP_S
START = (0.5, 0.0, 0.35)
DEPTH_M = 0.04
# Pointing down: 180 degrees about y, as x, y, z, w.
ORIENTATION = (0.0, 1.0, 0.0, 0.0)


def min_jerk(u):
    u = min(max(u, 0.0), 1.0)
    return u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)


def height(t):
    """The flange's z at time t (s)."""
    if t < DOWN_S:
        return START[2] - DEPTH_M * min_jerk(t / DOWN_S)
    if t < DOWN_S + PRESS_S:
        return START[2] - DEPTH_M
    return START[2] - DEPTH_M * (1.0 - min_jerk((t - DOWN_S - PRESS_S) / UP_S))


def force_z(t):
    """The force the surface exerts on the tool along +z (N)."""
    if t < DOWN_S or t > DOWN_S + PRESS_S:
        return 0.0
    u = (t - DOWN_S) / PRESS_S
    level = 10.0 * min(1.0, 5.0 * u, 5.0 * (1.0 - u))
    return level + 0.2 * math.sin(2.0 * math.pi * 7.0 * (t - DOWN_S))


def stamp(ns):
    return {"sec": ns // 10**9, "nanosec": ns % 10**9}


def main(path):
    with open(path, "wb") as out:
        writer = Writer(out)
        pose_schema = writer.register_msgdef("geometry_msgs/msg/PoseStamped", POSE_DEF)
        wrench_schema = writer.register_msgdef("geometry_msgs/msg/WrenchStamped", WRENCH_DEF)
        tf_schema = writer.register_msgdef("tf2_msgs/msg/TFMessage", TF_DEF)
        writer.write_message(
            topic="/tf_static",
            schema=tf_schema,
            message={
                "transforms": [
                    {
                        "header": {"stamp": stamp(EPOCH_NS), "frame_id": "world"},
                        "child_frame_id": "base_link",
                        "transform": {
                            "translation": {"x": 0.0, "y": 0.0, "z": 0.1},
                            "rotation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                        },
                    }
                ]
            },
            log_time=EPOCH_NS,
        )
        # Messages in time order, as a recorder writes them.
        events = []
        for k in range(int(DURATION_S * POSE_HZ) + 1):
            events.append((k * 10**9 // POSE_HZ, "pose", k))
        for k in range(int(DURATION_S * WRENCH_HZ)):
            events.append((k * 10**9 // WRENCH_HZ + 1_000_000, "wrench", k))
        events.sort()
        for ns, kind, _ in events:
            t = ns * 1e-9
            header = {"stamp": stamp(EPOCH_NS + ns), "frame_id": "base_link"}
            qx, qy, qz, qw = ORIENTATION
            if kind == "pose":
                position = {"x": START[0], "y": START[1], "z": height(t)}
                writer.write_message(
                    topic="/ee_pose",
                    schema=pose_schema,
                    message={
                        "header": header,
                        "pose": {"position": position, "orientation": {"x": qx, "y": qy, "z": qz, "w": qw}},
                    },
                    log_time=EPOCH_NS + ns,
                )
                writer.write_message(
                    topic="/tf",
                    schema=tf_schema,
                    message={
                        "transforms": [
                            {
                                "header": header,
                                "child_frame_id": "tool0",
                                "transform": {
                                    "translation": position,
                                    "rotation": {"x": qx, "y": qy, "z": qz, "w": qw},
                                },
                            }
                        ]
                    },
                    log_time=EPOCH_NS + ns,
                )
            else:
                writer.write_message(
                    topic="/ft_sensor",
                    schema=wrench_schema,
                    message={
                        "header": header,
                        "wrench": {
                            "force": {"x": 0.0, "y": 0.0, "z": force_z(t)},
                            "torque": {"x": 0.0, "y": 0.0, "z": 0.0},
                        },
                    },
                    log_time=EPOCH_NS + ns,
                )
        writer.finish()


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "tests/data/press_ros2.mcap")
