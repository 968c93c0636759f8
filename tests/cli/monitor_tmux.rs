//! `servobus monitor` in a real terminal: runs `scripts/monitor_tmux.sh`,
//! which drives the monitor under tmux against the simulator with servo 3
//! overheating and servo 5 disconnected and reads the screen back.

use crate::common;

use std::process::Command;

#[test]
#[ignore = "needs tmux (apt-get install -y tmux), then `cargo test --test cli -- --ignored` (the gate runs it)"]
fn monitor_in_tmux_shows_faults_updates_and_restores_the_terminal() {
    let tmux = Command::new("tmux").arg("-V").output();
    assert!(
        tmux.is_ok_and(|o| o.status.success()),
        "tmux is not installed, so the live view cannot be tested (apt-get install -y tmux)"
    );
    let out = Command::new("bash")
        .arg(common::repo("scripts/monitor_tmux.sh"))
        .arg(common::BIN)
        .output()
        .expect("the script runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "monitor_tmux.sh failed:\n{stdout}");
    for check in [
        "PASS: servo 5 shows as missing",
        "PASS: servo 3 shows the overheat flag",
        "PASS: servos 1 2 3 4 6 update",
        "PASS: q leaves the terminal as it was",
        "PASS: a panic restores the terminal",
        "PASS: play --monitor shows the running motion",
        "PASS: q stops the motion",
    ] {
        assert!(stdout.contains(check), "missing `{check}` in:\n{stdout}");
    }
}
