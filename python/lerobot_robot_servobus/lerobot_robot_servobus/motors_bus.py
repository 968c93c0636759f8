"""A ``FeetechMotorsBus`` whose transactions are servobus's.

LeRobot's bus classes do the control table, sign encoding, normalisation,
calibration (read, write, half-turn homing, ranges of motion), torque and
motor set-up on top of a few transactions: ping, broadcast ping, read,
write, sync read and sync write. This class keeps all of that and replaces
only the transactions, so LeRobot's calibration files and values are
unchanged, and a SYNC READ that misses one servo names it (and keeps the
others' values when errors are not raised).

It can also hand the port to servobus's live loop (:meth:`start_live`):
goal positions then become live targets of the loop, which moves the
joints there jerk-limited, within the live limits (by default what each
servo's model can do, as LeRobot's raw writes move it; lower ones in the
robot's config) and clamped to the calibrated range, and present positions
come from the loop's own readings. Any other transaction first ends the
live loop with a jerk-limited stop and takes the port back.

It tells the truth:

- once the live loop has stopped on a fault (its port gone, a servo
  missing), the next goal raises :class:`LiveLoopFault`, the fault in its
  first line, instead of being dropped;
- :meth:`disable_torque` (and so ``disconnect``) turns the torque off on
  every servo that answers, then names those that did not;
- a read or write outside the live loop is tried once more when a reply is
  missing, with deadlines from the link as measured at connection
  (:meth:`servobus.Bus.learn_latency`), so a loaded machine costs no
  configure or calibration;
- its messages start with the problem, on one line (the bus's ``repr`` is
  one line too).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict

import scservo_sdk as scs
import servobus
from lerobot.motors.feetech import FeetechMotorsBus
from lerobot.motors.feetech.tables import MODEL_NUMBER
from lerobot.utils.errors import DeviceNotConnectedError

# A reply missing from a read or write outside the live loop is asked for
# once more whatever LeRobot's own num_retry: one late reply on a loaded
# machine must not fail a configure() or a calibration.
MIN_RETRIES = 1

# The live limits' jerk: each joint reaches its acceleration limit in this
# long (servobus's ramp for live following, as `servobus follow` keeps), so
# the physical motion has no acceleration steps while the loop keeps up
# with raw writes.
JERK_RAMP_S = servobus.MODEL_JERK_RAMP_S

# The live loop's position limits: a turn less a degree each side; LeRobot's
# calibrated range then bounds each joint (servobus keeps a few degrees
# inside it).
TURN_DEG = 179.0


class LiveLoopFault(servobus.FaultError, ConnectionError):
    """servobus's live loop stopped on a fault (its port gone, a servo
    missing): ``fault`` says which (a dict: ``kind``, ``joint``,
    ``servo_id`` ...; None when only its text is known), ``report`` is the
    loop's report. A ``ConnectionError`` too, as LeRobot's own bus raises
    for a lost motor."""


class TorqueNotOff(ConnectionError):
    """The torque could not be turned off on some servos: ``missing``
    names them (motor to reason); it was turned off on ``turned_off``."""

    def __init__(self, message: str, missing: dict, turned_off: list) -> None:
        super().__init__(message)
        self.missing = missing
        self.turned_off = turned_off


class ServobusMotorsBus(FeetechMotorsBus):
    """LeRobot's Feetech bus on servobus: same constructor (plus
    ``baudrate``, and ``latency``: the adapter latency in s the reply
    deadlines allow, default what the port is assumed to need), same
    methods."""

    def __init__(self, port, motors, calibration=None, protocol_version=0, baudrate=1_000_000,
                 latency=None, robot=None, live_timeout=0.25, max_velocity=None,
                 max_acceleration=None, max_jerk=None):
        super().__init__(port, motors, calibration, protocol_version)
        self.baudrate = baudrate
        self.latency = latency
        self.robot = robot
        """servobus's robot (a robot file or a built-in name) whose joints'
        velocity, acceleration and jerk limits the live loop keeps, its
        joints named as the motors; None: what each servo's model can do
        (:func:`servobus.model_limits`)."""
        self.max_velocity = dict(max_velocity or {})
        """Lower live velocity limits, deg/s, by motor name."""
        self.max_acceleration = dict(max_acceleration or {})
        """Lower live acceleration limits, deg/s^2, by motor name."""
        self.max_jerk = dict(max_jerk or {})
        """Live jerk limits, deg/s^3, by motor name (default: the
        acceleration limit reached in ``JERK_RAMP_S``)."""
        self._ended: servobus.Report | None = None
        self.live_timeout = live_timeout
        """Seconds without a goal after which the live loop stops the joints
        (jerk-limited) and holds them until goals come back."""
        self._servobus: servobus.Bus | None = None
        self._live: servobus.Stream | None = None
        self._live_robot: servobus.Robot | None = None
        self._live_joints: dict[str, servobus.JointCalibration] = {}

    def __repr__(self) -> str:
        # One line: LeRobot puts the bus in its messages ("... is not
        # connected"), and a message starts with its problem.
        return f"ServobusMotorsBus(port={self.port!r}, motors={list(self.motors)})"

    __str__ = __repr__

    # --- the port -------------------------------------------------------
    @property
    def is_connected(self) -> bool:
        return self._servobus is not None or self._live is not None

    def _connect(self, handshake: bool = True) -> None:
        try:
            self._servobus = servobus.Bus(self.port, self.baudrate, latency=self.latency)
        except servobus.Error as e:
            raise ConnectionError(f"could not open port {self.port!r}: {e}") from e
        if handshake:
            try:
                self._handshake()
            except Exception:
                self._close()
                raise
        self._learn_link()

    def _learn_link(self) -> None:
        """Measures the adapter (PINGs of the motors) and lets the reply
        deadlines allow what it showed: the learned link. Motors that do
        not answer are the handshake's business, not this."""
        if self._servobus is None:
            return
        try:
            self._servobus.learn_latency([m.id for m in self.motors.values()])
        except servobus.MissingServo:
            pass

    def set_timeout(self, timeout_ms: int | None = None) -> None:
        """servobus derives every reply deadline from the link: nothing to set."""

    def get_baudrate(self) -> int:
        return self.baudrate

    def _close(self) -> None:
        if self._servobus is not None:
            self._servobus.close()
            self._servobus = None

    def disconnect(self, disable_torque: bool = True) -> None:
        """Stops the live loop (jerk-limited), turns the torque off on every
        servo that answers (with ``disable_torque``) and closes the port,
        whatever fails on the way; then raises the first problem
        (:class:`TorqueNotOff` names the servos that kept their torque)."""
        if not self.is_connected:
            raise DeviceNotConnectedError(f"{self} is not connected.")
        problems: list[Exception] = []
        # The joints come to a jerk-limited stop before the torque goes.
        try:
            self.end_live()
        except Exception as e:  # the port may be gone: the torque is still tried
            problems.append(e)
        try:
            if disable_torque and self._servobus is not None:
                self.disable_torque(num_retry=2)
        except Exception as e:
            problems.append(e)
        finally:
            self._close()
        if problems:
            raise problems[0]

    def disable_torque(self, motors=None, num_retry: int = 0) -> None:
        """Turns the torque off (and the EEPROM lock open, as LeRobot's own
        does) on every motor of ``motors``, going on past a motor that does
        not answer: LeRobot's stops at the first and leaves the rest
        powered. Raises :class:`TorqueNotOff` afterwards, naming the motors
        that did not answer."""
        turned_off, missing = [], {}
        for motor in self._get_motors_list(motors):
            try:
                self.write("Torque_Enable", motor, 0, num_retry=num_retry)
                self.write("Lock", motor, 0, num_retry=num_retry)
                turned_off.append(motor)
            except (ConnectionError, servobus.Error) as e:
                missing[motor] = str(e).splitlines()[0] if str(e) else type(e).__name__
        if missing:
            named = ", ".join(f"{m} (id {self.motors[m].id})" for m in missing)
            off = ", ".join(f"{m} (id {self.motors[m].id})" for m in turned_off) or "none"
            first = next(iter(missing.values()))
            raise TorqueNotOff(f"torque not turned off on {named}: {first}; turned off on {off}",
                               missing, turned_off)

    def _bus(self) -> servobus.Bus:
        """The port for a transaction: taken back from the live loop first."""
        self.end_live()
        if self._servobus is None:
            raise DeviceNotConnectedError(f"{self} is not connected.")
        return self._servobus

    def _assert_motors_exist(self) -> None:
        """LeRobot's check that every motor answers with its model, its
        message one line that names the motors: ``motors missing on
        '/dev/ttyACM0': elbow_flex (id 3) does not answer``."""
        expected = {m.id: self.model_number_table[m.model] for m in self.motors.values()}
        found = {}
        for id_ in self.ids:
            model = self.ping(id_, num_retry=MIN_RETRIES)
            if model is not None:
                found[id_] = model
        problems = [f"{self._id_to_name(i)} (id {i}) does not answer" for i in self.ids if i not in found]
        problems += [f"{self._id_to_name(i)} (id {i}) is model {got}, not {expected[i]}"
                     for i, got in found.items() if expected.get(i) != got]
        if problems:
            raise RuntimeError(f"motors missing on {self.port!r}: {'; '.join(problems)}")

    # --- the live loop --------------------------------------------------
    @property
    def is_live(self) -> bool:
        """Whether servobus's live loop has the port."""
        return self._live is not None

    def start_live(self) -> None:
        """Hands the port to servobus's live loop (``servobus stream``), the
        servos checked against the calibration first: from now on goal
        positions written with :meth:`sync_write` are the loop's targets and
        present positions read with :meth:`sync_read` its readings. Nothing
        to do when it runs already."""
        if self._live is not None:
            return
        if not self.calibration:
            raise RuntimeError(f"no calibration registered for {self}")
        lerobot = json.dumps({motor: asdict(cal) for motor, cal in self.calibration.items()})
        design = self._live_robot_yaml()
        calibration = servobus.Calibration.from_lerobot(lerobot, robot=design)
        self._close()
        try:
            robot = servobus.Robot(design, port=self.port, calibration=calibration)
            # The robot file's per-joint fault policy (see
            # _live_robot_yaml): a gripper closed on an object is held
            # there, an arm joint far off its path ends the loop.
            self._live = robot.stream(timeout=self.live_timeout, tracking_faults=True)
        except servobus.Error:
            self._connect(handshake=False)
            raise
        self._live_robot = robot
        self._live_joints = {j.name: j for j in calibration.joints}

    def live_limits(self) -> dict[str, tuple[float, float, float]]:
        """Each motor's live ``(max_velocity, max_acceleration, max_jerk)``
        in degrees: what its servo's model can do (top speed, and the
        acceleration LeRobot's ``configure_motors`` sets), or the limits
        of the joints of the same names in ``self.robot`` when one is
        given, lowered where ``max_velocity``, ``max_acceleration`` or
        ``max_jerk`` say. Raises ``ValueError`` for a limit above what the
        model can do, or for a motor the given robot does not have."""
        design = servobus.Robot(self.robot) if self.robot is not None else None
        named = design.limits if design is not None else {}
        to_deg = (lambda x: math.degrees(x)) if design is not None and design.units == "rad" else float
        for given in (self.max_velocity, self.max_acceleration, self.max_jerk):
            unknown = set(given) - set(self.motors)
            if unknown:
                raise ValueError(f"live limits for unknown motors {sorted(unknown)}: the motors are {list(self.motors)}")
        out = {}
        for motor, m in self.motors.items():
            v_model, a_model = servobus.model_limits(m.model)
            if design is not None:
                if motor not in named:
                    raise ValueError(f"servobus's robot {self.robot!r} has no joint {motor!r}")
                lim = named[motor]
                v, a = to_deg(lim.max_velocity), to_deg(lim.max_acceleration)
                j = None if lim.max_jerk is None else to_deg(lim.max_jerk)
            else:
                v, a, j = v_model, a_model, None
            for name, given, model in (("max_velocity", self.max_velocity, v_model),
                                       ("max_acceleration", self.max_acceleration, a_model)):
                if motor in given:
                    x = float(given[motor])
                    if not (0.0 < x <= model * (1 + 1e-9)):
                        raise ValueError(f"{name} {x} for {motor}: give more than 0 and at most "
                                         f"{model:.1f}, what its {m.model} can do")
                    if name == "max_velocity":
                        v = min(v, x)
                    else:
                        a = min(a, x)
            if motor in self.max_jerk:
                j = float(self.max_jerk[motor])
                if not (math.isfinite(j) and j > 0.0):
                    raise ValueError(f"max_jerk {j} for {motor}: give a positive number of deg/s^3")
            out[motor] = (v, a, j if j is not None else a / JERK_RAMP_S)
        return out

    def _live_robot_yaml(self) -> str:
        """servobus's robot file for the live loop (YAML text, degrees): the
        motors as its joints, with their :meth:`live_limits`, and no
        position limits but a turn: LeRobot's calibrated range bounds each
        joint (less servobus's margin of a few degrees at each end). The
        loop measures the adapter's latency at start-up and learns it while
        it runs (``latency`` is for the transactions of this class)."""
        limits = self.live_limits()
        design = servobus.Robot(self.robot if self.robot is not None else "so101")
        joints = []
        for motor, m in self.motors.items():
            v, a, j = limits[motor]
            joints.append(
                f"      - {{name: {motor}, id: {m.id}, model: {m.model}, min: {-TURN_DEG!r}, max: {TURN_DEG!r}, "
                f"max_velocity: {v!r}, max_acceleration: {a!r}, max_jerk: {j!r}, faults: {_faults(motor)}}}"
            )
        head = [f"name: {design.name}", "units: deg", f"rate: {design.rate_hz!r}", "buses:",
                "  - name: lerobot", f"    baud: {self.baudrate}", "    latency_us: auto",
                "    return_delay_us: 0", "    joints:"]
        return "\n".join(head + joints) + "\n"

    def end_live(self) -> None:
        """Stops the joints (jerk-limited), ends the live loop and takes the
        port back. Nothing to do when it does not run."""
        if self._live is None:
            return
        live, self._live, self._live_robot = self._live, None, None
        try:
            self._ended = live.stop()
        finally:
            self._connect(handshake=False)

    def _raise_if_faulted(self) -> None:
        """Raises :class:`LiveLoopFault` once the live loop has stopped on a
        fault: the loop ends (its report kept on the exception) and the port
        is taken back if it is still there; the next goal starts a new
        loop."""
        if self._live is None:
            return
        state = self._live.state()
        if not state.faults and not self._live.finished:
            return
        text = state.faults[0] if state.faults else None
        self._ended = None
        try:
            self.end_live()
        except Exception as e:
            # The port went with the loop: the fault is the news, the failed
            # reopening its consequence.
            raise LiveLoopFault(f"the live loop stopped on a fault: {text or e}") from e
        report = self._ended
        fault = None if report is None else report.fault
        if text is None and fault is not None:
            where = [f"{k} {fault[k]}" for k in ("joint", "servo_id") if fault.get(k) is not None]
            text = fault.get("kind", "fault") + (f" ({', '.join(where)})" if where else "")
        message = f"the live loop stopped on a fault: {text}" if text else "the live loop stopped"
        raise LiveLoopFault(message, fault=fault, report=report)

    def live_state(self) -> servobus.State:
        """The live loop's latest state, once every joint has a reading."""
        if self._live is None:
            raise RuntimeError(f"{self}: servobus's live loop is not running")
        deadline = time.monotonic() + 2.0
        while True:
            self._raise_if_faulted()
            state = self._live.state()
            if all(math.isfinite(p) for p in state.position) or time.monotonic() > deadline:
                return state
            time.sleep(0.005)

    def _degrees(self, angle: float) -> float:
        assert self._live_robot is not None
        return math.degrees(angle) if self._live_robot.units == "rad" else angle

    def _angle(self, degrees: float) -> float:
        assert self._live_robot is not None
        return math.radians(degrees) if self._live_robot.units == "rad" else degrees

    def sync_read(self, data_name, motors=None, *, normalize=True, num_retry=0):
        if self._live is None or data_name != "Present_Position":
            return super().sync_read(data_name, motors, normalize=normalize, num_retry=num_retry)
        state = self.live_state()
        ticks = {}
        for motor in self._get_motors_list(motors):
            angle = state.position[state.joints.index(motor)]
            if not math.isfinite(angle):
                raise ConnectionError(f"the live loop has no reading of {motor} on {self.port}")
            tick = self._live_joints[motor].tick_at(self._degrees(angle))
            ticks[self.motors[motor].id] = round(tick)
        values = self._normalize(ticks) if normalize else ticks
        return {self._id_to_name(id_): v for id_, v in values.items()}

    def sync_write(self, data_name, values, *, normalize=True, num_retry=0):
        if self._live is None or data_name != "Goal_Position":
            return super().sync_write(data_name, values, normalize=normalize, num_retry=num_retry)
        self._raise_if_faulted()
        ids_values = self._get_ids_values_dict(values)
        ticks = self._unnormalize(ids_values) if normalize else {i: int(v) for i, v in ids_values.items()}
        target = {}
        for id_, tick in ticks.items():
            motor = self._id_to_name(id_)
            target[motor] = self._angle(self._live_joints[motor].degrees_at(tick))
        try:
            self._live.send(target)
        except servobus.Error as e:
            # The loop has ended between the check and the send: its fault.
            self._raise_if_faulted()
            raise ConnectionError(f"the live loop took no goal: {e}") from e

    # --- the transactions -----------------------------------------------
    def ping(self, motor, num_retry: int = 0, raise_on_error: bool = False) -> int | None:
        id_ = self._get_motor_id(motor)
        for _ in range(1 + num_retry):
            if self._bus().ping(id_):
                model, comm, error = self._read(*MODEL_NUMBER, id_, raise_on_error=raise_on_error)
                if self._is_comm_success(comm) and not self._is_error(error):
                    return model
        if raise_on_error:
            raise ConnectionError(f"motor {id_} does not answer a ping on {self.port}")
        return None

    def broadcast_ping(self, num_retry: int = 0, raise_on_error: bool = False) -> dict[int, int] | None:
        found = self._bus().scan()
        if not found and raise_on_error:
            raise ConnectionError(f"no motor answers on '{self.port}'")
        return self._read_model_number(found, raise_on_error)

    def _read(self, address, length, motor_id, *, num_retry=0, raise_on_error=True, err_msg=""):
        last = None
        for _ in range(1 + max(num_retry, MIN_RETRIES)):
            try:
                value, flags = self._bus().read_raw(motor_id, address, length, status=True)
                if self._is_error(flags) and raise_on_error:
                    raise RuntimeError(_line(err_msg, f"motor {motor_id} reports status {flags:#04x}"))
                return value, scs.COMM_SUCCESS, flags
            except servobus.MissingServo as e:
                last = e
        if raise_on_error:
            raise ConnectionError(_line(err_msg, str(last))) from last
        return 0, scs.COMM_RX_TIMEOUT, 0

    def _write(self, addr, length, motor_id, value, *, num_retry=0, raise_on_error=True, err_msg=""):
        last = None
        for _ in range(1 + max(num_retry, MIN_RETRIES)):
            try:
                flags = self._bus().write_raw(motor_id, addr, length, value) or 0
                if self._is_error(flags) and raise_on_error:
                    raise RuntimeError(_line(err_msg, f"motor {motor_id} reports status {flags:#04x}"))
                return scs.COMM_SUCCESS, flags
            except servobus.MissingServo as e:
                last = e
        if raise_on_error:
            raise ConnectionError(_line(err_msg, str(last))) from last
        return scs.COMM_RX_TIMEOUT, 0

    def _sync_read(self, addr, length, motor_ids, *, num_retry=0, raise_on_error=True, err_msg=""):
        values: dict[int, int] = {}
        wanted = list(motor_ids)
        missing = {}
        for _ in range(1 + max(num_retry, MIN_RETRIES)):
            result = self._bus().sync_read_raw(addr, length, wanted)
            values.update({i: v for i, v in result.items() if v is not None})
            missing = result.missing
            wanted = list(missing)
            if not wanted:
                return values, scs.COMM_SUCCESS
        if raise_on_error:
            why = ", ".join(f"{m.id}: {m.reason}" for m in missing.values())
            raise ConnectionError(_line(err_msg, f"missing motors ({why})"))
        # Partial results are kept: the motors that answered have values.
        return values, scs.COMM_RX_TIMEOUT

    def _sync_write(self, addr, length, ids_values, num_retry=0, raise_on_error=True, err_msg=""):
        self._bus().sync_write_raw(addr, length, ids_values)
        return scs.COMM_SUCCESS


# How far (deg) an arm joint may be off its own path before the live loop
# ends: a joint that far behind is blocked for good or not driven at all (a
# blocked joint is held pressed long before, in a live session).
ARM_FOLLOWING_TOLERANCE_DEG = 45.0


def _faults(motor: str) -> str:
    """The robot file's ``faults:`` of ``motor`` in the live loop: a
    gripper closed on an object (or on its end stop) strains against it, as
    with LeRobot's follower, so its stalls and following errors hold it
    pressed; every other joint ends the loop when it is far off its path.
    Heat, over-current and a missing servo end it whatever the joint."""
    if motor == "gripper":
        return "{stall: hold, following_error: hold}"
    return f"{{following_tolerance: {ARM_FOLLOWING_TOLERANCE_DEG!r}}}"


def _line(context: str, problem: str) -> str:
    """A message of one line, the problem first: ``problem`` and then
    LeRobot's own context (its ``err_msg``), if any."""
    context = " ".join(str(context).split())
    problem = " ".join(str(problem).split())
    return f"{problem} ({context})" if context else problem
