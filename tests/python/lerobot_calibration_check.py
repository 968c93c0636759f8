#!/usr/bin/env python3
r"""Checks that LeRobot accepts a calibration written by `servobus calibrate`.

Usage: lerobot_calibration_check.py PORT CALIBRATION.json

The servos on PORT (six STS3215, IDs 1..6, the SO-101's) must hold the
calibration: `servobus calibrate --from-lerobot ... --write-servos
--to-lerobot CALIBRATION.json` stored it. This script loads the file the way
LeRobot loads a robot's calibration (one MotorCalibration per motor), hands
it to LeRobot's FeetechMotorsBus, and asks LeRobot whether the servos are
calibrated. Then it prints one line per motor, `name raw degrees m100 r100`:
the raw Present_Position and LeRobot's own normalisations of it (DEGREES,
RANGE_M100_100, RANGE_0_100), for the test to compare with servobus.
Prints `OK calibrated` last and exits 0, or `FAIL reason` and exits 1.
"""

import json
import pathlib
import sys

# The LeRobot import (with its stand-in for torch), the motor names and the
# failure line are those of the simulator's LeRobot check.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "crates/sim/tests/python"))
from lerobot_check import NAMES, fail, import_lerobot  # noqa: E402


def lerobot():
    _, Motor, MotorNormMode, FeetechMotorsBus, _ = import_lerobot()
    from lerobot.motors import MotorCalibration

    return Motor, MotorCalibration, MotorNormMode, FeetechMotorsBus


def main(port, path):
    Motor, MotorCalibration, MotorNormMode, FeetechMotorsBus = lerobot()
    with open(path) as f:
        calibration = {name: MotorCalibration(**values) for name, values in json.load(f).items()}
    if list(calibration) != NAMES:
        fail(f"motors {list(calibration)}")
    readings = {}
    for mode in (MotorNormMode.DEGREES, MotorNormMode.RANGE_M100_100, MotorNormMode.RANGE_0_100):
        motors = {name: Motor(calibration[name].id, "sts3215", mode) for name in NAMES}
        bus = FeetechMotorsBus(port=port, motors=motors, calibration=calibration)
        bus.connect()
        if not bus.is_calibrated:
            fail(f"LeRobot says not calibrated: servos hold {bus.read_calibration()}")
        raw = bus.sync_read("Present_Position", normalize=False)
        norm = bus.sync_read("Present_Position")
        again = bus.sync_read("Present_Position", normalize=False)
        if again != raw:
            fail(f"the servos moved while being read: {raw} then {again}")
        for name in NAMES:
            readings.setdefault(name, [raw[name]]).append(norm[name])
        bus.disconnect(disable_torque=False)
    for name in NAMES:
        print(name, *readings[name])
    print("OK calibrated")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        fail("usage: lerobot_calibration_check.py PORT CALIBRATION.json")
    main(sys.argv[1], sys.argv[2])
