//! `--rerun FILE.rrd` and `--rerun-connect [ADDR]`: recordings made by
//! `play`, `plan`, `follow`, `stream` and `sim`, read back by Rerun's own
//! Python SDK (rerun-sdk, pinned to the release of the Rust crate) in
//! tests/rerun/read_back.py: the robot's tree composed against `servobus
//! fk`, the URDF's meshes, every joint's series, a walking body's pose in
//! the world, refusals as events. Built and run with `--features rerun`
//! (the gate does); without a Python with rerun-sdk the reading back is
//! skipped, said on stderr (under `CI=true` it fails instead).
#![cfg(feature = "rerun")]

mod common;

use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

use common::{arg, repo, scratch, servobus_in, SO101_JOINTS};

/// The SO-101 whose geometry and meshes come from its URDF.
const SO101_URDF: &str = "testdata/urdf/so101_urdf.yaml";

/// Its URDF.
const URDF: &str = "testdata/urdf/so101/so101_new_calib.urdf";

/// What the tests that read recordings back need, when it is missing.
const NEEDS_RERUN_PYTHON: &str = "reading recordings back needs a Python with rerun-sdk 0.36.3: \
                                  `eval \"$(scripts/python_clients.sh)\"` sets \
                                  SERVOBUS_RERUN_PYTHON";

/// A `.rrd` file begins so.
const RRD_MAGIC: &[u8] = b"RRF2";

/// The Python with rerun-sdk (`scripts/python_clients.sh` sets it), or
/// `None` (said on stderr) when there is none.
fn rerun_python() -> Option<std::ffi::OsString> {
    std::env::var_os("SERVOBUS_RERUN_PYTHON")
        .or_else(|| common::missing_outside(NEEDS_RERUN_PYTHON))
}

/// Runs tests/rerun/read_back.py with `args` when a Python with rerun-sdk
/// is there: every check passes.
fn read_back(args: &[&str]) {
    let Some(python) = rerun_python() else {
        return;
    };
    let out = Command::new(python)
        .arg(repo("tests/rerun/read_back.py"))
        .args(args)
        .output()
        .expect("run the Python reader");
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success() && !text.contains("FAIL"), "{text}");
    assert!(text.contains("PASS"), "no check ran: {text}");
}

/// Checks `recording`, of the SO-101 `robot` whose URDF is [`URDF`]: a
/// whole recording, read back as an arm.
fn read_back_arm(recording: &Path, robot: &Path) {
    is_recording(recording);
    let joints = SO101_JOINTS.join(",");
    read_back(&[
        "arm",
        arg(recording),
        common::BIN,
        arg(robot),
        arg(&repo(URDF)),
        &joints,
    ]);
}

/// Runs `servobus ARGS` in `dir`: it must succeed.
fn ok(dir: &Path, args: &[&str]) -> String {
    let out = servobus_in(dir, args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "servobus {args:?}: {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// The recording at `path` is there and is a `.rrd` file.
fn is_recording(path: &Path) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        bytes.starts_with(RRD_MAGIC),
        "{} is no .rrd",
        path.display()
    );
}

#[test]
fn play_of_the_urdf_so101_reads_back_as_its_meshes_on_its_joints_at_the_measured_angles() {
    let dir = scratch("rerun-play");
    let robot = repo(SO101_URDF);
    let stdout = ok(
        &dir,
        &[
            "play",
            "arm-wave",
            "--robot",
            arg(&robot),
            "--rerun",
            "run.rrd",
            "--fast",
        ],
    );
    assert!(stdout.contains("rerun: run.rrd"), "{stdout}");
    let run = dir.join("run.rrd");
    read_back_arm(&run, &robot);
}

#[test]
fn plan_of_the_walk_and_turn_reads_back_as_a_body_400_mm_ahead_turned_90_deg() {
    let dir = scratch("rerun-plan");
    let stdout = ok(&dir, &["plan", "hexapod-walk-turn", "--rerun", "plan.rrd"]);
    assert!(stdout.contains("rerun: plan.rrd"), "{stdout}");
    // 300 mm forward, a quarter turn left on the spot, then 100 mm to the
    // body's right: the world's +x again (configs/motions/hexapod-walk-turn.yaml).
    let plan = dir.join("plan.rrd");
    is_recording(&plan);
    read_back(&["walk", arg(&plan), common::BIN, "hexapod", "400", "0", "90"]);
}

