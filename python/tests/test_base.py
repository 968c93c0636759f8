"""A mobile base from Python: the built-in lekiwi driven with
Stream.send_base, its odometry read back with Stream.base_pose."""

import time

import servobus


def test_lekiwi_driven_forward_reports_where_it_went():
    with servobus.Robot("lekiwi").stream(timeout=0.5) as stream:
        assert stream.base_pose == (0.0, 0.0, 0.0) or stream.base_pose is None
        start = time.monotonic()
        sends = 0
        while time.monotonic() - start < 1.5 and sends < 200:
            stream.send_base(0.2, 0.0, 0.0)
            sends += 1
            time.sleep(1 / 30)
        x, y, theta = stream.base_pose
    # Forward at 0.2 m/s for about 1.5 s (a loaded machine sends fewer):
    # well on its way, straight, not turned.
    assert 0.1 < x < 0.4, x
    assert abs(y) < 0.01, y
    assert abs(theta) < 1.0, theta


def test_a_robot_without_a_base_has_no_pose():
    with servobus.Robot("so101").stream(timeout=0.5) as stream:
        assert stream.base_pose is None
