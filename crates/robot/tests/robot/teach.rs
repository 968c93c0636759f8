//! Teaching by hand in virtual time: the simulator's hand poses the arm,
//! the teacher captures it, the motion file is played back and the body's
//! truth is compared with what was taught.

use crate::common;

use std::time::Duration;

use servobus_robot::sim::{new_truth, Hand, SimRobot};
use servobus_robot::teach::{
    check_pose, merge_identical, motion_yaml, reduce, trim_idle, StillCapture, Taught, TeachError,
    Teacher, TimedPose,
};
use servobus_runtime::config::{load_motion, plan_motion, Robot};
use servobus_runtime::VirtualRun;
use servobus_sim::{SimBus, Truth};

/// The SO-101's rest pose, deg.
const REST: [f64; 6] = [0.0, -90.0, 90.0, 45.0, 0.0, 10.0];

/// Five poses inside the arm's limits, deg.
const POSES: [[f64; 6]; 5] = [
    [30.0, -60.0, 70.0, 20.0, 10.0, 40.0],
    [-40.0, -20.0, 30.0, -10.0, 60.0, 80.0],
    [10.0, 20.0, -20.0, 40.0, -45.0, 20.0],
    [70.0, -45.0, 50.0, -60.0, 90.0, 5.0],
    [-20.0, 0.0, 10.0, 0.0, -30.0, 60.0],
];

fn pose_keys(t: f64, p: &[f64]) -> (f64, Vec<(usize, f64)>) {
    (t, p.iter().copied().enumerate().collect())
}

/// The arm moved by a hand through `keys`, and a teacher on it with the
/// torque off (the simulator is returned to keep it alive with the teacher).
fn hand_guided(robot: &Robot, keys: &[(f64, Vec<(usize, f64)>)]) -> (SimRobot, Teacher<SimBus>) {
    let sim = SimRobot::builder(robot)
        .hand(Hand::from_keyframes(robot, keys))
        .build()
        .expect("simulates");
    let mut t = Teacher::new(robot, sim.driver_buses(), &[]).expect("a teacher");
    t.release().expect("torque off");
    (sim, t)
}

