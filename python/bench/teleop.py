"""Teleoperation benchmark: how faithfully and how smoothly a follower arm
goes where LeRobot's SO101Leader is moved.

Run by hand, for a note (not a timed test), in LeRobot's venv with servobus
and lerobot_robot_servobus installed (``eval "$(bash scripts/python_clients.sh)"``;
``$SERVOBUS_LEROBOT_PYTHON python/bench/teleop.py``):

    python/bench/teleop.py [--servobus target/release/servobus] [--rounds 2] [--keep DIR] [--by-class]

Each run starts two simulated SO-101 arms on pseudo-terminals with
``servobus sim``: the leader, moved by a scripted hand (a hand file this
script writes: the motion classes below), and the follower, whose physical
angles ``--truth`` streams to a CSV. The leader's own ``--truth`` is the
reference. Three followers take turns on the same leader motion, alternated
over ``--rounds``:

- ``stock``: LeRobot's SO101Follower (raw Goal_Position writes), under
  LeRobot's teleop loop at 30 Hz (``lerobot_teleoperate.teleop_loop``'s
  steps with its identity processors; that module needs torchvision);
- ``so101_servobus``: this project's plugin (the live loop), under the same
  loop;
- ``follow``: ``servobus follow --leader <pty> --port <pty>``.

Motion classes (the leader's hand, physical degrees): a slow move; a fast
swing to the pan's limits; a flick out and back (wrist); a reversal wiggle
at 1 Hz and at 2 Hz (pan and elbow); a step (elbow, 30 ms); a hold.

Per follower and joint it prints: worst and RMS error against the leader
(at the same instant), lag (the time shift that minimises the RMS error),
overshoot beyond the envelope of the leader's positions over the last
0.5 s, RMS jerk and peak acceleration of the follower's physical motion,
and, for the LeRobot followers, send_action / get_observation p50 and p99.
``--by-class`` adds the same figures per motion class, for the joints the
hand moves in it: where a follower gains or loses is seen there. With
``--keep``, each run's directory also holds ``started.json`` (the wall
times both simulators started serving), so its truths can be compared
again later.
"""

from __future__ import annotations

import argparse
import importlib.machinery
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import types
from pathlib import Path

import numpy as np

JOINTS = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]
REST = {"shoulder_pan": 0.0, "shoulder_lift": -60.0, "elbow_flex": 70.0, "wrist_flex": 40.0,
        "wrist_roll": 0.0, "gripper": 20.0}
# The hand waits this long after the simulator starts, while the arms are
# calibrated and connected.
SETUP_S = 8.0
FPS = 30
ENVELOPE_S = 0.5


def stand_in_torch() -> None:
    """LeRobot names torch in annotations only; an empty module stands in
    when it is not installed (as the plugin's tests do)."""
    try:
        import torch  # noqa: F401
    except ImportError:
        torch = types.ModuleType("torch")
        torch.__spec__ = importlib.machinery.ModuleSpec("torch", None)
        torch.__getattr__ = lambda name: type(name, (), {})
        sys.modules["torch"] = torch


# --- the leader's motion ------------------------------------------------
def motion() -> tuple[list[dict], list[tuple[str, float, float]]]:
    """The hand's keyframes (every joint named in each) and the classes'
    time spans, s from the simulator's start."""
    frames: list[dict] = []
    pose = dict(REST)
    t = SETUP_S
    classes = []

    def at(dt: float, **changes: float) -> None:
        nonlocal t
        t += dt
        pose.update(changes)
        frames.append({"at": round(t, 4), "pose": dict(pose)})

    at(0.0)
    start = t
    # a slow move: a reach over 3 s
    at(3.0, shoulder_pan=35.0, shoulder_lift=-30.0, elbow_flex=40.0, wrist_flex=20.0)
    at(0.5)
    classes.append(("slow move", start, t))
    start = t
    # a fast swing to the pan's limits and back (about 230 deg/s peak)
    at(0.7, shoulder_pan=-100.0)
    at(0.3)
    at(0.9, shoulder_pan=100.0)
    at(0.3)
    at(0.7, shoulder_pan=0.0)
    at(0.4)
    classes.append(("fast swing at the limits", start, t))
    start = t
    # a flick out and back: the wrist snapped and returned
    at(0.15, wrist_flex=65.0, wrist_roll=50.0)
    at(0.15, wrist_flex=20.0, wrist_roll=0.0)
    at(0.6)
    classes.append(("flick out and back", start, t))
    start = t
    # a reversal wiggle at 1 Hz: +-20 deg on the pan, +-10 on the elbow
    for k in range(4):
        at(0.5 if k else 0.25, shoulder_pan=20.0, elbow_flex=50.0)
        at(0.5, shoulder_pan=-20.0, elbow_flex=30.0)
    at(0.25, shoulder_pan=0.0, elbow_flex=40.0)
    at(0.4)
    classes.append(("wiggle 1 Hz", start, t))
    start = t
    # at 2 Hz: +-12 deg on the pan, +-6 on the elbow
    for k in range(6):
        at(0.25 if k else 0.125, shoulder_pan=12.0, elbow_flex=46.0)
        at(0.25, shoulder_pan=-12.0, elbow_flex=34.0)
    at(0.125, shoulder_pan=0.0, elbow_flex=40.0)
    at(0.4)
    classes.append(("wiggle 2 Hz", start, t))
    start = t
    # a step: the elbow knocked 30 deg in 30 ms, held, knocked back
    at(0.03, elbow_flex=70.0)
    at(1.2)
    at(0.03, elbow_flex=40.0)
    at(1.0)
    classes.append(("step", start, t))
    start = t
    # a hold
    at(2.0)
    classes.append(("hold", start, t))
    return frames, classes


