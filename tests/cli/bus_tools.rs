//! End to end: start `servobus sim` on a pty and use `scan`, `ping`, `read`,
//! `write` and `set-id` against it as a user would.
//!
//! The simulator runs in wall-clock time here, so the commands are given a
//! generous adapter latency (`--latency-us`): on a loaded machine the
//! simulator's process may be scheduled milliseconds late. Nothing in this
//! test measures time.

use crate::common;

use common::{error, says, Sim};

/// The command fails with exit code `code` (1: a problem found, 2: a usage
/// error) and a one-line error naming `why`.
fn fails(sim: &Sim, args: &[&str], code: i32, why: &str) {
    says(&error(&sim.run(args), code), &[why]);
}

#[test]
fn scan_read_write_set_id_against_the_simulator() {
    let dir = common::scratch("bus-tools");
    let sim = Sim::start(&dir);

    // scan: the six servos of the arm, identified. A scan asks each absent
    // ID once, so a simulator process descheduled for longer than the
    // deadline on a loaded machine can hide a servo from one pass (a
    // servo on a real bus is never descheduled): up to 3 passes, the first
    // complete one counts, and it must say exactly this.
    let json = |out: String| -> serde_json::Value {
        serde_json::from_str(out.trim()).expect("scan --json")
    };
    let ids_of = |scan: &serde_json::Value| -> Vec<i64> {
        let servos = scan["servos"].as_array().expect("servos");
        servos.iter().filter_map(|s| s["id"].as_i64()).collect()
    };
    let scan = (0..2)
        .map(|_| json(sim.scan(&["--json"])))
        .find(|scan| ids_of(scan).len() == 6)
        .unwrap_or_else(|| json(sim.scan(&["--json"])));
    let servos = scan["servos"].as_array().expect("servos");
    assert_eq!(ids_of(&scan), [1, 2, 3, 4, 5, 6]);
    for s in servos {
        assert_eq!(s["model"], "STS3215");
        assert_eq!(s["model_number"], 777);
        assert!(s["voltage_v"].as_f64().is_some_and(|v| v > 4.0));
        assert!(s["position"]
            .as_i64()
            .is_some_and(|p| (0..4096).contains(&p)));
    }
    assert_eq!(scan["collisions"].as_array().map(Vec::len), Some(0));
    // The table form names the columns.
    let table = (0..2)
        .map(|_| sim.scan(&[]))
        .find(|t| t.contains("found 6 servo(s)"))
        .unwrap_or_else(|| sim.scan(&[]));
    assert!(
        table.contains("POSITION") && table.contains("found 6 servo(s)"),
        "{table}"
    );

    // ping and read.
    assert!(sim.ok(&["ping", "--id", "4"]).contains("servo 4 answered"));
    assert_eq!(sim.read("3", "model_number"), 777);
    let pos = sim.read("3", "present_position");
    assert!((0..4096).contains(&pos));
    assert!(sim
        .ok(&["read", "--id", "3", "Present_Voltage"])
        .starts_with("present_voltage = "));

    // write: RAM takes effect; EEPROM says it persists and is verified.
    sim.ok(&["write", "--id", "3", "acceleration", "20"]);
    assert_eq!(sim.read("3", "acceleration"), 20);
    let out = sim.ok(&["write", "--id", "3", "max_temperature", "65"]);
    assert!(out.contains("persist") && out.contains("verified"), "{out}");
    assert_eq!(sim.read("3", "max_temperature"), 65);
    assert_eq!(sim.read("3", "lock"), 1);

    // set-id: refuses a taken ID, then moves servo 3 to 9.
    fails(&sim, &["set-id", "--id", "3", "2"], 1, "already taken");
    let out = sim.ok(&["set-id", "--id", "3", "9"]);
    assert!(out.contains("now ID 9"), "{out}");
    assert!(sim.ok(&["ping", "--id", "9"]).contains("servo 9 answered"));
    fails(&sim, &["ping", "--id", "3"], 1, "servo 3");
    assert_eq!(sim.read("9", "id"), 9);

    // One-line errors for what a user gets wrong.
    for (args, why) in [
        (&["read", "--id", "1", "nonsense"][..], "no register called"),
        (
            &["read", "--id", "1", "nonsense"][..],
            "goal_position, goal_time, goal_speed",
        ),
        (
            &["write", "--id", "1", "nonsense", "1"][..],
            "servobus registers --series sts",
        ),
        (
            &["write", "--id", "1", "present_position", "5"],
            "read-only",
        ),
        (
            &["write", "--id", "1", "acceleration", "300"],
            "acceleration takes",
        ),
    ] {
        fails(&sim, args, 2, why);
    }

    let link = sim.link.clone();
    sim.stop();
    assert!(!link.exists(), "sim removes its link on exit");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn registers_lists_each_series_table() {
    let sts = common::stdout(&common::servobus_ok(&["registers", "--series", "sts"]));
    // Address, size, access and name, by hand from Feetech's STS table.
    says(
        &sts,
        &[
            "  42    2  RAM       goal_position",
            "  55    1  RAM       lock",
            "   6    1  EEPROM    baud_rate",
            "  56    2  read-only present_position",
        ],
    );
    assert!(!sts.contains("SCS servos"), "{sts}");
    let scs = common::stdout(&common::servobus_ok(&["registers", "--series", "scs"]));
    assert!(scs.contains("  48    1  RAM       lock"), "{scs}");
    let both = common::stdout(&common::servobus_ok(&["registers"]));
    assert!(
        both.contains("STS servos") && both.contains("SCS servos"),
        "{both}"
    );
    let out = common::servobus(&["registers", "--series", "xl"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn the_simulators_examples_are_built_in_and_listed() {
    let list = common::stdout(&common::servobus_ok(&["list"]));
    says(
        &list,
        &[
            "so101-mounting",
            "so101-hand",
            "--mounting NAME",
            "--hand NAME",
        ],
    );
    // By name (no file of that name in the working directory).
    let dir = common::scratch("sim-examples");
    let sim = Sim::start_with(&dir, &["--mounting", "so101-mounting"]);
    // The mounting puts shoulder_pan's zero (its rest) at tick 1300.
    assert_eq!(sim.read("1", "present_position"), 1300);
    sim.stop();
    // The hand loads and the simulator serves with it.
    Sim::start_with(&dir, &["--hand", "so101-hand"]).stop();
    let _ = std::fs::remove_dir_all(&dir);
}

/// Signals at swept moments of an EEPROM write: the helpers the tests of
/// `set-id`, `write`, `calibrate --write-servos` and `doctor --fix` share.
pub(crate) mod cut {
    use std::io::{BufRead, BufReader, Read};
    use std::process::{Command, Stdio};
    use std::sync::mpsc;
    use std::time::{Duration, Instant};

    use servobus_driver::{Bus, BusSettings, SerialTransport, SystemClock};
    use servobus_protocol::registers::Series;

    use crate::common::{repo, signal, BIN};

    /// The simulator's fault that widens the window: every reply 15 ms
    /// late, so that one EEPROM transaction lasts about 60 ms.
    pub(crate) const SLOW: &[&str] = &["--faults", "delay=1,delay_us=15000"];

    /// A command's `--latency-us` on [`SLOW`]: beyond its 15 ms.
    pub(crate) const LATENCY: &[&str] = &["--latency-us", "40000"];

    /// The STS lock register.
    const LOCK: usize = 55;

    /// The bus of the simulator at `port`, opened by the test itself
    /// (patient: [`SLOW`] delays every reply).
    pub(crate) fn bus(port: &str) -> Bus<SerialTransport<SystemClock>> {
        // A command the test just cut may still be exiting, holding the
        // port (it is refused as busy then): tried again for 10 s at most.
        let mut tries = 0;
        let transport = loop {
            match SerialTransport::open(port, 1_000_000, SystemClock::new()) {
                Ok(t) => break t,
                Err(_) if tries < 100 => {
                    tries += 1;
                    std::thread::sleep(Duration::from_millis(100));
                }
                Err(e) => panic!("pty {port}: {e:?}"),
            }
        };
        let settings = BusSettings::new(Series::Sts)
            .with_latency(Duration::from_millis(40))
            .with_retries(3);
        Bus::new(transport, settings)
    }

    /// A servo's EEPROM (addresses 0 to 39) and its lock byte, as read by
    /// the test; `None` when it does not answer.
    #[derive(Debug, Clone, PartialEq, Eq)]
    pub(crate) struct State {
        pub eeprom: Vec<u8>,
        pub lock: u8,
    }

    /// The state of servo `id` on `port`.
    pub(crate) fn state(port: &str, id: u8) -> Option<State> {
        let mut bus = bus(port);
        let mut bytes = [0u8; LOCK + 1];
        bus.read(id, 0, &mut bytes).ok()?;
        Some(State {
            eeprom: bytes[..40].to_vec(),
            lock: bytes[LOCK],
        })
    }

    /// The state of each of `ids`, which must answer.
    pub(crate) fn states(port: &str, ids: &[u8]) -> Vec<State> {
        ids.iter()
            .map(|&id| state(port, id).unwrap_or_else(|| panic!("servo {id} answers")))
            .collect()
    }

    /// How a cut run ended.
    #[derive(Debug)]
    pub(crate) struct Cut {
        /// The exit code; `None` when a signal ended the process (before
        /// it caught any).
        pub code: Option<i32>,
        pub stdout: String,
        pub stderr: String,
    }

    /// Runs `servobus ARGS` (stdout and stderr are pipes); once `after`
    /// lines of stdout contain `marker` (0: at its start), waits `wait`,
    /// then sends `signals` (names such as `INT`) 10 ms apart. Bounded: a
    /// run still going 20 s after the signals is killed and fails the test.
    pub(crate) fn run(
        args: &[&str],
        marker: &str,
        after: usize,
        wait: Duration,
        signals: &[&str],
    ) -> Cut {
        let mut child = Command::new(BIN)
            .args(args)
            .current_dir(repo(""))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start servobus");
        let (tx, rx) = mpsc::channel();
        let out = child.stdout.take().expect("stdout");
        let reader = std::thread::spawn(move || {
            let mut all = String::new();
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                let _ = tx.send(line.clone());
                all.push_str(&line);
                all.push('\n');
            }
            all
        });
        let mut err = child.stderr.take().expect("stderr");
        let errs = std::thread::spawn(move || {
            let mut all = String::new();
            let _ = err.read_to_string(&mut all);
            all
        });
        let mut seen = 0;
        let give_up = Instant::now() + Duration::from_secs(20);
        while seen < after {
            let left = give_up.saturating_duration_since(Instant::now());
            match rx.recv_timeout(left) {
                Ok(line) if line.contains(marker) => seen += 1,
                Ok(_) => {}
                // It ended (or hung) before the moment: no signal then.
                Err(_) => break,
            }
        }
        std::thread::sleep(wait);
        for (i, s) in signals.iter().enumerate() {
            if i > 0 {
                std::thread::sleep(Duration::from_millis(10));
            }
            signal(&child, s);
        }
        let deadline = Instant::now() + Duration::from_secs(20);
        let status = loop {
            if let Some(s) = child.try_wait().expect("wait") {
                break s;
            }
            if Instant::now() > deadline {
                let _ = child.kill();
                panic!("servobus {args:?} did not end 20 s after {signals:?}");
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        Cut {
            code: status.code(),
            stdout: reader.join().expect("stdout read"),
            stderr: errs.join().expect("stderr read"),
        }
    }

    /// The signals of sweep step `k`: SIGINT, SIGTERM, a double SIGINT.
    pub(crate) fn signals(k: usize) -> &'static [&'static str] {
        const KINDS: [&[&str]; 3] = [&["INT"], &["TERM"], &["INT", "INT"]];
        KINDS[k % KINDS.len()]
    }

    /// Every servo in `now` is locked and either as `before` or as `after`
    /// (fully written); which ones are written, by index.
    pub(crate) fn written(
        before: &[State],
        after: &[State],
        now: &[State],
        run: &Cut,
    ) -> Vec<usize> {
        let mut done = Vec::new();
        for (i, ((b, a), n)) in before.iter().zip(after).zip(now).enumerate() {
            assert_eq!(n.lock, 1, "servo #{i} left unlocked: {run:?}");
            if n.eeprom == a.eeprom {
                done.push(i);
            } else {
                assert_eq!(&n.eeprom, &b.eeprom, "servo #{i} half-written: {run:?}");
            }
        }
        done
    }
}

/// `set-id` cut by SIGINT, SIGTERM or a double SIGINT at swept moments:
/// the servo answers at exactly one of its IDs, locked, and the output says
/// whether it was given the new one.
#[test]
fn set_id_cut_by_a_signal_leaves_one_id_locked_and_says_which() {
    use std::time::Duration;
    let dir = common::scratch("set-id-cut");
    let sim = Sim::start_with(&dir, cut::SLOW);
    let port = sim.port().to_owned();
    let args = [
        &["set-id", "--port", &port, "--id", "1", "20"][..],
        cut::LATENCY,
    ]
    .concat();
    let (mut given, mut kept) = (0, 0);
    for k in 0..9 {
        let wait = Duration::from_millis(40 * k as u64);
        let run = cut::run(&args, "", 0, wait, cut::signals(k));
        let old = cut::state(&port, 1);
        let new = cut::state(&port, 20);
        let said = run.stdout.contains("servo 1 is now ID 20");
        match (old, new) {
            (None, Some(s)) => {
                assert_eq!(s.lock, 1, "{run:?}");
                assert!(said, "the new ID is not said: {run:?}");
                given += 1;
                // Back to ID 1 for the next moment.
                cut::bus(&port)
                    .write_eeprom(20, 5, &[1])
                    .expect("back to ID 1");
            }
            (Some(s), None) => {
                assert_eq!(s.lock, 1, "{run:?}");
                assert!(!said, "a new ID said but not given: {run:?}");
                kept += 1;
            }
            other => panic!("servo at both IDs or at neither ({other:?}): {run:?}"),
        }
        if run.code == Some(1) && run.stderr.contains("stopped by") {
            says(&run.stderr, &["stopped by SIG"]);
        }
    }
    assert!(
        given > 0 && kept > 0,
        "the sweep missed the write: {given} given, {kept} kept"
    );
}

/// `write` of an EEPROM register cut at swept moments: the register holds
/// the old value or the new one, the lock is closed, and the output says
/// which.
#[test]
fn an_eeprom_write_cut_by_a_signal_is_whole_or_not_at_all_and_locked() {
    use std::time::Duration;
    let dir = common::scratch("write-cut");
    let sim = Sim::start_with(&dir, cut::SLOW);
    let port = sim.port().to_owned();
    let args = [
        &[
            "write",
            "--port",
            &port,
            "--id",
            "2",
            "max_temperature",
            "61",
        ][..],
        cut::LATENCY,
    ]
    .concat();
    let before = cut::states(&port, &[2]);
    let mut after = before.clone();
    after[0].eeprom[13] = 61; // max_temperature
    assert_ne!(before[0].eeprom[13], 61);
    let (mut done, mut not) = (0, 0);
    for k in 0..9 {
        let wait = Duration::from_millis(35 * k as u64);
        let run = cut::run(&args, "", 0, wait, cut::signals(k));
        let now = cut::states(&port, &[2]);
        let written = cut::written(&before, &after, &now, &run);
        let said = run.stdout.lines().any(|l| {
            l.starts_with("max_temperature = 61")
                && l.ends_with("on servo 2 (unlocked, written, verified, locked)")
        });
        assert_eq!(said, !written.is_empty(), "{run:?}");
        if written.is_empty() {
            not += 1;
        } else {
            done += 1;
            cut::bus(&port)
                .write_eeprom(2, 13, &[before[0].eeprom[13]])
                .expect("put back");
        }
    }
    assert!(
        done > 0 && not > 0,
        "the sweep missed the write: {done} written, {not} not"
    );
}
