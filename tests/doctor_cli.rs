//! `servobus doctor` end to end: the built-in simulator, and `servobus sim
//! --faults` on a pseudo-terminal in wall-clock time (exit status, JSON,
//! `--fix`).

mod common;

use common::{arg, exited, json, repo, says, scratch, servobus, write_file, Sim};

fn doctor_json(args: &[&str]) -> (i32, serde_json::Value) {
    let out = servobus(args);
    (out.status.code().expect("exit code"), json(&out))
}

fn finding<'a>(
    list: &'a serde_json::Value,
    id: u64,
    register: &str,
) -> Option<&'a serde_json::Value> {
    list.as_array()?
        .iter()
        .find(|f| f["id"].as_u64() == Some(id) && f["register"] == register)
}

#[test]
fn the_built_in_simulator_has_only_the_gripper_warnings() {
    let out = servobus(&["doctor", "--robot", "configs/robots/so101.yaml"]);
    let (text, _) = exited(&out, 1);
    says(
        &text,
        &[
            "servo 6 max_torque",
            "0 error(s), 3 warning(s); 3 can be fixed with --fix",
        ],
    );
}

#[test]
fn doctor_finds_faults_on_a_pty_and_fix_brings_a_servo_back_to_the_bus_rate() {
    let dir = scratch("doctor-cli");
    let sim = Sim::start_with(&dir, &["--faults", "baud=4:115200,overheat=3"]);
    let robot = repo("configs/robots/so101.yaml");
    let robot = arg(&robot);
    let (code, v) = doctor_json(&["doctor", "--robot", robot, "--port", sim.port(), "--json"]);
    assert_eq!(code, 2, "{v}");
    let findings = &v["buses"][0]["findings"];
    let baud = finding(findings, 4, "baud_rate").unwrap_or_else(|| panic!("{v}"));
    assert_eq!(baud["severity"], "error");
    assert_eq!(baud["fixable"], true);
    assert_eq!(
        baud["fix"],
        format!(
            "servobus write --port {} --baud 115200 --id 4 baud_rate 0",
            sim.port()
        )
    );
    let hot = finding(findings, 3, "present_temperature").unwrap_or_else(|| panic!("{v}"));
    assert_eq!(hot["severity"], "error");

    let (code, v) = doctor_json(&[
        "doctor",
        "--robot",
        robot,
        "--port",
        sim.port(),
        "--json",
        "--fix",
    ]);
    let fixes = v["buses"][0]["fixes"].as_array().expect("fixes").clone();
    assert!(fixes.iter().all(|f| f["ok"] == true), "{v}");
    assert!(fixes.iter().any(|f| f["id"] == 4), "{v}");
    let after = &v["buses"][0]["after_fix"];
    assert!(finding(after, 4, "baud_rate").is_none(), "{v}");
    // Servo 3 is still hot: --fix does not pretend to cool it.
    assert!(finding(after, 3, "present_temperature").is_some(), "{v}");
    assert_eq!(code, 2);
    let read = servobus(&["read", "--port", sim.port(), "--id", "4", "baud_rate"]);
    assert_eq!(
        String::from_utf8_lossy(&read.stdout).trim(),
        "baud_rate = 0 index"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_calibration_the_robot_file_names_but_lacks_is_an_error() {
    let dir = scratch("doctor-calibration");
    let text = std::fs::read_to_string(repo("configs/robots/so101.yaml")).expect("so101");
    let robot = write_file(
        &dir,
        "arm.yaml",
        &format!("calibration: missing.yaml\n{text}"),
    );
    let robot = arg(&robot);
    let (code, v) = doctor_json(&["doctor", "--robot", robot, "--json"]);
    assert_eq!(code, 2, "{v}");
    let findings = v["buses"][0]["findings"].as_array().expect("findings");
    let f = findings
        .iter()
        .find(|f| {
            f["problem"]
                .as_str()
                .is_some_and(|p| p.contains("missing.yaml"))
        })
        .unwrap_or_else(|| panic!("{v}"));
    assert_eq!(f["severity"], "error");
    let fix = f["fix"].as_str().expect("fix");
    assert!(
        fix.starts_with(&format!(
            "servobus calibrate --robot {robot} --port <PORT> -o "
        )),
        "{fix}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
