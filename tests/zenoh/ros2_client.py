"""A ROS 2 client of `servobus serve --ros2` written without ROS: eclipse-zenoh
for the transport and rosbags' CDR serializer for the messages, laid out as
rmw_zenoh lays them out (key expressions, attachments, liveliness tokens).
Run by tests/serve_cli.rs (tests/serve_ros2.rs).

usage: ros2_client.py ENDPOINT ROBOT DOMAIN NAMESPACE SCENARIO

SCENARIO:
  topics   joint_trajectory (4 points at their times, a replacement mid-way,
           the other joints left), joint_commands (JointState like a stream,
           after `stop` too; Float64MultiArray), malformed CDR on each topic
  action   follow_joint_trajectory: a goal to SUCCEEDED with feedback at the
           state rate, a cancel, goals refused with a reason, malformed
           requests; the keys are found from the node's liveliness tokens
  stall    a goal with a tight path tolerance on a joint that meets a stop:
           ABORTED with PATH_TOLERANCE_VIOLATED
  latency  100 trajectories, then the report's latency from each publication
           to its first goal on the wire
Each check prints PASS or FAIL; the last line is a JSON summary.
"""

import json
import math
import os
import struct
import sys
import threading
import time

import numpy as np
import zenoh
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

endpoint, robot, domain, namespace, scenario = sys.argv[1:6]
NS = namespace.strip("/")
failures = []
summary = {}

# control_msgs and the action's own types (Jazzy), registered under names of
# our own: names do not reach the bytes, and the keys come from the node's
# liveliness tokens (as rmw_zenoh's graph cache finds them), not from here.
DEFINITIONS = {
    "control_msgs/msg/JointTolerance": "string name\nfloat64 position\nfloat64 velocity\nfloat64 acceleration\n",
    "control_msgs/msg/JointComponentTolerance": "string joint_name\nuint16 component\nfloat64 position\nfloat64 velocity\nfloat64 acceleration\n",
    "control_msgs/msg/FjtGoal": """trajectory_msgs/JointTrajectory trajectory
trajectory_msgs/MultiDOFJointTrajectory multi_dof_trajectory
control_msgs/JointTolerance[] path_tolerance
control_msgs/JointComponentTolerance[] component_path_tolerance
control_msgs/JointTolerance[] goal_tolerance
control_msgs/JointComponentTolerance[] component_goal_tolerance
builtin_interfaces/Duration goal_time_tolerance
""",
    "control_msgs/msg/FjtResult": "int32 error_code\nstring error_string\n",
    "control_msgs/msg/FjtFeedback": """std_msgs/Header header
string[] joint_names
trajectory_msgs/JointTrajectoryPoint desired
trajectory_msgs/JointTrajectoryPoint actual
trajectory_msgs/JointTrajectoryPoint error
string[] multi_dof_joint_names
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_desired
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_actual
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_error
""",
    "control_msgs/msg/FjtSendGoalRequest": "unique_identifier_msgs/UUID goal_id\ncontrol_msgs/FjtGoal goal\n",
    "control_msgs/msg/FjtSendGoalResponse": "bool accepted\nbuiltin_interfaces/Time stamp\n",
    "control_msgs/msg/FjtGetResultRequest": "unique_identifier_msgs/UUID goal_id\n",
    "control_msgs/msg/FjtGetResultResponse": "int8 status\ncontrol_msgs/FjtResult result\n",
    "control_msgs/msg/FjtFeedbackMessage": "unique_identifier_msgs/UUID goal_id\ncontrol_msgs/FjtFeedback feedback\n",
    "action_msgs/msg/CancelGoalRequest": "action_msgs/GoalInfo goal_info\n",
    "action_msgs/msg/CancelGoalResponse": "int8 return_code\naction_msgs/GoalInfo[] goals_canceling\n",
}
store = get_typestore(Stores.ROS2_JAZZY)
for _name, _text in DEFINITIONS.items():
    store.register(get_types_from_msg(_text, _name))
T = store.types


