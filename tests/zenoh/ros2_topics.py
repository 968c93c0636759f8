"""The topic scenarios of ros2_client.py: joint_trajectory, joint_commands,
malformed CDR, and the latency of trajectories. `c` is ros2_client."""

import math
import time

JT = "trajectory_msgs/msg/JointTrajectory"
JS = "sensor_msgs/msg/JointState"
FMA = "std_msgs/msg/Float64MultiArray"
# The SO-101's limits (configs/robots/so101.yaml), deg/s and deg/s^2.
MAX_VELOCITY = {"shoulder_pan": 180.0, "elbow_flex": 180.0}
MAX_ACCELERATION = {"shoulder_pan": 900.0, "elbow_flex": 900.0}
OTHERS = ["shoulder_lift", "wrist_flex", "wrist_roll", "gripper"]


def derivatives(docs, joint):
    """Commanded velocity and acceleration by finite differences over
    consecutive cycles (gaps of dropped states skipped)."""
    ts = [d["t"] for d in docs]
    q = [c.angle(d, "commanded", joint) for d in docs]
    v = []
    for i in range(1, len(q)):
        dt = ts[i] - ts[i - 1]
        if 0 < dt < 0.0075:
            v.append((ts[i], (q[i] - q[i - 1]) / dt))
    a = [(v[i][1] - v[i - 1][1]) / (v[i][0] - v[i - 1][0])
         for i in range(1, len(v)) if 0 < v[i][0] - v[i - 1][0] < 0.0075]
    return [x for _, x in v], a


def four_points():
    """Sends the trajectory; returns the check of the measured positions,
    which needs the loop's lead (the report's, at the end)."""
    before = c.latest()
    start_ns = time.time_ns() + 300_000_000
    # From where the arm is (the elbow starts bent), there and back.
    pan0 = c.angle(before, "commanded", "shoulder_pan")
    elbow0 = c.angle(before, "commanded", "elbow_flex")
    pan = [pan0 + d for d in [20.0, -10.0, 30.0, 0.0]]
    elbow = [elbow0 + d for d in [-15.0, -45.0, -30.0, -60.0]]
    tfs = [1.0, 2.0, 3.0, 4.0]
    points = [(t, [p, e]) for t, p, e in zip(tfs, pan, elbow)]
    sent = time.monotonic()
    c.publish("joint_trajectory", c.trajectory(["shoulder_pan", "elbow_flex"], points, start_ns), JT)
    time.sleep(4.8)
    docs = c.snapshot(sent)
    off = c.unix_offset()

    def worst(key, lead_s):
        w = 0.0
        for t, p, e in zip(tfs, pan, elbow):
            d = c.state_at(start_ns / 1e9 + t + lead_s, docs, off)
            w = max(w, abs(c.angle(d, key, "shoulder_pan") - p), abs(c.angle(d, key, "elbow_flex") - e))
        return w

    cmd = worst("commanded", 0.0)
    c.summary["four_points_commanded_deg"] = cmd
    c.check(cmd < 1.0, f"the goals on the wire are at each point at its time ({cmd:.3f} deg)")
    moved = max(c.spread([before] + docs, "commanded", j) for j in OTHERS)
    c.check(moved < 1e-6, f"the joints not named stay where they were ({moved} deg)")

    def measured(lead_s):
        meas = worst("measured", lead_s)
        c.summary["four_points_measured_deg"] = meas
        c.check(meas < 1.0, f"the arm is at each point at its time plus the lead, "
                            f"{lead_s * 1e3:.1f} ms ({meas:.3f} deg)")

    return measured


def replacement():
    sent = time.monotonic()
    pan0 = c.angle(c.latest(), "commanded", "shoulder_pan")
    first = c.trajectory(["shoulder_pan"], [(1.0, [pan0 + 20.0]), (2.0, [pan0 + 40.0])])
    c.publish("joint_trajectory", first, JT)
    time.sleep(1.0)
    second_ns = time.time_ns()
    c.publish("joint_trajectory", c.trajectory(["shoulder_pan"], [(1.0, [10.0]), (2.0, [-20.0])]), JT)
    time.sleep(2.6)
    docs = c.snapshot(sent)
    v, a = derivatives(docs, "shoulder_pan")
    vmax, amax = max(abs(x) for x in v), max(abs(x) for x in a)
    print(f"replacement: peak {vmax:.1f} deg/s, {amax:.0f} deg/s^2 over {len(v)} cycles")
    c.check(vmax <= MAX_VELOCITY["shoulder_pan"] * 1.02, f"no jump in velocity ({vmax:.1f} deg/s)")
    c.check(amax <= MAX_ACCELERATION["shoulder_pan"] * 1.05, f"no jump in acceleration ({amax:.0f} deg/s^2)")
    off = c.unix_offset()
    for t, want in [(1.0, 10.0), (2.0, -20.0)]:
        d = c.state_at(second_ns / 1e9 + t, docs, off)
        got = c.angle(d, "commanded", "shoulder_pan")
        c.check(abs(got - want) < 1.0, f"the replacement's point at {t} s: {got:.2f} deg (want {want})")


