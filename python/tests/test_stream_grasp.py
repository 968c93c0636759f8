"""Stream.send_grasp: a gripper told to grasp with an effort in percent of
its servo's torque, on the built-in simulator; a grasp the robot cannot
make raises a one-line UsageError and the stream goes on."""

import math

import pytest

import servobus


def test_a_grasp_is_accepted_beside_targets():
    with servobus.Robot("so101").stream(timeout=2.0) as stream:
        assert stream.send_grasp({"gripper": 40}) is None
        assert stream.send_grasp({"gripper": 100.0}) is None
        assert not stream.finished
        # The other joints still take targets; a position for the gripper
        # (which releases it) is taken too.
        assert stream.send({"shoulder_pan": 2.0}) == 0
        assert stream.send({"gripper": 10.0}) == 0
    live = stream.report.raw["live"]
    assert live["received"] == 4
    assert live["refused"] == 0


@pytest.mark.parametrize("grasps, says", [
    ({"gripper": 0}, "joint `gripper`: cannot grasp: its effort is a percentage"),
    ({"gripper": 150}, "joint `gripper`: cannot grasp: its effort is a percentage"),
    ({"gripper": -5}, "above 0 and at most 100"),
    ({"gripper": math.nan}, "above 0 and at most 100"),
    ({"thumb": 40}, "no joint is named `thumb`"),
    ({"gripper": "firm"}, "joint `gripper`: the effort is not a number"),
    ({}, "no joint named"),
    (40, "give a dict of joint name to effort"),
])
def test_a_grasp_the_robot_cannot_make_raises_one_line(grasps, says):
    with servobus.Robot("so101").stream(timeout=2.0) as stream:
        with pytest.raises(servobus.UsageError) as caught:
            stream.send_grasp(grasps)
        message = str(caught.value)
        assert says in message, message
        assert "\n" not in message
        # Refused whole: the stream goes on.
        assert stream.send_grasp({"gripper": 30}) is None
        assert not stream.finished