#[test]
fn a_run_refused_at_its_port_is_recorded_with_the_refusal() {
    let dir = scratch("rerun-refused");
    let out = servobus_in(
        &dir,
        &[
            "play",
            "arm-wave",
            "--robot",
            arg(&repo(SO101_URDF)),
            "--port",
            "/dev/servobus-no-such-port",
            "--rerun",
            "refused.rrd",
        ],
    );
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let refused = dir.join("refused.rrd");
    is_recording(&refused);
    read_back(&["refusal", arg(&refused), "servobus-no-such-port"]);
}

#[test]
fn a_recording_that_cannot_be_made_is_refused_before_anything_moves() {
    let dir = scratch("rerun-cannot");
    // A directory that is not there.
    let out = servobus_in(
        &dir,
        &["play", "arm-wave", "--fast", "--rerun", "missing/run.rrd"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--rerun missing/run.rrd"), "{stderr}");
    assert!(stderr.contains("nothing was moved"), "{stderr}");
    // No viewer at the address: on loopback, a port free a moment ago.
    let port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
        l.local_addr().expect("addr").port()
    };
    let address = format!("rerun+http://127.0.0.1:{port}/proxy");
    let out = servobus_in(
        &dir,
        &["play", "arm-wave", "--fast", "--rerun-connect", &address],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no Rerun viewer listens at"), "{stderr}");
    assert!(
        String::from_utf8_lossy(&out.stdout).is_empty(),
        "nothing ran"
    );
    // A motion that does not load leaves an earlier recording as it was.
    let kept = dir.join("kept.rrd");
    std::fs::write(&kept, b"an earlier recording").expect("write");
    let out = servobus_in(
        &dir,
        &["plan", "no-such-motion.yaml", "--rerun", "kept.rrd"],
    );
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert_eq!(std::fs::read(&kept).expect("kept"), b"an earlier recording");
}

/// Writes `lines` to a child's stdin one every 20 ms, as a program
/// streaming targets does, then closes it and waits: its output.
fn feed(mut child: std::process::Child, lines: &[String]) -> std::process::Output {
    let mut stdin = child.stdin.take().expect("stdin");
    for line in lines {
        stdin.write_all(line.as_bytes()).expect("write a target");
        stdin.flush().expect("flush");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    drop(stdin);
    child.wait_with_output().expect("wait")
}

#[test]
fn stream_records_the_targets_it_follows() {
    let dir = scratch("rerun-stream");
    let robot = repo(SO101_URDF);
    let lines: Vec<String> = (0..150)
        .map(|k| {
            let t = f64::from(k) * 0.02;
            let pan = 30.0 * (t * 2.0).sin();
            format!("{{\"joints\": {{\"shoulder_pan\": {pan:.3}, \"elbow_flex\": 60}}}}\n")
        })
        .collect();
    let child = Command::new(common::BIN)
        .args(["stream", "--robot", arg(&robot), "--rerun", "stream.rrd"])
        .current_dir(&dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("servobus stream");
    let out = feed(child, &lines);
    assert!(out.status.success(), "{out:?}");
    let recording = dir.join("stream.rrd");
    read_back_arm(&recording, &robot);
}

#[test]
fn follow_records_the_follower_and_its_goals() {
    let dir = scratch("rerun-follow");
    let robot = repo(SO101_URDF);
    let stdout = ok(
        &dir,
        &[
            "follow",
            "--robot",
            arg(&robot),
            "--leader-hand",
            "so101-hand",
            "--seconds",
            "3",
            "--rerun",
            "follow.rrd",
        ],
    );
    assert!(stdout.contains("rerun: follow.rrd"), "{stdout}");
    let recording = dir.join("follow.rrd");
    read_back_arm(&recording, &robot);
}

#[test]
fn sim_records_its_truth_as_a_hand_moves_the_arm() {
    let dir = scratch("rerun-sim");
    let robot = repo(SO101_URDF);
    let recording = dir.join("sim.rrd");
    let sim = common::Sim::start_robot(
        &dir,
        &robot,
        6,
        &["--hand", "so101-hand", "--rerun", arg(&recording)],
    );
    // The hand holds the arm still for 2 s, then raises it.
    sim.wait_until(4.0);
    sim.stop();
    is_recording(&recording);
    let joints = SO101_JOINTS.join(",");
    read_back(&[
        "truth",
        arg(&recording),
        common::BIN,
        arg(&robot),
        arg(&repo(URDF)),
        &joints,
    ]);
}
