"""LeRobot's SO-101 follower with servobus underneath.

Installing this distribution (its name starts with ``lerobot_robot_``, so
LeRobot imports it at start-up) registers the robot type
``so101_servobus``: LeRobot's own SO-101 follower code (calibration files,
normalisation, configure, observation and action) with its motor bus
replaced by :class:`ServobusMotorsBus`, whose bus transactions are
servobus's (derived deadlines, SYNC READ results per servo, the GIL
released while waiting).

    lerobot-teleoperate --robot.type=so101_servobus --robot.port=/dev/ttyACM0 \\
        --robot.id=my_arm --teleop.type=so101_leader --teleop.port=/dev/ttyACM1 --teleop.id=my_leader
    lerobot-record --robot.type=so101_servobus --robot.port=/dev/ttyACM0 --robot.id=my_arm ...
"""

from .config_so101_servobus import SO101ServobusConfig
from .motors_bus import LiveLoopFault, ServobusMotorsBus, TorqueNotOff
from .so101_servobus import SO101Servobus

__all__ = ["SO101ServobusConfig", "SO101Servobus", "ServobusMotorsBus", "LiveLoopFault", "TorqueNotOff"]
