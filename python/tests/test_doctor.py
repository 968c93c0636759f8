"""Robot.doctor: the library's checks as typed findings, on the built-in
simulator and on a pty."""

import servobus


# The built-in SO-101's gripper (servo 6) ships with the factory's torque
# and current limits; the doctor advises the gripper's own.
GRIPPER = {"max_torque": 1000, "protection_current": 500, "overload_torque": 80}


def test_the_doctor_finds_the_grippers_factory_limits_as_typed_findings():
    checkup = servobus.Robot("so101").doctor()
    assert isinstance(checkup, servobus.Checkup)
    assert checkup.status == 1, checkup
    (bus,) = checkup.buses
    assert (bus.name, bus.port, bus.baud) == ("arm", None, 1_000_000)
    assert (bus.servos, bus.expected) == (6, 6)
    warnings = [f for f in checkup.findings if f.severity == "warning"]
    assert {f.register: f.measured for f in warnings} == GRIPPER
    for f in warnings:
        assert isinstance(f, servobus.Finding)
        assert (f.bus, f.id, f.step, f.fixable) == ("arm", 6, "configure", True)
        assert f.advice, f
        assert "gripper" in f.problem
    # No calibration: worth knowing, not fixable by a write.
    (info,) = [f for f in checkup.findings if f.severity == "info"]
    assert info.step == "calibrate" and not info.fixable


def test_the_doctor_fixes_what_a_write_fixes_and_checks_again():
    checkup = servobus.Robot("so101").doctor(fix=True)
    (bus,) = checkup.buses
    assert sorted(f.id for f in bus.fixes) == [6, 6, 6]
    assert all(f.error is None for f in bus.fixes), bus.fixes
    assert not [f for f in checkup.findings if f.severity != "info"], checkup.findings
    assert checkup.status == 0


def test_a_missing_servo_is_an_error_on_a_pty():
    with servobus.Sim("so101", faults="vanish=3") as sim:
        checkup = servobus.Robot("so101", port=sim.port).doctor()
    assert checkup.status == 2, checkup
    errors = [f for f in checkup.findings if f.severity == "error"]
    assert [f.id for f in errors] == [3], errors
    assert checkup.buses[0].port == sim.port
