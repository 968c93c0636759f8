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


# A position joint ``arm`` (servo 1) that asks for P 16, and a wheel
# ``drive`` (servo 2); the same bus as the servos come from the box (every
# one in position mode, P 32) to serve them.
ROVER_JOINTS = """\
name: rover
units: deg
buses:
  - name: b
    joints:
      - name: arm
        id: 1
        model: sts3215
        min: -90
        max: 90
        max_velocity: 180
        max_acceleration: 900
{arm}
      - name: drive
        id: 2
        model: sts3215
{drive}
"""
ROVER = ROVER_JOINTS.format(
    arm="        servo: {p: 16}",
    drive="        mode: wheel\n        max_velocity: 250\n        max_acceleration: 500",
)
FRESH = ROVER_JOINTS.format(
    arm="",
    drive="        min: -90\n        max: 90\n        max_velocity: 180\n        max_acceleration: 900",
)


def test_a_finding_about_a_joints_setting_names_it_with_the_values_found_and_wanted():
    with servobus.Sim(FRESH) as sim:
        checkup = servobus.Robot(ROVER, port=sim.port).doctor()
    by = {(f.id, f.register): f for f in checkup.findings}
    mode = by[(2, "mode")].setting
    assert mode == servobus._doctor.SettingMismatch(
        joint="drive", setting="mode", register="mode", address=33,
        found=0, wanted=1, found_as="position", wanted_as="wheel",
    ), mode
    p = by[(1, "p_coefficient")].setting
    assert (p.joint, p.setting, p.found, p.wanted) == ("arm", "p", 32, 16), p
    assert (p.found_as, p.wanted_as) == (None, None), p
    # Every other finding has none.
    others = [f for f in checkup.findings if f.register not in ("mode", "p_coefficient")]
    assert others and all(f.setting is None for f in others), checkup.findings


def test_findings_of_the_built_in_robot_carry_no_setting():
    checkup = servobus.Robot("so101").doctor()
    assert checkup.findings
    assert all(f.setting is None for f in checkup.findings), checkup.findings
