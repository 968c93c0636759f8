#!/usr/bin/env python3
r"""Drives a simulated SO-101 arm with Hugging Face LeRobot's Feetech bus, unchanged.

Usage: lerobot_check.py PORT [--scan]
       (six STS3215 servos, IDs 1..6, at 1 Mbps: the SO-101 follower's motors)

Builds a `lerobot.motors.feetech.FeetechMotorsBus` for the six SO-101 joints
and runs through what LeRobot's SO-101 follower does with it: connect with
the handshake (ping and firmware check of every motor), broadcast ping, ping
each motor, read the calibration the servos hold and use it, configure the
motors with torque off, sync-read present positions raw and normalised,
sync-write goal positions (normalised, then raw) with torque on and check
that every joint got there, then disconnect (which turns torque off) and
check that it did. `--scan` also runs `FeetechMotorsBus.scan_port`, which
tries every baud rate LeRobot knows and takes about 16 s; the servos must
answer at 1 Mbps only. Exits 0 and prints one `OK 6 motors ...` line when
everything matched, prints `FAIL reason` and exits 1 otherwise.

Requires Python >= 3.12 (LeRobot 0.5 and later) and, in a virtualenv:
    pip install --no-deps lerobot==0.6.1
    pip install 'tqdm>=4.66,<5' 'feetech-servo-sdk>=1.0.0,<2' 'pyserial>=3.5,<4' \
        'deepdiff>=7.0.1,<9' 'huggingface-hub>=1.6,<2' 'numpy>=2.0,<2.3' \
        'draccus>=0.11.6,<0.12'
(`scripts/lerobot_check.sh` does this and starts the simulator.) PyTorch is
not needed: `lerobot.utils` imports torch only to annotate its device helpers,
which the motors code never calls, so when torch is missing this script puts
an empty stand-in module under that name before importing LeRobot. With
`pip install 'lerobot[feetech]'` (torch included) the real one is used.
"""

import contextlib
import importlib.machinery
import sys
import time
import types

NAMES = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]
STS3215 = 777
TICKS = 4096  # one turn
RAW_TOLERANCE = 2  # ticks
SETTLE_TIMEOUT = 3.0  # s; each move is at most ~20 degrees


def fail(msg):
    print(f"FAIL {msg}")
    sys.exit(1)


def import_lerobot():
    """Imports LeRobot's motor classes, with a stand-in for torch if it is absent."""
    try:
        import torch  # noqa: F401
    except ImportError:
        stand_in = types.ModuleType("torch")
        stand_in.__spec__ = importlib.machinery.ModuleSpec("torch", None)
        # Only these names are evaluated when lerobot.utils.device_utils is imported
        # (as annotations); nothing on the motors path calls into torch.
        stand_in.device = type("device", (), {})
        stand_in.dtype = type("dtype", (), {})
        sys.modules["torch"] = stand_in
    import lerobot
    from lerobot.motors import Motor, MotorNormMode
    from lerobot.motors.feetech import FeetechMotorsBus, OperatingMode

    return lerobot.__version__, Motor, MotorNormMode, FeetechMotorsBus, OperatingMode


def expected_raw(bus, name, value):
    """Raw ticks for a normalised value, computed here from the calibration."""
    cal = bus.calibration[name]
    lo, hi = cal.range_min, cal.range_max
    if name == "gripper":  # range 0..100 over [lo, hi]
        return round(lo + value / 100 * (hi - lo))
    return round((lo + hi) / 2 + value * (TICKS - 1) / 360)  # degrees about the middle


def wait_for(bus, goals_raw):
    """Polls Present_Position until every joint is within tolerance of its goal."""
    deadline = time.monotonic() + SETTLE_TIMEOUT
    while True:
        now = bus.sync_read("Present_Position", normalize=False)
        off = {n: now[n] - goals_raw[n] for n in NAMES}
        if all(abs(d) <= RAW_TOLERANCE for d in off.values()):
            return now
        if time.monotonic() > deadline:
            far = {n: (now[n], goals_raw[n]) for n in NAMES if abs(off[n]) > RAW_TOLERANCE}
            fail(f"joints not at goal after {SETTLE_TIMEOUT} s: (present, goal) {far}")
        time.sleep(0.05)


