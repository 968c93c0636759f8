"""The robot API: :class:`Robot`, its plans, runs, reports and streams."""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass, field
from operator import attrgetter
from typing import Any, Callable, Dict, List, Mapping, Optional, Union

import numpy as np

from . import _native
from ._calibration import Calibration, PathLike
from ._doctor import Checkup
from ._errors import Error, FaultError, UsageError


@dataclass(frozen=True)
class JointPeaks:
    """One joint's extremes along a plan, in the robot's units (per second,
    per second squared ... for the derivatives)."""

    name: str
    peak_velocity: float
    peak_acceleration: float
    peak_jerk: Optional[float]
    """None where the acceleration jumps (no jerk limit)."""
    min_position: float
    max_position: float


@dataclass(frozen=True)
class JointLimits:
    """One joint's limits, in the robot's units (its calibration applied:
    ``min``/``max`` within the measured range)."""

    name: str
    id: int
    """Its servo's ID."""
    min: float
    max: float
    max_velocity: float
    """Per second."""
    max_acceleration: float
    """Per second squared."""
    max_jerk: Optional[float]
    """Per second cubed; None: the acceleration may step."""


@dataclass(frozen=True)
class Segment:
    """One segment of a plan: arrival at keyframe ``keyframe`` of
    repetition ``cycle``, from ``start`` to ``end`` s."""

    keyframe: int
    cycle: int
    start: float
    end: float


@dataclass(frozen=True)
class Plan:
    """A motion's plan: its duration (s), segments and per-joint peaks."""

    duration_s: float
    units: str
    segments: List[Segment]
    joints: List[JointPeaks]


@dataclass(frozen=True)
class JointReport:
    """One joint's tracking over a run, in the report's units."""

    name: str
    rms_error: float
    max_error: float
    readings: int
    clamps: int
    stalls: int = 0
    """Times the joint was held on a stall (a gripper on its end stop or
    an object) instead of the run ending."""

    @classmethod
    def from_raw(cls, raw: Dict[str, Any]) -> "JointReport":
        """The report's joint entry; fields a newer report adds are kept in
        :attr:`Report.raw` only."""
        known = {f for f in cls.__dataclass_fields__}
        return cls(**{k: v for k, v in raw.items() if k in known})


@dataclass(frozen=True)
class Report:
    """What a run did. The figures of ``servobus play --json``, and the
    samples as numpy arrays of shape ``(samples, joints)`` (``time`` of
    shape ``(samples,)``), NaN where a joint had no reading yet."""

    finish: str
    """Why it ended: ``completed``, ``stopped``, ``torque_off``, ``fault``."""
    cycles: int
    achieved_rate_hz: float
    planned_rate_hz: float
    overruns: int
    timeouts: int
    retries: int
    missed_replies: int
    clamps: int
    duration_s: float
    units: str
    joints: List[JointReport]
    fault: Optional[Dict[str, Any]]
    warnings: List[str]
    joint_names: List[str]
    time: np.ndarray
    commanded: np.ndarray
    planned: np.ndarray
    measured: np.ndarray
    raw: Dict[str, Any] = field(repr=False)
    """The whole report as ``servobus play --json`` gives it."""

    @property
    def worst_rms_error(self) -> float:
        """The largest RMS tracking error over the joints."""
        return max((j.rms_error for j in self.joints), default=0.0)


def _report(text: str, names: List[str], time=(), commanded=None, planned=None, measured=None) -> Report:
    raw = json.loads(text)
    n = len(names)

    def matrix(columns) -> np.ndarray:
        if not columns:
            return np.zeros((len(time), n))
        return np.asarray(columns, dtype=float).T.reshape(len(time), n)

    return Report(
        finish=raw["finish"],
        cycles=raw["cycles"],
        achieved_rate_hz=raw["achieved_rate_hz"],
        planned_rate_hz=raw["planned_rate_hz"],
        overruns=raw["overruns"],
        timeouts=raw["timeouts"],
        retries=raw["retries"],
        missed_replies=raw["missed_replies"],
        clamps=raw["clamps"],
        duration_s=raw["duration_s"],
        units=raw["units"],
        joints=[JointReport.from_raw(j) for j in raw["joints"]],
        fault=raw.get("fault"),
        warnings=list(raw.get("warnings", [])),
        joint_names=list(names),
        time=np.asarray(time, dtype=float),
        commanded=matrix(commanded),
        planned=matrix(planned),
        measured=matrix(measured),
        raw=raw,
    )


