//! `servobus doctor` on the simulated SO-101 arm in virtual time: every
//! fault injected (simulator fault options, registers changed through the
//! driver, a servo at another baud rate, the supply out of range) is found,
//! its fix is named, and with `--fix` the fix works and persists.

#[path = "../common/mod.rs"]
mod common;

mod advice;
mod servo_settings;

use std::time::Duration;

use servobus::doctor::{self, BusPort, Finding, PortKind, Severity, Shown};
use servobus_driver::{Bus, StatusLevel};
use servobus_protocol::registers::{addr, Series};
use servobus_runtime::config::{load_robot, Robot, RobotOptions};
use servobus_sim::{Faults, SimBus};

const PORT: &str = "/dev/ttyACM0";

struct Arm {
    robot: Robot,
    sim: SimBus,
    bus: Bus<SimBus>,
}

fn target() -> BusPort {
    BusPort {
        port: Some(PORT.into()),
        baud: 1_000_000,
    }
}

impl Arm {
    /// The arm as `servobus sim` serves it, with `faults`.
    fn factory(faults: Faults) -> Arm {
        let robot = load_robot(
            &common::repo("configs/robots/so101.yaml"),
            &RobotOptions::default(),
        )
        .expect("robot");
        Arm::of(robot, faults)
    }

    /// `robot`'s servos as `servobus sim` serves them, with `faults`.
    fn of(robot: Robot, faults: Faults) -> Arm {
        let (sim, bus) = common::virtual_bus(&robot, faults);
        Arm { robot, sim, bus }
    }

    /// The arm with its gripper set up as LeRobot sets it up, so that a
    /// healthy arm has nothing wrong.
    fn tuned(faults: Faults) -> Arm {
        let mut arm = Arm::factory(Faults::none());
        for (name, value) in [
            ("max_torque", 500),
            ("protection_current", 250),
            ("overload_torque", 25),
        ] {
            arm.write(6, name, value);
        }
        arm.sim.set_faults(faults);
        arm
    }

    /// The tuned arm with `value` written to `register` of servo `id`, and
    /// what doctor then finds.
    fn written(id: u8, register: &str, value: i32) -> (Arm, Vec<Finding>) {
        let mut arm = Arm::tuned(Faults::none());
        arm.write(id, register, value);
        let findings = arm.examine();
        (arm, findings)
    }

    /// Writes a register through the driver (EEPROM: unlock-write-verify-lock).
    fn write(&mut self, id: u8, name: &str, value: i32) {
        let reg = Series::Sts.map().get(name).expect("register");
        // Wait as long as a servo at its factory return delay needs, and
        // expect no reply from one whose status level is being set to 0.
        let saved = *self.bus.settings();
        let mut s = saved.with_return_delay(Duration::from_micros(510));
        if name == "status_level" {
            s = s.with_replies(StatusLevel::PingAndRead);
        }
        self.bus.set_settings(s);
        self.bus
            .write_register(id, reg, value)
            .unwrap_or_else(|e| panic!("writing {name} = {value} to servo {id}: {e}"));
        self.bus.set_settings(saved);
    }

    /// The findings worth a warning or an error (the information that the
    /// arm has no calibration is left out).
    fn examine(&mut self) -> Vec<Finding> {
        self.examine_all()
            .into_iter()
            .filter(|f| f.severity > Severity::Info)
            .collect()
    }

    fn examine_all(&mut self) -> Vec<Finding> {
        self.examine_on(&PortKind::Simulator).findings
    }

    /// Everything doctor reports, as if the bus were on a port of `kind`.
    fn examine_on(&mut self, kind: &PortKind) -> doctor::Examined {
        let cfg = self.robot.buses[0].clone();
        doctor::examine(&mut self.bus, &self.robot, &cfg, &target(), kind).expect("examined")
    }

    /// `--fix`: applies the fixes; every one must succeed.
    fn fix(&mut self, findings: &[Finding]) {
        self.fix_storing(findings, false);
    }

    /// `--fix`, with `--write-servos` when `write_servos`.
    fn fix_storing(&mut self, findings: &[Finding], write_servos: bool) {
        let how = doctor::Fixing {
            robot: &self.robot,
            bus: 0,
            write_servos,
        };
        let outcomes = doctor::apply(&mut self.bus, findings, &how).expect("fixes applied");
        assert!(!outcomes.is_empty(), "nothing was fixed");
        for o in &outcomes {
            assert!(
                o.result.is_ok(),
                "fix `{}` failed: {:?}",
                doctor::applied_text(&o.applied),
                o.result
            );
        }
    }

    /// `--fix`, then the power switched off and on: what was fixed in
    /// EEPROM must stay fixed.
    fn fix_and_restart(&mut self, findings: &[Finding]) {
        self.fix(findings);
        self.sim.power_cycle();
    }

