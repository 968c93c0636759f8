"""The typed bus: :class:`Bus` and the result of its SYNC READ."""

from __future__ import annotations

import math
from typing import Dict, Iterable, Mapping, Optional, Tuple, Union

from . import _native
from ._errors import LimitError, UsageError

Number = Union[int, float]

# Ticks per turn of the STS/SMS position sensor: speeds in rpm.
_STS_TICKS_PER_TURN = 4096


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


class SyncRead(Dict[int, Optional[Number]]):
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
    matter). :meth:`read` and :meth:`write` take values in the register's
    physical unit (:meth:`unit`): positions in ticks, speeds in ticks/s (or
    ``unit="rpm"``), ``present_voltage`` in V, ``present_temperature`` in
    °C, ``present_load`` and torque limits in %, currents in mA, times in
    ms; ``unit="raw"`` gives the register's raw number.
    ``latency`` (s) is the adapter latency the reply deadlines allow
    (default: what the port is assumed to need). Every call releases the
    GIL while it waits on the bus, and Ctrl-C raises ``KeyboardInterrupt``
    from any call it came during (a transaction under way is finished
    first, never cut in half). ``baud`` is one the servos can be set to
    (1000000, 500000, 250000, 128000, 115200, 76800, 57600, 38400;
    :class:`servobus.ConfigError` otherwise). Use :meth:`Bus.sim` for an in-process
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
        self._scales: Dict[Tuple[str, Optional[str]], float] = {}

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

    def unit(self, register: str) -> str:
        """The unit of ``register``'s values in :meth:`read` and :meth:`write`:
        ``"ticks"``, ``"ticks/s"``, ``"ticks/s^2"``, ``"V"``, ``"°C"``,
        ``"%"``, ``"mA"``, ``"ms"``, ``"us"``, or ``""`` for a plain number
        (flags, modes, gains, IDs)."""
        return self._bus.unit(register)[1]

    def _scale(self, register: str, unit: Optional[str]) -> float:
        """What a raw value of ``register`` is multiplied by to be in
        ``unit`` (None: the register's own physical unit); kept per
        register and unit, so that a loop of reads pays for it once."""
        key = (register, unit)
        scale = self._scales.get(key)
        if scale is None:
            scale = self._scales[key] = self._find_scale(register, unit)
        return scale

    def _find_scale(self, register: str, unit: Optional[str]) -> float:
        scale, own = self._bus.unit(register)
        if unit is None or unit == own:
            return scale
        if unit == "raw":
            return 1.0
        if unit == "rpm" and own == "ticks/s" and self.series == "sts":
            return scale * 60.0 / _STS_TICKS_PER_TURN
        raise UsageError(f"register {register!r} is in {own or 'plain numbers'}: "
                         f"give unit=None, 'raw'{', or rpm' if own == 'ticks/s' else ''} (not {unit!r})")

    @staticmethod
    def _value(raw: int, scale: float) -> Number:
        return raw if scale == 1.0 else raw * scale

    @staticmethod
    def _raw(value: Number, scale: float, register: str = "the register") -> int:
        """``value`` as the register's raw number. A value that is no
        number (NaN, inf) raises :class:`LimitError` here; one too large for
        the register (1e30) raises it in the extension, with the range."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise UsageError(f"{register}: {value!r} is not a number") from None
        if isinstance(value, float) and not math.isfinite(value):
            raise LimitError(f"{register}: {value} is not a value a register can hold", value=value)
        return int(value) if scale == 1.0 else int(round(value / scale))

    def read(self, id: int, register: str, unit: Optional[str] = None) -> Number:
        """The value of ``register`` of servo ``id`` in its physical unit
        (:meth:`unit`; an int where that is the raw number, as ticks), or in
        ``unit``: ``"raw"`` for the raw number, ``"rpm"`` for a speed on STS
        servos (4096 ticks a turn).

        Raises :class:`servobus.TimeoutError` when the servo does not answer.
        """
        scale = self._scale(register, unit)
        return self._value(self._bus.read(id, register), scale)

    def write(self, id: int, register: str, value: Number, unit: Optional[str] = None) -> None:
        """Writes ``value`` (in the register's physical unit, or in ``unit``
        as :meth:`read` takes it; rounded to the register's step) to
        ``register`` of servo ``id`` (EEPROM registers persistently). Raises
        :class:`servobus.LimitError` for a value the register cannot
        hold."""
        self._bus.write(id, register, self._raw(value, self._scale(register, unit), register))

    def sync_read(self, register: str, ids: Iterable[int], unit: Optional[str] = None) -> SyncRead:
        """Reads ``register`` of every servo in ``ids`` with one SYNC READ
        (the servos missing from it are asked once more), in the unit
        :meth:`read` gives.

        Returns a :class:`SyncRead`: ID to value, None for a servo that did
        not answer, and ``.missing`` saying which and why.
        """
        scale = self._scale(register, unit)
        values, missing = self._bus.sync_read(register, list(ids))
        if scale != 1.0:
            values = [(i, None if v is None else v * scale) for i, v in values]
        return SyncRead(values, [Missing(*m) for m in missing])

    def sync_write(self, register: str, values: Mapping[int, Number], unit: Optional[str] = None) -> None:
        """Writes ``register`` of several servos with one SYNC WRITE:
        ``values`` maps each servo's ID to its value, in the unit
        :meth:`write` takes."""
        scale = self._scale(register, unit)
        self._bus.sync_write(register, [(int(k), self._raw(v, scale, register)) for k, v in values.items()])

    def read_raw(self, id: int, address: int, length: int, status: bool = False):
        """``length`` (1, 2 or 4) bytes at ``address`` of servo ``id`` as one
        unsigned number in the bus's byte order (for control tables of
        your own); with ``status``, ``(value, status flags of the reply)``.
        Raises :class:`servobus.UsageError` for an address beyond 0..255, a
        length other than 1, 2 or 4, or an ID beyond 0..253."""
        value, flags = self._bus.read_raw(id, address, length)
        return (value, flags) if status else value

    def write_raw(self, id: int, address: int, length: int, value: int) -> Optional[int]:
        """Writes the unsigned ``value`` as ``length`` bytes at ``address``
        of servo ``id`` (a plain WRITE): the reply's status flags, or None
        when the servo sends no reply."""
        return self._bus.write_raw(id, address, length, self._raw(value, 1.0, f"address {address}"))

    def sync_read_raw(self, address: int, length: int, ids: Iterable[int]) -> SyncRead:
        """As :meth:`sync_read`, by address and length: unsigned numbers."""
        values, missing = self._bus.sync_read_raw(address, length, list(ids))
        return SyncRead(values, [Missing(*m) for m in missing])

    def sync_write_raw(self, address: int, length: int, values: Mapping[int, int]) -> None:
        """As :meth:`sync_write`, by address and length: unsigned numbers."""
        self._bus.sync_write_raw(address, length,
                                 [(int(k), self._raw(v, 1.0, f"address {address}")) for k, v in values.items()])

    @property
    def latency(self) -> float:
        """The adapter latency (s) the reply deadlines allow now."""
        return self._bus.latency

    def learn_latency(self, ids: Iterable[int]) -> float:
        """Learns the link: PINGs the servos ``ids`` in turn (32 PINGs, as a
        live run measures its adapter at start-up) and raises the latency
        the reply deadlines allow to the most seen, never lowering it.
        Returns the latency now allowed, s. A busy machine or a slow adapter
        then costs no reply that is merely late."""
        return self._bus.learn_latency(list(ids))

    def close(self) -> None:
        """Closes the bus; later calls raise :class:`servobus.Error`."""
        self._bus.close()

    def __enter__(self) -> "Bus":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return repr(self._bus)
