"""A ``FeetechMotorsBus`` whose transactions are servobus's.

LeRobot's bus classes do the control table, sign encoding, normalisation,
calibration (read, write, half-turn homing, ranges of motion), torque and
motor set-up on top of a few transactions: ping, broadcast ping, read,
write, sync read and sync write. This class keeps all of that and replaces
only the transactions, so LeRobot's calibration files and values are
unchanged, and a SYNC READ that misses one servo names it (and keeps the
others' values when errors are not raised).
"""

from __future__ import annotations

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
                 latency=None):
        super().__init__(port, motors, calibration, protocol_version)
        self.baudrate = baudrate
        self.latency = latency
        self._servobus: servobus.Bus | None = None

    # --- the port -------------------------------------------------------
    @property
    def is_connected(self) -> bool:
        return self._servobus is not None

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
        try:
            if disable_torque:
                self.disable_torque(num_retry=5)
        finally:
            self._close()

    def _bus(self) -> servobus.Bus:
        if self._servobus is None:
            raise DeviceNotConnectedError(f"{self} is not connected.")
        return self._servobus

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
