//! `servobus serve` on loopback: a Python client (eclipse-zenoh) follows
//! `state`, decodes ROS 2 JointState and moves the arm; an unauthenticated
//! peer cannot; `stop` stops the motion and the node goes on serving until
//! `shutdown`; three robots start a motion together. Every endpoint is
//! an explicit `tcp/127.0.0.1:<port>`; scouting by multicast is off.
//! Built and run with `--features zenoh` (the gate does).
#![cfg(feature = "zenoh")]

mod common;
#[path = "zenoh/serve_ros2.rs"]
mod serve_ros2;

use std::process::Command;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::Running;
use servobus_node::zenoh::{self, Wait};

/// The node tests each run several processes at 100-200 Hz: one at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A loopback port free a moment ago.
fn free_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
    l.local_addr().expect("addr").port()
}

fn endpoint(port: u16) -> String {
    format!("tcp/127.0.0.1:{port}")
}

/// A Zenoh peer of the test, connected to `to` only.
fn peer(to: &[String], extra: &[(&str, &str)]) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"peer\"").expect("mode");
    c.insert_json5("scouting/multicast/enabled", "false")
        .expect("scouting");
    c.insert_json5("listen/endpoints", "[]").expect("listen");
    let to = serde_json::to_string(to).expect("json");
    c.insert_json5("connect/endpoints", &to).expect("connect");
    for (k, v) in extra {
        c.insert_json5(k, v).expect("config");
    }
    zenoh::open(c).wait().expect("open a zenoh session")
}

/// Waits until the node's `state` is seen from `session`.
fn wait_for_state(session: &zenoh::Session, robot: &str) -> bool {
    let sub = session
        .declare_subscriber(format!("servobus/{robot}/state"))
        .wait()
        .expect("subscribe");
    sub.recv_timeout(Duration::from_secs(30))
        .ok()
        .flatten()
        .is_some()
}

/// The last JSON line of a finished serve's stdout.
fn last_json(out: &str) -> serde_json::Value {
    let line = out.lines().last().unwrap_or_default();
    serde_json::from_str(line).unwrap_or_else(|e| panic!("not JSON ({e}): {out}"))
}

/// What the tests that need a Python with eclipse-zenoh say when ignored.
const NEEDS_ZENOH_PYTHON: &str = "needs a Python with eclipse-zenoh 1.10.1 and rosbags: \
                                  `eval \"$(scripts/python_clients.sh)\"` sets \
                                  SERVOBUS_ZENOH_PYTHON; the gate runs it with --include-ignored";

/// The Python with eclipse-zenoh and rosbags (`scripts/python_clients.sh`
/// sets it); the tests that need it are ignored by default, and fail
/// without it when run.
fn zenoh_python() -> std::ffi::OsString {
    std::env::var_os("SERVOBUS_ZENOH_PYTHON").unwrap_or_else(|| panic!("{NEEDS_ZENOH_PYTHON}"))
}

#[test]
#[ignore = "needs a Python with eclipse-zenoh: see NEEDS_ZENOH_PYTHON"]
fn a_python_client_reads_state_and_joint_states_moves_the_arm_and_reads_the_report() {
    let python = zenoh_python();
    let _one = serial();
    let port = free_port();
    let ep = endpoint(port);
    let serve = Running::start(&[
        "serve",
        "--robot",
        "so101",
        "--listen",
        &ep,
        "--ros2",
        "--ros-domain",
        "5",
        "--linger",
        "4",
        "--json",
    ]);
    let client = common::repo("tests/zenoh/client.py");
    let out = Command::new(python)
        .arg(&client)
        .args([&ep, "so101", "5"])
        .output()
        .expect("run the Python client");
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}{}", String::from_utf8_lossy(&out.stderr));
    let (status, stdout, stderr) = serve.finish();
    assert!(
        out.status.success(),
        "the client failed:\n{text}\nserve: {stderr}"
    );
    assert!(!text.contains("FAIL"), "{text}");
    // The client's summary, and the node's own account.
    let summary: serde_json::Value =
        serde_json::from_str(text.lines().last().unwrap_or_default()).expect("summary");
    assert!(
        summary["failures"].as_array().is_some_and(Vec::is_empty),
        "{summary}"
    );
    assert!(status.success(), "serve: {stderr}");
    let doc = last_json(&stdout);
    assert_eq!(doc["report"]["finish"], "stopped", "{doc}");
    assert!(doc["node"]["malformed"].as_u64() >= Some(5), "{doc}");
    assert!(doc["node"]["targets"].as_u64() > Some(30), "{doc}");
}

