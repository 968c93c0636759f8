"""Type stubs of the extension module ``servobus._native`` (the Rust side;
the package ``servobus`` wraps it with typed results)."""

from typing import Callable, List, Mapping, Optional, Tuple

__version__: str

class Bus:
    """A bus of Feetech servos on a serial port, or the in-process simulator."""

    def __init__(
        self, port: str, baud: Optional[int] = None, series: str = "sts", latency: Optional[float] = None
    ) -> None: ...
    @staticmethod
    def sim(robot: str = "so101") -> "Bus":
        """An in-process simulated bus with the servos of ``robot``."""
    @property
    def series(self) -> str:
        """``"sts"`` or ``"scs"``."""
    def unit(self, register: str) -> Tuple[float, str]:
        """``(scale, unit)``: a raw value times ``scale`` is in ``unit``."""
    def ping(self, id: int) -> bool:
        """PING servo ``id``: True when it answers."""
    def scan(self, ids: Optional[List[int]] = None) -> List[int]:
        """The IDs among ``ids`` (default 0..253) that answer a PING."""
    def read(self, id: int, register: str) -> int:
        """The value of ``register`` of servo ``id``."""
    def write(self, id: int, register: str, value: int) -> None:
        """Writes ``value`` to ``register`` of servo ``id``."""
    def sync_read(
        self, register: str, ids: List[int]
    ) -> Tuple[List[Tuple[int, Optional[int]]], List[Tuple[int, str, int]]]:
        """``(id, value or None)`` per servo, and ``(id, why, attempts)`` per missing one."""
    def sync_write(self, register: str, values: List[Tuple[int, int]]) -> None:
        """One SYNC WRITE of ``(id, value)`` pairs."""
    def read_raw(self, id: int, address: int, length: int) -> Tuple[int, int]:
        """``(unsigned value, status flags)`` of ``length`` bytes at ``address``."""
    def write_raw(self, id: int, address: int, length: int, value: int) -> Optional[int]:
        """A plain WRITE of ``length`` bytes; the reply's status flags."""
    def sync_read_raw(
        self, address: int, length: int, ids: List[int]
    ) -> Tuple[List[Tuple[int, Optional[int]]], List[Tuple[int, str, int]]]:
        """As ``sync_read``, by address and length."""
    def sync_write_raw(self, address: int, length: int, values: List[Tuple[int, int]]) -> None:
        """As ``sync_write``, by address and length."""
    @property
    def latency(self) -> float:
        """The adapter latency (s) the reply deadlines allow."""
    def learn_latency(self, ids: List[int]) -> float:
        """Measures the adapter with PINGs; raises the allowance to the most seen."""
    def close(self) -> None:
        """Closes the bus."""

class Sim:
    """A robot's simulated servos on a pseudo-terminal, served from a thread."""

    def __init__(
        self,
        robot: str = "so101",
        faults: Optional[str] = None,
        mounting: Optional[str] = None,
        hand: Optional[str] = None,
        pacing: bool = True,
    ) -> None: ...
    @property
    def port(self) -> str:
        """The path to open as a serial port."""
    @property
    def servo_count(self) -> int:
        """How many servos are served."""
    @property
    def running(self) -> bool:
        """Whether the server is still serving."""
    def close(self) -> None:
        """Stops serving."""
    def __enter__(self) -> "Sim": ...
    def __exit__(self, *args: object) -> bool: ...

class Stream:
    """A live run fed targets from Python."""

    def send_chunk(self, joints: List[Tuple[str, List[float]]], dt: Optional[float] = None,
                   times: Optional[List[float]] = None) -> int:
        """Sends an action chunk (dt spacing or times from now)."""
    def send(self, joints: List[Tuple[str, float]]) -> int:
        """Sends a target; returns how many angles were clamped."""
    def send_base(self, x: float, y: float, theta: float) -> int:
        """Sends a mobile base's velocity (m/s, m/s, robot units/s)."""
    def base_pose(self) -> Optional[Tuple[float, float, float]]:
        """A mobile base's odometry (m, m, robot units), or None."""
    def send_grasp(self, grasps: Mapping[str, float]) -> None:
        """Tells joints to grasp: joint name to effort, percent of the
        servo's torque (above 0, at most 100)."""
    def state(
        self,
    ) -> Tuple[float, List[float], List[float], List[float], List[float], List[int], List[str]]:
        """``(time, position, velocity, error, commanded, flags, faults)``."""
    @property
    def finished(self) -> bool:
        """Whether the run has ended."""
    def stop(self) -> Optional[str]:
        """Stops (jerk-limited); the report as JSON text."""
    def torque_off(self) -> Optional[str]:
        """Torque off; the report as JSON text."""

class Robot:
    """A robot file's robot."""

    def __init__(self, robot: str, port: Optional[str] = None, calibration: Optional[str] = None) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def joints(self) -> List[str]: ...
    @property
    def units(self) -> str: ...
    @property
    def port(self) -> Optional[str]: ...
    @property
    def rate_hz(self) -> float: ...
    @property
    def limits(self) -> List[Tuple[str, int, float, float, float, float, Optional[float]]]:
        """``(name, id, min, max, max_velocity, max_acceleration, max_jerk)`` per joint."""
    def plan(self, motion: str) -> str:
        """The plan as JSON text."""
    def play(
        self, motion: str, on_progress: Optional[object] = None, real_time: bool = False
    ) -> Tuple[str, List[float], List[List[float]], List[List[float]], List[List[float]], Optional[BaseException]]:
        """``(report JSON, time, commanded, planned, measured, the exception that stopped it)``."""
    def stream(self, rate: Optional[float] = None, timeout: float = 0.25, tracking_faults: bool = True) -> Stream:
        """Starts the live loop."""
    def calibrate(
        self,
        hand: Optional[str] = None,
        mounting: Optional[str] = None,
        timeout: float = 600.0,
        on_step: Optional[Callable[[str], object]] = None,
    ) -> str:
        """Runs the calibration procedure; the calibration as JSON text."""
    def doctor(self, fix: bool = False, write_servos: bool = False) -> str:
        """The doctor's checkup of every bus as JSON text."""
    def torque_off(self) -> None:
        """A broadcast torque off on every bus (nothing on the simulator)."""

def model_limits(model: str) -> Tuple[float, float]:
    """A servo model's (max_velocity deg/s, max_acceleration deg/s^2)."""

MODEL_JERK_RAMP_S: float
"""How long live following's jerk limit takes to reach a model's acceleration, s."""
def calibration_from_lerobot(robot: str, json: str) -> str:
    """The calibration (JSON text) a LeRobot calibration file describes."""
def calibration_to_lerobot(calibration: str) -> str:
    """The LeRobot calibration file (JSON text) of a calibration."""
def save_calibration(calibration: str, path: str) -> None:
    """Writes a calibration (JSON text) as a servobus calibration file."""
def load_calibration(path: str) -> str:
    """A servobus calibration file, as JSON text."""