def write_hand(path: Path) -> list[tuple[str, float, float]]:
    frames, classes = motion()
    first = {"at": 0.0, "pose": dict(REST)}
    lines = ["# The teleop benchmark's leader motion (python/bench/teleop.py).", "keyframes:"]
    for f in [first] + frames:
        pose = ", ".join(f"{j}: {f['pose'][j]:.3f}" for j in JOINTS)
        lines.append(f"  - {{at: {f['at']}, pose: {{{pose}}}}}")
    path.write_text("\n".join(lines) + "\n")
    return classes


# --- the simulators -----------------------------------------------------
class SimArm:
    """``servobus sim --robot so101`` on a pty, its link at ``link`` and its
    truth in ``truth``; ``started`` is the wall time it said it serves."""

    def __init__(self, servobus: str, link: Path, truth: Path, hand: Path | None = None) -> None:
        cmd = [servobus, "sim", "--robot", "so101", "--link", str(link), "--truth", str(truth)]
        if hand is not None:
            cmd += ["--hand", str(hand)]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline() if self.proc.stdout else ""
        self.started = time.time()
        if "serving" not in line:
            self.proc.kill()
            raise RuntimeError(f"servobus sim did not start: {line!r} {self.proc.stderr.read() if self.proc.stderr else ''}")
        self.port = str(link)
        self.truth = truth

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


def read_truth(path: Path, started: float) -> tuple[np.ndarray, np.ndarray]:
    """(wall times, angles of shape (rows, joints)) of a truth CSV."""
    rows = []
    with open(path) as f:
        header = f.readline().strip().split(",")
        cols = [header.index(j) for j in JOINTS]
        for line in f:
            parts = line.strip().split(",")
            if len(parts) == len(header):
                try:
                    rows.append([float(parts[0])] + [float(parts[c]) for c in cols])
                except ValueError:
                    continue
    a = np.asarray(rows)
    return a[:, 0] + started, a[:, 1:]


# --- the followers ------------------------------------------------------
def save_calibration(port: str, kind: str, ident: str, cal_dir: Path) -> None:
    """LeRobot's calibration of the simulated arm at ``port``, as read from
    the servos by its own FeetechMotorsBus, saved where ``kind``
    (robots/teleoperators) with ``ident`` finds it."""
    from lerobot.motors import Motor, MotorNormMode
    from lerobot.motors.feetech import FeetechMotorsBus

    norm = MotorNormMode.RANGE_M100_100
    motors = {j: Motor(i + 1, "sts3215", MotorNormMode.RANGE_0_100 if j == "gripper" else norm)
              for i, j in enumerate(JOINTS)}
    bus = FeetechMotorsBus(port=port, motors=motors)
    bus.connect()
    cal = bus.read_calibration()
    bus.disconnect(disable_torque=False)
    from dataclasses import asdict

    cal_dir.mkdir(parents=True, exist_ok=True)
    (cal_dir / f"{ident}.json").write_text(json.dumps({k: asdict(v) for k, v in cal.items()}, indent=4))


def timed(fn, store: list):
    def wrapper(*args, **kwargs):
        t = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            store.append(time.perf_counter() - t)
    return wrapper


def teleop_loop(teleop, robot, fps: int, until: float) -> None:
    """LeRobot 0.6.1's ``lerobot_teleoperate.teleop_loop`` with its default
    (identity) processors, step for step: observation, the leader's
    action, ``send_action``, then a sleep to the next period. (That module
    imports torchvision, which the benchmark's venv need not have.)"""
    while time.time() < until:
        loop_start = time.perf_counter()
        robot.get_observation()
        action = teleop.get_action()
        robot.send_action(action)
        left = 1.0 / fps - (time.perf_counter() - loop_start)
        if left > 0:
            time.sleep(left)


