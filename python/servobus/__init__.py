"""servobus: smooth, on-time motion for Feetech serial-bus servos.

- :class:`Bus`: a typed bus (ping, scan, read/write by register name,
  SYNC READ with partial results, SYNC WRITE), on a port or simulated.
- :class:`Sim`: a robot's simulated servos on a pseudo-terminal, served
  from a thread (``with Sim("so101") as sim: Bus(sim.port)``).
- :class:`Robot`: plan and play motions, stream live targets.

Every call that waits on a bus releases the GIL. Errors are subclasses of
:class:`Error`.
"""

from ._native import Sim, __version__
from ._errors import (
    CalibrationError,
    ConfigError,
    Error,
    FaultError,
    LimitError,
    MissingServo,
    PortError,
    TimeoutError,
    UsageError,
)
from ._bus import Bus, Missing, SyncRead
from ._robot import JointPeaks, JointReport, Plan, Report, Robot, Segment, State, Stream

__all__ = [
    "Bus",
    "Sim",
    "Robot",
    "Stream",
    "State",
    "Plan",
    "Segment",
    "JointPeaks",
    "Report",
    "JointReport",
    "SyncRead",
    "Missing",
    "Error",
    "ConfigError",
    "PortError",
    "CalibrationError",
    "MissingServo",
    "TimeoutError",
    "FaultError",
    "LimitError",
    "UsageError",
    "__version__",
]
