"""The robot API: plan, play on the simulator, and a scripted live stream."""

import time

import numpy as np
import pytest

import servobus

JOINTS = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]


def test_a_robot_opens_by_built_in_name():
    robot = servobus.Robot("so101")
    assert robot.joints == JOINTS
    assert robot.units == "deg"
    assert robot.port is None


def test_a_plan_gives_timing_and_peaks_within_the_limits():
    plan = servobus.Robot("so101").plan("arm-wave")
    assert plan.duration_s > 1.0
    pan = plan.joints[0]
    assert pan.name == "shoulder_pan"
    # arm-wave moves shoulder_pan from 0 deg to 20 deg and back.
    assert pan.min_position == pytest.approx(0.0, abs=1e-6)
    assert pan.max_position == pytest.approx(20.0, abs=1e-6)
    # The robot file limits shoulder_pan to 180 deg/s and 900 deg/s^2.
    assert 0 < pan.peak_velocity <= 180.0 + 1e-6
    assert pan.peak_acceleration <= 900.0 + 1e-6
    assert plan.segments[-1].end == pytest.approx(plan.duration_s)


def test_play_on_the_simulator_returns_a_typed_report_with_arrays():
    calls = []
    report = servobus.Robot("so101").play("arm-wave", on_progress=lambda t, d: calls.append((t, d)))
    assert report.finish == "completed"
    assert report.joint_names == JOINTS
    n = len(report.time)
    assert n == report.cycles
    assert report.measured.shape == (n, 6)
    assert report.planned.shape == (n, 6)
    assert np.all(np.diff(report.time) > 0)
    # arm-wave ends at rest: 0, -90, 90, 45, 0, 10 deg.
    assert np.allclose(report.measured[-1], [0, -90, 90, 45, 0, 10], atol=1.0)
    assert report.worst_rms_error < 5.0
    assert [j.name for j in report.joints] == JOINTS
    assert report.units == "deg"
    assert calls, "on_progress was called"


def test_an_exception_in_on_progress_stops_the_run_and_propagates():
    def boom(t, duration):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here") as caught:
        servobus.Robot("so101").play("arm-wave", on_progress=boom)
    assert caught.value.report.finish == "stopped"


def test_a_robot_file_with_an_error_names_line_and_column():
    text = "name: broken\nunits: deg\nbuses: 12\n"
    with pytest.raises(servobus.ConfigError) as caught:
        servobus.Robot(text)
    assert caught.value.line == 3
    assert isinstance(caught.value.column, int)


def test_a_missing_robot_file_is_a_config_error():
    with pytest.raises(servobus.ConfigError) as caught:
        servobus.Robot("/nonexistent/robot.yaml")
    assert caught.value.file == "/nonexistent/robot.yaml"


def test_a_scripted_stream_moves_the_arm_to_the_targets():
    robot = servobus.Robot("so101")
    sent = 0
    with robot.stream(timeout=0.5) as stream:
        # 1.5 s of targets at 50 Hz: shoulder_pan to 30 deg, elbow to 60.
        for _ in range(75):
            stream.send({"shoulder_pan": 30.0, "elbow_flex": 60.0})
            sent += 1
            time.sleep(0.02)
        state = robot.state()
    assert state.joints == JOINTS
    assert state["shoulder_pan"] == pytest.approx(30.0, abs=1.0)
    assert state["elbow_flex"] == pytest.approx(60.0, abs=1.0)
    # Joints not named hold where they rested.
    assert state["shoulder_lift"] == pytest.approx(-90.0, abs=1.0)
    assert state.faults == []
    report = stream.report
    assert report.finish == "stopped"
    assert report.raw["live"]["received"] == sent
    assert stream.finished


def test_a_stream_refuses_an_unknown_joint():
    with servobus.Robot("so101").stream() as stream:
        with pytest.raises(servobus.UsageError):
            stream.send({"no_such_joint": 1.0})


def test_a_target_beyond_the_limits_is_clamped_and_counted():
    with servobus.Robot("so101").stream() as stream:
        # shoulder_pan is limited to +-110 deg.
        assert stream.send({"shoulder_pan": 500.0}) == 1


def test_play_on_a_sim_pty_goes_through_the_port_in_real_time(sim):
    robot = servobus.Robot("so101", port=sim.port)
    assert robot.port == sim.port
    report = robot.play("arm-wave")
    assert report.finish == "completed"
    # Through a port the run takes the motion's own time, not less.
    assert report.duration_s >= servobus.Robot("so101").plan("arm-wave").duration_s
    assert np.allclose(report.measured[-1], [0, -90, 90, 45, 0, 10], atol=1.0)


def test_ctrl_c_stops_a_real_time_run_early_and_raises_keyboard_interrupt():
    import _thread
    import threading

    robot = servobus.Robot("so101")
    duration = robot.plan("arm-wave").duration_s
    # SIGINT as Ctrl-C gives it, 0.5 s into the run.
    timer = threading.Timer(0.5, _thread.interrupt_main)
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt) as caught:
            robot.play("arm-wave", real_time=True)
    finally:
        timer.cancel()
    assert caught.value.report.finish == "stopped"
    assert caught.value.report.duration_s < duration
    # A jerk-limited stop takes well under the rest of the motion.
    assert time.monotonic() - start < duration


def test_a_servo_that_goes_silent_ends_the_run_with_a_fault_error():
    # Servo 3 (elbow_flex) answers for 1 s, then never again.
    with servobus.Sim("so101", faults="vanish=3@1") as sim:
        robot = servobus.Robot("so101", port=sim.port)
        with pytest.raises(servobus.FaultError) as caught:
            robot.play("arm-wave")
    fault = caught.value.fault
    # Three cycles without its reply make a `missing` fault; on a loaded
    # machine its stale reading may first show as a following error.
    assert fault["kind"] in ("missing", "following_error")
    assert fault["servo_id"] == 3
    assert fault["joint"] == "elbow_flex"
    assert caught.value.report.finish == "fault"
    # Without check the report comes back with the fault in it.
    with servobus.Sim("so101", faults="vanish=3@1") as sim:
        report = servobus.Robot("so101", port=sim.port).play("arm-wave", check=False)
    assert report.finish == "fault" and report.fault["servo_id"] == 3


def test_torque_off_reaches_every_servo_on_the_port(sim):
    with servobus.Bus(sim.port, latency=0.05) as bus:
        bus.sync_write("torque_enable", {i: 1 for i in range(1, 7)})
        assert list(bus.sync_read("torque_enable", range(1, 7)).values()) == [1] * 6
    assert servobus.Robot("so101", port=sim.port).torque_off() is None
    with servobus.Bus(sim.port, latency=0.05) as bus:
        assert list(bus.sync_read("torque_enable", range(1, 7)).values()) == [0] * 6


def test_torque_off_ends_a_running_stream_with_its_report():
    robot = servobus.Robot("so101")
    stream = robot.stream()
    report = robot.torque_off()
    assert report.finish == "torque_off"
    assert stream.finished
