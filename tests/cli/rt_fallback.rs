//! `play --fifo` where the system refuses SCHED_FIFO: a warning in the
//! report and normal scheduling, never a failure. Runs on the wall clock
//! (real threads are what `--fifo` is about); the motion is a short nod.

use crate::common;

use common::{arg, repo, servobus_unprivileged, stderr, stdout, temp_file};

#[test]
fn a_refused_sched_fifo_is_a_warning_and_the_run_completes() {
    let motion = temp_file(
        "rt_fallback",
        "nod.yaml",
        "units: deg\nkeyframes:\n  - pose: {shoulder_pan: 0}\n  - pose: {shoulder_pan: 5}\n",
    );
    let args = ["play", arg(&motion), "--robot", "so101", "--fifo", "80"];
    // The refusal is arranged, whoever runs the tests: a real-time priority
    // limit of 0, and not root (see `servobus_unprivileged`).
    let out = servobus_unprivileged(&repo(""), &args);
    let (stdout, stderr) = (stdout(&out), stderr(&out));
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains(
            "warning: SCHED_FIFO priority 80 not applied (Operation not permitted (os error 1)); \
             running with normal scheduling"
        ),
        "{stdout}{stderr}"
    );
    // The run itself finished: the report's closing table is there.
    assert!(stdout.contains("shoulder_pan"), "{stdout}");
}
