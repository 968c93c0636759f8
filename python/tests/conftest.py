"""Fixtures: the SO-101 arm's simulated servos on a pty, served from a thread."""

import pytest

import servobus


@pytest.fixture
def sim():
    """The built-in SO-101 arm (servos 1..6) on a pseudo-terminal."""
    with servobus.Sim("so101") as s:
        yield s


# Reply deadlines allowing 50 ms of adapter latency: the simulator serves
# from a thread of this process, which a loaded machine may not schedule
# within the pty's usual allowance; a present servo must not look absent.
SLACK = 0.05


@pytest.fixture
def bus(sim):
    """A bus on the simulator's pty."""
    with servobus.Bus(sim.port, latency=SLACK) as b:
        yield b
