//! Live targets through the real loop, in virtual time on the simulated
//! SO-101: a run with no path follows a stream of targets with every joint
//! inside its velocity, acceleration and jerk limits (checked by finite
//! differences of the goals sent, independently of the planner), stops
//! when the stream stops and resumes smoothly, and refuses or clamps bad
//! targets.

use crate::common;

use common::{live_so101, record};
use servobus_runtime::config::{JointMap, Robot};
use servobus_runtime::{Command, LiveEvent, LiveTarget, TargetError};

const PERIOD: f64 = 0.005;

/// Where the simulated joints start (the middle tick of each servo), deg.
fn start_pose(robot: &Robot) -> Vec<f64> {
    robot
        .joints()
        .map(|j| {
            let map = JointMap::new(j, robot.units);
            robot.units.from_rad(map.from_ticks(2048))
        })
        .collect()
}

/// The smooth source path: joint `j` at `t` s, deg, from the start pose
/// (starts at rest there).
fn source(start: &[f64], j: usize, t: f64) -> f64 {
    let amp = [30.0, 25.0, 30.0, 20.0, 30.0, 25.0][j];
    let f = [0.4, 0.3, 0.5, 0.45, 0.35, 0.25][j];
    start[j] + amp * (1.0 - (2.0 * std::f64::consts::PI * f * t).cos())
}

