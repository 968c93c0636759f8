//! `servobus scan` against simulated buses that need what the README
//! promises: a warning when two servos share an ID, and `--all-bauds`
//! finding servos at another baud rate.
//!
//! The buses are served from this process on a pty (wall clock); the
//! commands get a generous adapter latency, as in `bus_tools.rs`, or
//! measure it themselves, and nothing here measures time.

use crate::common;

use std::process::{Command, Output};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

use common::BIN;
use servobus_sim::{PtyError, PtyServer, SimServo};

/// A bus served on a pty until dropped.
struct Served {
    path: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<(), PtyError>>>,
}

impl Served {
    fn start(baud: u32, servos: Vec<SimServo>) -> Served {
        let mut server = PtyServer::open(baud, servos).expect("a pseudo-terminal");
        let path = server.path().to_string_lossy().into_owned();
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let thread = std::thread::spawn(move || server.serve(&flag));
        Served {
            path,
            stop,
            thread: Some(thread),
        }
    }

    /// `servobus scan` on this bus with a generous latency.
    fn scan(&self, extra: &[&str]) -> Output {
        self.scan_bare(&[&["--latency-us", "10000"], extra].concat())
    }

    /// `servobus scan` on this bus, with the latency it measures itself
    /// (it asks silent IDs again when the adapter turns out slower).
    fn scan_bare(&self, extra: &[&str]) -> Output {
        Command::new(BIN)
            .args(["scan", "--port", &self.path])
            .args(extra)
            .output()
            .expect("run servobus scan")
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn json(out: &Output) -> serde_json::Value {
    assert!(out.status.success(), "{}", common::stderr(out));
    common::json(out)
}

fn ids(v: &serde_json::Value) -> Vec<u64> {
    v["servos"]
        .as_array()
        .expect("servos")
        .iter()
        .map(|s| s["id"].as_u64().expect("an id"))
        .collect()
}

#[test]
fn scan_reports_two_servos_sharing_an_id_and_exits_1() {
    // Two servos at ID 1 (answering at once, their replies garble each
    // other) and one alone at ID 2.
    let bus = Served::start(
        1_000_000,
        vec![
            SimServo::sts3215(1).with_position(0x0F0F),
            SimServo::sts3215(1).with_position(0x00F0),
            SimServo::sts3215(2),
        ],
    );
    let out = bus.scan(&["--json"]);
    assert_eq!(out.status.code(), Some(1), "a shared ID is a problem found");
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("scan --json prints its findings");
    assert_eq!(ids(&v), [2], "only the servo alone is identified: {v}");
    let collisions: Vec<u64> = v["collisions"]
        .as_array()
        .expect("collisions")
        .iter()
        .map(|c| c["id"].as_u64().expect("an id"))
        .collect();
    assert!(collisions.contains(&1), "{v}");
    assert_eq!(v["collisions"][0]["baud"], 1_000_000);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("error: ID 1 at 1000000 baud")
            && err.contains("two servos share this ID")
            && err.contains("set-id"),
        "{err}"
    );
}

#[test]
fn all_bauds_finds_servos_at_another_rate() {
    // Three STS3215 set to 500 kbaud (register 6 = 1), served at that rate:
    // a scan at the default 1 Mbps hears nothing, --all-bauds finds them.
    let at_500k = |id| SimServo::sts3215(id).with_byte(servobus_sim::addr::BAUD_RATE, 1);
    let bus = Served::start(500_000, vec![at_500k(3), at_500k(4), at_500k(7)]);
    let plain = bus.scan(&[]);
    assert_eq!(plain.status.code(), Some(1), "nothing at 1 Mbps");
    assert!(String::from_utf8_lossy(&plain.stderr).contains("--all-bauds"));

    // Eight rates of 254 IDs each: at the default latency, not 10 ms each.
    let v = json(&bus.scan_bare(&["--all-bauds", "--json"]));
    assert_eq!(ids(&v), [3, 4, 7], "{v}");
    for s in v["servos"].as_array().expect("servos") {
        assert_eq!(s["baud"], 500_000, "{s}");
        assert_eq!(s["model"], "STS3215", "{s}");
    }
    assert_eq!(v["collisions"].as_array().map(Vec::len), Some(0), "{v}");
}