/// Plays `yaml` (a taught motion) on a fresh arm at `start`, returning the
/// truth and the time of cycle 0.
fn play(robot: &Robot, yaml: &str, start: &[f64], name: &str) -> (Truth, Duration) {
    let dir = std::env::temp_dir().join(format!("servobus-teach-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join(name);
    std::fs::write(&file, yaml).expect("writes the motion");
    let (motion, robot2) = load_motion(&file, None).expect("play accepts the taught file");
    assert_eq!(robot2.name, robot.name);
    let path = plan_motion(&motion, &robot2).expect("plans");
    let truth = new_truth(robot);
    let sim = SimRobot::builder(robot)
        .pose(start)
        .truth(&truth)
        .build()
        .expect("simulates");
    let run = VirtualRun::new(robot, path, sim.driver_buses(), common::quiet()).expect("starts");
    let start_time = run.start();
    run.run();
    sim.buses()[0].clock().advance(Duration::from_millis(500));
    sim.settle();
    (truth, start_time)
}

fn robot_file() -> std::path::PathBuf {
    common::config("robots/so101.yaml")
        .canonicalize()
        .expect("the robot file")
}

#[test]
fn pose_and_pause_with_the_hand_then_play_passes_every_keyframe() {
    let robot = common::robot("so101.yaml");
    // Hold the rest pose, then move to each pose in 1 s and hold it 1.5 s.
    let mut keys = vec![pose_keys(0.0, &REST), pose_keys(0.5, &REST)];
    for (k, p) in POSES.iter().enumerate() {
        let t = 0.5 + 2.5 * k as f64;
        keys.push(pose_keys(t + 1.0, p));
        keys.push(pose_keys(t + 2.5, p));
    }
    let (_sim, mut teacher) = hand_guided(&robot, &keys);
    let start = teacher.pose().expect("reads");
    let mut capture = StillCapture::new(&start, robot.units);
    let mut taught: Vec<TimedPose> = Vec::new();
    let mut t = Duration::ZERO;
    while t < Duration::from_secs(14) {
        t += Duration::from_millis(20);
        teacher.sleep_until(t);
        let pose = teacher.pose().expect("reads");
        if let Some(k) = capture.push(teacher.now().as_secs_f64(), &pose) {
            taught.push((teacher.now().as_secs_f64(), k));
        }
    }
    assert_eq!(taught.len(), 5, "one keyframe per pose: {taught:?}");
    for ((_, got), want) in taught.iter().zip(&POSES) {
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 0.5, "taught {got:?}, posed {want:?}");
        }
    }
    let file = Taught::paced(&robot, &start, &taught);
    // The starting pose, then the five poses at the times they were
    // captured: moves of 1 s that the arm's limits allow.
    assert!(file.timed, "{:?}", file.notes);
    assert_eq!(file.keyframes.len(), 6);
    assert_eq!(file.keyframes[0], (0.0, start.clone()));
    for (k, (t, _)) in file.keyframes.iter().enumerate().skip(1) {
        // Captured once the hand had held pose k - 1 still for 0.7 s (it
        // reaches it at 1.5 + 2.5 (k - 1) s, easing in: still a little
        // before), and before it moved on.
        let reached = 1.5 + 2.5 * (k - 1) as f64;
        assert!(
            *t >= reached + 0.5 && *t <= reached + 1.5,
            "keyframe {k} at {t} s"
        );
    }
    let yaml = motion_yaml(&robot, &robot_file(), &file);
    assert!(yaml.contains("at: "), "{yaml}");
    let (truth, start_time) = play(&robot, &yaml, &start, "poses.yaml");
    let rows = truth.rows();
    // Each pose is reached at its time, as taught.
    for (t, k) in file.keyframes.iter().skip(1) {
        let at = start_time + Duration::from_secs_f64(*t);
        for (j, want) in k.iter().enumerate() {
            let got = truth.angle_at(j, at).expect("truth at the keyframe");
            assert!(
                (got - want).abs() <= 1.0,
                "joint {j} at {t} s: {got} vs {want}"
            );
        }
    }
    for (_, k) in &taught {
        let closest = rows
            .iter()
            .map(|r| servobus_robot::teach::distance(&r.angles_deg, k))
            .fold(f64::INFINITY, f64::min);
        assert!(closest <= 0.5, "the body passes {k:?} within {closest} deg");
    }
}

#[test]
fn continuous_take_reduces_to_few_keyframes_and_plays_back_within_a_degree() {
    let robot = common::robot("so101.yaml");
    // A 10 s hand-guided take through the poses, without stopping long.
    let mut keys = vec![pose_keys(0.0, &REST)];
    for (k, p) in POSES.iter().enumerate() {
        keys.push(pose_keys(2.0 * (k + 1) as f64, p));
    }
    let (_sim, mut teacher) = hand_guided(&robot, &keys);
    let period = Duration::from_secs_f64(1.0 / robot.rate_hz);
    let mut samples: Vec<TimedPose> = Vec::new();
    let mut t = Duration::ZERO;
    while t <= Duration::from_secs(10) {
        teacher.sleep_until(t);
        let pose = teacher.pose().expect("reads");
        samples.push((teacher.now().as_secs_f64(), pose));
        t += period;
    }
    let file = Taught::continuous(&robot, &samples, 0.5, 0.3).expect("reduces");
    let keyframes = file.keyframes.clone();
    assert!(
        keyframes.len() * 10 <= samples.len(),
        "{} keyframes for {} samples",
        keyframes.len(),
        samples.len()
    );
    let yaml = motion_yaml(&robot, &robot_file(), &file);
    let (truth, start) = play(&robot, &yaml, &keyframes[0].1, "take.yaml");
    let t0 = samples[0].0;
    let mut sum = 0.0;
    let mut n = 0.0;
    for (t, pose) in &samples {
        let at = start + Duration::from_secs_f64(t - t0);
        for (j, want) in pose.iter().enumerate() {
            let got = truth.angle_at(j, at).expect("truth at every sample");
            sum += (got - want).powi(2);
            n += 1.0;
        }
    }
    let rms = (sum / n).sqrt();
    assert!(rms <= 1.0, "path RMS error {rms} deg");
}

