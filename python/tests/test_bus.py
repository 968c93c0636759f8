"""The typed bus against servobus.Sim: registers by name, SYNC READ with
partial results, SYNC WRITE, and the exceptions."""

import builtins
import threading
import time

import pytest

import servobus

from conftest import SLACK

ARM = [1, 2, 3, 4, 5, 6]


def test_scan_finds_the_six_servos_of_the_arm(bus):
    assert bus.scan(range(0, 12)) == ARM
    assert bus.ping(1) is True
    assert bus.ping(9) is False


def test_a_written_goal_reads_back_and_the_servo_moves_there(bus):
    # shoulder_pan rests at the centre of the turn, 2048 ticks.
    assert bus.read(1, "torque_enable") in (0, 1)
    bus.write(1, "torque_enable", 1)
    bus.write(1, "goal_position", 2148)
    assert bus.read(1, "goal_position") == 2148
    deadline = time.monotonic() + 5.0
    while abs(bus.read(1, "present_position") - 2148) > 2:
        assert time.monotonic() < deadline, "servo 1 never reached its goal"
        time.sleep(0.02)


def test_register_names_forgive_case_and_separators(bus):
    assert bus.read(1, "Present_Position") == bus.read(1, "present position")


def test_sync_write_then_sync_read_gives_each_servo_its_value(bus):
    goals = {1: 2000, 2: 1100, 3: 3000}
    bus.sync_write("goal_position", goals)
    result = bus.sync_read("goal_position", [1, 2, 3])
    assert dict(result) == goals
    assert result.missing == {}
    assert result.complete


def test_a_missing_servo_gives_partial_results():
    with servobus.Sim("so101", faults="vanish=3") as sim, servobus.Bus(sim.port, latency=SLACK) as bus:
        result = bus.sync_read("present_position", ARM)
        assert list(result) == ARM, "one entry per servo, in the order asked"
        assert result[3] is None
        assert set(result.missing) == {3}
        assert result.missing[3].reason == "no reply"
        assert result.missing[3].attempts == 2, "asked, then asked again"
        # The arm rests with shoulder_pan at 2048 ticks and shoulder_lift at
        # -90 deg, 1024 ticks: the others' values are all there.
        assert abs(result[1] - 2048) <= 2
        assert abs(result[2] - 1024) <= 2
        assert all(isinstance(result[i], int) for i in (1, 2, 4, 5, 6))
        with pytest.raises(servobus.TimeoutError) as caught:
            bus.read(3, "present_position")
        assert caught.value.id == 3
        assert caught.value.reason == "no reply"
        assert isinstance(caught.value, servobus.MissingServo)
        assert isinstance(caught.value, servobus.Error)
        assert isinstance(caught.value, builtins.TimeoutError)


def test_the_in_process_simulated_bus_reads_like_the_pty():
    bus = servobus.Bus.sim("so101")
    assert bus.series == "sts"
    result = bus.sync_read("present_position", ARM + [7])
    assert result[7] is None and set(result.missing) == {7}
    assert abs(result[1] - 2048) <= 2


def test_the_gil_is_released_while_a_read_waits_on_an_absent_servo(sim):
    # Deadlines allowing 0.25 s of adapter latency (about the largest an
    # adapter has): a read of an absent servo waits at least that long, in
    # one call.
    with servobus.Bus(sim.port, latency=0.25) as bus:
        stamps = []
        done = threading.Event()

        def count():
            while not done.is_set():
                stamps.append(time.monotonic())
                time.sleep(0.001)

        counter = threading.Thread(target=count)
        counter.start()
        time.sleep(0.05)
        start = time.monotonic()
        with pytest.raises(servobus.TimeoutError):
            bus.read(42, "present_position")
        end = time.monotonic()
        done.set()
        counter.join()
    assert end - start >= 0.25
    during = [t for t in stamps if start <= t <= end]
    # A held GIL would freeze the counter for the whole wait; released, it
    # counts on (a loaded machine may pause it briefly).
    assert len(during) >= 20
    gaps = [b - a for a, b in zip([start] + during, during + [end])]
    assert max(gaps) < (end - start) / 2


def test_values_that_do_not_fit_and_unknown_names_raise(bus):
    with pytest.raises(servobus.LimitError) as caught:
        bus.write(1, "goal_position", 99999)
    assert caught.value.max == 32767
    with pytest.raises(servobus.UsageError):
        bus.read(1, "no_such_register")
    with pytest.raises(servobus.UsageError):
        bus.read(300, "present_position")
    with pytest.raises(servobus.UsageError):
        bus.write(1, "present_position", 5)
    with pytest.raises(ValueError):
        bus.sync_read("present_position", [1, 1])


def test_a_port_that_does_not_exist_is_a_port_error():
    with pytest.raises(servobus.PortError):
        servobus.Bus("/dev/servobus-no-such-port")


def test_a_closed_bus_refuses_calls(sim):
    bus = servobus.Bus(sim.port)
    bus.close()
    with pytest.raises(servobus.Error):
        bus.read(1, "present_position")


def test_the_sim_stops_at_the_end_of_its_block():
    with servobus.Sim("so101") as sim:
        assert sim.running
        assert sim.servo_count == 6
    assert not sim.running


def test_raw_access_by_address_matches_the_named_registers(bus):
    # present_position is 2 bytes at address 56; shoulder_pan rests at 2048.
    assert bus.read_raw(1, 56, 2) == bus.read(1, "present_position")
    bus.write_raw(2, 42, 2, 1500)  # goal_position
    assert bus.read(2, "goal_position") == 1500
    bus.sync_write_raw(42, 2, {1: 2100, 3: 2900})
    result = bus.sync_read_raw(42, 2, [1, 3])
    assert dict(result) == {1: 2100, 3: 2900}
    with pytest.raises(servobus.LimitError):
        bus.write_raw(1, 42, 2, 70000)
    with pytest.raises(servobus.UsageError):
        bus.read_raw(1, 56, 3)


def test_a_mounting_places_the_horns_where_its_file_says():
    # so101-mounting puts shoulder_pan's zero at tick 1300 and wrist_roll's
    # at 2048; both joints rest at 0 deg.
    with servobus.Sim("so101", mounting="so101-mounting") as sim, servobus.Bus(sim.port, latency=SLACK) as bus:
        result = bus.sync_read("present_position", [1, 5])
    assert abs(result[1] - 1300) <= 2
    assert abs(result[5] - 2048) <= 2


def test_bad_simulator_options_raise_typed_errors():
    with pytest.raises(servobus.UsageError):
        servobus.Sim("so101", faults="nonsense=1")
    with pytest.raises(servobus.ConfigError) as caught:
        servobus.Sim("so101", mounting="/nonexistent/mounting.yaml")
    assert caught.value.file == "/nonexistent/mounting.yaml"
