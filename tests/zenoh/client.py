"""A Zenoh client of `servobus serve`, written the way any Python program
would talk to a serving robot (eclipse-zenoh). Run by tests/serve_cli.rs.

usage: client.py ENDPOINT ROBOT DOMAIN

It connects to ENDPOINT only (no scouting), then:
1. receives `state` for 2 s and prints its rate;
2. decodes one ROS 2 JointState (rosbags' CDR deserializer), checks its
   key expression, type hash and attachment against rmw_zenoh's layout,
   and its names and positions against `state`;
3. sends a sine of targets to elbow_flex for 2 s, then a fixed pose, and
   waits until the arm is within 1 deg of it;
4. sends malformed targets and chunks and checks the arm stays where it
   was;
5. sends `shutdown` (`stop` would stop the motion and go on serving) and
   reads `report`.
Each check prints PASS or FAIL; the last line is a JSON summary.
"""

import json
import math
import struct
import sys
import threading
import time

import zenoh
from rosbags.typesys import Stores, get_typestore

endpoint, robot, domain = sys.argv[1], sys.argv[2], int(sys.argv[3])
failures = []


def check(ok, what):
    print(("PASS " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)


conf = zenoh.Config()
conf.insert_json5("mode", '"peer"')
conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
conf.insert_json5("listen/endpoints", "[]")
conf.insert_json5("scouting/multicast/enabled", "false")
session = zenoh.open(conf)

lock = threading.Lock()
states = []
ros = []


def on_state(sample):
    with lock:
        states.append((time.monotonic(), json.loads(bytes(sample.payload.to_bytes()))))


def on_ros(sample):
    att = sample.attachment
    with lock:
        ros.append(
            (
                str(sample.key_expr),
                bytes(sample.payload.to_bytes()),
                bytes(att.to_bytes()) if att is not None else None,
            )
        )


base = f"servobus/{robot}"
sub_state = session.declare_subscriber(f"{base}/state", on_state)
sub_ros = session.declare_subscriber(f"{domain}/{robot}/joint_states/**", on_ros)


def wait_for(pred, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.01)
    return pred()


check(wait_for(lambda: len(states) > 5, 20), "state arrives")
with lock:
    states.clear()
time.sleep(2.0)
with lock:
    got = list(states)
rate = (len(got) - 1) / (got[-1][0] - got[0][0]) if len(got) > 1 else 0.0
print(f"state rate: {rate:.1f} Hz over {len(got)} messages", flush=True)
check(35.0 <= rate <= 65.0, f"state comes at about 50 Hz ({rate:.1f})")

# 2. ROS 2 JointState.
check(wait_for(lambda: len(ros) > 0, 5), "a JointState arrives")
store = get_typestore(Stores.ROS2_JAZZY)
with lock:
    key, payload, att = ros[-1]
    last_state = states[-1][1] if states else None
parts = key.split("/")
expected_hash = store.hash_rihs01("sensor_msgs/msg/JointState")
check(
    parts[:4] == [str(domain), robot, "joint_states", "sensor_msgs::msg::dds_::JointState_"],
    f"the key expression is <domain>/<robot>/joint_states/<type>/<hash>: {key}",
)
check(parts[4] == expected_hash, f"the type hash is rosbags' {expected_hash}")
check(att is not None and len(att) == 33 and att[16] == 16, "the attachment is 8+8+1+16 bytes")
if att is not None and len(att) == 33:
    seq, stamp = struct.unpack("<qq", att[:16])
    check(seq >= 1, f"the attachment's sequence number counts ({seq})")
    check(abs(stamp / 1e9 - time.time()) < 60, "the attachment's timestamp is now")
msg = store.deserialize_cdr(payload, "sensor_msgs/msg/JointState")
names = list(msg.name)
check("elbow_flex" in names and "gripper" in names, f"JointState names the joints: {names}")
if last_state is not None and names == last_state["joints"]:
    meas = [m if m is not None else c for m, c in zip(last_state["measured"], last_state["commanded"])]
    to_rad = math.pi / 180 if last_state["units"] == "deg" else 1.0
    diff = max(abs(p - m * to_rad) for p, m in zip(msg.position, meas))
    check(diff < math.radians(5), f"JointState positions match state ({math.degrees(diff):.2f} deg)")


def measured(joint):
    with lock:
        s = states[-1][1]
    i = s["joints"].index(joint)
    return s["measured"][i]


def send(joints, **extra):
    body = {"joints": joints, "sent_ns": time.time_ns()}
    body.update(extra)
    session.put(f"{base}/target", json.dumps(body))


# 3. A sine of targets, then a pose to reach.
start = time.monotonic()
while time.monotonic() - start < 2.0:
    t = time.monotonic() - start
    send({"elbow_flex": 20.0 * math.sin(2 * math.pi * 0.5 * t)})
    time.sleep(1 / 30)
goal = {"elbow_flex": 25.0, "shoulder_lift": -10.0}
reached = False
end = time.monotonic() + 10
while time.monotonic() < end and not reached:
    send(goal)
    time.sleep(1 / 30)
    reached = all(
        measured(j) is not None and abs(measured(j) - a) <= 1.0 for j, a in goal.items()
    )
check(reached, f"the arm reaches the target within 1 deg: elbow_flex {measured('elbow_flex')}")

# 4. Malformed targets and chunks: counted, and the arm stays.
before = measured("elbow_flex")
for bad in [
    "not json",
    '{"joints": {"elbow_flex": "far"}}',
    '{"t": 1}',
    '{"chunk": {"dt": 0, "joints": {"elbow_flex": [10, 20]}}}',
    '{"chunk": {"dt": 0.02, "joints": {"elbow_flex": [10, 20], "wrist_flex": [1]}}}',
]:
    session.put(f"{base}/target", bad)
time.sleep(0.5)
after = measured("elbow_flex")
check(abs(after - before) < 0.5, f"malformed targets leave the arm where it was ({before} -> {after})")

# 5. Shut the node down, then the report.
session.put(f"{base}/command", "shutdown")
report = None
end = time.monotonic() + 15
while time.monotonic() < end and report is None:
    for reply in session.get(f"{base}/report", timeout=2.0):
        if reply.ok is not None:
            doc = json.loads(bytes(reply.ok.payload.to_bytes()))
            if not doc.get("running", True):
                report = doc
    time.sleep(0.1)
check(report is not None, "report answers after shutdown")
if report is not None:
    check(report["report"]["finish"] == "stopped", f"the run stopped: {report['report']['finish']}")
    check(report["node"]["malformed"] >= 5, f"malformed targets and chunks counted: {report['node']['malformed']}")
    live = report["report"].get("live") or {}
    print("live:", json.dumps(live), flush=True)
summary = {"failures": failures, "state_rate_hz": rate}
if report is not None:
    summary["latency_ms"] = (report["report"].get("live") or {}).get("latency_ms")
print(json.dumps(summary), flush=True)
session.close()
sys.exit(1 if failures else 0)