@dataclass(frozen=True)
class State:
    """The joints' latest state in a stream, in the robot's units: numpy
    arrays in the order of ``joints`` (NaN before a first reading)."""

    time: float
    """Time of the cycle since the stream started, s."""
    joints: List[str]
    position: np.ndarray
    velocity: np.ndarray
    error: np.ndarray
    """Commanded path minus measured position at the last reading."""
    commanded: np.ndarray
    flags: np.ndarray
    """Each servo's status byte at its last reply (0: no error)."""
    faults: List[str]

    def __getitem__(self, joint: str) -> float:
        """The position of ``joint``."""
        return float(self.position[self.joints.index(joint)])


def _check_output(output: PathLike) -> None:
    """Raises :class:`Error` (``file`` set) when a calibration could not be
    saved at ``output``: a directory, a folder that does not exist or
    cannot be written (a file is made there and removed to find out, as
    the save makes its temporary file beside the target)."""
    path = os.fspath(output)
    if os.path.isdir(path):
        raise Error(f"cannot save the calibration to {path}: it is a directory (give a file name)", file=path)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise Error(f"cannot save the calibration to {path}: the folder {folder} does not exist", file=path)
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise Error(f"cannot save the calibration to {path}: the file is read-only", file=path)
    try:
        probe, probe_path = tempfile.mkstemp(prefix=".servobus-probe-", dir=folder)
    except OSError as e:
        raise Error(f"cannot save the calibration to {path}: {e.strerror or e}", file=path) from None
    os.close(probe)
    os.unlink(probe_path)


class Stream:
    """The live loop of a robot (as ``servobus stream``): the joints hold,
    then follow every target sent, jerk-limited. A context manager: the
    joints stop (jerk-limited) at the end of the ``with`` block, and
    :attr:`report` holds the run's report."""

    def __init__(self, native: _native.Stream, joints: List[str]) -> None:
        self._stream = native
        self._joints = joints
        self.report: Optional[Report] = None

    def send(self, joints: Mapping[str, float]) -> int:
        """Sends a target: joint name to angle, in the robot's units (joints
        not named keep their targets). Returns how many angles were beyond
        the joint limits and clamped."""
        return self._stream.send([(str(k), float(v)) for k, v in joints.items()])

    def send_base(self, x: float = 0.0, y: float = 0.0, theta: float = 0.0) -> int:
        """Drives the robot's mobile base (a ``base:`` section in its robot
        file): ``x`` forward and ``y`` left in m/s, ``theta`` turning
        counter-clockwise in the robot's units per second. The wheels'
        speeds are scaled together within their limits, so the base keeps
        its direction of travel; the live timeout stops it when the sends
        stop. Raises :class:`servobus.UsageError` for a robot without a base
        or a velocity it cannot take (a differential base sideways)."""
        return self._stream.send_base(float(x), float(y), float(theta))

    def send_grasp(self, grasps: Mapping[str, float]) -> None:
        """Tells gripper joints to grasp: joint name to effort, in percent
        of the servo's torque (above 0, at most 100). Each closes towards
        its ``min`` until it meets something and holds there pushing with
        that effort, eased when warm, letting go near its temperature
        limit; a later target giving it a position releases it. Raises
        :class:`servobus.UsageError` for an unknown joint, an effort out of
        range or a wheel."""
        if isinstance(grasps, Mapping):
            # Efforts are passed as given: the extension names a bad one.
            grasps = {str(k): v for k, v in grasps.items()}
        self._stream.send_grasp(grasps)

    def send_chunk(self, times_or_dt, positions) -> int:
        """Sends an action chunk, as a policy (ACT, diffusion, pi0) emits
        one: ``times_or_dt`` is the points' spacing in s (a number) or
        their times in s from now (increasing); ``positions`` maps joint
        names to one angle per point (robot units), or is an array of shape
        ``(points, joints)`` in the order of the robot's joints. The loop
        follows the chunk as a timed path through its points, within the
        limits; a new chunk replaces what is left of the last from the
        commanded state (never a jump, never back in time: points already
        past are skipped). Single targets (:meth:`send`) and chunks mix in
        one stream. Returns how many positions were clamped to the limits.
        Raises :class:`servobus.UsageError` for a bad chunk (lengths that
        differ, times not increasing or more than an hour from now, an
        unknown joint, NaN)."""
        if isinstance(positions, Mapping):
            joints = [(str(k), [float(x) for x in np.asarray(v, dtype=float).ravel()])
                      for k, v in positions.items()]
        else:
            array = np.asarray(positions, dtype=float)
            if array.ndim != 2 or array.shape[1] != len(self._joints):
                raise UsageError(f"positions of shape {array.shape}: give (points, {len(self._joints)}) "
                                 f"for the joints {self._joints}, or a dict of joint to angles")
            joints = [(name, [float(x) for x in array[:, k]]) for k, name in enumerate(self._joints)]
        if isinstance(times_or_dt, (int, float, np.floating, np.integer)) and not isinstance(times_or_dt, bool):
            return self._stream.send_chunk(joints, dt=float(times_or_dt))
        times = [float(t) for t in np.asarray(times_or_dt, dtype=float).ravel()]
        return self._stream.send_chunk(joints, times=times)

    @property
    def base_pose(self):
        """A mobile base's odometry so far, from its wheels' measured
        speeds: ``(x, y, theta)``, metres forward and to the left of where
        the stream started and the heading in the robot's units
        (counter-clockwise); ``None`` for a robot without a ``base:``."""
        return self._stream.base_pose()

    def state(self) -> State:
        """The joints' latest positions, velocities, errors and faults."""
        t, pos, vel, err, cmd, flags, faults = self._stream.state()
        return State(
            time=t,
            joints=list(self._joints),
            position=np.asarray(pos, dtype=float),
            velocity=np.asarray(vel, dtype=float),
            error=np.asarray(err, dtype=float),
            commanded=np.asarray(cmd, dtype=float),
            flags=np.asarray(flags, dtype=np.uint8),
            faults=list(faults),
        )

    @property
    def finished(self) -> bool:
        """Whether the run has ended (stopped, torque off, or a fault)."""
        return self._stream.finished

    def _ended(self, text: Optional[str]) -> Optional[Report]:
        if text is not None:
            self.report = _report(text, self._joints)
        return self.report

    def stop(self) -> Optional[Report]:
        """Stops the joints (jerk-limited) and ends the run: its report."""
        return self._ended(self._stream.stop())

    def torque_off(self) -> Optional[Report]:
        """Turns every servo's torque off and ends the run: its report."""
        return self._ended(self._stream.torque_off())

    def __enter__(self) -> "Stream":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


