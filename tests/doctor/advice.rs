//! The advice itself: in the order a new arm needs it, commands that run
//! as printed (a built-in robot named by its name), the homing offset of a
//! session and one play would refuse, a swapped ID, an uncalibrated arm
//! (on a port and on the built-in simulator), `latency_us: auto`.

use std::path::Path;
use std::time::Duration;

use servobus::doctor::{self, PortKind, SetupStep, Severity, Shown};
use servobus_protocol::registers::addr;
use servobus_runtime::config::{load_robot, JointCalibration, RobotOptions};
use servobus_sim::Faults;

use super::{about, common, must, saying, show, Arm, PORT};

/// shoulder_pan (servo 1, at tick 2048 with homing offset 0) calibrated
/// with offset 0 over ticks 2000..4600: a range across the seam.
fn across_the_seam() -> JointCalibration {
    shoulder_pan("3.10", 0, [2000, 4600])
}

/// shoulder_pan (servo 1, an STS3215 posed at tick 2048) calibrated on
/// `firmware` with `homing_offset` over the ticks `range`.
fn shoulder_pan(firmware: &str, homing_offset: i32, range: [i64; 2]) -> JointCalibration {
    JointCalibration {
        name: "shoulder_pan".into(),
        id: 1,
        model: "STS3215".into(),
        firmware: Some(firmware.into()),
        homing_offset,
        pose_deg: 0.0,
        pose_tick: 2048.0,
        direction: 1,
        range,
    }
}

/// The play frame of [`across_the_seam`], worked out by hand: the middle of
/// 2000..4600 is 3300, which the offset 3300 - 2048 = 1252 brings to 2048.
const PLAY_OFFSET: u16 = 1252;

#[test]
fn an_offset_not_set_after_a_power_up_is_information_and_fix_sets_it_for_the_session() {
    let mut arm = Arm::tuned(Faults::none());
    arm.robot.buses[0].joints[0].calibration = Some(across_the_seam());
    let all = arm.examine_all();
    let f = must(&all, 1, Some("offset"));
    assert_eq!(f.severity, Severity::Info, "play sets it: nothing wrong");
    assert_eq!(f.step, SetupStep::Calibrate);
    assert!(
        f.problem.contains("not set for this session") && !f.problem.contains("replaced"),
        "{}",
        f.problem
    );
    let robot = common_robot_arg();
    assert_eq!(
        f.command_line().as_deref(),
        Some(format!("servobus doctor --robot {robot} --port {PORT} --fix").as_str())
    );
    // Read in the frame play will set, the joint is at 0: within limits.
    assert!(
        about(&all, 1, Some("present_position")).is_none(),
        "{}",
        show(&all)
    );
    assert_eq!(doctor::exit_status(&all), 0, "{}", show(&all));

    // --fix sets it as play does: for the session, not in EEPROM.
    arm.fix(&all);
    assert_eq!(
        arm.sim.servo(1, |s| s.read_u16(addr::OFFSET)),
        Some(PLAY_OFFSET)
    );
    assert!(about(&arm.examine_all(), 1, Some("offset")).is_none());
    arm.sim.power_cycle();
    assert_eq!(
        arm.sim.servo(1, |s| s.read_u16(addr::OFFSET)),
        Some(0),
        "nothing persisted without --write-servos"
    );

    // --fix --write-servos stores it.
    let all = arm.examine_all();
    arm.fix_storing(&all, true);
    arm.sim.power_cycle();
    assert_eq!(
        arm.sim.servo(1, |s| s.read_u16(addr::OFFSET)),
        Some(PLAY_OFFSET)
    );
    assert!(about(&arm.examine_all(), 1, Some("offset")).is_none());
}

/// The test arm's robot file as the commands name it.
fn common_robot_arg() -> String {
    super::common::repo("configs/robots/so101.yaml")
        .display()
        .to_string()
}

#[test]
fn two_servos_on_one_id_and_a_silent_servo_is_a_swapped_id() {
    let mut arm = Arm::tuned("duplicate=6:5".parse().expect("faults"));
    let findings = arm.examine();
    let f = must(&findings, 5, Some("id"));
    assert_eq!(f.severity, Severity::Error);
    common::says(
        &f.problem,
        &["servo 6 (joint `gripper`) is silent: servo 6 probably has ID 5"],
    );
    assert!(
        f.fix_text()
            .contains("unplug every servo but joint `gripper`'s")
            && f.fix_text()
                .contains("`servobus set-id --port /dev/ttyACM0 --id 5 6`")
            && f.fix_text().contains("plug the others back in"),
        "{}",
        f.fix_text()
    );
    assert_eq!(
        f.command_line(),
        None,
        "it takes hands: no command runs it alone"
    );
    assert!(
        about(&findings, 6, None).is_none(),
        "servo 6 is explained by the shared ID:\n{}",
        show(&findings)
    );
}

