//! `servobus play` on the wall clock, as a user runs it: the built binary,
//! no `--fast`, the built-in simulator on a pty, Ctrl-C sent as SIGINT.
//!
//! Time bounds are generous (a loaded machine may run late); what happened
//! is checked tightly, from the CSV log, against figures derived by hand
//! from the test robot's limits.
//!
//! The test robot is the SO-101 with a deliberately slow `shoulder_pan`
//! (30 deg/s, 10 deg/s^2, 100 deg/s^3) so that a stop lasts long enough to
//! see and to interrupt, and the motion sweeps it from -100 to 100 deg. By
//! hand, for that joint:
//! - reaching 30 deg/s from rest at 10 deg/s^2 and 100 deg/s^3 takes
//!   30/10 + 10/100 = 3.1 s over 30 * 3.1 / 2 = 46.5 deg (the acceleration
//!   profile is a symmetric trapezoid, so the mean speed is half the peak);
//! - so the sweep cruises at 30 deg/s for (200 - 2 * 46.5) / 30 = 3.57 s;
//! - and the shortest jerk-limited stop from cruise takes the same 3.1 s
//!   over the same 46.5 deg.
//!
//! A stop ends the run when it comes to rest: the joints then hold at the
//! last goal with their torque on (the report says `stopped`, exit 0).

use crate::common;

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use common::{arg, edited, joint_names, scratch, write_file, Running};

/// Cruise speed, acceleration and jerk limits of the test robot's pan.
const V: f64 = 30.0;
const A: f64 = 10.0;
const J: f64 = 100.0;
/// The shortest stop from cruise (s) and its distance (deg), by hand above.
const STOP_S: f64 = V / A + A / J;
const STOP_DEG: f64 = V * STOP_S / 2.0;
/// The motions' control rate (Hz).
const RATE: f64 = 10.0;
/// Held by each test: three wall-clock runs at once load the machine more
/// than the checks need.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Writes the SO-101 into `dir` as `robot.yaml` with `lead_ms: 0`, so
/// that the goal sent each cycle (`commanded` in the log) is the path at
/// the cycle's time, and with the slow pan when `slow_pan`.
///
/// The simulator answers from threads of this process that a loaded
/// machine may not run for 100 ms and more, which the runtime rightly
/// takes for missing servos (3 CPU hogs on 2 cores do that at 25 Hz). So
/// the robot allows 50 ms per transaction (`latency_us`) and the motions
/// run at 10 Hz ([`RATE`]): a servo counts as missing after 3 silent
/// cycles, 300 ms. The tests also run one at a time ([`ONE_AT_A_TIME`]).
fn write_robot(dir: &Path, slow_pan: bool) {
    let pan = "        max_velocity: 180    # deg/s (the servo manages ~300 unloaded)\n        \
               max_acceleration: 900   # deg/s^2\n        max_jerk: 9000          # deg/s^3, optional";
    let slow =
        format!("        max_velocity: {V}\n        max_acceleration: {A}\n        max_jerk: {J}");
    let mut edits = vec![
        ("\nrate: 200 ", "\nlead_ms: 0\nrate: 200 "),
        ("    latency_us: auto ", "    latency_us: 50000 #"),
    ];
    if slow_pan {
        edits.push((pan, &slow));
    }
    write_file(
        dir,
        "robot.yaml",
        &edited("configs/robots/so101.yaml", &edits),
    );
}

/// Writes the slow-pan robot and the sweep into `dir`; returns the motion.
fn slow_pan_files(dir: &Path) -> PathBuf {
    write_robot(dir, true);
    write_file(
        dir,
        "sweep.yaml",
        "robot: robot.yaml\nunits: deg\nrate: 10\nkeyframes:\n  - pose: {shoulder_pan: -100, \
         shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 10}\n  \
         - pose: {shoulder_pan: 100}\n",
    )
}

/// `servobus play MOTION --sim-pose=POSE --log LOG` on the wall clock.
fn play(motion: &Path, log: &Path, pose: &str) -> Running {
    Running::start(&[
        "play",
        arg(motion),
        &format!("--sim-pose={pose}"),
        "--log",
        arg(log),
    ])
}

