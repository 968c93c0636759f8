//! `servobus stream` on the built-in simulator: JSON lines piped in at
//! 30 Hz are followed, a malformed line is reported with its number and
//! skipped, telemetry comes out as JSON lines, and the end of input stops
//! the robot cleanly with the report as the last line.

use crate::common;

use std::io::Write;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::time::Duration;

const BIN: &str = env!("CARGO_BIN_EXE_servobus");

/// Spawns `servobus ARGS` from the repository's root with stdin, stdout and
/// stderr piped, and takes its stdin.
fn spawn_piped(args: &[&str]) -> (Child, ChildStdin) {
    let mut child = Command::new(BIN)
        .args(args)
        .current_dir(common::repo(""))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("servobus runs");
    let stdin = child.stdin.take().expect("a pipe");
    (child, stdin)
}

/// The last line of `stdout`, the report, as JSON.
fn last_line_json(stdout: &str) -> serde_json::Value {
    stdout
        .lines()
        .last()
        .and_then(|l| serde_json::from_str(l).ok())
        .expect("the report is the last line")
}

#[test]
fn piped_targets_are_followed_a_bad_line_is_reported_and_the_end_stops() {
    let (child, mut stdin) = spawn_piped(&["stream", "--robot", "so101", "--telemetry", "--json"]);
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
    assert_eq!(last["skipped_lines"], 1, "{last}");
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
    let (child, mut stdin) = spawn_piped(&["stream", "--robot", "so101", "--json"]);
    writeln!(stdin, "not json").expect("servobus reads its input");
    writeln!(stdin, "{{\"joints\": ").expect("servobus reads its input");
    drop(stdin);
    let out = child.wait_with_output().expect("servobus ends");
    let (stdout, _) = common::exited(&out, 0);
    let last = last_line_json(&stdout);
    let live = &last["report"]["live"];
    assert_eq!(live["received"], 0, "{last}");
    assert_eq!(last["skipped_lines"], 2, "{last}");
    assert!(live["envelope"].is_array(), "{last}");
}

/// A line that is not UTF-8 and one longer than 1 MiB are each reported
/// with their number and skipped (issue 36): neither ends the input, the
/// lines after them keep their numbers, and their targets are followed.
#[test]
fn a_line_not_utf8_or_longer_than_1_mib_is_skipped_and_the_input_goes_on() {
    let (child, mut stdin) = spawn_piped(&["stream", "--robot", "so101", "--json"]);
    let target = |pan: u32| format!("{{\"joints\": {{\"shoulder_pan\": {pan}}}}}\n");
    let mut input = target(1).into_bytes();
    // Line 2: a target behind two bytes that are no UTF-8.
    input.extend_from_slice(b"\xff\xfe");
    input.extend_from_slice(target(2).as_bytes());
    // Line 3: 2 MiB of spaces.
    input.extend_from_slice(&vec![b' '; 2 << 20]);
    input.push(b'\n');
    input.extend_from_slice(target(3).as_bytes());
    input.extend_from_slice(b"{\"joints\": \n");
    input.extend_from_slice(target(4).as_bytes());
    // Only the report comes out on stdout: the whole input goes in first.
    stdin.write_all(&input).expect("servobus reads its input");
    drop(stdin);
    let out = child.wait_with_output().expect("servobus ends");
    let (stdout, stderr) = common::exited(&out, 0);
    for said in [
        "line 2: not UTF-8 text; skipped",
        "line 3: longer than 1 MiB; skipped",
        "line 5: not JSON",
    ] {
        assert!(stderr.contains(said), "{said:?} in {stderr}");
    }
    assert_eq!(stderr.matches("skipped").count(), 3, "{stderr}");
    let last = last_line_json(&stdout);
    let live = &last["report"]["live"];
    assert_eq!(live["received"], 3, "lines 1, 4 and 6: {last}");
    assert_eq!(live["refused"], 0, "{last}");
    assert_eq!(last["skipped_lines"], 3, "{last}");
}

/// `stream < /dev/zero`: one line without end. Its buffer is capped at
/// 1 MiB, so after 256 MiB read the process's peak memory is still under
/// 128 MiB (it grew past 1.1 GB in 4 s before the cap); Ctrl-C then ends
/// the run as usual. Bounded: the reading is awaited 120 s at most (it
/// reads about 200 MB/s on a slow machine), the end 60 s.
#[cfg(target_os = "linux")]
#[test]
fn stream_from_dev_zero_keeps_its_memory_under_a_ceiling() {
    const READ: u64 = 256 << 20;
    const CEILING_KB: u64 = 128 << 10;
    let zero = std::fs::File::open("/dev/zero").expect("/dev/zero");
    let mut child = Command::new(BIN)
        .args(["stream", "--robot", "so101"])
        .current_dir(common::repo(""))
        .stdin(Stdio::from(zero))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("servobus runs");
    let proc_field = |file: &str, key: &str| -> Option<u64> {
        let text = std::fs::read_to_string(format!("/proc/{}/{file}", child.id())).ok()?;
        let line = text.lines().find(|l| l.starts_with(key))?;
        line[key.len()..].split_whitespace().next()?.parse().ok()
    };
    let started = std::time::Instant::now();
    let mut read = 0;
    while read < READ && started.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(100));
        read = proc_field("io", "rchar:").unwrap_or(0);
    }
    let peak_kb = proc_field("status", "VmHWM:");
    assert!(common::signal(&child, "INT"), "kill -INT");
    let ended = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if ended.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("servobus stream did not end 60 s after Ctrl-C");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut stderr = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = std::io::Read::read_to_string(&mut e, &mut stderr);
    }
    assert!(read >= READ, "only {read} bytes read in 120 s: {stderr}");
    let peak_kb = peak_kb.expect("VmHWM in /proc/PID/status");
    assert!(
        peak_kb < CEILING_KB,
        "peak memory {peak_kb} kB after {read} bytes of one line: {stderr}"
    );
    assert_eq!(status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