    /// `--fix`, then (when `restart`) the power off and on: servo `id` must
    /// then hold `value` at `address`, and doctor find nothing wrong.
    fn fixed(&mut self, findings: &[Finding], restart: bool, id: u8, address: u8, value: u8) {
        self.fix(findings);
        if restart {
            self.sim.power_cycle();
        }
        assert_eq!(self.register(id, address), value, "servo {id} @{address}");
        let left = self.examine();
        assert!(left.is_empty(), "{}", show(&left));
    }

    fn register(&self, id: u8, address: u8) -> u8 {
        self.sim.register(id, address).expect("servo present")
    }
}

fn about<'a>(findings: &'a [Finding], id: u8, register: Option<&str>) -> Option<&'a Finding> {
    findings
        .iter()
        .find(|f| f.id == Some(id) && (register.is_none() || f.register == register))
}

/// The finding about servo `id` and `register`; the test fails naming every
/// finding when there is none.
fn must<'a>(findings: &'a [Finding], id: u8, register: Option<&str>) -> &'a Finding {
    about(findings, id, register)
        .unwrap_or_else(|| panic!("nothing about servo {id} {register:?}:\n{}", show(findings)))
}

/// The finding whose problem says `text`.
fn saying<'a>(findings: &'a [Finding], text: &str) -> &'a Finding {
    findings
        .iter()
        .find(|f| f.problem.contains(text))
        .unwrap_or_else(|| panic!("nothing says {text:?}:\n{}", show(findings)))
}

/// [`must`], whose fix must be `servobus write` of `value` to `register`.
fn must_write<'a>(findings: &'a [Finding], id: u8, register: &str, value: i32) -> &'a Finding {
    let f = must(findings, id, Some(register));
    let want = format!("servobus write --port {PORT} --id {id} {register} {value}");
    assert_eq!(f.fix_text(), want, "{}", show(findings));
    assert_eq!(
        f.command_line().as_deref(),
        Some(want.as_str()),
        "runs as printed"
    );
    f
}

fn show(findings: &[Finding]) -> String {
    findings
        .iter()
        .map(|f| {
            format!(
                "{:?} {:?} {:?}: {} | {}\n",
                f.severity,
                f.id,
                f.register,
                f.problem,
                f.fix_text()
            )
        })
        .collect()
}

#[test]
fn a_healthy_arm_has_nothing_wrong() {
    let mut arm = Arm::tuned(Faults::none());
    let findings = arm.examine();
    assert!(findings.is_empty(), "{}", show(&findings));
    assert_eq!(doctor::exit_status(&findings), 0);
}

#[test]
fn a_factory_gripper_may_overheat_and_fix_sets_it_up() {
    let mut arm = Arm::factory(Faults::none());
    let findings = arm.examine();
    for (name, value) in [
        ("max_torque", 500),
        ("protection_current", 250),
        ("overload_torque", 25),
    ] {
        assert_eq!(
            must_write(&findings, 6, name, value).severity,
            Severity::Warning
        );
    }
    assert_eq!(findings.len(), 3, "{}", show(&findings));
    assert_eq!(doctor::exit_status(&findings), 1);
    arm.fix_and_restart(&findings);
    assert!(arm.examine().is_empty(), "the settings did not persist");
    assert_eq!(arm.register(6, addr::MAX_TORQUE), (500 & 0xFF) as u8);
    assert_eq!(
        arm.register(6, addr::LOCK),
        1,
        "lock closed after the EEPROM writes"
    );
}

#[test]
fn return_delay_left_at_500_us_is_an_error_and_fix_sets_it_to_0() {
    let (mut arm, findings) = Arm::written(3, "return_delay", 250);
    let f = must_write(&findings, 3, "return_delay", 0);
    assert_eq!(f.severity, Severity::Error);
    common::says(&f.problem, &["500 us"]);
    assert_eq!(
        f.measured,
        Some(250),
        "the register read, in its 2 us units"
    );
    assert_eq!(doctor::exit_status(&findings), 2);
    arm.fixed(&findings, true, 3, addr::RETURN_DELAY, 0);
}

#[test]
fn an_eeprom_lock_left_open_is_found_and_closed() {
    let mut arm = Arm::tuned(Faults::none());
    arm.bus.write(2, addr::LOCK, &[0]).expect("unlock");
    let findings = arm.examine();
    // A lock left open is a write cut short (or another program's): an
    // error, which motion refuses until it is mended.
    let lock = must_write(&findings, 2, "lock", 1);
    assert_eq!(lock.severity, Severity::Error);
    assert!(lock.problem.contains("half-written"), "{}", lock.problem);
    assert_eq!(doctor::exit_status(&findings), 2);
    arm.fixed(&findings, false, 2, addr::LOCK, 1);
}