def check(port, scan):
    version, Motor, MotorNormMode, FeetechMotorsBus, OperatingMode = import_lerobot()

    if scan:
        with contextlib.redirect_stdout(sys.stderr):  # its progress lines: stdout keeps one line
            found = FeetechMotorsBus.scan_port(port)
        if found != {1_000_000: [1, 2, 3, 4, 5, 6]}:
            fail(f"scan_port found {found}, expected servos 1..6 at 1000000 only")

    # As LeRobot's SO-101 follower: degrees for the joints, 0..100 for the gripper.
    motors = {
        name: Motor(i + 1, "sts3215", MotorNormMode.RANGE_0_100 if name == "gripper" else MotorNormMode.DEGREES)
        for i, name in enumerate(NAMES)
    }
    bus = FeetechMotorsBus(port=port, motors=motors)
    bus.connect()  # handshake: ping every ID, check models, read firmware versions

    found = bus.broadcast_ping()
    if found != {i: STS3215 for i in range(1, 7)}:
        fail(f"broadcast ping found {found}")
    for name in NAMES:
        model = bus.ping(name)
        if model != STS3215:
            fail(f"ping {name}: {model}")

    # The servos' own limits and homing offsets become the calibration; writing
    # them back (as calibration does) must leave the bus calibrated.
    calibration = bus.read_calibration()
    with bus.torque_disabled():
        bus.write_calibration(calibration)
        bus.configure_motors()
        for name in NAMES:
            bus.write("Operating_Mode", name, OperatingMode.POSITION.value)
            bus.write("P_Coefficient", name, 16)
            bus.write("I_Coefficient", name, 0)
            bus.write("D_Coefficient", name, 32)
    if not bus.is_calibrated:
        fail(f"not calibrated after writing {calibration}")
    torque = bus.sync_read("Torque_Enable")
    if any(v != 1 for v in torque.values()):
        fail(f"torque not enabled: {torque}")
    if any(bus.read("Return_Delay_Time", n) != 0 for n in NAMES):
        fail("Return_Delay_Time not 0 after configure_motors")

    start_raw = bus.sync_read("Present_Position", normalize=False)
    start = bus.sync_read("Present_Position")
    for n in NAMES:
        if abs(expected_raw(bus, n, start[n]) - start_raw[n]) > 1:
            fail(f"{n}: normalised {start[n]:.2f} does not match raw {start_raw[n]}")

    # Move 1: normalised goals, 15 degrees (10 % for the gripper) toward the middle.
    goals = {}
    for n in NAMES:
        step = 10.0 if n == "gripper" else 15.0
        middle = 50.0 if n == "gripper" else 0.0
        goals[n] = start[n] + (step if start[n] < middle else -step)
    bus.sync_write("Goal_Position", goals)
    goals_raw = {n: expected_raw(bus, n, goals[n]) for n in NAMES}
    reached = wait_for(bus, goals_raw)
    back = bus.sync_read("Goal_Position", normalize=False)
    if any(abs(back[n] - goals_raw[n]) > 1 for n in NAMES):
        fail(f"Goal_Position reads {back}, wrote {goals_raw}")

    # Move 2: raw goals, back to where the joints started.
    bus.sync_write("Goal_Position", start_raw, normalize=False)
    wait_for(bus, start_raw)

    bus.disconnect()  # turns torque off first
    bus.connect(handshake=False)
    torque = bus.sync_read("Torque_Enable")
    bus.disconnect(disable_torque=False)
    if any(v != 0 for v in torque.values()):
        fail(f"torque still on after disconnect: {torque}")

    moved = " ".join(f"{n}:{start_raw[n]}->{reached[n]}" for n in NAMES)
    print(
        f"OK 6 motors: LeRobot {version} FeetechMotorsBus: handshake, broadcast ping, ping, "
        f"calibration, configure, sync read, torque, sync write (normalised, raw), "
        f"disconnect{', scan' if scan else ''}; {moved}"
    )


def main():
    args = sys.argv[1:]
    if not args or args[0].startswith("-") or set(args[1:]) - {"--scan"}:
        print(__doc__)
        sys.exit(2)
    try:
        check(args[0], "--scan" in args)
    except SystemExit:
        raise
    except Exception as e:  # LeRobot reports bus trouble as exceptions
        first = str(e).strip().splitlines()
        fail(f"{type(e).__name__}: {' '.join(first) if first else ''}")


if __name__ == "__main__":
    main()