/// One joint's rows of a `play --log` CSV: (time s, the goal sent, the
/// reading). The goal is the path at the row's time (lead 0); the log's
/// `planned` is the path at the reading's time instead, which moves with
/// a late cycle's reading.
fn joint_rows(log: &Path, joint: &str) -> Vec<(f64, f64, Option<f64>)> {
    let text = std::fs::read_to_string(log).expect("the log");
    let mut rows = text.lines();
    let header: Vec<&str> = rows.next().expect("a header").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    let (t, j, p, m) = (
        col("time_s"),
        col("joint"),
        col("commanded_deg"),
        col("measured_deg"),
    );
    rows.map(|r| r.split(',').collect::<Vec<_>>())
        .filter(|f| f[j] == joint)
        .map(|f| {
            let num = |i: usize| f[i].parse::<f64>().expect("a number");
            (num(t), num(p), f[m].parse::<f64>().ok())
        })
        .collect()
}

/// The goal's speed (deg/s) at row `i`: a central difference over its
/// neighbours (one-sided at the ends).
fn speed(rows: &[(f64, f64, Option<f64>)], i: usize) -> f64 {
    let (a, b) = (i.saturating_sub(1), (i + 1).min(rows.len() - 1));
    ((rows[b].1 - rows[a].1) / (rows[b].0 - rows[a].0)).abs()
}

/// The largest third divided difference (times 3!) of the goals over
/// `[from, to]`, less what the log's rounding can contribute, on rows at
/// least 80 ms apart. Each is the path's jerk averaged over its span (mean
/// value theorem for divided differences), so none exceeds the jerk limit
/// if the path keeps it. Rounding to 4 decimals (errors e_i <= 5e-5 deg)
/// adds at most 6 * sum_i e_i / prod_(j != i) |t_i - t_j|, subtracted here.
fn max_jerk(rows: &[(f64, f64, Option<f64>)], from: f64, to: f64) -> f64 {
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for r in rows.iter().filter(|r| r.0 >= from && r.0 <= to) {
        if pts.last().is_none_or(|p| r.0 - p.0 >= 0.08 - 1e-9) {
            pts.push((r.0, r.1));
        }
    }
    let mut worst: f64 = 0.0;
    for w in pts.windows(4) {
        let mut dd = 0.0;
        let mut noise = 0.0;
        for i in 0..4 {
            let prod: f64 = (0..4)
                .filter(|&j| j != i)
                .map(|j| w[i].0 - w[j].0)
                .product();
            dd += w[i].1 / prod;
            noise += 5e-5 / prod.abs();
        }
        worst = worst.max(6.0 * (dd.abs() - noise));
    }
    worst
}

/// Starts the sweep from a pose the approach must leave (everything but the
/// slow pan away from the first keyframe) and sends the first Ctrl-C while
/// the pan cruises (run time 4 s: the approach of ~0.6 s, then 3.4 s of
/// the sweep, past its 3.1 s acceleration; the cruise lasts 3.57 s more).
fn sweep_and_interrupt(name: &str) -> (Running, PathBuf) {
    let dir = scratch(name);
    let motion = slow_pan_files(&dir);
    let log = dir.join("log.csv");
    let mut play = play(&motion, &log, "-100,-80,80,30,20,20");
    play.wait_for(true, "the approach's announcement", |l| {
        l.starts_with("moving to the first keyframe")
    });
    // Progress lines ("<time> / <total> s ...") come once a second.
    play.wait_for(false, "a progress line past 4 s", |l| {
        l.split(" / ")
            .next()
            .and_then(|t| t.trim().parse::<f64>().ok())
            .is_some_and(|t| t >= 4.0)
    });
    play.interrupt();
    play.wait_for(true, "the stop's announcement", |l| {
        l.contains("stopping (jerk-limited), then holding")
    });
    (play, log)
}

