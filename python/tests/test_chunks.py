"""Stream.send_chunk: an action chunk (a timed sequence of positions, as a
policy emits it) followed as a timed path through its points, in real time
on the built-in simulator."""

import math
import time

import numpy as np
import pytest

import servobus


def ramp(start, end, points):
    return [start + (end - start) * k / (points - 1) for k in range(points)]


def wait_until(stream, done, seconds):
    """Polls the stream's state every 20 ms until ``done(state)`` or
    ``seconds`` pass: the last state."""
    deadline = time.monotonic() + seconds
    while True:
        state = stream.state()
        if done(state) or time.monotonic() > deadline:
            return state
        time.sleep(0.02)


def test_a_chunk_at_50_hz_is_followed_to_its_last_point():
    robot = servobus.Robot("so101")
    with robot.stream(timeout=2.0) as stream:
        # 50 points at 50 Hz: the pan from its rest (0 deg) to 30 deg in 1 s,
        # the elbow to 40 deg.
        clamped = stream.send_chunk(0.02, {"shoulder_pan": ramp(0.0, 30.0, 50),
                                           "elbow_flex": ramp(0.0, 40.0, 50)})
        assert clamped == 0
        halfway = wait_until(stream, lambda s: s.time > 0.0 and s["shoulder_pan"] > 12.0, 3.0)
        end = wait_until(stream, lambda s: abs(s["shoulder_pan"] - 30.0) < 0.5, 3.0)
    pan = robot.joints.index("shoulder_pan")
    # On its way it passed through the chunk's middle, not jumped to its end.
    assert 12.0 < halfway.commanded[pan] < 29.0
    assert end["shoulder_pan"] == pytest.approx(30.0, abs=1.0)
    assert end["elbow_flex"] == pytest.approx(40.0, abs=1.0)
    assert stream.report.raw["live"]["received"] >= 1
    assert end.faults == []


def test_uneven_times_and_an_array_of_positions_are_taken():
    robot = servobus.Robot("so101")
    with robot.stream(timeout=2.0) as stream:
        times = [0.0, 0.05, 0.15, 0.3, 0.5]
        rest = wait_until(stream, lambda s: bool(np.all(np.isfinite(s.position))), 2.0)
        # Every joint where it rests, the wrist rolling to 20 deg.
        rows = np.tile(rest.position, (5, 1))
        rows[:, robot.joints.index("wrist_roll")] = [0.0, 2.0, 6.0, 12.0, 20.0]
        assert stream.send_chunk(times, rows) == 0
        # Evenly spaced times go as dt.
        assert stream.send_chunk([0.6, 0.7, 0.8], {"shoulder_pan": [5.0, 10.0, 15.0]}) == 0
        state = wait_until(stream, lambda s: abs(s["wrist_roll"] - 20.0) < 0.5
                           and abs(s["shoulder_pan"] - 15.0) < 0.5, 4.0)
    assert state["wrist_roll"] == pytest.approx(20.0, abs=1.0)
    assert state["shoulder_pan"] == pytest.approx(15.0, abs=1.0)


def test_a_chunk_beyond_the_limits_is_clamped_and_counted():
    with servobus.Robot("so101").stream(timeout=1.0) as stream:
        # shoulder_pan is limited to +-110 deg: two points beyond.
        assert stream.send_chunk(0.1, {"shoulder_pan": [0.0, 120.0, 130.0]}) == 2


@pytest.mark.parametrize("times_or_dt, positions", [
    (0.02, {"shoulder_pan": [0.0, 1.0], "elbow_flex": [0.0]}),
    ([0.0, 0.1, 0.05], {"shoulder_pan": [0.0, 1.0, 2.0]}),
    ([0.0, 0.1], {"shoulder_pan": [0.0, 1.0, 2.0]}),
    (0.0, {"shoulder_pan": [0.0, 1.0]}),
    (math.nan, {"shoulder_pan": [0.0, 1.0]}),
    (1e300, {"shoulder_pan": [0.0, 1.0]}),
    (0.02, {"no_such_joint": [0.0, 1.0]}),
    (0.02, {"shoulder_pan": [0.0, math.nan]}),
    (0.02, {"shoulder_pan": []}),
    (0.02, np.zeros((3, 2))),
])
def test_a_bad_chunk_is_a_usage_error(times_or_dt, positions):
    with servobus.Robot("so101").stream(timeout=1.0) as stream:
        with pytest.raises(servobus.UsageError):
            stream.send_chunk(times_or_dt, positions)


def test_targets_and_chunks_mix_in_one_stream():
    robot = servobus.Robot("so101")
    with robot.stream(timeout=2.0) as stream:
        stream.send_chunk(0.05, {"shoulder_pan": ramp(0.0, 10.0, 10)})
        wait_until(stream, lambda s: s["shoulder_pan"] > 9.5, 3.0)
        stream.send({"shoulder_pan": -10.0})
        state = wait_until(stream, lambda s: abs(s["shoulder_pan"] + 10.0) < 0.5, 3.0)
    assert state["shoulder_pan"] == pytest.approx(-10.0, abs=1.0)