/// A uniform number in [-1, 1) from a simple generator (repeatable).
fn jitter(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

#[test]
fn a_jittery_30_hz_stream_is_followed_within_the_limits_closely_and_with_little_lag() {
    let (mut run, robot) = live_so101();
    let start = start_pose(&robot);
    let source = |j, t| source(&start, j, t);
    let tx = run.targets();
    // Targets taken at 30 Hz, each +-5 ms off its slot, stamped with the
    // time they were taken and sent in the first cycle at or after it.
    let mut seed = 7;
    let stamps: Vec<f64> = (1..=105)
        .map(|i| i as f64 / 30.0 + 0.005 * jitter(&mut seed))
        .collect();
    let mut next = 0;
    let rec = record(&mut run, 720, |k| {
        let now = k as f64 * PERIOD;
        while next < stamps.len() && stamps[next] <= now {
            let s = stamps[next];
            let q = (0..6).map(|j| source(j, s).to_radians()).collect();
            tx.send(LiveTarget::all(s, q)).expect("a good target");
            next += 1;
        }
    });
    assert!(rec.faults.is_empty(), "{:?}", rec.faults);
    rec.assert_within_so101_limits(0, PERIOD);
    // RMS error of the goals against the source after 0.2 s, and the lag:
    // the delay of the source that fits the goals best.
    let span = (40u64..700).collect::<Vec<_>>();
    let rms = |lag: f64| {
        let mut sum = 0.0;
        let mut n = 0.0;
        for j in 0..6 {
            let c = rec.commanded(j);
            for &k in &span {
                let t = k as f64 * PERIOD;
                let e = c[k as usize] - source(j, t - lag);
                sum += e * e;
                n += 1.0;
            }
        }
        (sum / n).sqrt()
    };
    // Nothing is extrapolated past the newest target: the goals trail the
    // source by one target interval (33 ms, 38 with the jitter), within
    // a cycle, and are close to it so delayed.
    let best = (0..=100)
        .map(|ms| ms as f64 * 1e-3)
        .min_by(|a, b| rms(*a).total_cmp(&rms(*b)))
        .unwrap_or(1.0);
    let err = rms(best);
    assert!(err <= 0.5, "RMS error {err} deg at the best lag");
    assert!(best <= 0.038 + PERIOD, "lag {best} s");
    println!("RMS error {err:.3} deg, lag {:.0} ms", best * 1e3);
    let report = run.report();
    let live = report.live.expect("targets counted");
    assert_eq!((live.received, live.refused, live.clamped), (105, 0, 0));
}

#[test]
fn a_90_degree_step_is_a_jerk_limited_move_to_the_target() {
    let (mut run, _) = live_so101();
    let tx = run.targets();
    // A 30 Hz stream whose pan target steps from 0 to 90 deg at 0.05 s.
    let rec = record(&mut run, 500, |k| {
        if k % 7 == 3 {
            let now = k as f64 * PERIOD;
            let q: f64 = if now >= 0.05 { 90.0 } else { 0.0 };
            let t = LiveTarget::named(now, vec![("shoulder_pan".into(), q.to_radians())]);
            tx.send(t).expect("a good target");
        }
    });
    rec.assert_within_so101_limits(0, PERIOD);
    let pan = rec.commanded(0);
    let last = pan[pan.len() - 1];
    assert!((last - 90.0).abs() < 1e-6, "{last}");
    assert!(pan.iter().all(|&p| p <= 90.0 + 1e-9), "no overshoot");
    // The other joints were not named: they keep their targets (0).
    assert!(rec.commanded(1).iter().all(|p| p.abs() < 1e-9));
    // At 180 deg/s and 900 deg/s^2 the move takes at least 0.5 + 0.2 s.
    let start = pan.iter().position(|p| *p > 0.01).unwrap_or(0);
    let end = pan
        .iter()
        .position(|p| (*p - 90.0).abs() < 1e-6)
        .unwrap_or(0);
    assert!((end - start) as f64 * PERIOD >= 0.7, "{start}..{end}");
}

/// Sends a ramp of joint 0 at `speed` deg/s, from `from` deg, at 30 Hz
/// between times `t0` and `t1`, in the cycle `k`. Returns the angle sent.
fn ramp(
    tx: &servobus_runtime::TargetSender,
    k: u64,
    t0: f64,
    t1: f64,
    from: f64,
    speed: f64,
) -> Option<f64> {
    let now = k as f64 * PERIOD;
    let slot = (now * 30.0).round() / 30.0;
    if now >= t0 && now < t1 && (now - slot).abs() < PERIOD / 2.0 {
        let q = from + speed * (now - t0);
        let t = LiveTarget::named(now, vec![("shoulder_pan".into(), q.to_radians())]);
        tx.send(t).expect("a good target");
        return Some(q);
    }
    None
}

#[test]
fn a_stream_that_stops_comes_to_a_stop_and_holds_then_resumes_smoothly() {
    let (mut run, _) = live_so101();
    let tx = run.targets();
    let speed = 60.0;
    // 0.1..1.1 s: up at 60 deg/s; silence until 2.0 s; then down again.
    let mut last_target = f64::NAN;
    let rec = record(&mut run, 700, |k| {
        if let Some(q) = ramp(&tx, k, 0.1, 1.1, 0.0, speed) {
            last_target = q;
        }
        let _ = ramp(&tx, k, 2.0, 2.6, 60.0, -speed);
    });
    rec.assert_within_so101_limits(0, PERIOD);
    let pan = rec.commanded(0);
    // Nothing is extrapolated past the last target: the joint goes beyond
    // it only by its quickest stop from 60 deg/s, v sqrt(v / j) = 60
    // sqrt(60 / 9000), about 4.9 deg (the speed is under a^2 / j = 90
    // deg/s), by hand; it then turns back toward the target until the
    // timeout stops it there.
    let stop_distance = 60.0 * (60.0f64 / 9000.0).sqrt();
    let highest = pan.iter().fold(f64::MIN, |a, &b| a.max(b));
    assert!(
        highest <= last_target + stop_distance + 1e-6,
        "went to {highest}, last target {last_target}"
    );
    let held = pan[380];
    assert!(
        held >= last_target - 1e-6 && held <= highest,
        "held at {held}, last target {last_target}"
    );
    // Held still from the timeout's stop (1.1 + 0.25 s, then the stop) to
    // the resume (2.0 s).
    assert!(pan[320..400].iter().all(|&p| (p - held).abs() < 1e-9));
    // Resumed toward the new ramp.
    assert!(pan[699] < held - 10.0, "{}", pan[699]);
    let seen = &rec.live;
    // Stopped 0.25 s after the last target of each ramp, resumed once.
    assert_eq!(seen.len(), 3, "{seen:?}");
    assert_eq!(seen[0].0, LiveEvent::TimedOut);
    assert!(seen[0].1 > 1.3 && seen[0].1 < 1.4, "{seen:?}");
    assert_eq!(seen[1].0, LiveEvent::Resumed);
    assert!((seen[1].1 - 2.0).abs() < 0.01, "{seen:?}");
    assert_eq!(seen[2].0, LiveEvent::TimedOut);
    let live = run.report().live.expect("targets counted");
    assert_eq!((live.timeouts, live.resumes), (2, 1));
}

#[test]
fn bad_targets_are_refused_or_clamped_and_counted() {
    let (mut run, robot) = live_so101();
    let tx = run.targets();
    assert_eq!(tx.joint_names().len(), robot.joint_count());
    let good = || LiveTarget::named(0.0, vec![("elbow_flex".into(), 20f64.to_radians())]);
    assert_eq!(tx.send(good()), Ok(0));
    let nan = LiveTarget::all(0.01, vec![f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert!(matches!(tx.send(nan), Err(TargetError::NotFinite { .. })));
    let inf = LiveTarget::named(0.01, vec![("elbow_flex".into(), f64::INFINITY)]);
    assert!(matches!(tx.send(inf), Err(TargetError::NotFinite { .. })));
    let unknown = LiveTarget::named(0.01, vec![("tail".into(), 0.1)]);
    assert_eq!(
        tx.send(unknown),
        Err(TargetError::UnknownJoint("tail".into()))
    );
    let short = LiveTarget::all(0.01, vec![0.0; 5]);
    assert_eq!(
        tx.send(short),
        Err(TargetError::WrongLength {
            expected: 6,
            actual: 5
        })
    );
    // 200 deg is beyond the pan's 110.
    let far = |t| LiveTarget::named(t, vec![("shoulder_pan".into(), 200f64.to_radians())]);
    assert_eq!(tx.send(far(0.02)), Ok(1));
    // Both again at 20 Hz, so that the stream does not time out.
    let rec = record(&mut run, 600, |k| {
        if k > 0 && k % 10 == 0 {
            let t = k as f64 * PERIOD;
            assert_eq!(tx.send(far(t)), Ok(1));
            assert_eq!(tx.send(good()), Ok(0));
        }
    });
    {
        let c = rec.commanded(0);
        let mut best = (0.0, 0);
        for i in 1..c.len() - 1 {
            let a = (c[i + 1] - 2.0 * c[i] + c[i - 1]).abs();
            if a > best.0 {
                best = (a, i);
            }
        }
        eprintln!(
            "DBG {:?} {:?}",
            best,
            &c[best.1.saturating_sub(5)..best.1 + 5]
        );
    }
    rec.assert_within_so101_limits(0, PERIOD);
    let last = |j: usize| *rec.commanded(j).last().unwrap_or(&f64::NAN);
    // The refused targets changed nothing: the elbow went to 20 and the
    // pan to its limit (the last whole tick of the STS3215's 0.088 deg
    // below 110).
    assert!((last(2) - 20.0).abs() < 1e-6, "{}", last(2));
    assert!(last(0) <= 110.0 && last(0) > 110.0 - 0.088, "{}", last(0));
    assert!(rec.commanded(0).iter().all(|&p| p <= 110.0));
    let live = run.report().live.expect("targets counted");
    assert_eq!(
        (live.received, live.refused, live.clamped),
        (6 + 2 * 59, 4, 60),
        "{live:?}"
    );
}

#[test]
fn stop_ends_a_live_run_with_a_jerk_limited_stop() {
    let (mut run, _) = live_so101();
    let tx = run.targets();
    let commands = run.commands();
    let rec = record(&mut run, 2000, |k| {
        let _ = ramp(&tx, k, 0.0, 1.0, 0.0, 90.0);
        if k == 150 {
            commands.send(Command::Stop).expect("the run listens");
        }
    });
    rec.assert_within_so101_limits(0, PERIOD);
    let report = run.report();
    assert_eq!(report.finish, servobus_runtime::Finish::Stopped);
    // It stopped soon after the command, not at the end of the ramp.
    assert!(report.cycles < 300, "{}", report.cycles);
}
