//! `servobus doctor` end to end: the built-in simulator, and `servobus sim
//! --faults` on a pseudo-terminal in wall-clock time (exit status, JSON,
//! `--fix`).

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};

use common::{repo, scratch, servobus, BIN};

/// `servobus sim --faults SPEC` on a link in `dir`; killed when dropped.
struct FaultySim {
    child: Child,
    link: std::path::PathBuf,
}

impl FaultySim {
    fn start(dir: &std::path::Path, faults: &str) -> FaultySim {
        let link = dir.join("bus");
        let mut child = Command::new(BIN)
            .args(["sim", "--robot"])
            .arg(repo("configs/robots/so101.yaml"))
            .arg("--link")
            .arg(&link)
            .args(["--faults", faults])
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start servobus sim");
        let mut line = String::new();
        let stdout = child.stdout.take().expect("stdout");
        BufReader::new(stdout)
            .read_line(&mut line)
            .expect("sim's line");
        assert!(line.starts_with("serving 6 servos"), "{line}");
        FaultySim { child, link }
    }

    fn port(&self) -> &str {
        self.link.to_str().expect("utf-8")
    }
}

impl Drop for FaultySim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn doctor_json(args: &[&str]) -> (i32, serde_json::Value) {
    let out = servobus(args);
    let code = out.status.code().expect("exit code");
    let v = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "doctor {args:?}: not JSON ({e}): {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (code, v)
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
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("servo 6 max_torque"), "{text}");
    assert!(
        text.contains("0 error(s), 3 warning(s); 3 can be fixed with --fix"),
        "{text}"
    );
}

#[test]
fn doctor_finds_faults_on_a_pty_and_fix_brings_a_servo_back_to_the_bus_rate() {
    let dir = scratch("doctor-cli");
    let sim = FaultySim::start(&dir, "baud=4:115200,overheat=3");
    let robot = repo("configs/robots/so101.yaml");
    let robot = robot.to_str().expect("utf-8");
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
    let robot = dir.join("arm.yaml");
    std::fs::write(&robot, format!("calibration: missing.yaml\n{text}")).expect("robot");
    let robot = robot.to_str().expect("utf-8");
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