#[test]
fn a_pose_outside_the_limits_is_refused_naming_the_joint_and_whose_limit() {
    let robot = common::robot("so101.yaml");
    let mut pose = REST.to_vec();
    assert!(check_pose(&robot, &pose).is_ok());
    // The so101 file limits the elbow to [-100, 100] deg.
    pose[2] = 104.25;
    match check_pose(&robot, &pose) {
        Err(e @ TeachError::OutsideLimits { .. }) => {
            let text = e.to_string();
            for part in ["`elbow_flex`", "104.2 deg", "upper", "robot file"] {
                assert!(text.contains(part), "{part} in {text}");
            }
        }
        other => panic!("refused, not {other:?}"),
    }
    // Never clamped: a reduction of a path that leaves the limits is refused
    // too.
    let samples = vec![(0.0, REST.to_vec()), (1.0, pose)];
    assert!(matches!(
        reduce(&robot, &samples, 0.5),
        Err(TeachError::OutsideLimits { .. })
    ));
}

#[test]
fn idle_ends_are_trimmed_and_identical_keyframes_merged() {
    let p = |x: f64| vec![x, 0.0];
    // Idle for 2 s, a move at 3 s, still within 0.3 of the end from 4 s,
    // idle until 7 s.
    let samples: Vec<TimedPose> = vec![
        (0.0, p(0.0)),
        (1.0, p(0.1)),
        (2.0, p(0.0)),
        (2.6, p(0.2)),
        (3.0, p(2.0)),
        (4.0, p(5.0)),
        (4.4, p(5.2)),
        (5.0, p(5.0)),
        (7.0, p(5.0)),
    ];
    // Moves first at 3 s (more than 0.3 from the start), stays within 0.3
    // of the end from 4 s; 0.5 s of idle time is kept at each end: kept
    // from 2.6 s to 4.4 s.
    let kept = trim_idle(&samples, 0.3);
    assert_eq!(kept.first().map(|s| s.0), Some(2.6));
    assert_eq!(kept.last().map(|s| s.0), Some(4.4));
    // Nothing moved: one sample.
    assert_eq!(trim_idle(&samples[..3], 0.3).len(), 1);

    let keys: Vec<TimedPose> = vec![
        (0.0, p(1.0)),
        (1.0, p(1.0)),
        (2.0, p(1.0)),
        (3.0, p(4.0)),
        (4.0, p(4.0)),
    ];
    // Timed: a run keeps its first and last (a hold from 0 to 2 s).
    assert_eq!(
        merge_identical(keys.clone(), true),
        vec![(0.0, p(1.0)), (2.0, p(1.0)), (3.0, p(4.0)), (4.0, p(4.0))]
    );
    // Untimed: one of each run.
    assert_eq!(
        merge_identical(keys, false),
        vec![(0.0, p(1.0)), (3.0, p(4.0))]
    );
}

#[test]
fn a_take_stopped_while_the_arm_moves_is_reduced_and_plays_within_the_limits() {
    let robot = common::robot("so101.yaml");
    // The pan eases into a swing at 90 deg/s (smoothstep speed over 0.5 s)
    // and the take ends mid-swing (a Ctrl-C): the path cannot stop at the
    // last sample within the limits.
    let rate = robot.rate_hz;
    let samples: Vec<TimedPose> = (0..=(rate as usize))
        .map(|i| {
            let t = i as f64 / rate;
            let x = (t / 0.5).min(1.0);
            let pan = 45.0 * (x.powi(3) - x.powi(4) / 2.0) + 90.0 * (t - 0.5).max(0.0);
            let mut pose = REST.to_vec();
            pose[0] = pan;
            (t, pose)
        })
        .collect();
    let reduced = reduce(&robot, &samples, 0.5).expect("reduces");
    assert!(reduced.settle_s.is_some(), "came to rest later");
    assert!(
        reduced.keyframes.len() * 4 <= samples.len(),
        "{} keyframes for {} samples",
        reduced.keyframes.len(),
        samples.len()
    );
    let file = Taught::continuous(&robot, &samples, 0.5, 0.3).expect("reduces");
    assert!(file
        .notes
        .iter()
        .any(|n| n.contains("while the robot moved")));
    // The file plays: `play` accepts it and plans it within every limit.
    let yaml = motion_yaml(&robot, &robot_file(), &file);
    play(&robot, &yaml, &REST, "stopped.yaml");
}
