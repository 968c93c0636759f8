"""LeRobot's SO-101 follower code path with the so101_servobus robot type
against the simulated arm: the robot type, LeRobot's calibration file,
observations against LeRobot's own FeetechMotorsBus, and actions through
servobus's live loop (jerk-limited, within the joints' limits)."""

import time

import servobus
from conftest import SLACK, feetech_positions
from lerobot.robots import make_robot_from_config
from lerobot_robot_servobus import SO101Servobus

TICKS = 4096
MOTORS = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]
# The live loop's velocity limit: an STS3215's top speed, 3400 steps/s of
# 4096 a turn, deg/s (the same for every arm joint).
STS3215_DEG_S = 3400 * 360 / 4096
MAX_VELOCITY = {m: STS3215_DEG_S for m in MOTORS if m != "gripper"}


def tick_in_units(robot, motor):
    """One tick of ``motor`` in LeRobot's normalised units."""
    cal = robot.calibration[motor]
    if motor == "gripper":  # RANGE_0_100 over [range_min, range_max]
        return 100.0 / (cal.range_max - cal.range_min)
    return 360.0 / (TICKS - 1)  # DEGREES


def settle_at(robot, action, seconds=5.0):
    """Sends ``action`` every 20 ms until the arm is within 1 degree of it
    (the gripper left out) or ``seconds`` pass: the worst error per joint."""
    deadline = time.monotonic() + seconds
    while True:
        robot.send_action(action)
        now = robot.get_observation()
        err = {m: abs(now[f"{m}.pos"] - action[f"{m}.pos"]) for m in MOTORS if m != "gripper"}
        if max(err.values()) <= 1.0 or time.monotonic() > deadline:
            return err
        time.sleep(0.02)


def test_lerobot_makes_the_servobus_robot_from_its_config(config):
    robot = make_robot_from_config(config)
    assert isinstance(robot, SO101Servobus)
    assert robot.name == "so101_servobus"


def test_the_calibration_file_is_lerobots_and_the_robot_connects_calibrated(config, robot):
    saved = (config.calibration_dir / "sim_arm.json").read_text()
    assert '"homing_offset"' in saved and '"range_min"' in saved and '"drive_mode"' in saved
    assert robot.is_connected and robot.is_calibrated


def test_an_observation_matches_feetech_motors_bus_within_one_tick(robot):
    obs = robot.get_observation()
    theirs = feetech_positions(robot)
    worst = max(abs(obs[f"{m}.pos"] - theirs[m]) / tick_in_units(robot, m) for m in MOTORS)
    assert worst <= 1.0, f"{worst:.2f} ticks"


def test_an_action_moves_the_arm_there_through_the_live_loop(robot):
    obs = robot.get_observation()
    action = {f"{m}.pos": obs[f"{m}.pos"] for m in MOTORS}
    action["shoulder_pan.pos"] += 10.0
    action["elbow_flex.pos"] -= 8.0
    action["gripper.pos"] = 30.0
    err = settle_at(robot, action)
    assert robot.bus.is_live, "send_action started servobus's live loop"
    assert max(err.values()) <= 1.0, err
    # The loop's readings of the arm at rest are what LeRobot's own bus
    # reads once the loop has stopped, within 1 tick. (Not the gripper:
    # 30 % is past the simulated gripper's closed stop, at 44 % of the
    # range LeRobot read, so it presses against it as on an object.)
    time.sleep(0.2)
    seen = robot.get_observation()
    theirs = feetech_positions(robot)
    assert not robot.bus.is_live, "a transaction of its own took the port back"
    arm = [m for m in MOTORS if m != "gripper"]
    off = {m: abs(seen[f"{m}.pos"] - theirs[m]) / tick_in_units(robot, m) for m in arm}
    assert max(off.values()) <= 1.0, off
    for m in arm:
        assert abs(theirs[m] - action[f"{m}.pos"]) <= 1.0, (m, theirs[m], action)


def test_actions_at_30_hz_move_the_arm_smoothly_to_the_last(robot):
    """A teleoperator's jumps (40 deg at once on the pan, 30 on the elbow,
    then back part of the way) at 30 Hz: between two readings of the live
    loop no joint moves farther than its velocity limit allows in the time
    between them, and the arm ends within 1 deg of the last action."""
    start = robot.get_observation()
    action = {f"{m}.pos": start[f"{m}.pos"] for m in MOTORS}
    jumps = [(0, {"shoulder_pan": 40.0, "elbow_flex": -30.0}),
             (15, {"shoulder_pan": 25.0, "wrist_flex": 20.0}),
             (30, {"shoulder_pan": 25.0, "elbow_flex": -10.0, "wrist_flex": 20.0})]
    period = 1.0 / 30.0
    readings = []  # (loop time, {motor: deg}) of each new reading
    for step in range(120):
        for at, offsets in jumps:
            if step == at:
                for m, d in offsets.items():
                    action[f"{m}.pos"] = start[f"{m}.pos"] + d
        robot.send_action(action)
        state = robot.bus.live_state()
        if not readings or state.time > readings[-1][0]:
            readings.append((state.time, {m: state[m] for m in MAX_VELOCITY}))
        time.sleep(period)
    assert len(readings) > 60, "the loop kept reading while the actions came"
    worst = {}
    for (t0, p0), (t1, p1) in zip(readings, readings[1:]):
        for m, vmax in MAX_VELOCITY.items():
            # What the limit allows, plus a tick each side of the readings
            # and 10 % for the servo catching up with its goal.
            allowed = 1.1 * vmax * (t1 - t0) + 2 * 360.0 / TICKS
            worst[m] = max(worst.get(m, 0.0), abs(p1[m] - p0[m]) / allowed)
    assert max(worst.values()) <= 1.0, worst
    err = settle_at(robot, action, seconds=3.0)
    assert max(err.values()) <= 1.0, err


def test_disconnect_stops_the_live_loop_then_turns_the_torque_off(robot):
    obs = robot.get_observation()
    action = {f"{m}.pos": obs[f"{m}.pos"] for m in MOTORS}
    action["wrist_roll.pos"] += 15.0
    robot.send_action(action)
    assert robot.bus.is_live
    robot.disconnect()
    assert not robot.is_connected
    with servobus.Bus(robot.bus.port, latency=SLACK) as bus:
        torque = [bus.read(robot.bus.motors[m].id, "torque_enable") for m in MOTORS]
    assert torque == [0] * len(MOTORS)
