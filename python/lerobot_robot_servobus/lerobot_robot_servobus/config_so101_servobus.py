"""The configuration of the ``so101_servobus`` robot type."""

from dataclasses import dataclass, field

from lerobot.robots.config import RobotConfig
from lerobot.robots.so_follower.config_so_follower import SOFollowerRobotConfig


@RobotConfig.register_subclass("so101_servobus")
@dataclass
class SO101ServobusConfig(SOFollowerRobotConfig):
    """The SO-101 follower's options (``port``, ``id``, ``calibration_dir``,
    ``use_degrees``, ``max_relative_target``, cameras ...), unchanged."""

    baudrate: int = 1_000_000
    """The bus's baud rate (the SO-101's servos are at 1 Mbps)."""
    latency: float | None = None
    """The adapter latency (s) the reply deadlines allow at first; the bus
    then learns what the adapter shows at connection, never less."""
    servobus_robot: str | None = None
    """servobus's robot file (or built-in name, e.g. ``"so101"`` for its
    gentle choreography limits) whose joint limits the live loop keeps:
    velocity, acceleration and jerk, its joints named and numbered as the
    SO-101's motors. None (the default): what each servo's model can do
    (an STS3215: 299 deg/s, 2232 deg/s^2), so that the loop keeps up the
    way LeRobot's raw writes do."""
    max_velocity: dict[str, float] = field(default_factory=dict)
    """Lower live velocity limits, deg/s, by motor name
    (``{"shoulder_pan": 120}``); at most what the motor's model can do."""
    max_acceleration: dict[str, float] = field(default_factory=dict)
    """Lower live acceleration limits, deg/s^2, by motor name."""
    max_jerk: dict[str, float] = field(default_factory=dict)
    """Live jerk limits, deg/s^3, by motor name (default: each joint's
    acceleration limit reached in 20 ms, ``servobus.MODEL_JERK_RAMP_S``)."""
    live: bool = True
    """``send_action`` through servobus's live loop (jerk-limited motion
    towards each action); False: goal positions written as LeRobot does."""
    live_timeout: float = 0.25
    """Seconds without an action after which the live loop stops the arm
    (jerk-limited) and holds it until actions come back."""
