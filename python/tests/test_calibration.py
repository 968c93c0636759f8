"""Calibrations: Robot.calibrate on the simulated arm (the first-arm
walkthrough's scripted hand moving the joints, in virtual time), saving and
loading, and LeRobot's calibration files in and out."""

import json

import pytest

import servobus

TICKS_PER_DEG = 4096 / 360.0


@pytest.fixture(scope="module")
def calibration():
    """The simulated SO-101 calibrated by the procedure of `servobus calibrate`."""
    return servobus.Robot("so101").calibrate(hand="so101-first-arm-hand")


def test_calibrate_on_the_simulator_measures_pose_direction_and_range(calibration):
    assert calibration.robot == "so101"
    names = [j.name for j in calibration.joints]
    assert names == ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]
    for j in calibration.joints:
        assert j.direction == 1, j
        assert j.homing_offset == 0, j
        assert j.model == "STS3215"
    # The robot file's servos as designed: angle 0 at tick 2048, the
    # gripper's at its offset of -20 deg (2048 - 20 x 4096/360 = 1820.4).
    assert calibration["shoulder_pan"].pose_tick == pytest.approx(2048, abs=1)
    assert calibration["gripper"].pose_tick == pytest.approx(1820.4, abs=1)
    # The hand sweeps the pan to +-115 deg and the elbow to +-102 deg.
    lo, hi = calibration["shoulder_pan"].range
    assert lo == pytest.approx(2048 - 115 * TICKS_PER_DEG, abs=3)
    assert hi == pytest.approx(2048 + 115 * TICKS_PER_DEG, abs=3)
    lo, hi = calibration["elbow_flex"].range
    assert lo == pytest.approx(2048 - 102 * TICKS_PER_DEG, abs=3)
    assert hi == pytest.approx(2048 + 102 * TICKS_PER_DEG, abs=3)
    # Ticks and angles through the joint's calibration.
    pan = calibration["shoulder_pan"]
    assert pan.degrees_at(pan.pose_tick + 1024) == pytest.approx(90.0)
    assert pan.tick_at(-90.0) == pytest.approx(pan.pose_tick - 1024)


def test_a_calibration_saved_loads_the_same_and_a_robot_applies_it(calibration, tmp_path):
    path = tmp_path / "arm.calibration.yaml"
    calibration.save(path)
    assert "pose_tick" in path.read_text()
    assert servobus.Calibration.load(path) == calibration
    robot = servobus.Robot("so101", calibration=path)
    same = servobus.Robot("so101", calibration=calibration)
    assert robot.limits == same.limits
    # The robot file's limits are narrower than the measured pan range.
    pan = robot.limits["shoulder_pan"]
    assert (pan.min, pan.max, pan.max_velocity) == (-110.0, 110.0, 180.0)


def test_calibrate_says_each_step_and_saves_to_output(tmp_path):
    out = tmp_path / "out.yaml"
    steps = []
    cal = servobus.Robot("so101").calibrate(out, hand="so101-first-arm-hand", on_step=steps.append)
    assert steps == ["torque_off", "hold_pose", "sweep", "done"]
    assert servobus.Calibration.load(out) == cal


def test_an_exception_in_on_step_ends_the_procedure_and_nothing_is_saved(tmp_path):
    out = tmp_path / "out.yaml"

    def refuse(step):
        if step == "sweep":
            raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        servobus.Robot("so101").calibrate(out, hand="so101-first-arm-hand", on_step=refuse)
    assert not out.exists()


def test_a_calibration_goes_to_lerobot_and_back(calibration):
    lerobot = json.loads(calibration.to_lerobot())
    assert lerobot["shoulder_pan"] == {
        "id": 1,
        "drive_mode": 0,
        "homing_offset": 0,
        "range_min": calibration["shoulder_pan"].range[0],
        "range_max": calibration["shoulder_pan"].range[1],
    }
    back = servobus.Calibration.from_lerobot(calibration.to_lerobot(), robot="so101")
    # LeRobot files have no pose: it is the middle of the range.
    lo, hi = calibration["elbow_flex"].range
    assert back["elbow_flex"].pose_tick == pytest.approx((lo + hi) / 2)
    assert back["elbow_flex"].range == (lo, hi)


def test_a_lerobot_file_of_another_robot_is_a_config_error():
    with pytest.raises(servobus.ConfigError, match="shoulder_pan"):
        servobus.Calibration.from_lerobot('{"base": {"id": 1, "drive_mode": 0, "homing_offset": 0, '
                                          '"range_min": 0, "range_max": 4095}}')


def test_calibrate_on_the_simulator_without_a_hand_is_a_usage_error():
    with pytest.raises(servobus.UsageError, match="hand"):
        servobus.Robot("so101").calibrate()