def run_lerobot(kind: str, leader: SimArm, follower: SimArm, work: Path, until: float) -> dict:
    from lerobot.robots import make_robot_from_config
    from lerobot.robots.so_follower.config_so_follower import SOFollowerRobotConfig
    from lerobot.teleoperators import make_teleoperator_from_config
    from lerobot.teleoperators.so_leader.config_so_leader import SOLeaderTeleopConfig
    from lerobot_robot_servobus import SO101ServobusConfig

    cal = work / "calibration"
    save_calibration(leader.port, "teleoperators", "bench_leader", cal / "leader")
    save_calibration(follower.port, "robots", "bench_follower", cal / "follower")
    tconf = SOLeaderTeleopConfig(port=leader.port, id="bench_leader", calibration_dir=cal / "leader")
    if kind == "stock":
        rconf = SOFollowerRobotConfig(port=follower.port, id="bench_follower", calibration_dir=cal / "follower")
    else:
        rconf = SO101ServobusConfig(port=follower.port, id="bench_follower", calibration_dir=cal / "follower",
                                    latency=0.01)
    robot = make_robot_from_config(rconf)
    teleop = make_teleoperator_from_config(tconf)
    robot.connect(calibrate=False)
    teleop.connect(calibrate=False)
    sends: list[float] = []
    obs: list[float] = []
    robot.send_action = timed(robot.send_action, sends)
    robot.get_observation = timed(robot.get_observation, obs)
    try:
        teleop_loop(teleop, robot, FPS, until)
    finally:
        for device in (teleop, robot):
            try:
                device.disconnect()
            except Exception as e:  # a benchmark reports, it does not stop
                print(f"  ({kind}: disconnect: {str(e).splitlines()[0] if str(e) else e!r})", file=sys.stderr)
    return {"send_action": sends, "get_observation": obs}


