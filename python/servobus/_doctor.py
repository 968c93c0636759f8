"""The doctor's checkup of a robot: typed findings and the fixes applied."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Dict, List, Optional


@dataclass(frozen=True)
class SettingMismatch:
    """A register whose value the robot file asks for and the servo does
    not hold: a joint's operating mode or one of its ``servo:`` settings."""

    joint: str
    """The joint."""
    setting: str
    """What the robot file calls it: ``"mode"``, or the ``servo:`` key
    (``"p"``, ``"protection_current"`` ...)."""
    register: str
    """The register's name."""
    address: int
    """The register's address."""
    found: int
    """The value the servo holds, in the register's units."""
    wanted: int
    """The value the robot file asks for, in the register's units."""
    found_as: Optional[str]
    """``found`` in the robot file's terms (``"position"``,
    ``"3250 mA"``); None for a plain number."""
    wanted_as: Optional[str]
    """``wanted`` in the robot file's terms."""


@dataclass(frozen=True)
class Finding:
    """One thing found wrong (or worth knowing) about a bus."""

    severity: str
    """``"info"``, ``"warning"`` or ``"error"``."""
    step: str
    """Where it belongs in setting a robot up (``"connect"``,
    ``"configure"``, ``"calibrate"`` ...)."""
    bus: str
    """The robot file's bus."""
    id: Optional[int]
    """The servo, when it concerns one."""
    register: Optional[str]
    """The register at fault, if one is."""
    measured: Optional[int]
    """The value read, when the finding is about a register's value (in
    the register's units)."""
    problem: str
    """What is wrong, in words."""
    advice: Dict[str, Any]
    """What to do about it, as data: a write, a baud-rate or ID change, a
    calibration, a change to the robot file ..."""
    fixable: bool
    """Whether ``Robot.doctor(fix=True)`` applies the fix."""
    setting: Optional[SettingMismatch] = None
    """The robot file's setting the finding is about (a joint's mode or
    ``servo:`` setting), with the values found and wanted; None for any
    other finding."""

    @classmethod
    def from_dict(cls, raw: Dict[str, Any]) -> "Finding":
        """The finding from one of the extension's JSON objects."""
        fields = dict(raw)
        setting = fields.pop("setting", None)
        return cls(
            **fields,
            setting=None if setting is None else SettingMismatch(**setting),
        )


@dataclass(frozen=True)
class AppliedFix:
    """A fix the doctor applied to a servo."""

    id: int
    applied: Dict[str, Any]
    """What it did, as data."""
    error: Optional[str]
    """Why it failed; None when it worked."""


@dataclass(frozen=True)
class BusCheckup:
    """What the doctor found on one bus."""

    name: str
    port: Optional[str]
    """None: the built-in simulator."""
    baud: int
    servos: int
    """Servos that answered."""
    expected: int
    """Servos the robot file names for this bus."""
    findings: List[Finding]
    """The findings that stand (after the fixes, when any were applied)."""
    fixes: List[AppliedFix]


@dataclass(frozen=True)
class Checkup:
    """What the doctor found on a robot (``Robot.doctor()``)."""

    status: int
    """0: nothing wrong, 1: warnings, 2: errors (``servobus doctor``'s exit
    code)."""
    buses: List[BusCheckup]
    unchecked: List[str]
    """Buses with no port while others have one."""

    @property
    def findings(self) -> List[Finding]:
        """Every standing finding, bus by bus."""
        return [f for b in self.buses for f in b.findings]

    @classmethod
    def from_json(cls, text: str) -> "Checkup":
        """The checkup from the extension's JSON text."""
        doc = json.loads(text)
        buses = [
            BusCheckup(
                name=b["name"],
                port=b["port"],
                baud=b["baud"],
                servos=b["servos"],
                expected=b["expected"],
                findings=[Finding.from_dict(f) for f in b["findings"]],
                fixes=[AppliedFix(**f) for f in b["fixes"]],
            )
            for b in doc["buses"]
        ]
        return cls(status=doc["status"], buses=buses, unchecked=doc["unchecked"])
