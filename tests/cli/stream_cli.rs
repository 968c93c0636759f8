//! `servobus stream` on the built-in simulator: JSON lines piped in at
//! 30 Hz are followed, a malformed line is reported with its number and
//! skipped, telemetry comes out as JSON lines, and the end of input stops
//! the robot cleanly with the report as the last line.

use crate::common;

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::Duration;

const BIN: &str = env!("CARGO_BIN_EXE_servobus");

#[test]
fn piped_targets_are_followed_a_bad_line_is_reported_and_the_end_stops() {
    let mut child = Command::new(BIN)
        .args(["stream", "--robot", "so101", "--telemetry", "--json"])
        .current_dir(common::repo(""))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("servobus runs");
    let mut stdin = child.stdin.take().expect("a pipe");
    // 1.5 s of the pan rising from 0 to 30 deg, then 0.5 s held at 30; the
    // 10th line is not JSON.
    let mut sent = 0;
    for i in 0..60 {
        let t = i as f64 / 30.0;
        let line = if i == 9 {
            "{\"joints\": {\"shoulder_pan\": 12".to_string()
        } else {
            sent += 1;
            let pan = 20.0 * t.min(1.5);
            format!("{{\"t\": {t}, \"joints\": {{\"shoulder_pan\": {pan}}}}}")
        };
        writeln!(stdin, "{line}").expect("servobus reads its input");
        std::thread::sleep(Duration::from_millis(33));
    }
    drop(stdin);
    let out = child.wait_with_output().expect("servobus ends");
    let (stdout, stderr) = common::exited(&out, 0);
    assert!(stderr.contains("line 10: not JSON"), "{stderr}");
    assert_eq!(stderr.matches("skipped").count(), 1, "{stderr}");
    let lines: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    let (last, samples) = lines.split_last().expect("some lines");
    let report = &last["report"];
    assert_eq!(report["finish"], "stopped", "{report}");
    assert_eq!(report["live"]["received"], sent, "{report}");
    assert_eq!(report["live"]["refused"], 0, "{report}");
    // At least 50 samples a second, each with every joint.
    let span = common::num(&samples[samples.len() - 1], "t") - common::num(&samples[0], "t");
    assert!(
        samples.len() as f64 >= 50.0 * span,
        "{} in {span} s",
        samples.len()
    );
    for s in samples {
        assert_eq!(s["commanded"].as_object().map(|m| m.len()), Some(6), "{s}");
        assert!(s["faults"].as_array().is_some_and(|f| f.is_empty()), "{s}");
    }
    // The pan went to 30 and came to rest there; the others stayed.
    let pan = |s: &serde_json::Value| s["commanded"]["shoulder_pan"].as_f64().unwrap_or(f64::NAN);
    let end = &samples[samples.len() - 1];
    assert!((pan(end) - 30.0).abs() < 0.5, "{end}");
    let measured = end["measured"]["shoulder_pan"].as_f64().unwrap_or(f64::NAN);
    assert!((measured - 30.0).abs() < 2.0, "{end}");
    let lift = |s: &serde_json::Value| s["commanded"]["shoulder_lift"].as_f64();
    assert_eq!(lift(end), lift(&samples[0]));
}

#[test]
fn a_stream_that_brought_no_target_still_reports_its_live_section() {
    // Only bad lines, then the end of input: nothing was followed, and the
    // report says so instead of leaving its live section out.
    let mut child = Command::new(BIN)
        .args(["stream", "--robot", "so101", "--json"])
        .current_dir(common::repo(""))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("servobus runs");
    let mut stdin = child.stdin.take().expect("a pipe");
    writeln!(stdin, "not json").expect("servobus reads its input");
    writeln!(stdin, "{{\"joints\": ").expect("servobus reads its input");
    drop(stdin);
    let out = child.wait_with_output().expect("servobus ends");
    let (stdout, _) = common::exited(&out, 0);
    let last: serde_json::Value = stdout
        .lines()
        .last()
        .and_then(|l| serde_json::from_str(l).ok())
        .expect("the report is the last line");
    let live = &last["report"]["live"];
    assert_eq!(live["received"], 0, "{last}");
    assert!(live["envelope"].is_array(), "{last}");
}
