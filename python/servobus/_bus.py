"""The typed bus: :class:`Bus` and the result of its SYNC READ."""

from __future__ import annotations

from typing import Dict, Iterable, Mapping, Optional

from . import _native


class Missing:
    """Why a servo is missing from a SYNC READ: ``id``, ``reason``
    (``"no reply"``, ``"corrupted reply"``, ...) and ``attempts``."""

    __slots__ = ("id", "reason", "attempts")

    def __init__(self, id: int, reason: str, attempts: int) -> None:
        self.id = id
        self.reason = reason
        self.attempts = attempts

    def __repr__(self) -> str:
        return f"Missing(id={self.id}, reason={self.reason!r}, attempts={self.attempts})"


class SyncRead(Dict[int, Optional[int]]):
    """The result of :meth:`Bus.sync_read`: a dict of servo ID to value, in
    the order asked; a servo that did not answer maps to None and is in
    :attr:`missing` with the reason. Partial results are never thrown away.
    """

    missing: Dict[int, Missing]

    def __init__(self, values, missing) -> None:
        super().__init__(values)
        self.missing = {m.id: m for m in missing}

    @property
    def complete(self) -> bool:
        """Whether every servo answered."""
        return not self.missing


class Bus:
    """A bus of Feetech servos on a serial port:
    ``Bus(port, baud=1_000_000, series="sts", latency=None)``.

    Registers are named as in the control table (``"present_position"``,
    ``"goal_position"``, ``"torque_enable"``; case and separators do not
    matter); values are the registers' raw units (ticks for positions).
    ``latency`` (s) is the adapter latency the reply deadlines allow
    (default: what the port is assumed to need). Every call releases the
    GIL while it waits on the bus. Use :meth:`Bus.sim` for an in-process
    simulated bus. A context manager: the port closes at the end.
    """

    def __init__(
        self,
        port: str,
        baud: int = 1_000_000,
        series: str = "sts",
        latency: Optional[float] = None,
        *,
        _native_bus: Optional[_native.Bus] = None,
    ) -> None:
        self._bus = _native_bus if _native_bus is not None else _native.Bus(port, baud, series, latency)

    @classmethod
    def sim(cls, robot: str = "so101") -> "Bus":
        """An in-process simulated bus with the servos of ``robot`` (a robot
        file, a built-in name or YAML text), in real time. For a simulator
        any program can open as a serial port, see :class:`servobus.Sim`."""
        return cls("<sim>", _native_bus=_native.Bus.sim(robot))

    @property
    def series(self) -> str:
        """The servo series whose registers are read: ``"sts"`` or ``"scs"``."""
        return self._bus.series

    def ping(self, id: int) -> bool:
        """PING servo ``id``: True when it answers."""
        return self._bus.ping(id)

    def scan(self, ids: Optional[Iterable[int]] = None) -> list:
        """The IDs among ``ids`` (default 0..253) that answer a PING."""
        return self._bus.scan(None if ids is None else list(ids))

    def read(self, id: int, register: str) -> int:
        """The value of ``register`` of servo ``id``.

        Raises :class:`servobus.TimeoutError` when the servo does not answer.
        """
        return self._bus.read(id, register)

    def write(self, id: int, register: str, value: int) -> None:
        """Writes ``value`` to ``register`` of servo ``id`` (EEPROM registers
        persistently). Raises :class:`servobus.LimitError` for a value the
        register cannot hold."""
        self._bus.write(id, register, int(value))

    def sync_read(self, register: str, ids: Iterable[int]) -> SyncRead:
        """Reads ``register`` of every servo in ``ids`` with one SYNC READ
        (the servos missing from it are asked once more).

        Returns a :class:`SyncRead`: ID to value, None for a servo that did
        not answer, and ``.missing`` saying which and why.
        """
        values, missing = self._bus.sync_read(register, list(ids))
        return SyncRead(values, [Missing(*m) for m in missing])

    def sync_write(self, register: str, values: Mapping[int, int]) -> None:
        """Writes ``register`` of several servos with one SYNC WRITE:
        ``values`` maps each servo's ID to its value."""
        self._bus.sync_write(register, [(int(k), int(v)) for k, v in values.items()])

    def read_raw(self, id: int, address: int, length: int, status: bool = False):
        """``length`` (1, 2 or 4) bytes at ``address`` of servo ``id`` as one
        unsigned number in the bus's byte order (for control tables of
        your own); with ``status``, ``(value, status flags of the reply)``."""
        value, flags = self._bus.read_raw(id, address, length)
        return (value, flags) if status else value

    def write_raw(self, id: int, address: int, length: int, value: int) -> Optional[int]:
        """Writes the unsigned ``value`` as ``length`` bytes at ``address``
        of servo ``id`` (a plain WRITE): the reply's status flags, or None
        when the servo sends no reply."""
        return self._bus.write_raw(id, address, length, int(value))

    def sync_read_raw(self, address: int, length: int, ids: Iterable[int]) -> SyncRead:
        """As :meth:`sync_read`, by address and length: unsigned numbers."""
        values, missing = self._bus.sync_read_raw(address, length, list(ids))
        return SyncRead(values, [Missing(*m) for m in missing])

    def sync_write_raw(self, address: int, length: int, values: Mapping[int, int]) -> None:
        """As :meth:`sync_write`, by address and length: unsigned numbers."""
        self._bus.sync_write_raw(address, length, [(int(k), int(v)) for k, v in values.items()])

    def close(self) -> None:
        """Closes the bus; later calls raise :class:`servobus.Error`."""
        self._bus.close()

    def __enter__(self) -> "Bus":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return repr(self._bus)