class Robot:
    """A robot: ``Robot(robot, port=None, calibration=None)``.

    ``robot`` is a robot file, a built-in name (``"so101"``) or YAML text;
    ``port`` the serial port of its first bus (None: the built-in
    simulator); ``calibration`` a calibration file (or a
    :class:`Calibration`) to use instead of the one the robot file names. Angles are in the robot's units
    (:attr:`units`).
    """

    def __init__(
        self,
        robot: str,
        port: Optional[str] = None,
        calibration: Union[None, PathLike, Calibration] = None,
    ) -> None:
        self._kept: Optional[tempfile.TemporaryDirectory] = None
        if isinstance(calibration, Calibration):
            # The loader takes a file: the calibration is written to one
            # kept as long as the robot (motions load it again).
            self._kept = tempfile.TemporaryDirectory(prefix="servobus-")
            path = os.path.join(self._kept.name, "calibration.yaml")
            calibration.save(path)
            calibration = path
        self._robot = _native.Robot(str(robot), None if port is None else str(port),
                                    None if calibration is None else os.fspath(calibration))
        self._stream: Optional[Stream] = None

    name = property(attrgetter("_robot.name"), doc="The robot's name (str).")
    joints = property(attrgetter("_robot.joints"), doc="Its joints' names (list of str), in the robot file's order.")
    units = property(attrgetter("_robot.units"), doc='The unit of its angles: ``"deg"`` or ``"rad"``.')
    port = property(attrgetter("_robot.port"), doc="Its port (str; None: the built-in simulator).")
    rate_hz = property(attrgetter("_robot.rate_hz"), doc="Its default control rate, Hz (float).")

    @property
    def limits(self) -> Dict[str, JointLimits]:
        """Every joint's :class:`JointLimits`, by name, in the robot file's
        order."""
        return {t[0]: JointLimits(*t) for t in self._robot.limits}

    def plan(self, motion: str) -> Plan:
        """Plans ``motion`` (a motion file or a built-in name): its timing and
        per-joint peaks, without moving anything."""
        raw = json.loads(self._robot.plan(str(motion)))
        return Plan(
            duration_s=raw["duration_s"],
            units=raw["units"],
            segments=[
                Segment(s["keyframe"], s["repetition"], s["start_s"], s["end_s"])
                for s in raw["segments"]
            ],
            joints=[
                JointPeaks(
                    j["name"],
                    j["peak_velocity"],
                    j["peak_acceleration"],
                    j["peak_jerk"],
                    j["min_position"],
                    j["max_position"],
                )
                for j in raw["joints"]
            ],
        )

    def play(
        self,
        motion: str,
        on_progress: Optional[Callable[[float, float], Any]] = None,
        *,
        real_time: bool = False,
        check: bool = True,
    ) -> Report:
        """Plays ``motion`` and returns its :class:`Report`.

        On the built-in simulator it runs in virtual time (as fast as the
        computer goes) unless ``real_time``. ``on_progress(t, duration)`` is
        called about 20 times a second. Ctrl-C stops the joints with a
        jerk-limited stop, then raises ``KeyboardInterrupt`` (as does an
        exception raised by ``on_progress``), its ``.report`` the stopped
        run's. With ``check``
        a run ended by a fault raises :class:`servobus.FaultError`.
        """
        text, t, cmd, plan, meas, stopped_by = self._robot.play(str(motion), on_progress, real_time)
        report = _report(text, self.joints, t, cmd, plan, meas)
        if stopped_by is not None:
            # The run stopped (jerk-limited) and its report is kept with
            # the exception that stopped it.
            stopped_by.report = report
            raise stopped_by
        if check and report.finish == "fault":
            raise FaultError(f"the run ended on a fault: {report.fault}", fault=report.fault, report=report)
        return report

    def stream(self, rate: Optional[float] = None, timeout: float = 0.25, *,
               tracking_faults: bool = True) -> Stream:
        """Starts the live loop (as ``servobus stream``) and returns its
        :class:`Stream`, a context manager. ``rate`` in Hz (default the
        robot's); after ``timeout`` s without a target the joints stop and
        hold until targets come back. On the simulator it runs in real time.
        On real servos the servos are checked against the calibration first
        (:class:`servobus.CalibrationError`). Without ``tracking_faults`` a
        joint held back (a gripper closed on an object) or far behind its
        target does not end the run; missing servos and status flags still
        do.
        """
        if self._stream is not None and not self._stream.finished:
            raise Error("a stream of this robot is running: stop it first")
        self._stream = Stream(self._robot.stream(rate, timeout, tracking_faults), self.joints)
        return self._stream

    def state(self) -> State:
        """The joints' state in the running stream (see :meth:`stream`)."""
        if self._stream is None:
            raise Error("no stream is running: start one with robot.stream()")
        return self._stream.state()

    def calibrate(
        self,
        output: Optional[PathLike] = None,
        *,
        hand: Optional[str] = None,
        mounting: Optional[str] = None,
        timeout: float = 600.0,
        on_step: Optional[Callable[[str], Any]] = None,
    ) -> Calibration:
        """Calibrates the robot as ``servobus calibrate --yes`` does: torque
        off, the joints held in the robot file's calibration pose, then each
        joint swept through its whole range; each step ends once the joints
        have moved and then been held still for 2 s. Returns the
        :class:`Calibration` (saved to ``output`` when given).

        On the built-in simulator (no port) it runs in virtual time, with
        ``hand`` (a hand file or a built-in name, e.g.
        ``"so101-first-arm-hand"``) moving the joints and the servos mounted
        as ``mounting`` says (as ``servobus sim --hand/--mounting``).
        ``timeout`` (s) bounds each step. ``on_step(name)`` is called as
        each step begins: ``"torque_off"``, ``"hold_pose"`` (hold the robot
        in its calibration pose), ``"sweep"`` (move each joint the positive
        way first, then from end stop to end stop), ``"done"``. Ctrl-C, or
        an exception raised by ``on_step``, ends the procedure at once and
        is raised (nothing is saved). ``output`` is checked before anything
        moves: a directory, a missing or read-only folder raises
        :class:`servobus.Error` (its ``file`` the path) at once, so a
        calibration is never taken only to be lost. Raises
        :class:`servobus.CalibrationError` when the procedure cannot take a
        calibration (a step that does not end, a joint not swept).
        """
        if output is not None:
            _check_output(output)
        cal = Calibration.from_json(self._robot.calibrate(hand, mounting, float(timeout), on_step))
        if output is not None:
            cal.save(output)
        return cal

    def doctor(self, fix: bool = False, *, write_servos: bool = False) -> Checkup:
        """Checks every bus as ``servobus doctor`` does: each servo answers
        at its ID and the bus's rate, its model, voltage, temperature,
        limits, gripper protection and calibration. On the robot's port, or
        on the built-in simulator when it has none. Returns the
        :class:`Checkup`: typed findings, each with its advice as data.

        With ``fix``, the fixes that are writes are applied and the bus is
        checked again (homing offsets are set for the session; stored in
        EEPROM only with ``write_servos``). Raises :class:`PortError` when
        a port cannot be opened."""
        return Checkup.from_json(self._robot.doctor(bool(fix), bool(write_servos)))

    def torque_off(self) -> Optional[Report]:
        """Turns the torque off on every servo. A running stream ends, and
        its report is returned; otherwise every bus gets a broadcast torque
        off (on the built-in simulator there is nothing to turn off) and
        None is returned."""
        if self._stream is not None and not self._stream.finished:
            return self._stream.torque_off()
        self._robot.torque_off()
        return None

    def __repr__(self) -> str:
        return repr(self._robot)
