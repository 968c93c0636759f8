//! What the robot file asks of each servo's EEPROM: the operating mode of
//! a wheel or a position joint, and the EEPROM `servo:` settings. Each
//! difference is found, fixed only with `--write-servos` (the mode with
//! the torque off at every moment it changes), and the doctor finds
//! nothing left afterwards. The simulated servos start as they leave the
//! factory: mode 0, P = 32, D = 32, I = 0 (the simulated robot would start
//! a wheel's servo in its mode: [`from_the_box`] puts it back).

use std::path::Path;
use std::time::Duration;

use servobus::doctor::{self, Action, Applied, Finding, Severity, Shown};
use servobus_driver::{Bus, Transport, TransportError};
use servobus_protocol::registers::{addr, sts};
use servobus_runtime::config::{load_robot, Robot, RobotOptions, RobotSource};
use servobus_sim::{Faults, SimBus};

use super::{must, show, Arm, PORT};

/// A two-joint robot: a position joint `arm` (servo 1) with the `servo:`
/// line `arm_servo` (empty: none), and joint `drive` (servo 2), a wheel
/// when `wheel`.
fn robot(arm_servo: &str, wheel: bool) -> Robot {
    robot_named("arm", arm_servo, wheel)
}

/// [`robot`] with the position joint called `first`.
fn robot_named(first: &str, arm_servo: &str, wheel: bool) -> Robot {
    let drive = if wheel {
        "mode: wheel\n        max_velocity: 250\n        max_acceleration: 500"
    } else {
        "min: -90\n        max: 90\n        max_velocity: 180\n        max_acceleration: 900"
    };
    let arm_servo = if arm_servo.is_empty() {
        String::new()
    } else {
        format!("\n        servo: {arm_servo}")
    };
    let text = format!(
        "name: rover\nunits: deg\nbuses:\n  - name: b\n    joints:\n      - name: {first}\n        \
         id: 1\n        model: sts3215\n        min: -90\n        max: 90\n        \
         max_velocity: 180\n        max_acceleration: 900{arm_servo}\n      - name: drive\n        \
         id: 2\n        model: sts3215\n        {drive}\n"
    );
    let source = RobotSource::Text {
        name: Path::new("rover.yaml"),
        text: &text,
    };
    load_robot(source, &RobotOptions::default()).expect("the robot file loads")
}

/// The simulated `robot` with every servo in operating mode 0, stored, as
/// new servos come (the simulated robot sets a wheel's up as its joint
/// asks).
fn from_the_box(robot: Robot) -> Arm {
    let arm = Arm::of(robot, Faults::none());
    for id in arm.sim.ids() {
        arm.sim
            .servo(id, |s| *s = s.clone().with_byte(addr::MODE, 0));
    }
    arm
}

/// The findings about what the robot file asks of the servos.
fn asked(findings: &[Finding]) -> Vec<&Finding> {
    findings.iter().filter(|f| f.setting.is_some()).collect()
}

#[test]
fn a_wheel_on_a_servo_in_position_mode_is_an_error_fixed_only_with_write_servos() {
    let mut arm = from_the_box(robot("", true));
    assert_eq!(arm.register(2, addr::MODE), 0, "the factory's mode");
    let findings = arm.examine();
    let f = must(&findings, 2, Some("mode"));
    assert_eq!(f.severity, Severity::Error, "a run refuses the servo");
    assert_eq!(doctor::exit_status(&findings), 2);
    assert!(
        f.problem.contains("mode is 0 (position)") && f.problem.contains("joint `drive`"),
        "{}",
        f.problem
    );
    let m = f.setting.as_ref().expect("what the file asks");
    assert_eq!(
        (m.joint.as_str(), m.setting, m.address, m.found, m.wanted),
        ("drive", "mode", 33, 0, 1)
    );
    assert_eq!(m.wanted_as.as_deref(), Some("wheel"));
    assert_eq!(f.fix_flags(), Some("--fix --write-servos"));
    assert!(f.needs_write_servos());
    assert_eq!(
        f.command_line().as_deref(),
        Some(
            format!("servobus doctor --robot rover.yaml --port {PORT} --fix --write-servos")
                .as_str()
        ),
        "the command the runtime's refusal names"
    );
    assert!(matches!(
        f.action,
        Some(Action::Store {
            id: 2,
            value: 1,
            torque_off: true,
            ..
        })
    ));
    // Only this: the wheel has no limits to be outside of.
    assert_eq!(findings.len(), 1, "{}", show(&findings));

    // `--fix` alone writes nothing.
    let how = doctor::Fixing {
        robot: &arm.robot,
        bus: 0,
        write_servos: false,
    };
    let outcomes = doctor::apply(&mut arm.bus, &findings, &how).expect("applied");
    assert!(outcomes.is_empty(), "{outcomes:?}");
    assert_eq!(arm.register(2, addr::MODE), 0, "nothing written");

    // `--fix --write-servos` stores it, and it persists.
    arm.fix_storing(&findings, true);
    arm.sim.power_cycle();
    assert_eq!(arm.register(2, addr::MODE), 1);
    assert_eq!(arm.register(2, addr::LOCK), 1, "locked again");
    let left = arm.examine();
    assert!(left.is_empty(), "{}", show(&left));
}

