//! Every numeric option of every command, given 0, -1, NaN, inf, 1e-300
//! and 1e300: each run exits 0, 1 or 2, never 101 (a panic) or by a
//! signal. A value out of range is a usage error (exit 2) said at once; a
//! value taken runs, bounded.
//!
//! The options come from each command's `--help`: every option that takes
//! a value is either swept here ([`NUMERIC`], with the arguments that make
//! the rest of the command line valid) or named as taking no number
//! ([`NOT_NUMERIC`]), so an option added to the command line without a
//! place in one of the two lists fails this test. Numbers given as
//! positional arguments are listed in [`POSITIONAL`].
//!
//! Built with `--features zenoh`, `serve` and `play --zenoh-group` are
//! swept too ([`ZENOH_NUMERIC`]).
//!
//! Bounds: every run is on the built-in simulator (virtual time where the
//! command has it) or on a port that does not exist; one still running
//! after [`BOUND`] is sent SIGTERM (as a user would stop a server) and
//! must then end, by exiting 0, 1 or 2 or by that signal. The runs go four
//! at a time.

use crate::common;

use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::ExitStatus;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use common::scratch;

/// The values every numeric option is given.
const HOSTILE: [&str; 6] = ["0", "-1", "NaN", "inf", "1e-300", "1e300"];

/// How long a run may go on before it is stopped with SIGTERM.
const BOUND: Duration = Duration::from_secs(4);

/// Runs at once.
const THREADS: usize = 4;

/// `(command line before the option, the option, its value with `V` for
/// the number)`. `P` in a command line is a port that does not exist, `O`
/// a file in the run's scratch directory.
const NUMERIC: &[(&str, &str, &str)] = &[
    ("play arm-wave --fast", "--rate", "V"),
    ("play arm-wave --fast", "--core", "V"),
    ("play arm-wave --fast", "--fifo", "V"),
    ("play arm-wave --fast", "--sim-pose", "V,0,0,0,0,0"),
    ("budget --robot so101", "--rate", "V"),
    ("bench --robot so101", "--seconds", "V"),
    ("scan --port P", "--latency-us", "V"),
    ("scan --port P", "--baud", "V"),
    ("ping --port P --id 1", "--latency-us", "V"),
    ("ping --port P --id 1", "--baud", "V"),
    ("ping --port P", "--id", "V"),
    ("read --port P --id 1 present_position", "--latency-us", "V"),
    ("read --port P --id 1 present_position", "--baud", "V"),
    ("read --port P present_position", "--id", "V"),
    (
        "write --port P --id 1 goal_position 2048",
        "--latency-us",
        "V",
    ),
    ("write --port P --id 1 goal_position 2048", "--baud", "V"),
    ("write --port P goal_position 2048", "--id", "V"),
    ("set-id --port P --id 1 2", "--latency-us", "V"),
    ("set-id --port P --id 1 2", "--baud", "V"),
    ("set-id --port P 2", "--id", "V"),
    ("teach --robot so101 -o O --continuous", "--tolerance", "V"),
    ("teach --robot so101 -o O", "--duration", "V"),
    ("monitor --robot so101 --json --count 1", "--rate", "V"),
    ("monitor --robot so101 --json", "--count", "V"),
    ("stream --robot so101", "--rate", "V"),
    ("stream --robot so101", "--timeout", "V"),
    ("follow --robot so101", "--seconds", "V"),
    ("fk --robot so101", "--pose", "{shoulder_pan: V}"),
    ("ik --robot so101 --frame tool", "--xyz", "V,0,200"),
    (
        "ik --robot so101 --frame tool --xyz 200,0,200",
        "--pitch",
        "V",
    ),
    (
        "ik --robot so101 --frame tool --xyz 200,0,200",
        "--roll",
        "V",
    ),
    ("sim --robot so101 --link O", "--unit", "V"),
    ("sim --robot so101 --link O", "--faults", "drop=V"),
    (
        "sim --robot so101 --link O",
        "--faults",
        "delay=1,delay_us=V",
    ),
    ("sim --robot so101 --link O", "--faults", "seed=V"),
];