#[test]
fn a_shared_id_with_two_silent_servos_names_both_and_blames_neither() {
    // Servo 6 answers as ID 5, and servo 3 is gone: either silent servo
    // may be the second one on ID 5, and the bus cannot say which.
    let mut arm = Arm::tuned("duplicate=6:5,vanish=3".parse().expect("faults"));
    let findings = arm.examine();
    let f = must(&findings, 5, Some("id"));
    assert_eq!(f.severity, Severity::Error);
    common::says(
        &f.problem,
        &[
            "two servos answer as ID 5 and servos 3 (joint `elbow_flex`) and 6 (joint `gripper`) \
             are silent: one of them probably has ID 5, and one does not answer at any baud rate",
        ],
    );
    // Each silent servo, alone on the bus, gets its own command.
    let fix = f.fix_text();
    common::says(
        &fix,
        &[
            "one at a time, each alone on the bus",
            "joint `elbow_flex`'s: `servobus set-id --port /dev/ttyACM0 --id 5 3`",
            "joint `gripper`'s: `servobus set-id --port /dev/ttyACM0 --id 5 6`",
            "plug the others back in",
        ],
    );
    assert_eq!(f.command_line(), None, "it takes hands");
    let doctor::Advice::UnplugOthersOneOf(silent) = &f.advice else {
        panic!("{:?}", f.advice);
    };
    let ids: Vec<u8> = silent.iter().map(|s| s.id).collect();
    assert_eq!(ids, [3, 6]);
    // Neither is told it is the one, nor that it is simply unplugged.
    for id in [3, 6] {
        assert!(
            about(&findings, id, None).is_none(),
            "servo {id}:\n{}",
            show(&findings)
        );
    }
    assert!(!f.problem.contains("servo 3 probably"), "{}", f.problem);
    assert_eq!(doctor::exit_status(&findings), 2);
}

#[test]
fn an_uncalibrated_arm_on_a_port_is_told_to_calibrate_first_not_to_move_a_joint() {
    let mut arm = Arm::tuned(Faults::none());
    // 1400 ticks from the middle: 123 degrees by the robot file's design,
    // which means nothing on an uncalibrated arm.
    arm.sim.servo(1, |s| s.move_joint(2048 + 1400));
    let all = arm.examine_on(&PortKind::Pty).findings;
    assert!(
        about(&all, 1, Some("present_position")).is_none(),
        "{}",
        show(&all)
    );
    assert!(
        !all.iter().any(|f| f.fix_text().contains("by hand")),
        "{}",
        show(&all)
    );
    let f = all
        .iter()
        .find(|f| f.step == SetupStep::Calibrate && f.id.is_none())
        .unwrap_or_else(|| panic!("{}", show(&all)));
    common::says(&f.problem, &["calibrate first"]);
    let robot = common_robot_arg();
    assert_eq!(
        f.command_line().as_deref(),
        Some(
            format!("servobus calibrate --robot {robot} --port {PORT} -o my-arm.calibration.yaml")
                .as_str()
        )
    );
}

#[test]
fn a_builtin_robot_is_named_by_its_name_in_every_command() {
    let path = servobus::builtin::robot_path_or_name(Path::new("so101"));
    let robot = load_robot(&path, &RobotOptions::default()).expect("built-in so101");
    let mut arm = Arm::of(robot, Faults::none());
    arm.robot.buses[0].joints[0].calibration = Some(across_the_seam());
    // A slow adapter where the robot file says 0 us: a file to edit.
    arm.sim = arm.sim.clone().with_latency(Duration::from_millis(2));
    arm.robot.buses[0].latency_auto = false;
    let all = arm.examine_on(&PortKind::Serial(None)).findings;
    // The calibrate and doctor commands: what follows each `--robot`.
    let commands: Vec<String> = all.iter().filter_map(|f| f.command_line()).collect();
    let robot_args: Vec<&str> = commands
        .iter()
        .flat_map(|c| c.split(" --robot ").skip(1))
        .filter_map(|rest| rest.split_whitespace().next())
        .collect();
    assert_eq!(robot_args.len(), 2, "{}", show(&all));
    assert!(robot_args.iter().all(|&r| r == "so101"), "{robot_args:?}");
    assert!(
        !all.iter().any(|f| f.fix_text().contains("<built-in>")),
        "{}",
        show(&all)
    );
    let offset = must(&all, 1, Some("offset"));
    assert_eq!(
        offset.command_line().as_deref(),
        Some("servobus doctor --robot so101 --port /dev/ttyACM0 --fix")
    );
    let latency = saying(&all, "round trip");
    assert!(
        latency
            .fix_text()
            .contains("`servobus init --robot so101` writes robot.yaml")
            && latency.fix_text().contains("pass --robot robot.yaml"),
        "{}",
        latency.fix_text()
    );
}

