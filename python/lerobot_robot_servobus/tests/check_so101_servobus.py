#!/usr/bin/env python3
"""LeRobot's SO-101 follower code path with the ``so101_servobus`` robot
type, against servobus's simulated arm (``servobus.Sim``).

Run with a Python that has LeRobot (0.6.1, installed as
scripts/python_clients.sh installs it), servobus and this distribution:

1. LeRobot's own ``FeetechMotorsBus`` (Feetech's SDK underneath) reads the
   calibration the simulated servos hold; it is saved as LeRobot's
   calibration file ``<id>.json``, unchanged.
2. The robot is made by LeRobot's ``make_robot_from_config`` from
   ``SO101ServobusConfig`` and connects without asking to calibrate (the
   file matches the servos).
3. ``get_observation()`` matches what ``FeetechMotorsBus`` reads from the
   same simulator within 1 tick per joint.
4. ``send_action()`` moves the simulated arm to the action within 1 degree
   (checked by ``FeetechMotorsBus`` too).
5. ``disconnect()`` turns the torque off.

Prints ``PASS ...`` lines and a closing ``N passed, 0 failed``; exits 1 on
the first failure.
"""

import importlib.machinery
import sys
import tempfile
import time
import types
from pathlib import Path

TICKS = 4096
PASSED = []


def stand_in_torch():
    """LeRobot's utilities name torch in annotations only; without torch
    installed an empty module stands in (as the repository's LeRobot checks do)."""
    try:
        import torch  # noqa: F401
    except ImportError:
        torch = types.ModuleType("torch")
        torch.__spec__ = importlib.machinery.ModuleSpec("torch", None)
        # Any name LeRobot's types take from torch (device, dtype, Tensor,
        # ...) is an empty class: they are used in annotations only on
        # the robot's path.
        torch.__getattr__ = lambda name: type(name, (), {})
        sys.modules["torch"] = torch


def check(name, ok, detail=""):
    if not ok:
        print(f"FAIL {name}: {detail}")
        print(f"{len(PASSED)} passed, 1 failed")
        sys.exit(1)
    PASSED.append(name)
    print(f"PASS {name}")


def tick_in_units(bus, motor):
    """One tick of `motor` in LeRobot's normalised units."""
    cal = bus.calibration[motor]
    if motor == "gripper":  # RANGE_0_100 over [range_min, range_max]
        return 100.0 / (cal.range_max - cal.range_min)
    return 360.0 / (TICKS - 1)  # DEGREES


def feetech_positions(port, motors, calibration):
    from lerobot.motors.feetech import FeetechMotorsBus

    bus = FeetechMotorsBus(port=port, motors=motors, calibration=calibration)
    bus.connect()
    try:
        return bus.sync_read("Present_Position", num_retry=2), bus
    finally:
        bus.disconnect(disable_torque=False)


def main():
    stand_in_torch()
    import servobus
    from lerobot.motors.feetech import FeetechMotorsBus
    from lerobot.robots import make_robot_from_config
    from lerobot.utils.import_utils import register_third_party_plugins

    # LeRobot's own discovery of distributions named lerobot_robot_*.
    register_third_party_plugins()
    from lerobot_robot_servobus import SO101Servobus, SO101ServobusConfig

    with servobus.Sim("so101") as sim, tempfile.TemporaryDirectory() as tmp:
        cal_dir = Path(tmp)
        # 50 ms of adapter latency allowed: the simulator serves from a
        # thread of this process, which a loaded machine may not schedule
        # within a pty's usual allowance.
        config = SO101ServobusConfig(port=sim.port, id="sim_arm", calibration_dir=cal_dir, latency=0.05)
        robot = make_robot_from_config(config)
        check("make_robot_from_config gives the servobus robot", isinstance(robot, SO101Servobus),
              type(robot).__name__)
        motors = robot.bus.motors

        # 1. The servos' calibration, through LeRobot's own bus, as its file.
        lerobot_bus = FeetechMotorsBus(port=sim.port, motors=motors)
        lerobot_bus.connect()
        calibration = lerobot_bus.read_calibration()
        lerobot_bus.disconnect(disable_torque=False)
        robot.calibration = calibration
        robot.bus.calibration = calibration
        robot._save_calibration()
        saved = (cal_dir / "sim_arm.json").read_text()
        check("the calibration file is LeRobot's", '"homing_offset"' in saved and '"range_min"' in saved)

        # 2. Connect: the file matches the servos, nothing interactive.
        robot = make_robot_from_config(config)
        robot.connect()
        check("connects calibrated", robot.is_connected and robot.is_calibrated)

        # 3. Observation against FeetechMotorsBus on the same simulator.
        obs = robot.get_observation()
        robot.bus.disconnect(disable_torque=False)
        theirs, their_bus = feetech_positions(sim.port, motors, calibration)
        robot.bus.connect(handshake=False)
        worst = max(abs(obs[f"{m}.pos"] - theirs[m]) / tick_in_units(their_bus, m) for m in motors)
        check("get_observation matches FeetechMotorsBus within 1 tick", worst <= 1.0, f"{worst:.2f} ticks")

        # 4. An action moves the arm there.
        action = {f"{m}.pos": obs[f"{m}.pos"] for m in motors}
        action["shoulder_pan.pos"] += 10.0
        action["elbow_flex.pos"] -= 8.0
        action["gripper.pos"] = 30.0
        robot.bus.enable_torque()
        deadline = time.monotonic() + 5.0
        while True:
            robot.send_action(action)
            now = robot.get_observation()
            err = {m: abs(now[f"{m}.pos"] - action[f"{m}.pos"]) for m in motors if m != "gripper"}
            if max(err.values()) <= 1.0 or time.monotonic() > deadline:
                break
            time.sleep(0.02)
        check("send_action moves the arm to the action within 1 deg", max(err.values()) <= 1.0, err)
        robot.bus.disconnect(disable_torque=False)
        theirs, _ = feetech_positions(sim.port, motors, calibration)
        off = abs(theirs["shoulder_pan"] - action["shoulder_pan.pos"])
        check("FeetechMotorsBus sees the joint there", off <= 1.0, f"{off:.2f} deg")

        # 5. Disconnect turns the torque off.
        robot.bus.connect(handshake=False)
        robot.disconnect()
        with servobus.Bus(sim.port, latency=0.05) as bus:
            torque = [bus.read(motors[m].id, "torque_enable") for m in motors]
        check("disconnect turns the torque off", torque == [0] * len(motors), torque)

    print(f"{len(PASSED)} passed, 0 failed")


if __name__ == "__main__":
    main()