def run_follow(servobus: str, leader: SimArm, follower: SimArm, until: float) -> dict:
    proc = subprocess.Popen([servobus, "follow", "--robot", "so101", "--port", follower.port,
                             "--leader", leader.port, "--leader-robot", "so101", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    while time.time() < until and proc.poll() is None:
        time.sleep(0.1)
    early = proc.poll() is not None
    if not early:
        proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=15)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
    if early or proc.returncode not in (0, 1):
        when = "before the motion's end" if early else ""
        print(f"  (follow exited {proc.returncode} {when}: {err.strip().splitlines()[-3:] if err else ''})",
              file=sys.stderr)
    return {}


# --- the figures ----------------------------------------------------------
def figures(lt, lq, ft, fq, t0, t1) -> dict:
    """Per joint: the figures of the module's doc, over [t0, t1] (wall)."""
    dt = 0.005
    grid = np.arange(t0, t1, dt)
    out = {}
    for k, j in enumerate(JOINTS):
        lead = np.interp(grid, lt, lq[:, k])
        foll = np.interp(grid, ft, fq[:, k])
        err = foll - lead
        best, lag = None, 0.0
        for s in np.arange(0.0, 0.4, 0.005):
            shifted = np.interp(grid - s, lt, lq[:, k])
            rms = float(np.sqrt(np.mean((foll - shifted) ** 2)))
            if best is None or rms < best:
                best, lag = rms, s
        n = int(round(ENVELOPE_S / dt))
        over = 0.0
        for i in range(len(grid)):
            w = lead[max(0, i - n):i + 1]
            over = max(over, foll[i] - w.max(), w.min() - foll[i])
        # The physical motion at the truth's own rate (resampled evenly at
        # its median step), differentiated.
        step = float(np.median(np.diff(ft)))
        g2 = np.arange(t0, t1, step)
        p = np.interp(g2, ft, fq[:, k])
        acc = np.diff(p, 2) / step**2
        jerk = np.diff(p, 3) / step**3
        out[j] = {
            "worst": float(np.max(np.abs(err))), "rms": float(np.sqrt(np.mean(err**2))),
            "lag_ms": lag * 1000.0, "overshoot": max(0.0, over),
            "rms_jerk": float(np.sqrt(np.mean(jerk**2))), "peak_acc": float(np.max(np.abs(acc))),
            "span": float(np.ptp(lead)),
        }
    return out


def print_by_class(classes, kinds, results) -> None:
    """The figures of each motion class, for the joints the hand moves in
    it (the leader's span over the class above 2 deg), means over rounds."""
    print("\nper motion class (joints the hand moves in it):")
    print(f"{'class':<26}{'joint':<14}{'follower':<16}{'worst':>8}{'rms':>7}{'lag':>6}{'over':>7}{'jerk':>8}")
    for name, _, _ in classes:
        for j in JOINTS:
            rows = []
            for kind in kinds:
                runs = [c[name][j] for _, _, c in results[kind] if name in c]
                if runs:
                    rows.append((kind, {key: statistics.fmean(x[key] for x in runs) for key in runs[0]}))
            if not rows or max(r["span"] for _, r in rows) < 2.0:
                continue
            for kind, m in rows:
                print(f"{name:<26}{j:<14}{kind:<16}{m['worst']:8.1f}{m['rms']:7.2f}{m['lag_ms']:6.0f}"
                      f"{m['overshoot']:7.1f}{m['rms_jerk'] / 1000:8.1f}")


def quantiles(samples: list[float]) -> str:
    if not samples:
        return "-"
    ms = sorted(s * 1000.0 for s in samples)
    p = lambda q: ms[min(len(ms) - 1, int(q * len(ms)))]  # noqa: E731
    return f"{p(0.5):.2f}/{p(0.99):.2f}"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--servobus", default=os.environ.get("SERVOBUS", "servobus"),
                    help="the servobus command (default: $SERVOBUS or servobus on PATH)")
    ap.add_argument("--rounds", type=int, default=1, help="rounds of the three followers, alternated")
    ap.add_argument("--followers", default="stock,so101_servobus,follow")
    ap.add_argument("--keep", type=Path, help="keep the truth CSVs and hand file here")
    ap.add_argument("--by-class", action="store_true",
                    help="also print the figures of each motion class, per joint that moves in it")
    args = ap.parse_args()
    if not 1 <= args.rounds <= 20:
        ap.error("--rounds: 1 to 20")
    stand_in_torch()
    from lerobot.utils.import_utils import register_third_party_plugins

    register_third_party_plugins()
    kinds = [k.strip() for k in args.followers.split(",") if k.strip()]
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="servobus-teleop-"))
    work.mkdir(parents=True, exist_ok=True)
    hand = work / "hand.yaml"
    classes = write_hand(hand)
    motion_start, motion_end = classes[0][1], classes[-1][2]
    results: dict[str, list] = {k: [] for k in kinds}
    for r in range(args.rounds):
        order = kinds if r % 2 == 0 else kinds[::-1]
        for kind in order:
            run = work / f"{kind}-{r}"
            run.mkdir(exist_ok=True)
            print(f"round {r + 1}: {kind} ...", file=sys.stderr)
            leader = SimArm(args.servobus, run / "leader", run / "leader.csv", hand)
            follower = SimArm(args.servobus, run / "follower", run / "follower.csv")
            until = leader.started + motion_end + 0.5
            try:
                if kind == "follow":
                    timings = run_follow(args.servobus, leader, follower, until)
                else:
                    timings = run_lerobot(kind, leader, follower, run, until)
            finally:
                follower.stop()
                leader.stop()
            (run / "started.json").write_text(json.dumps({"leader": leader.started, "follower": follower.started}))
            lt, lq = read_truth(leader.truth, leader.started)
            ft, fq = read_truth(follower.truth, follower.started)
            t0, t1 = leader.started + motion_start, min(leader.started + motion_end, ft[-1], lt[-1])
            spans = [(name, leader.started + a, min(leader.started + b, t1)) for name, a, b in classes]
            per_class = {name: figures(lt, lq, ft, fq, a, b) for name, a, b in spans if b - a > 0.2}
            results[kind].append((figures(lt, lq, ft, fq, t0, t1), timings, per_class))
    print(f"\nteleop at {FPS} Hz, {args.rounds} round(s); motion classes: "
          + "; ".join(f"{n} ({b - a:.1f} s)" for n, a, b in classes))
    print("angles in deg; worst/RMS error; lag ms; overshoot beyond the 0.5 s envelope deg; "
          "RMS jerk k deg/s^3; peak acceleration deg/s^2")
    print(f"{'joint':<14}{'follower':<16}{'worst':>8}{'rms':>7}{'lag':>6}{'over':>7}{'jerk':>8}{'acc':>8}")
    for j in JOINTS:
        for kind in kinds:
            runs = [f[j] for f, _, _ in results[kind]]
            mean = {key: statistics.fmean(x[key] for x in runs) for key in runs[0]}
            print(f"{j:<14}{kind:<16}{mean['worst']:8.1f}{mean['rms']:7.2f}{mean['lag_ms']:6.0f}"
                  f"{mean['overshoot']:7.1f}{mean['rms_jerk'] / 1000:8.1f}{mean['peak_acc']:8.0f}")
    print("\nsend_action / get_observation, ms p50/p99:")
    for kind in kinds:
        sends = [s for _, t, _ in results[kind] for s in t.get("send_action", [])]
        obs = [s for _, t, _ in results[kind] for s in t.get("get_observation", [])]
        print(f"  {kind:<16} {quantiles(sends):>14} {quantiles(obs):>14}")
    if args.by_class:
        print_by_class(classes, kinds, results)
    print(f"\n(files in {work})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
