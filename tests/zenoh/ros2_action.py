"""The action scenarios of ros2_client.py: follow_joint_trajectory found from
the node's liveliness tokens and called the way rmw_zenoh calls services
(a query with the request's CDR and an attachment). `c` is ros2_client."""

import os
import threading
import time

import numpy as np
import zenoh

import ros2_topics

STATUS = {"UNKNOWN": 0, "EXECUTING": 2, "CANCELING": 3, "SUCCEEDED": 4, "CANCELED": 5, "ABORTED": 6}
SEND, SEND_R = "control_msgs/msg/FjtSendGoalRequest", "control_msgs/msg/FjtSendGoalResponse"
RESULT, RESULT_R = "control_msgs/msg/FjtGetResultRequest", "control_msgs/msg/FjtGetResultResponse"
CANCEL, CANCEL_R = "action_msgs/msg/CancelGoalRequest", "action_msgs/msg/CancelGoalResponse"


def tokens():
    """The node's entities: {(name, kind, type): (entity id, type, hash)}."""
    found = {}
    for reply in c.session.liveliness().get(f"@ros2_lv/{c.domain}/**", timeout=3.0):
        if reply.ok is None:
            continue
        parts = str(reply.ok.key_expr).split("/")
        if len(parts) >= 12:
            found[(parts[9].replace("%", "/"), parts[5], parts[10])] = (parts[4], parts[10], parts[11])
        elif len(parts) >= 9 and parts[5] == "NN":
            found[(parts[8], "NN", None)] = (parts[4], None, None)
    return found


def entity(ents, name, kind):
    return next((v for (n, k, _), v in ents.items() if n == name and k == kind), None)


def discover():
    ents = tokens()
    action = f"/{c.NS}/follow_joint_trajectory" if c.NS else "/follow_joint_trajectory"
    keys = {}
    for part, kind in [("send_goal", "SS"), ("cancel_goal", "SS"), ("get_result", "SS"),
                       ("feedback", "MP"), ("status", "MP")]:
        name = f"{action}/_action/{part}"
        got = entity(ents, name, kind)
        if c.check(got is not None, f"a liveliness token for {name} ({kind})"):
            keys[part] = f"{c.domain}/{name.strip('/')}/{got[1]}/{got[2]}"
    traj = entity(ents, f"/{c.NS}/joint_trajectory", "MS")
    want = c.store.hash_rihs01("trajectory_msgs/msg/JointTrajectory")
    c.check(traj is not None and traj[2] == want, f"joint_trajectory's token has rosbags' type hash {want}")
    ids = [v[0] for (_, kind, _), v in ents.items() if kind != "NN"]
    c.check(len(ids) == len(set(ids)) and len(ids) == 9, f"every entity has its own id: {sorted(ids)}")
    c.check(any(k == "NN" for (_, k, _) in ents), "the node's own token")
    return keys


def call(key, payload, with_attachment=True, timeout=30.0):
    """A request as rmw_zenoh's clients send it: ('ok', payload, attachment)
    or ('err', text, None), and the attachment sent."""
    att = c.attachment() if with_attachment else None
    for reply in c.session.get(key, payload=payload, attachment=att, timeout=timeout):
        if reply.ok is not None:
            a = reply.ok.attachment
            return ("ok", bytes(reply.ok.payload.to_bytes()), bytes(a.to_bytes()) if a else None), att
        return ("err", bytes(reply.err.payload.to_bytes()).decode(errors="replace"), None), att
    return ("none", None, None), att


def uuid():
    return c.T["unique_identifier_msgs/msg/UUID"](uuid=np.frombuffer(os.urandom(16), dtype=np.uint8))


def tolerance(name, position):
    return c.T["control_msgs/msg/JointTolerance"](name=name, position=position, velocity=0.0, acceleration=0.0)


def goal(goal_id, traj, path=(), ends=(), goal_time=0.0):
    multi = c.T["trajectory_msgs/msg/MultiDOFJointTrajectory"](header=c.header(), joint_names=[], points=[])
    g = c.T["control_msgs/msg/FjtGoal"](
        trajectory=traj, multi_dof_trajectory=multi, path_tolerance=list(path), component_path_tolerance=[],
        goal_tolerance=list(ends), component_goal_tolerance=[], goal_time_tolerance=c.ros_duration(goal_time))
    return c.cdr(c.T[SEND](goal_id=goal_id, goal=g), SEND)


def send_goal(keys, goal_id, traj, **kw):
    (kind, payload, att), sent = call(keys["send_goal"], goal(goal_id, traj, **kw))
    if not c.check(kind == "ok", f"send_goal answers ({kind}: {payload})"):
        return False
    c.check(att is not None and att[:8] == sent[:8] and att[17:] == sent[17:],
            "the reply's attachment echoes the sequence number and the client's GID")
    return c.store.deserialize_cdr(payload, SEND_R).accepted