def check(ok, what):
    print(("PASS " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)
    return ok


conf = zenoh.Config()
conf.insert_json5("mode", '"peer"')
conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
conf.insert_json5("listen/endpoints", "[]")
conf.insert_json5("scouting/multicast/enabled", "false")
session = zenoh.open(conf)
lock = threading.Lock()
states = []  # (monotonic, state JSON)


def on_state(sample):
    doc = json.loads(bytes(sample.payload.to_bytes()))
    with lock:
        states.append((time.monotonic(), doc))


base = f"servobus/{robot}"
_sub_state = session.declare_subscriber(f"{base}/state", on_state)
GID = os.urandom(16)
_seq = [0]


def attachment():
    _seq[0] += 1
    return struct.pack("<qqB", _seq[0], time.time_ns(), 16) + GID


def wait_for(pred, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.01)
    return pred()


def snapshot(since=None):
    with lock:
        return [d for (m, d) in states if since is None or m >= since]


def latest():
    with lock:
        return states[-1][1]


def angle(doc, key, joint):
    value = doc[key][doc["joints"].index(joint)]
    return value if value is not None else float("nan")


def unix_offset():
    """Seconds from a state's `t` to the UNIX time it was gathered at (the
    smallest seen: the quickest gathering)."""
    return min(d["stamp_ns"] / 1e9 - d["t"] for d in snapshot())


def state_at(unix_s, docs, off):
    return min(docs, key=lambda d: abs(d["t"] + off - unix_s))


def spread(docs, key, joint):
    a = [angle(d, key, joint) for d in docs]
    return max(a) - min(a) if a else float("nan")


# --- messages -------------------------------------------------------------

def f64(values):
    return np.array(values, dtype=np.float64)


def ros_time(ns):
    return T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def ros_duration(s):
    ns = int(round(s * 1e9))
    return T["builtin_interfaces/msg/Duration"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def header(stamp_ns=0):
    return T["std_msgs/msg/Header"](stamp=ros_time(stamp_ns), frame_id="")


def trajectory(joints, points, stamp_ns=0):
    """points: (tfs, positions in degrees[, velocities in deg/s])."""
    msg_points = []
    for p in points:
        vel = [math.radians(v) for v in p[2]] if len(p) > 2 else []
        msg_points.append(T["trajectory_msgs/msg/JointTrajectoryPoint"](
            positions=f64([math.radians(q) for q in p[1]]), velocities=f64(vel),
            accelerations=f64([]), effort=f64([]), time_from_start=ros_duration(p[0])))
    return T["trajectory_msgs/msg/JointTrajectory"](
        header=header(stamp_ns), joint_names=list(joints), points=msg_points)


def cdr(msg, typename):
    return bytes(store.serialize_cdr(msg, typename))


def topic_key(name, typename):
    dds = typename.replace("/msg/", "::msg::dds_::") + "_"
    prefix = f"{domain}/{NS}/" if NS else f"{domain}/"
    return f"{prefix}{name}/{dds}/{store.hash_rihs01(typename)}"


def publish(name, msg, typename):
    session.put(topic_key(name, typename), cdr(msg, typename), attachment=attachment())


def joint_state(joints, degrees, stamp_ns=0):
    return T["sensor_msgs/msg/JointState"](
        header=header(stamp_ns), name=list(joints), position=f64([math.radians(d) for d in degrees]),
        velocity=f64([]), effort=f64([]))


def command(text):
    session.put(f"{base}/command", text)


def report():
    for _ in range(50):
        for reply in session.get(f"{base}/report", timeout=2.0):
            if reply.ok is not None:
                doc = json.loads(bytes(reply.ok.payload.to_bytes()))
                if not doc.get("running", True):
                    return doc
        time.sleep(0.2)
    return None


def shutdown():
    command("shutdown")
    doc = report()
    check(doc is not None, "report answers after shutdown")
    return doc or {"node": {}, "report": {}}


if scenario in ("action", "stall"):
    import ros2_action  # noqa: E402  (the action scenarios: ros2_action.py)

    ros2_action.run(sys.modules[__name__])
elif scenario == "topics":
    import ros2_topics  # noqa: E402

    ros2_topics.run(sys.modules[__name__])
elif scenario == "latency":
    import ros2_topics  # noqa: E402

    ros2_topics.latency(sys.modules[__name__])
else:
    check(False, f"a known scenario ({scenario})")

summary["failures"] = failures
print(json.dumps(summary), flush=True)
session.close()
sys.exit(1 if failures else 0)