#[test]
fn first_ctrl_c_stops_jerk_limited_then_holds_reports_and_exits_0() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (play, log) = sweep_and_interrupt("rt-stop");
    let (status, out, err) = play.finish();
    assert_eq!(status.code(), Some(0), "stdout {out}\nstderr {err}");
    assert!(
        out.lines().any(|l| l.starts_with("stopped: ")),
        "the report says stopped: {out}"
    );
    for joint in ["shoulder_pan", "gripper"] {
        assert!(
            out.lines().any(|l| l.trim_start().starts_with(joint)),
            "the report lists {joint}: {out}"
        );
    }

    let pan = joint_rows(&log, "shoulder_pan");
    let (t_last, p_end, measured_end) = *pan.last().expect("rows");
    // The stop ends where the plan stops moving for good.
    let end = pan
        .iter()
        .rposition(|r| (r.1 - p_end).abs() > 1e-4)
        .expect("the pan moved")
        + 1;
    let t_end = pan[end].0;
    // The cruise before the stop: the latest row at full speed, at least a
    // stop's length before its end.
    let cruise = (0..end)
        .rev()
        .find(|&i| pan[i].0 < t_end - STOP_S - 0.05 && (speed(&pan, i) - V).abs() < 0.01)
        .unwrap_or_else(|| panic!("no cruise at {V} deg/s before the stop (ended {t_end} s)"));
    let (t_c, p_c) = (pan[cruise].0, pan[cruise].1);
    // A time-optimal stop from cruise starts at t_s with p = p_c + V (t_s -
    // t_c) and ends STOP_S later, STOP_DEG further: so t_s is fixed by the
    // end position, and the end time follows from it.
    let t_s = t_c + (p_end - STOP_DEG - p_c) / V;
    assert!(
        (t_end - (t_s + STOP_S)).abs() < 1.5 / RATE,
        "stop from cruise at {t_s:.3} s should end at {:.3} s, {STOP_DEG} deg on; ended {t_end:.3} s",
        t_s + STOP_S
    );
    assert!(
        p_end < 100.0 - 1.0,
        "the sweep was cut short (ended at {p_end} deg)"
    );
    let jerk = max_jerk(&pan, t_s - 0.2, t_end + 0.2);
    assert!(
        jerk <= J * 1.001,
        "the stop keeps the jerk limit {J}: {jerk}"
    );
    assert!(jerk > J * 0.5, "the stop uses its jerk: {jerk}");
    // The run ends as the stop comes to rest, and the servo is there.
    assert!(
        t_last - t_end < 2.5 / RATE,
        "the run ends with the stop ({t_end:.3} s), not {t_last:.3} s"
    );
    // The last step ends at rest: it can hold at most the stop's final
    // jerk phase, whose speed is J t^2 / 2, so its mean speed is at most
    // J h^2 / 6 for a cycle of h (0.167 deg/s), plus the log's rounding
    // (1e-4 deg / h).
    let last = &pan[pan.len() - 2..];
    let v = (last[1].1 - last[0].1) / (last[1].0 - last[0].0);
    let h = 1.0 / RATE;
    assert!(
        v.abs() <= J * h * h / 6.0 + 1e-4 / h + 1e-9,
        "the last goal is at rest: {v} deg/s"
    );
    let measured = measured_end.expect("the last row has a reading");
    assert!(
        (measured - p_end).abs() < 0.3,
        "the pan holds at {p_end}: measured {measured}"
    );
}

#[test]
fn second_ctrl_c_turns_the_torque_off_and_exits_1() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (play, log) = sweep_and_interrupt("rt-torque");
    // The stop lasts 3.1 s: time enough for the second.
    play.interrupt();
    let (status, out, err) = play.finish();
    assert_eq!(status.code(), Some(1), "stdout {out}\nstderr {err}");
    assert!(
        err.lines().any(|l| l.trim() == "torque off"),
        "stderr says torque off: {err}"
    );
    assert!(
        out.lines().any(|l| l.starts_with("torque off: ")),
        "the report says torque off: {out}"
    );
    assert!(
        !out.lines().any(|l| l.starts_with("stopped: ")),
        "not reported as a stop: {out}"
    );
    // The run ended at the second Ctrl-C: the log ends before the stop
    // could have come to rest, the pan still moving.
    let pan = joint_rows(&log, "shoulder_pan");
    let (t_last, p_last, _) = *pan.last().expect("rows");
    let cruise_rows: Vec<usize> = (0..pan.len())
        .filter(|&i| (speed(&pan, i) - V).abs() < 0.01)
        .collect();
    let last_cruise = *cruise_rows.last().expect("the pan cruised");
    assert!(
        t_last < pan[last_cruise].0 + STOP_S - 1.0 / RATE,
        "ended at {t_last} s, after a whole stop from {} s",
        pan[last_cruise].0
    );
    assert!(p_last < 100.0 - 1.0, "the sweep did not complete");
    assert!(
        speed(&pan, pan.len() - 1) > 0.1,
        "the torque went off before the stop came to rest"
    );
}