def stream_until(send, reached, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        send()
        time.sleep(1 / 30)
        if reached():
            return True
    return False


def joint_commands():
    start = time.monotonic()
    while time.monotonic() - start < 2.0:
        t = time.monotonic() - start
        c.publish("joint_commands", c.joint_state(["wrist_flex"], [20.0 * math.sin(math.pi * t)]), JS)
        time.sleep(1 / 30)
    swing = c.spread(c.snapshot(start), "commanded", "wrist_flex")
    c.check(swing > 25.0, f"a JointState stream is followed ({swing:.1f} deg of swing)")

    def at(joint, want):
        return lambda: abs(c.angle(c.latest(), "measured", joint) - want) < 1.0

    ok = stream_until(lambda: c.publish("joint_commands", c.joint_state(["wrist_flex"], [25.0], time.time_ns()), JS),
                      at("wrist_flex", 25.0), 8)
    c.check(ok, "JointState (stamped) reaches its pose within 1 deg")
    c.command("stop")
    time.sleep(0.8)
    held_from = time.monotonic()
    time.sleep(0.5)
    c.check(c.spread(c.snapshot(held_from), "commanded", "wrist_flex") < 1e-6, "held after stop")
    ok = stream_until(lambda: c.publish("joint_commands", c.joint_state(["wrist_flex"], [-15.0]), JS),
                      at("wrist_flex", -15.0), 8)
    c.check(ok, "the first JointState after stop moves the arm again")
    now = c.latest()
    pose = [c.angle(now, "commanded", j) for j in now["joints"]]
    pose[now["joints"].index("gripper")] += 20.0
    goal = pose[now["joints"].index("gripper")]
    data = c.T[FMA]
    layout = c.T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
    array = data(layout=layout, data=c.f64([math.radians(q) for q in pose]))
    ok = stream_until(lambda: c.publish("joint_commands", array, FMA), at("gripper", goal), 8)
    c.check(ok, "Float64MultiArray (every joint, the robot's order) reaches its pose")


def malformed():
    """Returns how many malformed messages were sent."""
    time.sleep(0.5)
    bad = []
    for name, typename in [("joint_trajectory", JT), ("joint_commands", JS), ("joint_commands", FMA)]:
        key = c.topic_key(name, typename)
        bad += [(key, b"\x00\x01\x00\x00garbage"), (key, b"")]
    good = c.cdr(c.trajectory(["shoulder_pan"], [(1.0, [30.0])]), JT)
    jt = c.topic_key("joint_trajectory", JT)
    bad.append((jt, good[:-6]))
    bad.append((jt, c.cdr(c.trajectory(["thumb"], [(1.0, [30.0])]), JT)))
    bad.append((jt, c.cdr(c.trajectory(["shoulder_pan"], [(1.0, [30.0]), (2.0, [150.0])]), JT)))
    mismatch = c.joint_state(["wrist_flex", "gripper"], [10.0])
    bad.append((c.topic_key("joint_commands", JS), c.cdr(mismatch, JS)))
    layout = c.T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=9)
    far = c.T[FMA](layout=layout, data=c.f64([0.0] * 6))
    bad.append((c.topic_key("joint_commands", FMA), c.cdr(far, FMA)))
    since = time.monotonic()
    for key, payload in bad:
        c.session.put(key, payload, attachment=c.attachment())
    time.sleep(0.8)
    docs = c.snapshot(since)
    moved = max(c.spread(docs, "commanded", j) for j in docs[0]["joints"])
    c.check(moved < 1e-6, f"malformed CDR moves nothing ({moved} deg)")
    return len(bad)


def run(client):
    global c
    c = client
    if not c.check(c.wait_for(lambda: len(c.snapshot()) > 20, 30), "state arrives"):
        return
    measured = four_points()
    replacement()
    joint_commands()
    bad = malformed()
    doc = c.shutdown()
    measured((doc["report"].get("lead_ms") or 0.0) / 1e3)
    node = doc["node"]
    c.check(node.get("malformed") == bad, f"each malformed message counted: {node.get('malformed')} of {bad}")
    c.check(node.get("trajectories") == 3, f"the three trajectories taken: {node.get('trajectories')}")
    c.check(node.get("targets", 0) > 60, f"the joint commands taken: {node.get('targets')}")
    c.summary["node"] = node


def latency(client):
    """Trajectories published 50 ms apart, each stamped (attachment) at its
    publication; the node's report gives the latency to the first goals
    on the wire after each."""
    global c
    c = client
    if not c.check(c.wait_for(lambda: len(c.snapshot()) > 20, 30), "state arrives"):
        return
    for k in range(100):
        q = 10.0 * math.sin(k / 10)
        c.publish("joint_trajectory", c.trajectory(["shoulder_pan"], [(0.2, [q])]), JT)
        time.sleep(0.05)
    doc = c.shutdown()
    lat = (doc["report"].get("live") or {}).get("latency_ms") or {}
    print(f"JointTrajectory published -> first goal on the wire: p50 {lat.get('p50')} ms, "
          f"p99 {lat.get('p99')} ms", flush=True)
    c.summary["latency_ms"] = lat
    c.check(doc["node"].get("trajectories") == 100, f"every trajectory taken: {doc['node'].get('trajectories')}")
    c.check(lat.get("p50") is not None and lat["p50"] < 20, f"latency measured: {lat}")
