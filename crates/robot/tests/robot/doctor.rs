//! The doctor through the facade: findings and fixes as data, on the
//! built-in simulator and on a pty, and the fixes applied by a library call.

use crate::common::Pty;
use servobus_robot::doctor::{Advice, Applied, CheckOptions, Fix, SetupStep, Severity};
use servobus_robot::Robot;

/// The gripper's protection settings as the simulator ships them, and the
/// values the doctor asks for (LeRobot's SO-101 set-up).
const GRIPPER: [(&str, i32, i32); 3] = [
    ("max_torque", 1000, 500),
    ("protection_current", 500, 250),
    ("overload_torque", 80, 25),
];

#[test]
fn the_simulated_arm_has_only_the_gripper_warnings_each_a_typed_write() {
    let robot = Robot::open("so101").expect("opens");
    let none: [&str; 0] = [];
    let checkup = robot
        .doctor(&none, &CheckOptions::default())
        .expect("checked");
    assert!(checkup.unchecked.is_empty());
    assert_eq!(checkup.buses.len(), 1);
    let bus = &checkup.buses[0];
    assert_eq!(bus.at.port, None, "the built-in simulator");
    assert_eq!(bus.first.servos.len(), 6);
    let warnings: Vec<_> = bus
        .standing()
        .iter()
        .filter(|f| f.severity > Severity::Info)
        .collect();
    assert_eq!(warnings.len(), GRIPPER.len(), "{warnings:#?}");
    for (f, (name, measured, want)) in warnings.iter().zip(GRIPPER) {
        assert_eq!(f.severity, Severity::Warning);
        assert_eq!(f.step, SetupStep::Configure);
        assert_eq!(f.id, Some(6));
        assert_eq!(f.register, Some(name));
        assert_eq!(f.measured, Some(measured), "{name}");
        assert!(f.fixable());
        let expected = Fix::Write {
            port: None,
            baud: 1_000_000,
            id: 6,
            register: name.to_owned(),
            value: want,
        };
        assert_eq!(f.advice, Advice::Run(expected.clone()));
        // Plain data for a program (the Python bindings): serde's tags.
        let json = serde_json::json!({"run": {"write": {
            "port": null, "baud": 1_000_000, "id": 6, "register": name, "value": want,
        }}});
        assert_eq!(serde_json::to_value(&f.advice).expect("serialises"), json);
        assert_eq!(f.advice.command(), Some(&expected));
        assert!(expected.has_placeholder(), "no port to run it on");
    }
}

#[test]
fn fixing_on_a_pty_writes_the_gripper_limits_and_nothing_stands_after() {
    let robot = Robot::open("so101").expect("opens");
    let pty = Pty::serve(robot.config(), None);
    let options = CheckOptions {
        fix: true,
        write_servos: false,
    };
    let checkup = robot
        .doctor(&[pty.path.as_str()], &options)
        .expect("checked");
    let bus = &checkup.buses[0];
    assert_eq!(bus.at.port.as_deref(), Some(pty.path.as_str()));
    assert_eq!(bus.fixes.len(), GRIPPER.len(), "{:#?}", bus.fixes);
    for fx in &bus.fixes {
        assert_eq!(fx.id, 6);
        assert!(fx.result.is_ok(), "{fx:?}");
        let Applied::Advice(Advice::Run(Fix::Write { port, .. })) = &fx.applied else {
            panic!("a write: {fx:?}");
        };
        assert_eq!(port.as_deref(), Some(pty.path.as_str()));
    }
    let after = bus.after.as_ref().expect("examined again");
    assert!(
        after.findings.iter().all(|f| f.severity == Severity::Info),
        "{:#?}",
        after.findings
    );
    assert!(
        !after
            .findings
            .iter()
            .any(|f| f.id == Some(6) && f.fixable()),
        "{:#?}",
        after.findings
    );
}