#[test]
fn narrowed_angle_limits_are_found_and_widened_to_the_robot_file() {
    let mut arm = Arm::tuned(Faults::none());
    arm.write(1, "min_angle_limit", 1500);
    arm.write(1, "max_angle_limit", 2600);
    // shoulder_pan: -110..110 degrees about tick 2048, 4096 ticks a turn.
    let half = (110.0f64 * 4096.0 / 360.0).round() as i32;
    let (lo, hi) = (2048 - half, 2048 + half);
    let findings = arm.examine();
    for (name, want) in [("min_angle_limit", lo), ("max_angle_limit", hi)] {
        assert_eq!(
            must_write(&findings, 1, name, want).severity,
            Severity::Error
        );
    }
    arm.fix_and_restart(&findings);
    let limits = arm.sim.servo(1, |s| {
        (
            s.read_u16(addr::MIN_ANGLE_LIMIT),
            s.read_u16(addr::MAX_ANGLE_LIMIT),
        )
    });
    assert_eq!(limits, Some((lo as u16, hi as u16)));
    assert!(arm.examine().is_empty());
}

#[test]
fn a_joint_outside_its_limits_is_an_error() {
    let mut arm = Arm::tuned(Faults::none());
    // 1400 ticks is 123 degrees: past shoulder_pan's 110.
    arm.sim.servo(1, |s| s.move_joint(2048 + 1400));
    let findings = arm.examine();
    let f = must(&findings, 1, Some("present_position"));
    assert_eq!(f.severity, Severity::Error);
    common::says(&f.fix_text(), &["--id 1 torque_enable 0"]);
    assert!(!f.fixable(), "moving a joint is not for --fix");
}

#[test]
fn a_servo_at_another_baud_is_found_and_brought_back() {
    let mut arm = Arm::tuned(Faults::none().baud(4, 4));
    let findings = arm.examine();
    let f = must(&findings, 4, Some("baud_rate"));
    assert_eq!(f.severity, Severity::Error);
    common::says(&f.problem, &["115200"]);
    assert_eq!(
        f.fix_text(),
        "servobus write --port /dev/ttyACM0 --baud 115200 --id 4 baud_rate 0"
    );
    assert_eq!(findings.len(), 1, "{}", show(&findings));
    arm.fix(&findings);
    assert_eq!(arm.sim.baud(), 1_000_000, "the bus is back at its own rate");
    arm.sim.power_cycle();
    assert_eq!(arm.register(4, addr::BAUD_RATE), 0);
    assert_eq!(arm.register(4, addr::LOCK), 1);
    assert!(arm.examine().is_empty());
}

#[test]
fn status_level_0_is_found_and_set_back_without_waiting_for_replies() {
    let (mut arm, findings) = Arm::written(4, "status_level", 0);
    must_write(&findings, 4, "status_level", 1);
    arm.fixed(&findings, true, 4, addr::STATUS_LEVEL, 1);
}

#[test]
fn protection_that_does_not_release_the_torque_is_found_and_fixed() {
    let (mut arm, findings) = Arm::written(2, "unloading_condition", 0);
    // Overheat (0x04) and overload (0x20).
    must_write(&findings, 2, "unloading_condition", 36);
    arm.fix(&findings);
    assert!(arm.examine().is_empty());
}

#[test]
fn every_simulator_fault_is_found() {
    use Severity::{Error, Warning};
    // (faults, servo, register, severity, words of the problem)
    #[rustfmt::skip]
    let cases: [(&str, u8, Option<&str>, Severity, &str); 8] = [
        ("overheat=3", 3, Some("present_temperature"), Error, "overheat"),
        ("vanish=5", 5, None, Error, "does not answer"),
        ("supply=3:3.5", 3, Some("present_voltage"), Error, "voltage flag"),
        ("supply=5.0", 1, Some("present_voltage"), Warning, "rating 6.0..12.6 V"),
        ("supply=13.5", 2, Some("present_voltage"), Warning, "rating 6.0..12.6 V"),
        ("supply=5:11.2", 5, Some("present_voltage"), Warning, "drops 0.8 V"),
        ("firmware=2:3.9", 2, Some("firmware_major"), Warning, "3.9 differs from 3.10"),
        ("duplicate=6:5", 5, Some("id"), Error, "servo 6 probably has ID 5"),
    ];
    for (spec, id, register, severity, words) in cases {
        let faults: Faults = spec.parse().expect(spec);
        let mut arm = Arm::tuned(faults);
        let findings = arm.examine();
        let f = about(&findings, id, register)
            .unwrap_or_else(|| panic!("{spec}: nothing about servo {id}:\n{}", show(&findings)));
        assert_eq!(f.severity, severity, "{spec}: {}", f.problem);
        assert!(f.problem.contains(words), "{spec}: {}", f.problem);
        assert!(!f.fix_text().is_empty(), "{spec}: no fix named");
        let worst = if severity == Severity::Error { 2 } else { 1 };
        assert_eq!(doctor::exit_status(&findings), worst, "{spec}");
    }
}

