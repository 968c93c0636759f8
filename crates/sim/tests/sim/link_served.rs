//! A second simulator does not take the link of one that is running in
//! another process; the link of one that has gone is taken as before.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use servobus_sim::{PtyError, PtyServer, SimServo};

/// A stand-in for a simulator in another process: a Python process that
/// holds both ends of a pseudo-terminal open (as a simulator does) until
/// its stdin closes. `None` where there is no Python 3 to run.
fn other_server() -> Option<(std::process::Child, String)> {
    let script = "import os, sys\nm, s = os.openpty()\nprint(os.ttyname(s), flush=True)\n\
                  sys.stdin.read()\n";
    let mut child = Command::new("python3")
        .args(["-c", script])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .ok()?;
    let mut line = String::new();
    let stdout = child.stdout.take()?;
    BufReader::new(stdout).read_line(&mut line).ok()?;
    Some((child, line.trim().to_owned()))
}

#[test]
fn a_link_a_running_simulator_serves_is_not_taken() {
    if !std::path::Path::new("/proc/self/fdinfo").exists() {
        return; // no way to tell who serves a terminal here
    }
    let Some((mut child, pty)) = other_server() else {
        eprintln!("skipped: no python3 to stand in for another simulator");
        return;
    };
    let link = std::env::temp_dir().join(format!("servobus-sim-served-{}", std::process::id()));
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(&pty, &link).expect("a link to the other server's terminal");
    let mut second = PtyServer::open(1_000_000, [SimServo::sts3215(1)]).expect("a pty");
    match second.link_to(&link) {
        Err(e @ PtyError::LinkServed { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains(&format!("(pid {}) serves {pty} through it", child.id())),
                "{text}"
            );
            assert!(
                text.contains("is the link of a running simulator"),
                "{text}"
            );
        }
        other => panic!("the link was taken: {other:?}"),
    }
    assert_eq!(
        std::fs::read_link(&link).expect("still a link"),
        std::path::PathBuf::from(&pty),
        "the running simulator's link was changed"
    );
    // Once that simulator has gone, its link is stale and is taken.
    drop(child.stdin.take());
    child.wait().expect("the stand-in ends");
    second.link_to(&link).expect("a stale link is replaced");
    assert_eq!(std::fs::read_link(&link).expect("a link"), second.path());
    drop(second);
    assert!(std::fs::symlink_metadata(&link).is_err());
}
