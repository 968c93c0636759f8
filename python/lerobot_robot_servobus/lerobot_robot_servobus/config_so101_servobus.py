"""The configuration of the ``so101_servobus`` robot type."""

from dataclasses import dataclass

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
    """The adapter latency (s) the reply deadlines allow; default what the
    port is assumed to need."""
    servobus_robot: str = "so101"
    """servobus's robot file (or built-in name) whose joint limits the live
    loop keeps: velocity, acceleration and jerk (its joints named and
    numbered as the SO-101's motors)."""
    live: bool = True
    """``send_action`` through servobus's live loop (jerk-limited motion
    towards each action); False: goal positions written as LeRobot does."""
    live_timeout: float = 0.25
    """Seconds without an action after which the live loop stops the arm
    (jerk-limited) and holds it until actions come back."""