#[test]
#[ignore = "needs a Python with eclipse-zenoh: see NEEDS_ZENOH_PYTHON"]
fn the_python_example_drives_the_elbow_and_prints_the_report() {
    // examples/python/zenoh_sine.py as the README runs it: ten seconds of
    // a sine to the elbow, then `shutdown`, then the report.
    let python = zenoh_python();
    let _one = serial();
    let port = free_port();
    let ep = endpoint(port);
    let serve = Running::start(&["serve", "--robot", "so101", "--listen", &ep, "--json"]);
    let example = common::repo("examples/python/zenoh_sine.py");
    let out = Command::new(python)
        .arg(&example)
        .args([&ep, "so101"])
        .output()
        .expect("run the example");
    let text = String::from_utf8_lossy(&out.stdout);
    let (status, stdout, stderr) = serve.finish();
    assert!(
        out.status.success(),
        "the example failed:\n{text}{}\nserve: {stderr}",
        String::from_utf8_lossy(&out.stderr)
    );
    // It printed the elbow's measured angle moving, then the report.
    let measured: Vec<f64> = text
        .split("measured")
        .skip(1)
        .filter_map(|s| s.split_whitespace().next()?.parse().ok())
        .collect();
    let (lo, hi) = measured
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &q| {
            (a.min(q), b.max(q))
        });
    assert!(hi - lo > 30.0, "the elbow hardly moved: {lo}..{hi}\n{text}");
    let report = text
        .find("\n{")
        .map(|i| &text[i + 1..])
        .unwrap_or_else(|| panic!("no report printed:\n{text}"));
    let report: serde_json::Value =
        serde_json::from_str(report).unwrap_or_else(|e| panic!("{e}: {report}"));
    assert_eq!(report["report"]["finish"], "stopped", "{report}");
    assert!(status.success(), "serve: {stderr}");
    assert!(
        last_json(&stdout)["node"]["targets"].as_u64() > Some(200),
        "{stdout}"
    );
}

#[test]
fn a_peer_without_credentials_cannot_move_or_stop_the_robot() {
    let _one = serial();
    let dir = common::scratch("serve-auth");
    let port = free_port();
    let ep = endpoint(port);
    let dict = common::write_file(&dir, "users.txt", "robot:s3cret\n");
    let config = format!(
        r#"{{
  mode: "peer",
  listen: {{ endpoints: ["{ep}"] }},
  scouting: {{ multicast: {{ enabled: false }} }},
  transport: {{ auth: {{ usrpwd: {{ user: "robot", password: "s3cret", dictionary_file: "{}" }} }} }},
}}"#,
        dict.display()
    );
    let config = common::write_file(&dir, "zenoh.json5", &config);
    let serve = Running::start(&[
        "serve",
        "--robot",
        "so101",
        "--zenoh-config",
        common::arg(&config),
        "--linger",
        "1",
        "--json",
    ]);
    let credentials = [
        ("transport/auth/usrpwd/user", "\"robot\""),
        ("transport/auth/usrpwd/password", "\"s3cret\""),
    ];
    let friend = peer(std::slice::from_ref(&ep), &credentials);
    assert!(
        wait_for_state(&friend, "so101"),
        "the authenticated peer sees state"
    );

    // A stranger: targets and a stop, for a second.
    let stranger = peer(std::slice::from_ref(&ep), &[]);
    let until = Instant::now() + Duration::from_secs(1);
    while Instant::now() < until {
        let _ = stranger
            .put("servobus/so101/target", r#"{"joints": {"elbow_flex": 40}}"#)
            .wait();
        let _ = stranger.put("servobus/so101/command", "stop").wait();
        std::thread::sleep(Duration::from_millis(50));
    }
    // Still running: the stranger's stop never arrived.
    let replies = friend
        .get("servobus/so101/report")
        .timeout(Duration::from_secs(5))
        .wait()
        .expect("query");
    let reply = replies
        .recv_timeout(Duration::from_secs(10))
        .ok()
        .flatten()
        .expect("a reply");
    let doc: serde_json::Value =
        serde_json::from_slice(&reply.result().expect("a report").payload().to_bytes())
            .expect("JSON");
    assert_eq!(doc["running"], true, "{doc}");
    friend
        .put("servobus/so101/command", "shutdown")
        .wait()
        .expect("shutdown");
    let (status, stdout, stderr) = serve.finish();
    assert!(status.success(), "{stderr}");
    let doc = last_json(&stdout);
    assert_eq!(
        doc["node"]["targets"], 0,
        "no target of the stranger's: {doc}"
    );
    assert_eq!(
        doc["node"]["commands"], 1,
        "the friend's shutdown only: {doc}"
    );
    assert_eq!(doc["report"]["finish"], "stopped");
}

