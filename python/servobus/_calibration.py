"""Calibrations: where one physical robot's joints really are.

:class:`Calibration` is a servobus calibration file's content (``servobus
calibrate``, :meth:`servobus.Robot.calibrate`), typed; it converts to and
from LeRobot's calibration files.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass
from typing import List, Optional, Tuple, Union

from . import _native

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class JointCalibration:
    """One joint's calibration: the present position (ticks, in the frame of
    ``homing_offset``) it read in the calibration pose, which way the ticks
    run, and the range it was measured to travel."""

    name: str
    id: int
    model: str
    """The servo's model, as it reported it (``"STS3215"``)."""
    homing_offset: int
    """Register 31 while calibrating: present position = actual - offset."""
    pose_deg: float
    """The joint's angle in the calibration pose, degrees."""
    pose_tick: float
    """Present position in the calibration pose."""
    direction: int
    """+1 when rising ticks turn the joint positive, -1 otherwise."""
    range: Tuple[int, int]
    """Lowest and highest present position measured (unwrapped: the
    highest may pass a turn when the range crosses the seam)."""
    deg_per_tick: Optional[float] = None
    """Degrees per tick of the servo's model (None for an unknown model)."""
    firmware: Optional[str] = None
    """Firmware version, ``major.minor`` (None when imported)."""

    def _per_tick(self) -> float:
        if self.deg_per_tick is None:
            raise ValueError(f"joint {self.name}: unknown servo model {self.model}")
        return self.deg_per_tick

    def degrees_at(self, tick: float) -> float:
        """The joint's angle, degrees, at the present position ``tick``."""
        return self.pose_deg + self.direction * (tick - self.pose_tick) * self._per_tick()

    def tick_at(self, degrees: float) -> float:
        """The present position (ticks, not rounded) at the joint angle
        ``degrees``."""
        return self.pose_tick + self.direction * (degrees - self.pose_deg) / self._per_tick()


@dataclass(frozen=True)
class Calibration:
    """One physical robot's calibration (a servobus calibration file):
    ``robot`` (the robot file's name), ``taken`` (when, or where it came
    from) and every joint's :class:`JointCalibration` in the robot's
    order."""

    robot: str
    taken: str
    joints: List[JointCalibration]

    def __getitem__(self, joint: str) -> JointCalibration:
        """The calibration of the joint named ``joint``."""
        for j in self.joints:
            if j.name == joint:
                return j
        raise KeyError(joint)

    @classmethod
    def from_json(cls, text: str) -> "Calibration":
        """A calibration from the JSON text of :meth:`to_json`."""
        raw = json.loads(text)
        joints = [JointCalibration(**{**j, "range": tuple(j["range"])}) for j in raw["joints"]]
        return cls(robot=raw["robot"], taken=raw["taken"], joints=joints)

    def to_json(self) -> str:
        """The calibration as JSON text (the calibration file's fields)."""
        return json.dumps(asdict(self))

    @classmethod
    def load(cls, path: PathLike) -> "Calibration":
        """Loads the servobus calibration file at ``path``. Raises
        :class:`servobus.ConfigError` (with the file, line and column) for
        an invalid one."""
        return cls.from_json(_native.load_calibration(os.fspath(path)))

    def save(self, path: PathLike) -> None:
        """Writes the calibration to ``path`` as a servobus calibration file
        (YAML), replacing it whole or not at all. Give the file to
        :class:`servobus.Robot` (``calibration=``) or name it in the robot
        file."""
        _native.save_calibration(self.to_json(), os.fspath(path))

    @classmethod
    def from_lerobot(cls, lerobot: str, robot: str = "so101") -> "Calibration":
        """The calibration of ``robot`` (a robot file, a built-in name or
        YAML text) that a LeRobot calibration file describes: ``lerobot`` is
        the file's JSON text (one object per motor, named as the robot's
        joints). Each joint's calibration pose is the middle of its LeRobot
        range. Raises :class:`servobus.ConfigError` for a file that does not
        fit the robot."""
        return cls.from_json(_native.calibration_from_lerobot(str(robot), lerobot))

    def to_lerobot(self) -> str:
        """The calibration as a LeRobot calibration file's JSON text."""
        return _native.calibration_to_lerobot(self.to_json())
