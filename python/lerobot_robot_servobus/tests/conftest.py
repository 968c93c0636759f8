"""Fixtures of the so101_servobus checks: LeRobot 0.6.1's SO-101 follower
code path with the servobus robot type, against servobus's simulated arm
(``servobus.Sim``), in a Python with LeRobot installed as
scripts/python_clients.sh installs it (without torch)."""

import importlib.machinery
import sys
import types

import pytest


def _stand_in_torch():
    """LeRobot's utilities name torch in annotations only; without torch
    installed an empty module stands in (as the repository's LeRobot checks
    do): any name taken from it (device, dtype, Tensor, ...) is an empty
    class."""
    try:
        import torch  # noqa: F401
    except ImportError:
        torch = types.ModuleType("torch")
        torch.__spec__ = importlib.machinery.ModuleSpec("torch", None)
        torch.__getattr__ = lambda name: type(name, (), {})
        sys.modules["torch"] = torch


_stand_in_torch()

import servobus  # noqa: E402
from lerobot.motors.feetech import FeetechMotorsBus  # noqa: E402
from lerobot.robots import make_robot_from_config  # noqa: E402
from lerobot.utils.import_utils import register_third_party_plugins  # noqa: E402

# LeRobot's own discovery of distributions named lerobot_robot_*.
register_third_party_plugins()

from lerobot_robot_servobus import SO101ServobusConfig  # noqa: E402

# 50 ms of adapter latency allowed: the simulator serves from a thread of
# this process, which a loaded machine may not schedule within a pty's
# usual allowance.
SLACK = 0.05


@pytest.fixture
def sim():
    """The simulated SO-101 arm on a pseudo-terminal."""
    with servobus.Sim("so101") as s:
        yield s


def make_config(sim, tmp_path, **options):
    """The so101_servobus configuration of the simulated arm ``sim``
    (``options`` its fields), its LeRobot calibration file (read from the
    servos by LeRobot's own ``FeetechMotorsBus``) saved in ``tmp_path`` as
    ``sim_arm.json``."""
    config = SO101ServobusConfig(port=sim.port, id="sim_arm", calibration_dir=tmp_path, latency=SLACK,
                                 **options)
    robot = make_robot_from_config(config)
    theirs = FeetechMotorsBus(port=sim.port, motors=robot.bus.motors)
    theirs.connect()
    calibration = theirs.read_calibration()
    theirs.disconnect(disable_torque=False)
    robot.calibration = calibration
    robot._save_calibration()
    return config


@pytest.fixture
def config(sim, tmp_path):
    """:func:`make_config` of the simulated arm."""
    return make_config(sim, tmp_path)


@pytest.fixture
def robot(config):
    """The so101_servobus robot, connected (calibrated by its file)."""
    robot = make_robot_from_config(config)
    robot.connect()
    yield robot
    if robot.is_connected:
        robot.disconnect()


def feetech_positions(robot):
    """What LeRobot's ``FeetechMotorsBus`` reads of the arm (degrees, the
    gripper 0..100), the robot's bus off the port meanwhile."""
    robot.bus.disconnect(disable_torque=False)
    theirs = FeetechMotorsBus(port=robot.bus.port, motors=robot.bus.motors, calibration=robot.calibration)
    theirs.connect()
    try:
        return theirs.sync_read("Present_Position", num_retry=2)
    finally:
        theirs.disconnect(disable_torque=False)
        robot.bus.connect(handshake=False)