#[test]
fn a_position_joint_on_a_servo_left_in_wheel_mode_is_found_and_set_back() {
    let mut arm = Arm::of(robot("", false), Faults::none());
    arm.write(1, "mode", 1);
    let findings = arm.examine();
    let f = must(&findings, 1, Some("mode"));
    assert_eq!(f.severity, Severity::Error);
    assert!(f.problem.contains("mode is 1 (wheel)"), "{}", f.problem);
    let m = f.setting.as_ref().expect("what the file asks");
    assert_eq!((m.found, m.wanted), (1, 0));
    assert_eq!(asked(&findings).len(), 1, "{}", show(&findings));
    arm.fix_storing(&findings, true);
    assert_eq!(arm.register(1, addr::MODE), 0);
    let left = arm.examine();
    assert!(left.is_empty(), "{}", show(&left));
}

/// The simulator on a transport that notes, before every packet the doctor
/// sends, servo 2's torque and operating mode.
struct Watched {
    sim: SimBus,
    seen: Vec<(u8, u8)>,
}

impl Watched {
    fn note(&mut self) {
        let at = |a| self.sim.register(2, a).expect("servo 2");
        let state = (at(addr::TORQUE_ENABLE), at(addr::MODE));
        self.seen.push(state);
    }
}

impl Transport for Watched {
    type Clock = <SimBus as Transport>::Clock;
    fn clock(&self) -> &Self::Clock {
        Transport::clock(&self.sim)
    }
    fn baud(&self) -> u32 {
        Transport::baud(&self.sim)
    }
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.note();
        self.sim.write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        self.sim.read(buf, deadline)
    }
    fn discard_input(&mut self) -> Result<(), TransportError> {
        self.sim.discard_input()
    }
}

#[test]
fn the_mode_changes_only_with_the_torque_off() {
    let mut arm = from_the_box(robot("", true));
    // A servo holding its position, torque on.
    arm.write(2, "torque_enable", 1);
    assert_eq!(arm.register(2, addr::TORQUE_ENABLE), 1);
    let findings = arm.examine();
    assert!(must(&findings, 2, Some("mode")).needs_write_servos());
    let watched = Watched {
        sim: arm.sim.clone(),
        seen: Vec::new(),
    };
    let mut bus = Bus::new(watched, *arm.bus.settings());
    let how = doctor::Fixing {
        robot: &arm.robot,
        bus: 0,
        write_servos: true,
    };
    let outcomes = doctor::apply(&mut bus, &findings, &how).expect("applied");
    let [done] = outcomes.as_slice() else {
        panic!("one fix: {outcomes:?}");
    };
    assert!(done.result.is_ok(), "{:?}", done.result);
    assert_eq!(
        done.applied,
        Applied::Stored {
            register: "mode",
            value: 1,
            shown: Some("wheel".into()),
            torque_off: true,
        }
    );
    assert_eq!(
        servobus::doctor::applied_text(&done.applied),
        "mode 1 (wheel) stored in EEPROM, the torque turned off first"
    );
    let mut seen = bus.transport().seen.clone();
    seen.push((
        arm.register(2, addr::TORQUE_ENABLE),
        arm.register(2, addr::MODE),
    ));
    assert_eq!(seen.first(), Some(&(1, 0)), "torque on before: {seen:?}");
    assert_eq!(seen.last(), Some(&(0, 1)), "torque off, wheel: {seen:?}");
    assert!(
        seen.iter().all(|&(torque, mode)| mode == 0 || torque == 0),
        "the mode changed with the torque on: {seen:?}"
    );
}

