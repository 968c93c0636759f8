"""The plugin tells the truth: a fault of the live loop is raised by the
next send_action, disconnect turns the torque off on every servo that
still answers, errors start with their problem on one line, and the live
limits are what the servos can do unless the config lowers them."""

import time

import pytest
import servobus
from conftest import SLACK, make_config
from lerobot.robots import make_robot_from_config
from lerobot_robot_servobus import LiveLoopFault, TorqueNotOff

MOTORS = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]
STS3215_DEG_S = 3400 * 360 / 4096
STS3215_DEG_S2 = 254 * 100 * 360 / 4096


def hold_action(robot):
    obs = robot.get_observation()
    return {f"{m}.pos": obs[f"{m}.pos"] for m in MOTORS}


def act_until_it_raises(robot, action, seconds):
    """send_action at 30 Hz until it raises (its exception) or ``seconds``
    pass (None)."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            robot.send_action(action)
        except Exception as e:  # what is raised is the test's to judge
            return e
        time.sleep(1 / 30)
    return None


def first_line(e):
    return str(e).splitlines()[0] if str(e) else ""


def test_send_action_after_the_port_is_killed_raises_the_fault(sim, tmp_path):
    robot = make_robot_from_config(make_config(sim, tmp_path))
    robot.connect()
    action = hold_action(robot)
    robot.send_action(action)
    assert robot.bus.is_live
    sim.close()  # the port is gone: a cable pulled
    raised = act_until_it_raises(robot, action, seconds=5.0)
    assert isinstance(raised, LiveLoopFault), repr(raised)
    assert isinstance(raised, ConnectionError), "LeRobot's own kind of error for a lost bus"
    line = first_line(raised)
    assert line.startswith("the live loop stopped on a fault: "), line
    assert len(line) > len("the live loop stopped on a fault: "), "the fault is named"
    assert len(str(raised).splitlines()) == 1
    # The action is never taken silently: the next one raises too (the
    # port is still gone).
    with pytest.raises(Exception):
        robot.send_action(action)


def test_disconnect_with_servo_3_vanished_leaves_the_torque_off_on_the_others(tmp_path):
    # Servo 3 (elbow_flex) answers for 4 s from the bus's first byte, then
    # never again: after the connection, during the session.
    with servobus.Sim("so101", faults="vanish=3@4") as sim:
        robot = make_robot_from_config(make_config(sim, tmp_path))
        robot.connect()
        raised = act_until_it_raises(robot, hold_action(robot), seconds=15.0)
        # The live loop's missing servo is send_action's exception.
        assert isinstance(raised, LiveLoopFault), repr(raised)
        assert "elbow_flex" in str(raised) or "3" in str(raised), str(raised)
        # Torque on for the servos that answer, as a session leaves them
        # (whatever the fault's reaction did).
        others = [m for m in MOTORS if m != "elbow_flex"]
        robot.bus.enable_torque(others)
        assert [robot.bus.read("Torque_Enable", m) for m in others] == [1] * len(others)
        with pytest.raises(TorqueNotOff) as caught:
            robot.disconnect()
        assert list(caught.value.missing) == ["elbow_flex"]
        assert caught.value.turned_off == others
        assert first_line(caught.value).startswith("torque not turned off on elbow_flex (id 3)")
        assert not robot.is_connected, "the port is closed all the same"
        with servobus.Bus(sim.port, latency=SLACK) as bus:
            torque = {i: bus.read(i, "torque_enable") for i in (1, 2, 4, 5, 6)}
            with pytest.raises(servobus.TimeoutError):
                bus.read(3, "torque_enable")
    assert torque == {1: 0, 2: 0, 4: 0, 5: 0, 6: 0}


def test_an_errors_first_line_names_the_problem(tmp_path):
    with servobus.Sim("so101", faults="vanish=3") as sim:
        robot = make_robot_from_config(make_config_without_servo_3(sim, tmp_path))
        with pytest.raises(Exception) as caught:
            robot.connect()
    text = str(caught.value)
    line = first_line(caught.value)
    assert "Motors:" not in text and "Port:" not in text, "no repr of the bus"
    assert line, "the message does not start with an empty line"
    assert "3" in line or "elbow_flex" in line, line
    # A port that is not there.
    config = make_config_on("/dev/servobus-no-such-port", tmp_path)
    with pytest.raises(ConnectionError) as caught:
        make_robot_from_config(config).connect()
    line = first_line(caught.value)
    assert line.startswith("could not open port '/dev/servobus-no-such-port'"), line


def make_config_without_servo_3(sim, tmp_path):
    """A configuration of ``sim``'s arm with a calibration file taken from
    a healthy arm (servo 3 then missing from ``sim``)."""
    with servobus.Sim("so101") as healthy:
        config = make_config(healthy, tmp_path)
    config.port = sim.port
    return config


def make_config_on(port, tmp_path):
    from lerobot_robot_servobus import SO101ServobusConfig

    return SO101ServobusConfig(port=port, id="nowhere", calibration_dir=tmp_path, latency=SLACK)


def test_the_bus_repr_is_one_line(robot):
    assert "\n" not in repr(robot.bus) and robot.bus.port in repr(robot.bus)


def test_live_limits_default_to_what_the_servo_model_can_do(robot):
    limits = robot.bus.live_limits()
    for m in MOTORS:
        v, a, j = limits[m]
        assert v == pytest.approx(STS3215_DEG_S)
        assert a == pytest.approx(STS3215_DEG_S2)
        # Reached in 20 ms, as `servobus follow` (MODEL_JERK_RAMP_S).
        assert j == pytest.approx(STS3215_DEG_S2 / 0.02)
        assert servobus.MODEL_JERK_RAMP_S == pytest.approx(0.02)


def test_a_user_lowers_the_live_limits_in_the_config(sim, tmp_path):
    config = make_config(sim, tmp_path, max_velocity={"shoulder_pan": 90.0},
                         max_acceleration={"elbow_flex": 500.0}, max_jerk={"wrist_roll": 5000.0})
    robot = make_robot_from_config(config)
    limits = robot.bus.live_limits()
    assert limits["shoulder_pan"][0] == 90.0
    assert limits["elbow_flex"][1] == 500.0
    assert limits["wrist_roll"][2] == 5000.0
    assert limits["shoulder_lift"][0] == pytest.approx(STS3215_DEG_S)


def test_a_live_limit_above_the_model_or_for_no_motor_is_refused(sim, tmp_path):
    robot = make_robot_from_config(make_config(sim, tmp_path, max_velocity={"shoulder_pan": 1000.0}))
    with pytest.raises(ValueError, match="at most 298.8"):
        robot.bus.live_limits()
    robot = make_robot_from_config(make_config(sim, tmp_path, max_acceleration={"elbow": 100.0}))
    with pytest.raises(ValueError, match="unknown motors"):
        robot.bus.live_limits()


def test_servobus_robot_gives_its_choreography_limits(sim, tmp_path):
    robot = make_robot_from_config(make_config(sim, tmp_path, servobus_robot="so101"))
    design = servobus.Robot("so101").limits
    assert robot.bus.live_limits()["shoulder_pan"][0] == pytest.approx(design["shoulder_pan"].max_velocity)


def test_reads_outside_the_live_loop_are_tried_once_more_on_the_learned_link(robot):
    # The link was measured at connection: its allowance is at least what
    # the config gave.
    assert robot.bus._servobus.latency >= SLACK
    # A missing reply is asked for again even with LeRobot's num_retry=0.
    tries = []
    real = robot.bus._servobus.read_raw

    def flaky(*args, **kwargs):
        tries.append(args)
        if len(tries) == 1:
            raise servobus.TimeoutError("servo 1: no reply (simulated)", id=1, reason="no reply")
        return real(*args, **kwargs)

    robot.bus._servobus.read_raw = flaky
    try:
        value = robot.bus.read("Torque_Enable", "shoulder_pan", num_retry=0)
    finally:
        robot.bus._servobus.read_raw = real
    assert len(tries) == 2 and value in (0, 1)