/// With `--features zenoh` (the gate's Zenoh step runs this sweep so
/// built): `serve`'s numeric options, and `play --zenoh-group`'s. Each
/// node listens on a loopback port the system picks (`:0`), so that four
/// run at once, and lingers for no time after the SIGTERM that ends it.
/// The conductor connects to a loopback port where nothing serves (9,
/// discard): it finds no robot and ends.
#[cfg(feature = "zenoh")]
const ZENOH_NUMERIC: &[(&str, &str, &str)] = &[
    (
        "serve --robot so101 --listen tcp/127.0.0.1:0 --linger 0",
        "--state-hz",
        "V",
    ),
    (
        "serve --robot so101 --listen tcp/127.0.0.1:0 --linger 0 --ros2",
        "--ros-domain",
        "V",
    ),
    (
        "serve --robot so101 --listen tcp/127.0.0.1:0 --linger 0",
        "--rate",
        "V",
    ),
    (
        "serve --robot so101 --listen tcp/127.0.0.1:0 --linger 0",
        "--timeout",
        "V",
    ),
    (
        "serve --robot so101 --listen tcp/127.0.0.1:0",
        "--linger",
        "V",
    ),
    (
        "play arm-wave --zenoh-group g --connect tcp/127.0.0.1:9",
        "--start-in",
        "V",
    ),
];

/// Without the `zenoh` feature there is no `serve` and no group play.
#[cfg(not(feature = "zenoh"))]
const ZENOH_NUMERIC: &[(&str, &str, &str)] = &[];

/// Every numeric option swept in this build: [`NUMERIC`], and
/// [`ZENOH_NUMERIC`] when the build has them.
fn numeric() -> impl Iterator<Item = &'static (&'static str, &'static str, &'static str)> {
    NUMERIC.iter().chain(ZENOH_NUMERIC)
}

/// Numbers given as positional arguments: `(command line, with V for the
/// number)`.
const POSITIONAL: &[&str] = &[
    "write --port P --id 1 goal_position V",
    "set-id --port P --id 1 V",
    "decode V",
];

/// `(command, option)`: options that take a value with no number in it
/// (paths, names, choices).
const NOT_NUMERIC: &[(&str, &str)] = &[
    ("*", "--robot"),
    ("*", "--port"),
    ("*", "--calibration"),
    ("*", "--log"),
    ("*", "--plot"),
    ("*", "--rerun"),
    ("*", "--bus"),
    ("*", "--output"),
    ("calibrate", "--from-lerobot"),
    ("calibrate", "--to-lerobot"),
    ("sim", "--link"),
    ("sim", "--mounting"),
    ("sim", "--hand"),
    ("sim", "--truth"),
    ("teach", "--hold"),
    ("registers", "--series"),
    ("decode", "--from"),
    ("decode", "--model"),
    ("follow", "--leader"),
    ("follow", "--leader-robot"),
    ("follow", "--leader-calibration"),
    ("follow", "--leader-hand"),
    ("follow", "--record"),
    ("follow", "--limits"),
    ("ik", "--frame"),
    // `serve` and `play`'s group options (built with --features zenoh).
    ("serve", "--zenoh-config"),
    ("serve", "--listen"),
    ("serve", "--connect"),
    ("serve", "--name"),
    ("serve", "--group"),
    ("serve", "--ros-namespace"),
    ("play", "--zenoh-group"),
    ("play", "--connect"),
];

/// The commands `servobus --help` lists.
fn commands() -> Vec<String> {
    let help = common::stdout(&common::servobus(&["--help"]));
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_owned)
        .collect()
}

/// The options of `command` that take a value (`--name <VALUE>` in its
/// `--help`).
fn value_options(command: &str) -> Vec<String> {
    let help = common::stdout(&common::servobus(&[command, "--help"]));
    help.lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l.strip_prefix("-o, ").unwrap_or(l);
            let (name, rest) = l.strip_prefix("--")?.split_once(' ')?;
            rest.starts_with('<').then(|| format!("--{name}"))
        })
        .collect()
}

