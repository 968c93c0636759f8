//! Teaching by hand in virtual time: the simulator's hand poses the arm,
//! the teacher captures it, the motion file is played back and the body's
//! truth is compared with what was taught.

mod common;

use std::time::Duration;

use servobus_driver::ManualClock;
use servobus_runtime::config::{load_motion, plan_motion, Robot};
use servobus_runtime::sim::{new_truth, Hand, SimRobot};
use servobus_runtime::teach::{motion_yaml, reduce, StillCapture, Teacher, TimedPose};
use servobus_runtime::{RunOptions, VirtualRun};
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

fn teacher(sim: &SimRobot, robot: &Robot) -> Teacher<SimBus, ManualClock> {
    let mut t = Teacher::new(robot, sim.driver_buses(), &[]).expect("a teacher");
    t.release().expect("torque off");
    t
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
    let options = RunOptions {
        telemetry_capacity: 0,
        ..RunOptions::default()
    };
    let run = VirtualRun::new(robot, path, sim.driver_buses(), options).expect("starts");
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
    let hand = Hand::from_keyframes(&robot, &keys);
    let sim = SimRobot::builder(&robot)
        .hand(hand)
        .build()
        .expect("simulates");
    let mut teacher = teacher(&sim, &robot);
    let start = teacher.pose().expect("reads");
    let mut capture = StillCapture::new(&start, robot.units);
    let mut taught: Vec<TimedPose> = Vec::new();
    let mut t = Duration::ZERO;
    while t < Duration::from_secs(14) {
        t += Duration::from_millis(20);
        teacher.sleep_until(t);
        let pose = teacher.pose().expect("reads");
        if let Some(k) = capture.push(teacher.now().as_secs_f64(), &pose) {
            taught.push((0.0, k));
        }
    }
    assert_eq!(taught.len(), 5, "one keyframe per pose: {taught:?}");
    for ((_, got), want) in taught.iter().zip(&POSES) {
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 0.5, "taught {got:?}, posed {want:?}");
        }
    }
    let yaml = motion_yaml(&robot, &robot_file(), &taught, false, "test");
    let (truth, _) = play(&robot, &yaml, &taught[0].1, "poses.yaml");
    let rows = truth.rows();
    for (_, k) in &taught {
        let closest = rows
            .iter()
            .map(|r| servobus_runtime::teach::distance(&r.angles_deg, k))
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
    let hand = Hand::from_keyframes(&robot, &keys);
    let sim = SimRobot::builder(&robot)
        .hand(hand)
        .build()
        .expect("simulates");
    let mut teacher = teacher(&sim, &robot);
    let period = Duration::from_secs_f64(1.0 / robot.rate_hz);
    let mut samples: Vec<TimedPose> = Vec::new();
    let mut t = Duration::ZERO;
    while t <= Duration::from_secs(10) {
        teacher.sleep_until(t);
        let pose = teacher.pose().expect("reads");
        samples.push((teacher.now().as_secs_f64(), pose));
        t += period;
    }
    let keyframes = reduce(&robot, &samples, 0.5);
    assert!(
        keyframes.len() * 10 <= samples.len(),
        "{} keyframes for {} samples",
        keyframes.len(),
        samples.len()
    );
    let yaml = motion_yaml(&robot, &robot_file(), &keyframes, true, "test");
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
