//! `play --fifo` where the system refuses SCHED_FIFO: a warning in the
//! report and normal scheduling, never a failure. Runs on the wall clock
//! (real threads are what `--fifo` is about); the motion is a short nod.

use crate::common;

use common::{arg, is_root, servobus, servobus_as_nobody, stderr, stdout, temp_file};

#[test]
fn a_refused_sched_fifo_is_a_warning_and_the_run_completes() {
    let motion = temp_file(
        "rt_fallback",
        "nod.yaml",
        "units: deg\nkeyframes:\n  - pose: {shoulder_pan: 0}\n  - pose: {shoulder_pan: 5}\n",
    );
    let args = ["play", arg(&motion), "--robot", "so101", "--fifo", "80"];
    let root = is_root();
    let out = if root {
        // Root may set SCHED_FIFO: run as `nobody`, whose real-time
        // priority limit is 0, so the request is refused.
        let Some(out) = servobus_as_nobody(&args) else {
            return;
        };
        out
    } else {
        servobus(&args)
    };
    let (stdout, stderr) = (stdout(&out), stderr(&out));
    if !root && !stdout.contains("SCHED_FIFO") {
        // An unprivileged user allowed real-time priority: nothing to show.
        eprintln!("\n*** SKIPPED: this user may use SCHED_FIFO ***\n");
        return;
    }
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
