//! The wall-clock pty server: a client that opens the terminal as a serial
//! port talks to the simulated servos. These tests exchange whole frames and
//! assert on bytes only, never on timing.

use std::io::{Read, Write};
use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use servobus_protocol::{encode, parse_frame, StatusFlags};
use servobus_sim::{PtyServer, SimServo};

/// Runs `f` with a server of `servos` on a pty, serving in a thread.
fn with_server(servos: Vec<SimServo>, pacing: bool, f: impl FnOnce(&Path)) {
    let mut server = PtyServer::open(1_000_000, servos).expect("a pty");
    server.set_pacing(pacing);
    let path = server.path().to_owned();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let thread = std::thread::spawn(move || server.serve(&flag).map(|()| server.stats()));
    f(&path);
    stop.store(true, Ordering::SeqCst);
    let stats = thread.join().expect("server thread").expect("served");
    assert!(stats.requests > 0);
}

/// Opens the terminal raw, as a serial library would.
fn open_raw(path: &Path) -> std::fs::File {
    use std::os::unix::fs::OpenOptionsExt;
    // O_NOCTTY: the test process must not adopt the terminal as its own.
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(libc::O_NOCTTY)
        .open(path)
        .expect("open the pty")
}

fn read_frame(file: &mut std::fs::File) -> Vec<u8> {
    let mut got = Vec::new();
    let mut buf = [0u8; 64];
    loop {
        if let Ok((p, _)) = parse_frame(&got) {
            return p.bytes().to_vec();
        }
        let n = file.read(&mut buf).expect("read the pty");
        got.extend_from_slice(&buf[..n]);
    }
}

#[test]
fn a_client_pings_and_reads_through_the_pty() {
    let servos = vec![
        SimServo::sts3215(1)
            .with_return_delay(Duration::ZERO)
            .with_position(1000),
        SimServo::sts3215(2).with_return_delay(Duration::ZERO),
    ];
    for pacing in [true, false] {
        with_server(servos.clone(), pacing, |path| {
            let mut port = open_raw(path);
            let mut frame = [0u8; 16];
            let n = encode::ping(&mut frame, 2).unwrap();
            port.write_all(&frame[..n]).unwrap();
            let mut want = [0u8; 16];
            let m = encode::status(&mut want, 2, StatusFlags(0), &[]).unwrap();
            assert_eq!(read_frame(&mut port), &want[..m]);

            let n = encode::read(&mut frame, 1, 56, 2).unwrap();
            port.write_all(&frame[..n]).unwrap();
            let m = encode::status(&mut want, 1, StatusFlags(0), &1000u16.to_le_bytes()).unwrap();
            assert_eq!(read_frame(&mut port), &want[..m]);
        });
    }
}

#[test]
fn the_link_points_at_the_pty_and_is_removed_on_drop() {
    let dir = std::env::temp_dir().join(format!("servobus-sim-link-{}", std::process::id()));
    let mut server = PtyServer::open(1_000_000, [SimServo::sts3215(1)]).unwrap();
    server.link_to(&dir).unwrap();
    assert_eq!(std::fs::read_link(&dir).unwrap(), server.path());
    assert_eq!(server.client_path(), dir.as_path());
    drop(server);
    assert!(std::fs::symlink_metadata(&dir).is_err());
}

/// Feetech's Python SDK against the simulator (skipped without python3 and
/// `pip install feetech-servo-sdk`).
#[test]
fn feetech_python_sdk_works_unchanged() {
    let probe = Command::new("python3")
        .args(["-c", "import scservo_sdk"])
        .output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!(
            "skipped: python3 with scservo_sdk (pip install feetech-servo-sdk) is not available"
        );
        return;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/scservo_check.py");
    let servos = (1..=6)
        .map(|id| SimServo::sts3215(id).with_return_delay(Duration::ZERO))
        .collect();
    with_server(servos, true, |path| {
        let out = Command::new("python3")
            .arg(&script)
            .arg(path)
            .output()
            .expect("run python3");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(stdout.starts_with("OK 6 servos"), "{stdout}");
    });
}