#[test]
fn latency_auto_is_measured_not_an_assumed_0_us() {
    let mut arm = Arm::tuned(Faults::none());
    assert!(
        arm.robot.buses[0].latency_auto,
        "so101 says `latency_us: auto`"
    );
    arm.sim = arm.sim.clone().with_latency(Duration::from_millis(2));
    let all = arm.examine_on(&PortKind::Serial(None)).findings;
    let f = saying(&all, "round trip");
    assert_eq!(f.severity, Severity::Info, "auto follows the adapter");
    assert!(
        f.problem.contains("`latency_us: auto` measures it") && !f.problem.contains("assumes"),
        "{}",
        f.problem
    );
}

#[test]
fn advice_comes_in_the_order_a_new_arm_needs_it() {
    let mut arm = Arm::tuned("overheat=3".parse().expect("faults"));
    arm.write(2, "return_delay", 250);
    arm.sim.add_servo(servobus_sim::SimServo::sts3215(9));
    let findings = arm.examine();
    let at = |id: u8, register: &str| {
        findings
            .iter()
            .position(|f| f.id == Some(id) && f.register == Some(register))
            .unwrap_or_else(|| panic!("servo {id} {register}:\n{}", show(&findings)))
    };
    // A servo the file lacks (connect), a setting (configure), then a hot
    // servo (check), though that one is the worst.
    assert!(at(9, "id") < at(2, "return_delay"), "{}", show(&findings));
    assert!(
        at(2, "return_delay") < at(3, "present_temperature"),
        "{}",
        show(&findings)
    );
    let steps: Vec<SetupStep> = findings.iter().map(|f| f.step).collect();
    assert!(steps.windows(2).all(|w| w[0] <= w[1]), "{steps:?}");
}

#[test]
fn an_uncalibrated_robot_is_told_how_to_calibrate() {
    let mut arm = Arm::tuned(Faults::none());
    let all = arm.examine_all();
    let f = saying(&all, "no calibration");
    assert_eq!(f.severity, Severity::Info, "information only: exit 0");
    assert!(
        f.fix_text().starts_with("servobus calibrate --robot ")
            && f.fix_text()
                .contains("so101.yaml --port /dev/ttyACM0 -o my-arm.calibration.yaml"),
        "{}",
        f.fix_text()
    );
    assert_eq!(doctor::exit_status(&all), 0);
}

#[test]
fn a_homing_offset_or_firmware_other_than_the_calibrations_is_found() {
    let mut arm = Arm::tuned(Faults::none());
    // The calibration of shoulder_pan was taken with homing offset 100 on
    // firmware 3.9; the servo holds 0 and reports 3.10.
    arm.robot.buses[0].joints[0].calibration = Some(shoulder_pan("3.9", 100, [600, 3500]));
    let findings = arm.examine();
    let offset = must(&findings, 1, Some("offset"));
    assert_eq!(
        offset.command_line().as_deref(),
        Some("servobus write --port /dev/ttyACM0 --id 1 offset 100")
    );
    assert_eq!(offset.severity, Severity::Error);
    common::says(&offset.problem, &["homing offset is 0"]);
    let firmware = must(&findings, 1, Some("firmware_major"));
    common::says(&firmware.problem, &["calibrated on 3.9"]);
    // Its fix is marked as needing both flags: --fix alone leaves it.
    assert_eq!(offset.fix_flags(), Some("--fix --write-servos"));
    assert!(offset.needs_write_servos());
    assert_eq!(firmware.fix_flags(), None);
    // Without --write-servos, --fix leaves an offset play refuses alone.
    let how = doctor::Fixing {
        robot: &arm.robot,
        bus: 0,
        write_servos: false,
    };
    let outcomes = doctor::apply(&mut arm.bus, &findings, &how).expect("fixes");
    assert!(outcomes.iter().all(|o| o.id != 1), "{outcomes:?}");
    arm.fix_storing(&findings, true);
    arm.sim.power_cycle();
    assert_eq!(
        arm.sim.servo(1, |s| s.read_u16(addr::OFFSET)),
        Some(100),
        "the offset persists"
    );
    assert!(about(&arm.examine(), 1, Some("offset")).is_none());
}