/// Every `state` seen from `session`: its `t` and its commanded angles by
/// joint name. The subscriber lives as long as the session.
fn watch_states(session: &zenoh::Session, robot: &str) -> Arc<Mutex<Vec<(f64, Commanded)>>> {
    let seen = Arc::new(Mutex::new(Vec::new()));
    let keep = Arc::clone(&seen);
    session
        .declare_subscriber(format!("servobus/{robot}/state"))
        .callback(move |sample| {
            let Ok(doc) = serde_json::from_slice::<serde_json::Value>(&sample.payload().to_bytes())
            else {
                return;
            };
            let (Some(t), Some(names), Some(angles)) = (
                doc["t"].as_f64(),
                doc["joints"].as_array(),
                doc["commanded"].as_array(),
            ) else {
                return;
            };
            let commanded = names
                .iter()
                .zip(angles)
                .filter_map(|(n, a)| Some((n.as_str()?.to_string(), a.as_f64()?)))
                .collect();
            keep.lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .push((t, commanded));
        })
        .background()
        .wait()
        .expect("subscribe to state");
    seen
}

/// Commanded angles by joint name, as `state` gives them.
type Commanded = Vec<(String, f64)>;

fn angle(c: &Commanded, joint: &str) -> f64 {
    c.iter()
        .find(|(n, _)| n == joint)
        .map_or(f64::NAN, |(_, a)| *a)
}

/// The states seen after `since` (s of the run).
fn states_after(seen: &Mutex<Vec<(f64, Commanded)>>, since: f64) -> Vec<(f64, Commanded)> {
    let seen = seen
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    seen.iter().filter(|(t, _)| *t > since).cloned().collect()
}

/// The largest change of any joint's commanded angle over `states`.
fn spread(states: &[(f64, Commanded)]) -> f64 {
    let Some((_, first)) = states.first() else {
        return f64::NAN;
    };
    first
        .iter()
        .map(|(name, _)| {
            let a: Vec<f64> = states.iter().map(|(_, c)| angle(c, name)).collect();
            a.iter().copied().fold(f64::MIN, f64::max) - a.iter().copied().fold(f64::MAX, f64::min)
        })
        .fold(0.0, f64::max)
}

/// The `t` of the newest state seen.
fn newest(seen: &Mutex<Vec<(f64, Commanded)>>) -> f64 {
    states_after(seen, f64::MIN).last().map_or(0.0, |s| s.0)
}

