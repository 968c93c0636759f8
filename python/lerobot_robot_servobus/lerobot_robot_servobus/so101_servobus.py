"""The ``so101_servobus`` robot: LeRobot's SO-101 follower on servobus."""

from lerobot.robots.so_follower.so_follower import SOFollower

from .config_so101_servobus import SO101ServobusConfig
from .motors_bus import ServobusMotorsBus


class SO101Servobus(SOFollower):
    """LeRobot's SO-101 follower, its motor bus servobus's."""

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
        )
