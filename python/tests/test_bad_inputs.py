"""Python matches the command line's rules on bad input: a baud from the
table only, Ctrl-C raising KeyboardInterrupt from every blocking call, bad
values raising the documented exceptions (never OverflowError or a panic),
durations and rates range-checked, and a calibration's output checked
before anything moves."""

import math
import os
import signal
import threading
import time

import pytest

import servobus

from conftest import SLACK


@pytest.mark.parametrize("baud", [0, -1, 1, 999_999, 2**40])
def test_a_baud_outside_the_servos_table_is_a_config_error(sim, baud):
    with pytest.raises(servobus.ConfigError) as caught:
        servobus.Bus(sim.port, baud=baud)
    message = str(caught.value)
    assert f"{baud} baud" in message and "1000000" in message and "38400" in message


def test_a_table_baud_opens(sim):
    with servobus.Bus(sim.port, baud=1_000_000, latency=SLACK) as bus:
        assert bus.ping(1)


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 1e30, -1e30, 2**70])
def test_a_value_no_register_holds_is_a_limit_error(bus, value):
    with pytest.raises(servobus.LimitError) as caught:
        bus.write(1, "goal_position", value)
    assert "goal_position" in str(caught.value)
    with pytest.raises(servobus.LimitError):
        bus.sync_write("goal_position", {1: value})


def test_a_too_large_value_names_the_register_range(bus):
    with pytest.raises(servobus.LimitError) as caught:
        bus.write(1, "goal_position", 1e30)
    # goal_position on STS servos: 15 bits and a sign bit.
    assert (caught.value.min, caught.value.max) == (-32767, 32767)
    assert caught.value.value == 1e30


@pytest.mark.parametrize("call", [
    lambda b: b.read_raw(1, 1000, 2),
    lambda b: b.read_raw(1, -1, 2),
    lambda b: b.read_raw(1, 56, 3),
    lambda b: b.read_raw(1, 56, 2**70),
    lambda b: b.read_raw(2**70, 56, 2),
    lambda b: b.sync_read_raw(1000, 2, [1]),
    lambda b: b.write_raw(1, 1000, 2, 0),
    lambda b: b.ping(-1),
    lambda b: b.read(254, "present_position"),
])
def test_an_address_length_or_id_out_of_range_is_a_usage_error(bus, call):
    with pytest.raises(servobus.UsageError) as caught:
        call(bus)
    assert not isinstance(caught.value, OverflowError)


@pytest.mark.parametrize("value", [-1, 70000, 2**70, math.nan])
def test_a_raw_value_the_bytes_cannot_hold_is_a_limit_error(bus, value):
    with pytest.raises(servobus.LimitError):
        bus.write_raw(1, 42, 2, value)


def test_a_read_of_address_1000_does_not_touch_the_bus(bus):
    with pytest.raises(servobus.UsageError, match="address 1000"):
        bus.read_raw(1, 1000, 2)
    assert bus.read_raw(1, 56, 2) in range(4096), "the bus still answers"


@pytest.mark.parametrize("latency", [math.nan, math.inf, -0.001, 1e300, 10.0])
def test_a_latency_out_of_range_is_a_usage_error(sim, latency):
    with pytest.raises(servobus.UsageError, match="latenc"):
        servobus.Bus(sim.port, latency=latency)


@pytest.mark.parametrize("timeout", [0.0, -1.0, math.nan, math.inf, 1e-300, 1e20, 1e300])
def test_a_stream_timeout_out_of_range_is_a_usage_error(timeout):
    robot = servobus.Robot("so101")
    with pytest.raises(servobus.UsageError, match="timeout"):
        robot.stream(timeout=timeout)


@pytest.mark.parametrize("rate", [0.0, -1.0, math.nan, math.inf, 1e-300, 1e300])
def test_a_stream_rate_out_of_range_is_a_usage_error(rate):
    robot = servobus.Robot("so101")
    with pytest.raises(servobus.UsageError, match="Hz"):
        robot.stream(rate=rate)


@pytest.mark.parametrize("timeout", [0.0, -1.0, math.nan, math.inf, 1e300])
def test_a_calibration_timeout_out_of_range_is_a_usage_error(timeout):
    robot = servobus.Robot("so101")
    with pytest.raises(servobus.UsageError, match="timeout"):
        robot.calibrate(hand="so101-first-arm-hand", timeout=timeout)