#[test]
fn an_eeprom_servo_setting_is_found_and_stored_only_with_write_servos() {
    let mut arm = Arm::of(robot("{p: 16}", false), Faults::none());
    let findings = arm.examine();
    let f = must(&findings, 1, Some("p_coefficient"));
    assert_eq!(f.severity, Severity::Warning);
    assert_eq!(f.measured, Some(32), "the factory's P");
    let m = f.setting.as_ref().expect("what the file asks");
    assert_eq!(
        (m.setting, m.register, m.address, m.found, m.wanted),
        ("p", "p_coefficient", 21, 32, 16)
    );
    assert_eq!(
        (m.found_as.as_deref(), m.wanted_as.as_deref()),
        (None, None)
    );
    assert!(
        f.problem.contains("is 32") && f.problem.contains("`servo: p` asks for 16"),
        "{}",
        f.problem
    );
    assert_eq!(
        f.fix_text(),
        format!("servobus write --port {PORT} --id 1 p_coefficient 16")
    );
    assert!(f.needs_write_servos());
    assert_eq!(asked(&findings).len(), 1, "{}", show(&findings));
    assert_eq!(doctor::exit_status(&findings), 1);

    let how = doctor::Fixing {
        robot: &arm.robot,
        bus: 0,
        write_servos: false,
    };
    let outcomes = doctor::apply(&mut arm.bus, &findings, &how).expect("applied");
    assert!(outcomes.is_empty(), "{outcomes:?}");
    assert_eq!(arm.register(1, addr::P_GAIN), 32, "nothing written");

    arm.fix_storing(&findings, true);
    arm.sim.power_cycle();
    assert_eq!(arm.register(1, addr::P_GAIN), 16);
    let left = arm.examine();
    assert!(left.is_empty(), "{}", show(&left));
}

#[test]
fn settings_the_servo_holds_already_and_ram_settings_are_not_findings() {
    // D = 32 and I = 0 are the factory's; the torque limit and the
    // acceleration are RAM, which a run writes at every start.
    let mut arm = Arm::of(
        robot("{d: 32, i: 0, torque_limit: 60, acceleration: 100}", false),
        Faults::none(),
    );
    let findings = arm.examine();
    assert!(asked(&findings).is_empty(), "{}", show(&findings));
    assert!(findings.is_empty(), "{}", show(&findings));
}

#[test]
fn a_protection_current_is_shown_in_ma() {
    // 1501.5 mA is 231 steps of 6.5 mA; the factory's 500 is 3250 mA.
    let mut arm = Arm::of(robot("{protection_current: 1501.5}", false), Faults::none());
    let findings = arm.examine();
    let f = must(&findings, 1, Some("protection_current"));
    let m = f.setting.as_ref().expect("what the file asks");
    assert_eq!((m.found, m.wanted), (500, 231));
    assert_eq!(m.found_as.as_deref(), Some("3250 mA"));
    assert_eq!(m.wanted_as.as_deref(), Some("1501.5 mA"));
    assert!(
        f.problem.contains("3250 mA (500)") && f.problem.contains("1501.5 mA (231)"),
        "{}",
        f.problem
    );
    arm.fix_storing(&findings, true);
    let left = arm.examine();
    assert!(left.is_empty(), "{}", show(&left));
}

#[test]
fn a_grippers_protection_current_is_the_robot_files_to_choose() {
    // 3003 mA is 462 steps: above the 250 the doctor otherwise keeps a
    // gripper to, which would fight the file's value fix after fix.
    let mut arm = Arm::of(
        robot_named("gripper", "{protection_current: 3003}", false),
        Faults::none(),
    );
    let findings = arm.examine();
    let about: Vec<&Finding> = findings
        .iter()
        .filter(|f| f.id == Some(1) && f.register == Some("protection_current"))
        .collect();
    let [f] = about.as_slice() else {
        panic!("one finding: {}", show(&findings));
    };
    let m = f.setting.as_ref().expect("what the file asks");
    assert_eq!((m.found, m.wanted), (500, 462));
    // The gripper's other protection settings are still the doctor's.
    assert_eq!(
        must(&findings, 1, Some("max_torque")).severity,
        Severity::Warning
    );
    arm.fix_storing(&findings, true);
    assert_eq!(
        arm.register(1, sts::PROTECTION_CURRENT.register().address),
        (462 & 0xFF) as u8
    );
    let left = arm.examine();
    assert!(left.is_empty(), "{}", show(&left));
}
