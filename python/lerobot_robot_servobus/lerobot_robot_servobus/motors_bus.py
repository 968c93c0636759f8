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
joints there jerk-limited, within the robot file's velocity, acceleration
and jerk limits and clamped to the calibrated range, and present positions
come from the loop's own readings. Any other transaction first ends the
live loop with a jerk-limited stop and takes the port back.
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


class ServobusMotorsBus(FeetechMotorsBus):
    """LeRobot's Feetech bus on servobus: same constructor (plus
    ``baudrate``, and ``latency``: the adapter latency in s the reply
    deadlines allow, default what the port is assumed to need), same
    methods."""

    def __init__(self, port, motors, calibration=None, protocol_version=0, baudrate=1_000_000,
                 latency=None, robot="so101", live_timeout=0.25):
        super().__init__(port, motors, calibration, protocol_version)
        self.baudrate = baudrate
        self.latency = latency
        self.robot = robot
        """servobus's robot (a robot file or a built-in name) whose joints
        and limits the live loop moves: its joints are named and numbered
        as the motors."""
        self.live_timeout = live_timeout
        """Seconds without a goal after which the live loop stops the joints
        (jerk-limited) and holds them until goals come back."""
        self._servobus: servobus.Bus | None = None
        self._live: servobus.Stream | None = None
        self._live_robot: servobus.Robot | None = None
        self._live_joints: dict[str, servobus.JointCalibration] = {}

    # --- the port -------------------------------------------------------
    @property
    def is_connected(self) -> bool:
        return self._servobus is not None or self._live is not None

    def _connect(self, handshake: bool = True) -> None:
        try:
            self._servobus = servobus.Bus(self.port, self.baudrate, latency=self.latency)
        except servobus.Error as e:
            raise ConnectionError(f"\nCould not connect on port '{self.port}': {e}") from e
        if handshake:
            try:
                self._handshake()
            except Exception:
                self._close()
                raise

    def set_timeout(self, timeout_ms: int | None = None) -> None:
        """servobus derives every reply deadline from the link: nothing to set."""

    def get_baudrate(self) -> int:
        return self.baudrate

    def _close(self) -> None:
        if self._servobus is not None:
            self._servobus.close()
            self._servobus = None

    def disconnect(self, disable_torque: bool = True) -> None:
        if not self.is_connected:
            raise DeviceNotConnectedError(f"{self} is not connected.")
        # The joints come to a jerk-limited stop before the torque goes.
        self.end_live()
        try:
            if disable_torque:
                self.disable_torque(num_retry=5)
        finally:
            self._close()

    def _bus(self) -> servobus.Bus:
        """The port for a transaction: taken back from the live loop first."""
        self.end_live()
        if self._servobus is None:
            raise DeviceNotConnectedError(f"{self} is not connected.")
        return self._servobus

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
            raise RuntimeError(f"{self} has no calibration registered.")
        lerobot = json.dumps({motor: asdict(cal) for motor, cal in self.calibration.items()})
        design = self._live_robot_yaml()
        calibration = servobus.Calibration.from_lerobot(lerobot, robot=design)
        self._close()
        try:
            robot = servobus.Robot(design, port=self.port, calibration=calibration)
            # As LeRobot's follower: a gripper closed on an object strains
            # against it (its servo's own protection limits the current).
            self._live = robot.stream(timeout=self.live_timeout, tracking_faults=False)
        except servobus.Error:
            self._connect(handshake=False)
            raise
        self._live_robot = robot
        self._live_joints = {j.name: j for j in calibration.joints}

    def _live_robot_yaml(self) -> str:
        """servobus's robot file for the live loop (YAML text): the motors
        as its joints, with the velocity, acceleration and jerk limits of
        the joints of the same names in ``self.robot``, and no position
        limits but a turn: LeRobot's calibrated range bounds each joint
        (less servobus's margin of a few degrees at each end). The loop
        measures the adapter's latency at start-up and learns it while it
        runs (``latency`` is for the transactions of this class)."""
        design = servobus.Robot(self.robot)
        limits = design.limits
        turn = 179.0 if design.units == "deg" else math.radians(179.0)
        joints = []
        for motor, m in self.motors.items():
            if motor not in limits:
                raise ValueError(f"servobus's robot {self.robot!r} has no joint {motor!r}")
            lim = limits[motor]
            jerk = "" if lim.max_jerk is None else f", max_jerk: {lim.max_jerk!r}"
            joints.append(
                f"      - {{name: {motor}, id: {m.id}, model: {m.model}, min: {-turn!r}, max: {turn!r}, "
                f"max_velocity: {lim.max_velocity!r}, max_acceleration: {lim.max_acceleration!r}{jerk}}}"
            )
        head = [f"name: {design.name}", f"units: {design.units}", f"rate: {design.rate_hz!r}", "buses:",
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
            live.stop()
        finally:
            self._connect(handshake=False)

    def live_state(self) -> servobus.State:
        """The live loop's latest state, once every joint has a reading."""
        if self._live is None:
            raise RuntimeError(f"{self}: servobus's live loop is not running")
        deadline = time.monotonic() + 2.0
        while True:
            state = self._live.state()
            if state.faults:
                raise ConnectionError(f"{self}: the live loop stopped on a fault: {state.faults[-1]}")
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
                raise ConnectionError(f"{self}: the live loop has no reading of {motor}")
            tick = self._live_joints[motor].tick_at(self._degrees(angle))
            ticks[self.motors[motor].id] = round(tick)
        values = self._normalize(ticks) if normalize else ticks
        return {self._id_to_name(id_): v for id_, v in values.items()}

    def sync_write(self, data_name, values, *, normalize=True, num_retry=0):
        if self._live is None or data_name != "Goal_Position":
            return super().sync_write(data_name, values, normalize=normalize, num_retry=num_retry)
        ids_values = self._get_ids_values_dict(values)
        ticks = self._unnormalize(ids_values) if normalize else {i: int(v) for i, v in ids_values.items()}
        target = {}
        for id_, tick in ticks.items():
            motor = self._id_to_name(id_)
            target[motor] = self._angle(self._live_joints[motor].degrees_at(tick))
        try:
            self._live.send(target)
        except servobus.Error as e:
            # The loop has ended (a fault): its report is collected and the
            # port taken back; the next action starts a new loop.
            self.end_live()
            raise ConnectionError(f"{self}: the live loop took no goal: {e}") from e

    # --- the transactions -----------------------------------------------
    def ping(self, motor, num_retry: int = 0, raise_on_error: bool = False) -> int | None:
        id_ = self._get_motor_id(motor)
        for _ in range(1 + num_retry):
            if self._bus().ping(id_):
                model, comm, error = self._read(*MODEL_NUMBER, id_, raise_on_error=raise_on_error)
                if self._is_comm_success(comm) and not self._is_error(error):
                    return model
        if raise_on_error:
            raise ConnectionError(f"motor {id_} does not answer a ping")
        return None

    def broadcast_ping(self, num_retry: int = 0, raise_on_error: bool = False) -> dict[int, int] | None:
        found = self._bus().scan()
        if not found and raise_on_error:
            raise ConnectionError(f"no motor answers on '{self.port}'")
        return self._read_model_number(found, raise_on_error)

    def _read(self, address, length, motor_id, *, num_retry=0, raise_on_error=True, err_msg=""):
        last = None
        for _ in range(1 + num_retry):
            try:
                value, flags = self._bus().read_raw(motor_id, address, length, status=True)
                if self._is_error(flags) and raise_on_error:
                    raise RuntimeError(f"{err_msg} motor {motor_id} reports status {flags:#04x}")
                return value, scs.COMM_SUCCESS, flags
            except servobus.MissingServo as e:
                last = e
        if raise_on_error:
            raise ConnectionError(f"{err_msg} {last}") from last
        return 0, scs.COMM_RX_TIMEOUT, 0

    def _write(self, addr, length, motor_id, value, *, num_retry=0, raise_on_error=True, err_msg=""):
        last = None
        for _ in range(1 + num_retry):
            try:
                flags = self._bus().write_raw(motor_id, addr, length, value) or 0
                if self._is_error(flags) and raise_on_error:
                    raise RuntimeError(f"{err_msg} motor {motor_id} reports status {flags:#04x}")
                return scs.COMM_SUCCESS, flags
            except servobus.MissingServo as e:
                last = e
        if raise_on_error:
            raise ConnectionError(f"{err_msg} {last}") from last
        return scs.COMM_RX_TIMEOUT, 0

    def _sync_read(self, addr, length, motor_ids, *, num_retry=0, raise_on_error=True, err_msg=""):
        values: dict[int, int] = {}
        wanted = list(motor_ids)
        missing = {}
        for _ in range(1 + num_retry):
            result = self._bus().sync_read_raw(addr, length, wanted)
            values.update({i: v for i, v in result.items() if v is not None})
            missing = result.missing
            wanted = list(missing)
            if not wanted:
                return values, scs.COMM_SUCCESS
        if raise_on_error:
            why = ", ".join(f"{m.id}: {m.reason}" for m in missing.values())
            raise ConnectionError(f"{err_msg} missing motors ({why})")
        # Partial results are kept: the motors that answered have values.
        return values, scs.COMM_RX_TIMEOUT

    def _sync_write(self, addr, length, ids_values, num_retry=0, raise_on_error=True, err_msg=""):
        self._bus().sync_write_raw(addr, length, ids_values)
        return scs.COMM_SUCCESS