#[test]
fn play_approaches_the_first_keyframe_from_wherever_the_joints_are() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // wrist_roll starts 60 deg from the first keyframe; at 25 % of its
    // limits (270 deg/s, 1500 deg/s^2, 15000 deg/s^3: 67.5, 375, 3750) it
    // reaches 67.5 deg/s in 67.5/375 + 375/3750 = 0.28 s over
    // 67.5 * 0.28 / 2 = 9.45 deg, cruises (60 - 18.9) / 67.5 = 0.609 s, and
    // arrives after 2 * 0.28 + 0.609 = 1.169 s. The other joints start
    // 5 deg off, which takes well under 0.6 s even for the gentlest
    // (shoulder_lift: (32 * 5 / 1750)^(1/3) = 0.45 s on jerk alone). The
    // motion then holds the first keyframe for 1 s, so every joint must be
    // exactly there from the approach's end until 1.169 + 1 s.
    let dir = scratch("rt-approach");
    write_robot(&dir, false);
    let motion = write_file(
        &dir,
        "short.yaml",
        "robot: robot.yaml\nunits: deg\nrate: 10\nkeyframes:\n  - {at: 0, pose: {shoulder_pan: 0, \
         shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 10}}\n  \
         - {at: 1, pose: {shoulder_pan: 0}}\n  - {at: 2, pose: {shoulder_pan: 20, gripper: 40}}\n",
    );
    let log = dir.join("log.csv");
    let start = [5.0, -85.0, 85.0, 40.0, 60.0, 15.0];
    let pose = start.map(|a| a.to_string()).join(",");
    let play = play(&motion, &log, &pose);
    let (status, out, err) = play.finish();
    assert_eq!(status.code(), Some(0), "stdout {out}\nstderr {err}");
    assert!(out.lines().any(|l| l.starts_with("completed: ")), "{out}");
    assert!(
        err.contains("moving to the first keyframe, 1.2 s"),
        "the approach is announced with its length: {err}"
    );

    let first = [0.0, -90.0, 90.0, 45.0, 0.0, 10.0];
    let names = joint_names("configs/robots/so101.yaml");
    assert_eq!(names.len(), 6, "{names:?}");
    // One STS3215 tick is 360/4096 = 0.088 deg.
    for ((name, &s), &k) in names.iter().zip(&start).zip(&first) {
        let rows = joint_rows(&log, name);
        let (_, planned, measured) = rows[0];
        let measured = measured.expect("a first reading");
        assert!(
            (measured - s).abs() < 0.09,
            "{name} starts at {s}: {measured}"
        );
        assert!(
            (planned - measured).abs() < 0.01,
            "{name}'s plan starts where it is: {planned} vs {measured}"
        );
        // At the first keyframe from the approach's end, through the hold.
        for r in rows.iter().filter(|r| r.0 > 1.169 && r.0 < 2.169) {
            assert!(
                (r.1 - k).abs() < 1e-4,
                "{name} at {k} after the approach: {r:?}"
            );
        }
    }
    let roll = joint_rows(&log, "wrist_roll");
    let arrived = roll
        .iter()
        .position(|r| r.1.abs() < 1e-4)
        .expect("wrist_roll arrives");
    // Between the rows around 1.169 s: not yet at the row before.
    assert!(
        roll[arrived].0 >= 1.169 && roll[arrived].0 < 1.169 + 1.0 / RATE,
        "wrist_roll arrives at 1.169 s: {}",
        roll[arrived].0
    );
    let peak = (0..arrived).map(|i| speed(&roll, i)).fold(0.0, f64::max);
    assert!(
        (peak - 67.5).abs() < 0.1,
        "the approach cruises at 25 % of 270 deg/s: {peak}"
    );
    let jerk = max_jerk(&roll, 0.0, 1.169);
    assert!(
        jerk <= 3750.0 * 1.001,
        "and keeps 25 % of the jerk limit: {jerk}"
    );
}