@pytest.mark.parametrize("times", [
    [0.0, 1e300],
    [-1e300, 0.0],
    [0.0, 0.1, 3601.0],
    [0.0, math.inf],
    [math.nan, 0.1],
])
def test_a_chunk_time_beyond_an_hour_or_not_a_number_is_a_usage_error(times):
    with servobus.Robot("so101").stream(timeout=1.0) as stream:
        with pytest.raises(servobus.UsageError) as caught:
            stream.send_chunk(times, {"shoulder_pan": [0.0] * len(times)})
        assert "-3600 to 3600 s from now" in str(caught.value)
        # Refused whole: the stream goes on taking chunks.
        assert stream.send_chunk([0.0, 0.1], {"shoulder_pan": [0.0, 1.0]}) == 0


def test_a_base_velocity_for_a_robot_without_a_base_is_a_usage_error_that_says_so():
    with servobus.Robot("so101").stream(timeout=1.0) as stream:
        with pytest.raises(servobus.UsageError) as caught:
            stream.send_base(0.1, 0.0, 0.0)
        assert "no mobile base" in str(caught.value)
        # The stream goes on taking targets.
        assert stream.send({"shoulder_pan": 1.0}) == 0


def test_calibrate_refuses_a_directory_as_output_before_it_starts(tmp_path):
    steps = []
    robot = servobus.Robot("so101")
    with pytest.raises(servobus.Error) as caught:
        robot.calibrate(output=tmp_path, hand="so101-first-arm-hand", on_step=steps.append)
    assert "directory" in str(caught.value)
    assert caught.value.file == str(tmp_path)
    assert steps == [], "nothing was measured"


def test_calibrate_refuses_a_missing_folder_before_it_starts(tmp_path):
    steps = []
    robot = servobus.Robot("so101")
    out = tmp_path / "nowhere" / "cal.yaml"
    with pytest.raises(servobus.Error, match="does not exist"):
        robot.calibrate(output=out, hand="so101-first-arm-hand", on_step=steps.append)
    assert steps == []


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes a read-only folder")
def test_calibrate_refuses_a_read_only_folder_before_it_starts(tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        with pytest.raises(servobus.Error):
            servobus.Robot("so101").calibrate(output=folder / "cal.yaml", hand="so101-first-arm-hand")
    finally:
        folder.chmod(0o700)


def test_calibrate_saves_to_a_good_output(tmp_path):
    out = tmp_path / "cal.yaml"
    cal = servobus.Robot("so101").calibrate(output=out, hand="so101-first-arm-hand")
    assert out.exists()
    assert [j.name for j in servobus.Calibration.load(out).joints] == [j.name for j in cal.joints]
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".servobus-probe")]


def _sigint_storm(stop: threading.Event, first_after: float = 0.2) -> threading.Thread:
    """SIGINT to this process (as Ctrl-C sends it, a real signal that cuts a
    system call short), every 50 ms from ``first_after`` s until ``stop``
    is set, 200 times at most."""

    def run():
        if stop.wait(first_after):
            return
        for _ in range(200):
            os.kill(os.getpid(), signal.SIGINT)
            if stop.wait(0.05):
                return

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def test_ctrl_c_during_a_scan_raises_keyboard_interrupt_at_once(bus):
    # 248 absent IDs at 50 ms of allowed latency each: the whole scan takes
    # more than 12 s; Ctrl-C ends it at the next PING.
    stop = threading.Event()
    storm = _sigint_storm(stop)
    start = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            bus.scan()
    finally:
        stop.set()
        storm.join()
    assert time.monotonic() - start < 6.0, "the scan went on past Ctrl-C"
    assert bus.ping(1), "the bus is usable after the interrupt"


@pytest.mark.parametrize("call", [
    lambda b: b.read(1, "present_position"),
    lambda b: b.sync_read("present_position", [1, 2, 3, 4, 5, 6]),
    lambda b: b.sync_read_raw(56, 2, [1, 2, 3, 4, 5, 6]),
    lambda b: b.write(1, "goal_position", 2048),
])
def test_ctrl_c_during_blocking_calls_raises_keyboard_interrupt(bus, call):
    stop = threading.Event()
    storm = _sigint_storm(stop, first_after=0.05)
    try:
        with pytest.raises(KeyboardInterrupt):
            # Bounded: 20000 transactions take far longer than the storm's
            # first signal.
            for _ in range(20000):
                call(bus)
    finally:
        stop.set()
        storm.join()
    assert bus.ping(1)
