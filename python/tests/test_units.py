"""Physical units of Bus.read/write: volts, degrees Celsius, percent,
ticks/s or rpm, from the control table's units; positions stay in ticks."""

import pytest

import servobus


def test_each_register_says_its_unit(bus):
    assert bus.unit("present_position") == "ticks"
    assert bus.unit("present_speed") == "ticks/s"
    assert bus.unit("present_voltage") == "V"
    assert bus.unit("present_temperature") == "°C"
    assert bus.unit("present_load") == "%"
    assert bus.unit("present_current") == "mA"
    assert bus.unit("torque_enable") == ""


def test_reads_are_in_physical_units_and_raw_on_request(bus):
    # The simulated STS3215 reports 12.0 V (raw 120, tenths of a volt) and
    # 25 degrees Celsius at rest.
    assert bus.read(1, "present_voltage") == pytest.approx(12.0)
    assert bus.read(1, "present_voltage", unit="raw") == 120
    temperature = bus.read(1, "present_temperature")
    assert temperature == 25 and isinstance(temperature, int)
    position = bus.read(1, "present_position")
    assert isinstance(position, int) and position == bus.read(1, "present_position", unit="raw")
    assert 0.0 <= abs(bus.read(1, "present_load")) <= 100.0


def test_writes_take_physical_units(bus):
    # 50 % of the torque ceiling is raw 500 (tenths of a percent).
    bus.write(1, "torque_limit", 50.0)
    assert bus.read(1, "torque_limit", unit="raw") == 500
    assert bus.read(1, "torque_limit") == pytest.approx(50.0)
    # 60 rpm is a turn a second: 4096 ticks/s on an STS3215.
    bus.write(1, "goal_speed", 60, unit="rpm")
    assert bus.read(1, "goal_speed") == 4096
    assert bus.read(1, "goal_speed", unit="rpm") == pytest.approx(60.0)


def test_sync_read_and_write_use_the_same_units(bus):
    bus.sync_write("torque_limit", {1: 25.0, 2: 75.0})
    assert bus.sync_read("torque_limit", [1, 2], unit="raw") == {1: 250, 2: 750}
    volts = bus.sync_read("present_voltage", [1, 2, 3])
    assert volts == {1: pytest.approx(12.0), 2: pytest.approx(12.0), 3: pytest.approx(12.0)}


def test_a_unit_the_register_does_not_have_is_a_usage_error(bus):
    with pytest.raises(servobus.UsageError, match="rpm"):
        bus.read(1, "present_voltage", unit="rpm")
