"""The exceptions servobus raises, all under :class:`servobus.Error`."""

from __future__ import annotations

import builtins
from typing import Any, Optional


class Error(Exception):
    """Base of every servobus exception."""

    def __init__(self, message: str, **fields: Any) -> None:
        super().__init__(message)
        self.message = message
        for name, value in fields.items():
            setattr(self, name, value)


class ConfigError(Error):
    """A robot, motion or calibration file (or YAML text) is invalid.

    ``file``, ``line`` and ``column`` (1-based) say where, ``field`` which
    field (``buses[0].joints[2].min``); ``line`` and ``column`` are None
    when the file could not be read at all.
    """

    file: Optional[str] = None
    line: Optional[int] = None
    column: Optional[int] = None
    field: Optional[str] = None


class PortError(Error):
    """A serial port cannot be opened or failed; ``port`` names it."""

    port: Optional[str] = None


class CalibrationError(Error):
    """The servos on ``port`` do not match the robot's calibration (nothing
    was read through the bus and nothing moved), or the calibration
    procedure (:meth:`servobus.Robot.calibrate`) could not take one: a step
    that did not end, a joint not swept."""

    port: Optional[str] = None


class MissingServo(Error):
    """Servo ``id`` did not answer as asked; ``reason`` says why
    (``"no reply"``, ``"corrupted reply"``, ...)."""

    id: Optional[int] = None
    reason: Optional[str] = None


class TimeoutError(MissingServo, builtins.TimeoutError):
    """Servo ``id`` sent no reply before the deadline derived from the link."""


class FaultError(Error):
    """A run ended on a fault: ``fault`` describes it (a dict with its
    ``kind``, ``bus``, ``joint``, ``servo_id``, ``time_s`` ...), ``report``
    is the run's :class:`servobus.Report`."""

    fault: Optional[dict] = None
    report: Any = None


class LimitError(Error, ValueError):
    """A value beyond what its register (``min``..``max``) or its joint
    allows."""

    value: Optional[float] = None
    min: Optional[float] = None
    max: Optional[float] = None


class UsageError(Error, ValueError):
    """An argument servobus cannot use: an unknown register or joint, an
    ID out of range, a read-only register written ..."""


__all__ = [
    "Error",
    "ConfigError",
    "PortError",
    "CalibrationError",
    "MissingServo",
    "TimeoutError",
    "FaultError",
    "LimitError",
    "UsageError",
]