#[test]
fn every_option_that_takes_a_value_is_swept_or_takes_no_number() {
    let commands = commands();
    assert!(commands.len() > 20, "commands listed: {commands:?}");
    let mut unlisted = Vec::new();
    for command in &commands {
        for option in value_options(command) {
            let swept = numeric().any(|(line, o, _)| {
                *o == option && line.split_whitespace().next() == Some(command.as_str())
            });
            let named = NOT_NUMERIC
                .iter()
                .any(|(c, o)| *o == option && (*c == "*" || c == command));
            if !swept && !named {
                unlisted.push(format!("{command} {option}"));
            }
        }
    }
    assert!(
        unlisted.is_empty(),
        "options neither swept nor named as taking no number: {unlisted:?}"
    );
    // And the other way: each option swept is one the command has.
    for (line, option, _) in numeric() {
        let command = line.split_whitespace().next().unwrap_or("");
        assert!(
            value_options(command).iter().any(|o| o == option),
            "`{command}` has no {option} in its --help"
        );
    }
}

/// How a run ended.
struct Ended {
    status: ExitStatus,
    /// Whether it was sent SIGTERM for running past [`BOUND`].
    stopped: bool,
    stderr: String,
}

impl Ended {
    /// Exited 0, 1 or 2, or ended by the SIGTERM it was sent, and said no
    /// panic.
    fn fine(&self) -> bool {
        let code_ok = matches!(self.status.code(), Some(0..=2));
        let stopped_ok = self.stopped && self.status.signal() == Some(libc::SIGTERM);
        (code_ok || stopped_ok) && !self.stderr.contains("panicked")
    }
}

/// One run: `args` in `dir`, stdin empty, stopped with SIGTERM after
/// [`BOUND`].
fn run(dir: &Path, args: &[String]) -> Ended {
    let mut child = common::spawn_stderr_piped(dir, args);
    let mut stderr = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = std::io::Read::read_to_string(&mut stderr, &mut text);
        text
    });
    let start = Instant::now();
    let mut stopped = false;
    // Bounded: SIGTERM at BOUND, SIGKILL (a failure) at twice BOUND.
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if !stopped && start.elapsed() > BOUND {
            stopped = common::signal(&child, "TERM");
        }
        if start.elapsed() > 2 * BOUND {
            let _ = child.kill();
            break child.wait().expect("wait");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Ended {
        status,
        stopped,
        stderr: reader.join().unwrap_or_default(),
    }
}

/// Every command line of the sweep, its words with `P`, `O` and `V`
/// replaced.
fn cases(dir: &Path) -> Vec<Vec<String>> {
    let port = dir.join("no-such-port").display().to_string();
    let words = |line: &str, out: &str| -> Vec<String> {
        line.split_whitespace()
            .map(|w| match w {
                "P" => port.clone(),
                "O" => dir.join(out).display().to_string(),
                _ => w.to_owned(),
            })
            .collect()
    };
    let mut all = Vec::new();
    for (n, (line, option, value)) in numeric().enumerate() {
        for v in HOSTILE {
            let mut args = words(line, &format!("out-{n}-{v}"));
            args.push(format!("{option}={}", value.replace('V', v)));
            all.push(args);
        }
    }
    for (n, line) in POSITIONAL.iter().enumerate() {
        for v in HOSTILE {
            let mut args = words(line, &format!("pos-{n}-{v}"));
            // `--` lets a negative number through as the value it is.
            let at = args.iter().position(|w| w == "V").expect("a V");
            args[at] = v.to_owned();
            args.insert(at, "--".to_owned());
            all.push(args);
        }
    }
    all
}

#[test]
fn no_numeric_option_panics_on_hostile_values() {
    let dir = scratch("sweep");
    let queue = Mutex::new(cases(&dir));
    let failed = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..THREADS {
            s.spawn(|| loop {
                let Some(args) = queue.lock().unwrap_or_else(|e| e.into_inner()).pop() else {
                    break;
                };
                let ended = run(&dir, &args);
                if !ended.fine() {
                    let err = &ended.stderr;
                    let line = err.lines().find(|l| l.contains("panicked")).unwrap_or("");
                    failed
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .push(format!(
                            "servobus {}: {} {line}",
                            args.join(" "),
                            ended.status
                        ));
                }
            });
        }
    });
    let failed = failed.into_inner().unwrap_or_else(|e| e.into_inner());
    assert!(failed.is_empty(), "{}", failed.join("\n"));
    let _ = std::fs::remove_dir_all(&dir);
}
