"""Fixtures: the SO-101 arm's simulated servos on a pty, served from a thread."""

import pytest

import servobus


@pytest.fixture
def sim():
    """The built-in SO-101 arm (servos 1..6) on a pseudo-terminal."""
    with servobus.Sim("so101") as s:
        yield s


@pytest.fixture
def bus(sim):
    """A bus on the simulator's pty."""
    with servobus.Bus(sim.port) as b:
        yield b