#[test]
fn stop_stops_the_motion_and_the_node_serves_on_until_shutdown() {
    let _one = serial();
    let ep = endpoint(free_port());
    let serve = Running::start(&[
        "serve", "--robot", "so101", "--listen", &ep, "--linger", "1", "--json",
    ]);
    let operator = peer(std::slice::from_ref(&ep), &[]);
    assert!(wait_for_state(&operator, "so101"), "the node serves");
    let seen = watch_states(&operator, "so101");
    let put = |key: &str, what: &str| {
        operator
            .put(format!("servobus/so101/{key}"), what)
            .wait()
            .expect("put");
    };
    // The wave plays for 5.4 s; stopped once it moves.
    put("command", "play arm-wave");
    let deadline = Instant::now() + Duration::from_secs(20);
    let started = loop {
        assert!(Instant::now() < deadline, "the wave never moved");
        std::thread::sleep(Duration::from_millis(100));
        let t = newest(&seen);
        if t > 0.0 && spread(&states_after(&seen, t - 0.2)) > 1.0 {
            break t;
        }
    };
    put("command", "stop");
    // A jerk-limited stop takes well under a second; then 2.5 s more of
    // `state`, the joints held, where the wave would have gone on moving.
    std::thread::sleep(Duration::from_millis(1000));
    let held_from = newest(&seen);
    std::thread::sleep(Duration::from_millis(2500));
    let held = states_after(&seen, held_from);
    let span = held.last().map_or(0.0, |s| s.0) - held_from;
    assert!(span > 2.0, "state goes on after stop: {span} s of it");
    assert!(held.len() > 50, "{} states in {span} s", held.len());
    assert!(
        held_from < started + 4.0,
        "stopped within the wave: {started} -> {held_from}"
    );
    let still = spread(&held);
    assert!(still < 1e-6, "held after stop: {still} deg");
    // `resume` does not bring the stopped wave back.
    put("command", "resume");
    std::thread::sleep(Duration::from_millis(500));
    let after = states_after(&seen, held_from);
    assert!(spread(&after) < 1e-6, "resume after stop leaves it held");
    // A target moves the arm again.
    let goal = -20.0;
    let deadline = Instant::now() + Duration::from_secs(20);
    let moved = loop {
        assert!(Instant::now() < deadline, "the target never moved the arm");
        put(
            "target",
            &format!(r#"{{"joints": {{"elbow_flex": {goal}}}}}"#),
        );
        std::thread::sleep(Duration::from_millis(33));
        let last = states_after(&seen, newest(&seen) - 0.01);
        if let Some((_, c)) = last.last() {
            if (angle(c, "elbow_flex") - goal).abs() < 0.5 {
                break angle(c, "elbow_flex");
            }
        }
    };
    println!("stopped at {held_from:.2} s, then followed to {moved:.2} deg");
    put("command", "shutdown");
    let (status, stdout, stderr) = serve.finish();
    assert!(status.success(), "{stderr}");
    let doc = last_json(&stdout);
    assert_eq!(doc["report"]["finish"], "stopped", "{doc}");
    assert_eq!(
        doc["node"]["commands"], 3,
        "play, stop and shutdown (not resume): {doc}"
    );
    assert!(doc["node"]["targets"].as_u64() > Some(0), "{doc}");
    assert!(stderr.contains("stopped, not paused"), "{stderr}");
}

#[test]
fn ctrl_c_ends_the_node_as_shutdown_does_after_its_linger_for_report() {
    let _one = serial();
    let ep = endpoint(free_port());
    let serve = Running::start(&[
        "serve", "--robot", "so101", "--listen", &ep, "--linger", "3", "--json",
    ]);
    let client = peer(std::slice::from_ref(&ep), &[]);
    assert!(wait_for_state(&client, "so101"), "the node serves");
    serve.interrupt();
    // Within the linger, `report` answers with the finished run.
    let deadline = Instant::now() + Duration::from_secs(10);
    let doc = loop {
        assert!(
            Instant::now() < deadline,
            "no finished report in the linger"
        );
        std::thread::sleep(Duration::from_millis(100));
        let Ok(replies) = client
            .get("servobus/so101/report")
            .timeout(Duration::from_secs(1))
            .wait()
        else {
            continue;
        };
        let reply = replies.recv_timeout(Duration::from_secs(2)).ok().flatten();
        let Some(Ok(sample)) = reply.map(|r| r.into_result()) else {
            continue;
        };
        let doc: serde_json::Value =
            serde_json::from_slice(&sample.payload().to_bytes()).expect("JSON");
        if doc["running"] == false {
            break doc;
        }
    };
    assert_eq!(doc["report"]["finish"], "stopped", "{doc}");
    let (status, stdout, stderr) = serve.finish();
    assert!(status.success(), "{stderr}");
    assert_eq!(last_json(&stdout)["report"]["finish"], "stopped");
}

#[test]
fn three_robots_start_a_motion_on_the_same_control_cycle() {
    let _one = serial();
    let period = 1.0 / 100.0;
    let ports: Vec<String> = (0..3).map(|_| endpoint(free_port())).collect();
    let mut robots = Vec::new();
    for (i, ep) in ports.iter().enumerate() {
        let name = format!("arm{i}");
        robots.push(Running::start(&[
            "serve", "--robot", "so101", "--name", &name, "--group", "troupe", "--listen", ep,
            "--rate", "100", "--linger", "0.5", "--json",
        ]));
    }
    let conductor = peer(&ports, &[]);
    for i in 0..3 {
        assert!(
            wait_for_state(&conductor, &format!("arm{i}")),
            "arm{i} serves"
        );
    }
    // `play --zenoh-group` tells every member, through the robots' own
    // endpoints, to start two seconds from now.
    let mut args = vec![
        "play",
        "arm-wave",
        "--zenoh-group",
        "troupe",
        "--start-in",
        "2s",
    ];
    for ep in &ports {
        args.extend(["--connect", ep.as_str()]);
    }
    let told = common::servobus_ok(&args);
    let said = common::stdout(&told);
    assert!(said.contains("3 robot(s)"), "{said}");
    std::thread::sleep(Duration::from_millis(2500));
    conductor
        .put("servobus/group/troupe/command", "shutdown")
        .wait()
        .expect("shutdown");
    let mut offsets = Vec::new();
    for r in robots {
        let (status, stdout, stderr) = r.finish();
        assert!(status.success(), "{stderr}");
        let doc = last_json(&stdout);
        let o = doc["node"]["start_offsets_s"][0]
            .as_f64()
            .unwrap_or_else(|| panic!("a start offset: {doc}"));
        offsets.push(o);
    }
    println!(
        "start offsets (ms): {:?}",
        offsets.iter().map(|o| o * 1e3).collect::<Vec<_>>()
    );
    // Each starts on the first cycle at or after the instant: within one
    // period of it (plus 2 ms for a cycle started late on a loaded machine).
    let slack = 0.002;
    for o in &offsets {
        assert!(
            (-1e-4..period + slack).contains(o),
            "offset {o} s, period {period} s"
        );
    }
    let spread = offsets.iter().copied().fold(f64::MIN, f64::max)
        - offsets.iter().copied().fold(f64::MAX, f64::min);
    assert!(spread < period + slack, "spread {spread} s");
}
