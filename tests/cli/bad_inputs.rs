//! Hostile and mistaken inputs (issue 22): files that ask for unbounded
//! work, values that cannot work, the wrong file blamed, and messages in
//! the code's terms. Each case runs the `servobus` binary on a file of
//! `tests/bad_inputs/` (or one made here when it is large) and expects a
//! refusal: exit 2, no panic, a message naming the limit or the field, and
//! an end (a generous time-out is only a safety net, not a measurement).

use crate::common;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use common::{repo, temp_file};

/// A safety net only: every case here ends in well under a second.
const SAFETY_NET: Duration = Duration::from_secs(120);

/// The corpus folder.
fn corpus() -> PathBuf {
    repo("tests/bad_inputs")
}

/// Runs `servobus ARGS` in `dir`, killed if it outlives [`SAFETY_NET`];
/// its exit code and standard error.
fn run_in(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let mut child = common::spawn_stderr_piped(dir, args);
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("the child can be waited for") {
            break status;
        }
        if started.elapsed() > SAFETY_NET {
            let _ = child.kill();
            let _ = child.wait();
            panic!("servobus {args:?} did not end within {SAFETY_NET:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    if let Some(mut stderr) = child.stderr.take() {
        stderr.read_to_string(&mut err).expect("stderr is text");
    }
    (status.code(), err)
}

/// `servobus ARGS` in the corpus folder must be refused with exit 2, no
/// panic, and a message holding every one of `words` and none of `never`.
fn refused(args: &[&str], words: &[&str], never: &[&str]) -> String {
    refused_in(&corpus(), args, words, never)
}

fn refused_in(dir: &Path, args: &[&str], words: &[&str], never: &[&str]) -> String {
    let (code, err) = run_in(dir, args);
    assert_eq!(code, Some(2), "servobus {args:?}: {err}");
    for bad in ["panicked", "RUST_BACKTRACE", "stack backtrace"] {
        assert!(!err.contains(bad), "servobus {args:?} panicked: {err}");
    }
    assert!(err.starts_with("error: "), "servobus {args:?}: {err}");
    for w in words {
        assert!(err.contains(w), "servobus {args:?} should say {w:?}: {err}");
    }
    for w in never {
        assert!(
            !err.contains(w),
            "servobus {args:?} should not say {w:?}: {err}"
        );
    }
    err
}

#[test]
fn a_mistyped_built_in_name_is_answered_with_the_nearest_one() {
    refused(
        &["budget", "--robot", "so100"],
        &[
            "so100: cannot read",
            "did you mean the built-in robot `so101`?",
        ],
        &[],
    );
    refused(
        &["plan", "arm_wave"],
        &["did you mean the built-in motion `arm-wave`?"],
        &[],
    );
    // Nothing near: the general hint, no guess.
    refused(
        &["budget", "--robot", "quadruped-9"],
        &["give a file path or the name of a built-in robot or motion"],
        &["did you mean"],
    );
}

#[test]
fn a_small_file_cannot_ask_for_unbounded_work() {
    refused(
        &["plan", "motion-repeat-billion.yaml"],
        &["motion-repeat-billion.yaml:6:9: repeat:", "limit of 500000"],
        &[],
    );
    refused(
        &["plan", "motion-at-1e12.yaml"],
        &["keyframes[1].at: 1e12 s", "limit of 86400 s"],
        &[],
    );
    refused(
        &["plan", "motion-too-slow.yaml"],
        &["motion-too-slow.yaml:5:5: keyframes[1]", "limit of 86400 s"],
        &[],
    );
    refused(
        &[
            "play",
            "--fast",
            "recording-1e9s.csv",
            "--robot",
            "robot-tiny.yaml",
        ],
        &["recording-1e9s.csv", "1e9 s", "limit of 86400 s"],
        &[],
    );
    refused(
        &["budget", "--robot", "/dev/zero"],
        &["/dev/zero: larger than 1 MiB"],
        &[],
    );
    refused(
        &["budget", "--robot", "robot-nested-40.yaml"],
        &["robot-nested-40.yaml:2:", "nested more than 32 levels"],
        &[],
    );
    refused(
        &["plan", "motion-walk-period-tiny.yaml"],
        &[
            "motion-walk-period-tiny.yaml:13:44: keyframes[1].walk.period",
            "from 0.2 to 3600 s, got 1e-9",
        ],
        &[],
    );
    refused(
        &["plan", "motion-walk-long.yaml"],
        &[
            "motion-walk-long.yaml:13:11: keyframes[1].walk",
            "this walk would make 150201 samples",
        ],
        &[],
    );
    refused(
        &["plan", "motion-body-below-ground.yaml"],
        &[
            "motion-body-below-ground.yaml:13:20: keyframes[1].body.height",
            "above the ground, > 0 mm, got -100",
        ],
        &[],
    );
    refused(
        &["plan", "motion-line-tolerance-tiny.yaml"],
        &[
            "motion-line-tolerance-tiny.yaml:8:16: keyframes[2].tolerance",
            "from 0.01 to 100 mm, got 1e-9",
        ],
        &[],
    );
}

/// Every duration in a file is checked at parse time against a range the
/// message gives (issue 36): a walk segment's, a keyframe's `at` below 0,
/// a hand's keyframe 1e300 s after the simulator's start.
#[test]
fn a_duration_in_a_file_is_refused_with_its_range() {
    refused(
        &["plan", "motion-walk-duration-huge.yaml"],
        &[
            "motion-walk-duration-huge.yaml:13:88: keyframes[1].walk.segments[0].duration",
            "a time above 0 and up to 3600 s, got 1e300",
        ],
        &[],
    );
    refused(
        &["plan", "motion-at-negative.yaml"],
        &[
            "motion-at-negative.yaml:5:9: keyframes[1].at",
            "from 0 to 86400 s (a day), got -1",
        ],
        &[],
    );
    // Refused before it serves: a hand taken would serve until the
    // safety net.
    refused(
        &["sim", "--robot", "so101", "--hand", "hand-at-1e300.yaml"],
        &[
            "hand-at-1e300.yaml:5:10: keyframes[1].at",
            "from 0 to 86400 s (a day) from the simulator's start, got 1e300",
        ],
        &[],
    );
}

/// A recording of more rows than the limit is refused at the first row
/// past it, before the rows are kept (issue 36: every generator of
/// samples checks its count before it allocates). 2,000,001 rows 10 us
/// apart are 20 s: without the row limit it would play.
#[test]
fn a_recording_of_more_rows_than_the_limit_is_refused_at_the_row() {
    let mut text = String::from("time_s,pan\n");
    for i in 0..=2_000_000u32 {
        text.push_str(&format!("{i}e-5,0\n"));
    }
    let rec = temp_file("bad-inputs", "rows.csv", &text);
    refused(
        &[
            "play",
            "--fast",
            common::arg(&rec),
            "--robot",
            "robot-tiny.yaml",
        ],
        &[
            "rows.csv:2000002:1",
            "more than 2000000 rows, the limit for a recording",
        ],
        &[],
    );
}

#[test]
fn ports_that_are_no_serial_port_say_what_they_are() {
    refused(
        &["ping", "--port", "", "--id", "1"],
        &["the port is empty"],
        &[],
    );
    refused(
        &["ping", "--port", "/dev/tty", "--id", "1"],
        &["this program's own terminal"],
        &[],
    );
    let dir = servobus_test_dir("port-loop");
    let link = dir.join("loop");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(&link, &link).expect("a link to itself");
    refused(
        &[
            "ping",
            "--port",
            link.to_str().expect("a UTF-8 path"),
            "--id",
            "1",
        ],
        &["leads back to itself"],
        &[],
    );
}

/// A fresh scratch directory of this test binary.
fn servobus_test_dir(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("servobus-bad-inputs-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    dir
}

#[test]
fn large_and_deep_files_are_refused_before_they_are_parsed() {
    // 400 KB nested 100,000 deep: serde_yaml took a minute on it.
    let deep = temp_file("bad-inputs", "deep.yaml", &"{a: ".repeat(100_000));
    refused(
        &["budget", "--robot", common::arg(&deep)],
        &["deep.yaml:1:", "nested more than 32 levels"],
        &[],
    );
    let huge = format!("name: x\n{}", "# padding\n".repeat(200_000));
    let huge = temp_file("bad-inputs", "huge.yaml", &huge);
    refused(
        &["plan", "motion-tiny.yaml", "--robot", common::arg(&huge)],
        &["huge.yaml: larger than 1 MiB"],
        &[],
    );
}

#[test]
fn values_that_cannot_work_are_refused_with_their_range() {
    let baud_table = "use one of 1000000, 500000, 250000, 128000, 115200, 76800, 57600, 38400";
    for baud in ["0", "1", "12345"] {
        refused(
            &["scan", "--port", "/dev/null", "--baud", baud],
            &[&format!("{baud} baud is not a rate"), baud_table],
            &[],
        );
    }
    refused(
        &[
            "ping",
            "--port",
            "/dev/null",
            "--id",
            "1",
            "--latency-us",
            "999999999",
        ],
        &["999999999 us", "0 to 255000 us"],
        &[],
    );
    refused(
        &["budget", "--robot", "robot-latency-huge.yaml"],
        &["buses[0].latency_us: 999999999 us", "0 to 255000 us"],
        &[],
    );
    refused(
        &["play", "--fast", "motion-tiny.yaml", "--rate", "0.001"],
        &["0.001 Hz", "10 to 10000 Hz"],
        &[],
    );
    refused(
        &["plan", "motion-rate-tiny.yaml"],
        &[
            "motion-rate-tiny.yaml:3:7: rate: 0.001 Hz",
            "10 to 10000 Hz",
        ],
        &[],
    );
    refused(
        &["budget", "--robot", "robot-rate-tiny.yaml"],
        &["robot-rate-tiny.yaml:3:7: rate: 0.001 Hz", "10 to 10000 Hz"],
        &[],
    );
}

#[test]
fn the_file_at_fault_is_the_one_named() {
    // A --calibration that cannot be read is not the motion's `robot:`.
    refused(
        &["plan", "motion-tiny.yaml", "--calibration", "nope.yaml"],
        &["nope.yaml: cannot read: no such file"],
        &["robot:", "motion-tiny.yaml"],
    );
    // A calibration the robot file names but that does not exist: plan
    // and play (here on the built-in simulator) refuse, naming it.
    for args in [
        &["plan", "motion-missing-calibration.yaml"][..],
        &["play", "--fast", "motion-missing-calibration.yaml"],
        &[
            "play",
            "--fast",
            "recording-1e9s.csv",
            "--robot",
            "robot-missing-calibration.yaml",
        ],
    ] {
        refused(
            args,
            &[
                "robot-missing-calibration.yaml:4:14: calibration:",
                "no-such.calibration.yaml does not exist",
            ],
            &[],
        );
    }
}

#[test]
fn messages_speak_in_the_files_terms() {
    let rust = ["untagged", "LatencySpec", "struct", "Raw", "f64", "u64"];
    refused(
        &["budget", "--robot", "robot-latency-list.yaml"],
        &[
            "robot-latency-list.yaml:8:17: buses[0].latency_us:",
            "a number of microseconds or `auto`",
        ],
        &rust,
    );
    refused(
        &["plan", "motion-list.yaml"],
        &["motion-list.yaml:2:1:", "expected a motion file"],
        &rust,
    );
    refused(
        &["sim", "--robot", "so101", "--hand", "hand-list.yaml"],
        &["hand-list.yaml:2:1:", "expected a hand file"],
        &rust,
    );
    refused(
        &[
            "play",
            "--fast",
            "recording-not-a-number.csv",
            "--robot",
            "robot-tiny.yaml",
        ],
        &["recording-not-a-number.csv:3:2: `1e999x` in column `pan` is not a number"],
        &["float literal"],
    );
    let err = refused(
        &["budget", "--robot", "robot-309-digits.yaml"],
        &["buses[0].joints[0].max_velocity: must be positive, got -1e308"],
        &[],
    );
    assert!(!err.contains("0000000000"), "a long number echoed: {err}");
}
