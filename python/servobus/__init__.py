"""servobus: smooth, on-time motion for Feetech serial-bus servos.

- :class:`Bus`: a typed bus (ping, scan, read/write by register name,
  SYNC READ with partial results, SYNC WRITE), on a port or simulated.
- :class:`Sim`: a robot's simulated servos on a pseudo-terminal, served
  from a thread (``with Sim("so101") as sim: Bus(sim.port)``).
- :class:`Robot`: plan and play motions, stream live targets, calibrate.
- :class:`Calibration`: a robot's calibration, from and to LeRobot's files.
- :class:`Checkup`: what ``Robot.doctor()`` finds, as typed findings.
- :func:`model_limits`: a servo model's top speed and acceleration, deg;
  ``MODEL_JERK_RAMP_S``: how long live following's jerk limit takes to
  reach that acceleration (as ``servobus follow``), s.

Every call that waits on a bus releases the GIL. Errors are subclasses of
:class:`Error`.
"""

from . import _errors
from ._native import Sim, __version__
from ._native import MODEL_JERK_RAMP_S, model_limits
from ._errors import *  # noqa: F401,F403 (the exception classes, listed in _errors.__all__)
from ._bus import Bus, Missing, SyncRead
from ._calibration import Calibration, JointCalibration
from ._doctor import AppliedFix, BusCheckup, Checkup, Finding
from ._robot import JointLimits, JointPeaks, JointReport, Plan, Report, Robot, Segment, State, Stream

__all__ = [
    "Bus",
    "Sim",
    "Robot",
    "Stream",
    "State",
    "Plan",
    "Segment",
    "JointPeaks",
    "JointLimits",
    "Report",
    "JointReport",
    "Calibration",
    "JointCalibration",
    "Checkup",
    "BusCheckup",
    "Finding",
    "AppliedFix",
    "SyncRead",
    "Missing",
    "model_limits",
    "MODEL_JERK_RAMP_S",
    "__version__",
] + _errors.__all__
