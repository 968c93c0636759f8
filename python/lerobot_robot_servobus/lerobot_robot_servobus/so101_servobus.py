"""The ``so101_servobus`` robot: LeRobot's SO-101 follower on servobus."""

from lerobot.robots.so_follower.so_follower import SOFollower

from .config_so101_servobus import SO101ServobusConfig
from .motors_bus import ServobusMotorsBus


class SO101Servobus(SOFollower):
    """LeRobot's SO-101 follower, its motor bus servobus's.

    ``send_action`` goes through servobus's live loop (unless the
    configuration's ``live`` is False): each action is a target the joints
    move to jerk-limited, within the live limits (the servos' own by
    default) and the calibrated range, instead of a goal written raw;
    ``get_observation`` then reads the loop's own present positions. Once
    the loop has stopped on a fault, ``send_action`` raises it
    (:class:`~lerobot_robot_servobus.motors_bus.LiveLoopFault`).
    ``disconnect`` stops the arm (jerk-limited), then turns the torque off
    on every servo that answers, even when one is missing.
    """

    config_class = SO101ServobusConfig
    name = "so101_servobus"

    def __init__(self, config: SO101ServobusConfig):
        super().__init__(config)
        # The same motors, normalisation modes and calibration as LeRobot's
        # follower; only the bus underneath changes.
        self.bus = ServobusMotorsBus(
            port=config.port,
            motors=self.bus.motors,
            calibration=self.calibration,
            baudrate=config.baudrate,
            latency=config.latency,
            robot=config.servobus_robot,
            live_timeout=config.live_timeout,
            max_velocity=config.max_velocity,
            max_acceleration=config.max_acceleration,
            max_jerk=config.max_jerk,
        )

    def send_action(self, action):
        """LeRobot's ``send_action``, its goal positions the targets of
        servobus's live loop (started at the first action)."""
        if self.config.live and self.is_connected:
            self.bus.start_live()
        return super().send_action(action)