#[test]
fn a_supply_that_sags_under_load_is_found_under_load_only() {
    // 6.1 V: inside the STS3215's rating at rest.
    let mut arm = Arm::tuned("supply=6.1".parse().expect("faults"));
    assert!(arm.examine().is_empty());
    // Servo 2 holds against a heavy load (80 % of its torque): its supply
    // sags below the rating there.
    arm.bus
        .write(2, addr::TORQUE_ENABLE, &[1])
        .expect("torque on");
    arm.sim.servo(2, |s| s.set_external_load(0.8));
    arm.sim.clock().advance(Duration::from_millis(200));
    let findings = arm.examine();
    let f = must(&findings, 2, Some("present_voltage"));
    assert_eq!(f.severity, Severity::Warning);
    // The servo strains at its torque limit: 80 % of load plus the error.
    common::says(&f.problem, &["% load"]);
    assert!(!f.problem.contains("at rest"), "{}", f.problem);
    common::says(&f.problem, &["rating 6.0..12.6 V"]);
    assert!(
        about(&findings, 1, Some("present_voltage")).is_none(),
        "{}",
        show(&findings)
    );
}

#[test]
fn the_adapter_latency_is_measured_and_the_ftdi_timer_read() {
    let mut arm = Arm::tuned(Faults::none());
    // An adapter that holds every byte 2 ms, where the robot file says 0
    // (`latency_us: 0`, not so101's `auto`).
    let sim = arm.sim.clone().with_latency(Duration::from_millis(2));
    arm.sim = sim;
    arm.robot.buses[0].latency_auto = false;
    let ftdi = servobus_driver::FtdiLatency {
        sysfs_path: "/sys/bus/usb-serial/devices/ttyUSB0/latency_timer".into(),
        latency: Duration::from_millis(16),
    };
    let examined = arm.examine_on(&PortKind::Serial(Some(ftdi)));
    let findings = examined.findings;
    let timer = findings
        .iter()
        .find(|f| f.fix_text().contains("latency_timer"))
        .unwrap_or_else(|| panic!("{}", show(&findings)));
    assert_eq!(
        timer.fix_text(),
        "echo 1 | sudo tee /sys/bus/usb-serial/devices/ttyUSB0/latency_timer"
    );
    let measured = saying(&findings, "round trip");
    assert_eq!(measured.severity, Severity::Warning);
    common::says(
        &measured.fix_text(),
        &["`latency_us: 2000` (or `auto`) on bus `arm`"],
    );
    assert_eq!(
        examined.servos.len(),
        6,
        "every servo found despite the slow adapter"
    );
}

#[test]
fn a_model_other_than_the_robot_files_is_an_error() {
    let mut arm = Arm::tuned(Faults::none());
    arm.robot.buses[0].joints[1].model =
        servobus_protocol::registers::model_by_name("sts3250").expect("model");
    let findings = arm.examine();
    let f = must(&findings, 2, Some("model_number"));
    assert_eq!(f.severity, Severity::Error);
    common::says(&f.problem, &["is a STS3215, the robot file says STS3250"]);
    // The model number read: Feetech's 777 for the STS3215.
    assert_eq!(f.measured, Some(777));
    let edit = doctor::Edit {
        robot: doctor::RobotFile::File(common::repo("configs/robots/so101.yaml")),
        change: doctor::Change::SetModel {
            joint: "shoulder_lift".into(),
            model: "sts3215".into(),
        },
    };
    let advice = doctor::Advice::FitModel {
        model: "STS3250".into(),
        edit,
    };
    assert_eq!(f.advice, advice);
    assert_eq!(findings.len(), 1, "{}", show(&findings));
}

#[test]
fn an_extra_servo_is_found_and_offered_the_missing_servos_id() {
    let mut arm = Arm::tuned("vanish=5".parse().expect("faults"));
    arm.sim.add_servo(servobus_sim::SimServo::sts3215(9));
    let findings = arm.examine();
    let extra = must(&findings, 9, Some("id"));
    assert_eq!(extra.severity, Severity::Warning);
    let missing = must(&findings, 5, None);
    assert_eq!(missing.severity, Severity::Error);
    assert!(
        missing
            .fix_text()
            .ends_with("servobus set-id --port /dev/ttyACM0 --id 9 5"),
        "{}",
        missing.fix_text()
    );
    let give = doctor::Advice::GiveItsId {
        servo: 9,
        joint: "wrist_roll".into(),
        fix: doctor::Fix::SetId {
            port: Some(PORT.into()),
            baud: 1_000_000,
            id: 9,
            new_id: doctor::NewId::Id(5),
        },
    };
    assert_eq!(missing.advice, give);
}