def get_result(keys, goal_id):
    req = c.cdr(c.T[RESULT](goal_id=goal_id), RESULT)
    (kind, payload, _), _ = call(keys["get_result"], req, timeout=40.0)
    if not c.check(kind == "ok", f"get_result answers ({kind})"):
        return None
    return c.store.deserialize_cdr(payload, RESULT_R)


class Listen:
    """Samples of a key, with when they came."""

    def __init__(self, key):
        self.got = []
        self.lock = threading.Lock()
        self.sub = c.session.declare_subscriber(key, self.take)

    def take(self, sample):
        with self.lock:
            self.got.append((time.monotonic(), bytes(sample.payload.to_bytes())))

    def since(self, t):
        with self.lock:
            return [p for (m, p) in self.got if m >= t]


def statuses(listen, since, goal_id):
    out = []
    for p in listen.since(since):
        for s in c.store.deserialize_cdr(p, "action_msgs/msg/GoalStatusArray").status_list:
            if bytes(s.goal_info.goal_id.uuid) == bytes(goal_id.uuid):
                out.append(s.status)
    return out


def succeeds(keys, feedback, status):
    now = c.latest()
    q = {j: c.angle(now, "commanded", j) for j in ["shoulder_pan", "elbow_flex", "wrist_flex"]}
    points = [
        (0.0, [q["shoulder_pan"], q["elbow_flex"], q["wrist_flex"]], [0, 0, 0]),
        (1.0, [25.0, 10.0, 15.0], [0.0, 12.0, -10.0]),
        (2.5, [-15.0, 30.0, -10.0], [0, 0, 0]),
    ]
    traj = c.trajectory(["shoulder_pan", "elbow_flex", "wrist_flex"], points)
    gid = uuid()
    start = time.monotonic()
    ends = [tolerance(j, 0.02) for j in q]
    c.check(send_goal(keys, gid, traj, ends=ends, goal_time=1.0) is True, "a goal within the limits is accepted")
    r = get_result(keys, gid)
    took = time.monotonic() - start
    if r is not None:
        c.check(r.status == STATUS["SUCCEEDED"] and r.result.error_code == 0,
                f"the goal succeeds ({r.status}, {r.result.error_code}: {r.result.error_string})")
    fb = [c.store.deserialize_cdr(p, "control_msgs/msg/FjtFeedbackMessage") for p in feedback.since(start)]
    fb = [f for f in fb if bytes(f.goal_id.uuid) == bytes(gid.uuid)]
    docs = c.snapshot(start)
    state_rate = len(docs) / took
    rate = len(fb) / took
    print(f"goal: {took:.2f} s, {len(fb)} feedback ({rate:.1f} Hz), state at {state_rate:.1f} Hz", flush=True)
    c.summary["feedback_hz"] = rate
    c.check(abs(rate - state_rate) < 0.2 * state_rate, f"feedback comes at the state rate ({rate:.1f} Hz)")
    if fb:
        f = fb[len(fb) // 2].feedback
        c.check(list(f.joint_names) == ["shoulder_pan", "elbow_flex", "wrist_flex"], "feedback names the goal's joints")
        err = max(abs(e) for e in f.error.positions)
        c.check(len(f.desired.positions) == 3 and len(f.actual.positions) == 3 and err < 0.05,
                f"feedback has desired, actual and a small error ({err:.4f} rad)")
    seen = statuses(status, start, gid)
    c.check(seen[:1] == [STATUS["EXECUTING"]] and seen[-1:] == [STATUS["SUCCEEDED"]], f"status went {seen}")
    late(keys, gid)


def late(keys, gid):
    """A subscriber arriving after the goal still gets the last status, as
    from a transient-local publisher."""
    got = []
    history = zenoh.ext.HistoryConfig(detect_late_publishers=True)
    sub = zenoh.ext.declare_advanced_subscriber(c.session, keys["status"], lambda s: got.append(bytes(s.payload.to_bytes())), history=history)
    c.wait_for(lambda: len(got) > 0, 3)
    last = [c.store.deserialize_cdr(p, "action_msgs/msg/GoalStatusArray") for p in got]
    ids = [bytes(s.goal_info.goal_id.uuid) for a in last for s in a.status_list]
    c.check(bytes(gid.uuid) in ids, "a late subscriber to status gets the last status")
    sub.undeclare()


def cancels(keys, status):
    pan0 = c.angle(c.latest(), "commanded", "shoulder_pan")
    traj = c.trajectory(["shoulder_pan"], [(2.0, [pan0 + 30.0]), (4.0, [pan0 + 60.0])])
    gid = uuid()
    start = time.monotonic()
    c.check(send_goal(keys, gid, traj) is True, "a long goal is accepted")
    time.sleep(1.2)
    info = c.T["action_msgs/msg/GoalInfo"](goal_id=gid, stamp=c.ros_time(0))
    (kind, payload, _), _ = call(keys["cancel_goal"], c.cdr(c.T[CANCEL](goal_info=info), CANCEL))
    canceled_at = time.monotonic()
    if c.check(kind == "ok", "cancel_goal answers"):
        resp = c.store.deserialize_cdr(payload, CANCEL_R)
        c.check(resp.return_code == 0 and len(resp.goals_canceling) == 1, f"the goal is canceling ({resp.return_code})")
    r = get_result(keys, gid)
    if r is not None:
        c.check(r.status == STATUS["CANCELED"], f"the result is CANCELED ({r.status}: {r.result.error_string})")
    time.sleep(max(0.0, canceled_at + 1.6 - time.monotonic()))
    docs = c.snapshot(start)
    v, a = ros2_topics.derivatives(docs, "shoulder_pan")
    amax = max(abs(x) for x in a)
    final = c.angle(docs[-1], "commanded", "shoulder_pan")
    after = c.snapshot(canceled_at + 1.0)
    c.check(len(after) > 50 and c.spread(after, "commanded", "shoulder_pan") < 1e-6,
            f"stopped within a second and held ({len(after)} states after)")
    c.check(final < pan0 + 40.0, f"stopped on the way ({pan0:.1f} -> {final:.1f}, the goal went to {pan0 + 60:.1f})")
    c.check(amax <= 900 * 1.05, f"the stop is within the acceleration limit ({amax:.0f} deg/s^2)")
    seen = statuses(status, start, gid)
    c.check(STATUS["CANCELING"] in seen and seen[-1:] == [STATUS["CANCELED"]], f"status went {seen}")


def refuses(keys):
    since = time.monotonic()
    for joints, points, code, words in [
        (["shoulder_pan"], [(1.0, [30.0]), (2.0, [150.0])], -1, ["shoulder_pan", "maximum", "110.00 deg"]),
        (["shoulder_pan", "thumb"], [(1.0, [10.0, 10.0])], -2, ["thumb"]),
    ]:
        gid = uuid()
        c.check(send_goal(keys, gid, c.trajectory(joints, points)) is False, f"a goal with {points} is refused")
        r = get_result(keys, gid)
        if r is not None:
            why = r.result.error_string
            c.check(r.result.error_code == code and all(w in why for w in words),
                    f"its result says why ({r.result.error_code}: {why})")
    time.sleep(0.3)
    docs = c.snapshot(since)
    c.check(max(c.spread(docs, "commanded", j) for j in docs[0]["joints"]) < 1e-6, "a refused goal moves nothing")


def malformed(keys):
    good = goal(uuid(), c.trajectory(["shoulder_pan"], [(1.0, [5.0])]))
    for key, payload, att in [(keys["send_goal"], b"\x00\x01\x00\x00junk", True),
                              (keys["send_goal"], good, False),
                              (keys["cancel_goal"], b"\x00\x01", True),
                              (keys["get_result"], b"", True)]:
        (kind, _, _), _ = call(key, payload, with_attachment=att, timeout=5.0)
        c.check(kind == "err", f"a malformed request gets an error reply ({key.split('/')[-3]}, {kind})")
    return 4


def stall(keys):
    """The pan meets a stop at 15 deg (the simulator's mounting) on its way
    to 40: its tight path tolerance breaks."""
    pan0 = c.angle(c.latest(), "commanded", "shoulder_pan")
    traj = c.trajectory(["shoulder_pan"], [(2.0, [40.0])])
    gid = uuid()
    c.check(send_goal(keys, gid, traj, path=[tolerance("shoulder_pan", 0.05)]) is True, "the goal is accepted")
    r = get_result(keys, gid)
    if r is not None:
        why = r.result.error_string
        c.check(r.status == STATUS["ABORTED"] and r.result.error_code == -4 and "shoulder_pan" in why,
                f"aborted with PATH_TOLERANCE_VIOLATED ({r.status}, {r.result.error_code}: {why})")
    time.sleep(1.0)
    held = c.snapshot(time.monotonic() - 0.5)
    c.check(c.spread(held, "commanded", "shoulder_pan") < 1e-6, f"then held (from {pan0:.1f})")


def run(client):
    global c
    c = client
    ros2_topics.c = client
    if not c.check(c.wait_for(lambda: len(c.snapshot()) > 20, 30), "state arrives"):
        return
    keys = discover()
    if len(keys) < 5:
        return
    feedback, status = Listen(keys["feedback"]), Listen(keys["status"])
    if c.scenario == "stall":
        stall(keys)
        c.summary["node"] = c.shutdown()["node"]
        return
    succeeds(keys, feedback, status)
    cancels(keys, status)
    refuses(keys)
    bad = malformed(keys)
    node = c.shutdown()["node"]
    c.check(node.get("malformed") == bad, f"malformed requests counted: {node.get('malformed')} of {bad}")
    c.check(node.get("goals") == 2, f"two goals accepted: {node.get('goals')}")
    c.summary["node"] = node
