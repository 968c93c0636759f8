//! `servobus sim` with a body on a pty: a mounting, a hand and the truth
//! file, while a client reads positions.

use crate::common;

use std::time::{Duration, Instant};

use common::{arg, read_truth, repo, scratch, servobus_fails, write_file, Sim};

/// Ticks per degree of an STS3215.
const TPD: f64 = 4096.0 / 360.0;

/// The tick a servo mounted with its zero at `zero` and direction `dir`
/// reads at `angle` degrees.
fn raw(zero: f64, dir: f64, angle: f64) -> i64 {
    ((zero + dir * angle * TPD).round() as i64).rem_euclid(4096)
}

#[test]
fn sim_with_mounting_hand_and_truth_on_a_pty() {
    let dir = scratch("sim-body");
    // Lift from -90 to +40 deg between 1 and 2 s: across its servo's seam
    // in the shipped mounting (zero tick 3900). The hand then lets go.
    let hand = "keyframes:\n  - {at: 0, pose: {shoulder_lift: -90}}\n  - {at: 1, pose: {shoulder_lift: -90}}\n  - {at: 2, pose: {shoulder_lift: 40}}\n";
    let mounting = repo("configs/sim/so101-mounting.yaml");
    let robot = repo("configs/robots/so101.yaml");
    let started = Instant::now();
    let (sim, truth) = Sim::start_hand(&dir, &robot, 6, hand, &["--mounting", arg(&mounting)]);
    std::thread::sleep(Duration::from_millis(2500).saturating_sub(started.elapsed()));
    // The hand has let go at +40 deg: tick 3900 + 40 * 4096 / 360 = 4355 -> 259.
    let lift = sim.read("2", "present_position");
    assert!(
        (lift - raw(3900.0, 1.0, 40.0)).abs() <= 1,
        "lift reads {lift}"
    );
    // The elbow (reversed, zero 2500) rests at its home, 90 deg.
    let elbow = sim.read("3", "present_position");
    assert!(
        (elbow - raw(2500.0, -1.0, 90.0)).abs() <= 1,
        "elbow reads {elbow}"
    );
    std::thread::sleep(Duration::from_millis(3500).saturating_sub(started.elapsed()));
    let ran = started.elapsed().as_secs_f64();
    sim.stop();

    let (header, rows) = read_truth(&truth);
    assert_eq!(
        header.join(","),
        "time_s,shoulder_pan,shoulder_lift,elbow_flex,wrist_flex,wrist_roll,gripper"
    );
    let last = rows.last().expect("rows")[0];
    assert!(
        last > 3.0 && last < ran + 0.1,
        "ran {ran} s, truth to {last} s"
    );
    let per_second = (rows.len() - 1) as f64 / last;
    assert!(per_second >= 50.0, "{per_second} rows a second");
    let at = |t: f64| {
        rows.iter()
            .find(|r| (r[0] - t).abs() < 0.006)
            .unwrap_or_else(|| panic!("a row at {t} s"))
    };
    assert!((at(0.5)[2] + 90.0).abs() < 0.01);
    assert!((at(1.5)[2] + 25.0).abs() < 0.01, "halfway: {}", at(1.5)[2]);
    assert!((at(3.0)[2] - 40.0).abs() < 0.01);
    assert!((at(3.0)[3] - 90.0).abs() < 0.01);
}

#[test]
fn sim_refuses_a_bad_mounting_with_file_line_and_field() {
    let dir = scratch("sim-body-bad");
    let bad = write_file(
        &dir,
        "m.yaml",
        "shoulder_pan: {zero_tick: 100}\nelbow_flex: {zero_tick: 9, direction: 0}\n",
    );
    let robot = repo("configs/robots/so101.yaml");
    let err = servobus_fails(&["sim", "--robot", arg(&robot), "--mounting", arg(&bad)]);
    assert!(
        err.contains("m.yaml:2:") && err.contains("elbow_flex.direction"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

/// The complete lines of the truth file at `path` as it is now (a line the
/// writer has not finished yet is not counted): the header, then each row's
/// numbers. An absent file reads as no lines.
fn truth_so_far(path: &std::path::Path) -> (Option<String>, Vec<Vec<f64>>) {
    let Ok(text) = std::fs::read_to_string(path) else {
        return (None, Vec::new());
    };
    let complete = match text.rfind('\n') {
        Some(end) => &text[..end],
        None => "",
    };
    let mut lines = complete.lines();
    let header = lines.next().map(str::to_owned);
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or_else(|_| panic!("a number in {l:?}")))
                .collect::<Vec<f64>>()
        })
        .collect();
    (header, rows)
}

/// Polls the truth file at `path` until `enough` holds for its rows, for at
/// most a minute (a loaded machine): the rows then.
fn truth_until(
    path: &std::path::Path,
    what: &str,
    enough: impl Fn(&[Vec<f64>]) -> bool,
) -> Vec<Vec<f64>> {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let (header, rows) = truth_so_far(path);
        if let Some(header) = &header {
            assert_eq!(
                header,
                "time_s,shoulder_pan,shoulder_lift,elbow_flex,wrist_flex,wrist_roll,gripper"
            );
        }
        for row in &rows {
            assert_eq!(row.len(), 7, "a whole row: {row:?}");
        }
        if enough(&rows) {
            return rows;
        }
        assert!(
            Instant::now() < deadline,
            "{what}: the truth file has {} rows after a minute",
            rows.len()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn the_truth_file_grows_while_the_simulator_runs() {
    let dir = scratch("sim-truth-live");
    let truth = write_file(&dir, "t.csv", "an earlier file\n");
    let sim = Sim::start_robot(
        &dir,
        std::path::Path::new("so101"),
        6,
        &["--truth", arg(&truth)],
    );
    // Serving: the earlier file is gone, the header is there at once.
    let (header, _) = truth_so_far(&truth);
    assert!(header.is_some(), "no header once the simulator serves");
    // Rows come while it runs, not when it stops: half a second of them,
    // then more.
    let first = truth_until(&truth, "running", |rows| {
        rows.last().is_some_and(|r| r[0] >= 0.5)
    });
    let seen = first.last().map_or(0.0, |r| r[0]);
    let later = truth_until(&truth, "still running", |rows| {
        rows.last().is_some_and(|r| r[0] >= seen + 0.5)
    });
    assert!(later.len() > first.len());
    // Rows are in time order, 10 ms apart.
    for pair in later.windows(2) {
        let step = pair[1][0] - pair[0][0];
        assert!((step - 0.01).abs() < 0.0015, "rows {pair:?}");
    }

    // A second simulator on the same link is refused at start: its truth
    // file, an earlier one, is left as it was, and no other file appears.
    let other = write_file(&dir, "other.csv", "time_s,a\n0.000,1.000\n");
    let out = std::process::Command::new(common::BIN)
        .args(["sim", "--robot", "so101", "--link", sim.port(), "--truth"])
        .arg(&other)
        .output()
        .expect("run servobus sim");
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert_eq!(
        std::fs::read_to_string(&other).expect("read"),
        "time_s,a\n0.000,1.000\n"
    );
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .expect("list")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    assert_eq!(names, ["bus", "other.csv", "t.csv"]);

    // The first one still streams; stopped, its file ends with a whole row.
    let running = truth_until(&truth, "after the refusal", |rows| rows.len() > later.len());
    sim.stop();
    let text = std::fs::read_to_string(&truth).expect("the truth file");
    assert!(text.ends_with('\n'), "a whole last row");
    let (_, rows) = read_truth(&truth);
    assert!(rows.len() >= running.len());
}
