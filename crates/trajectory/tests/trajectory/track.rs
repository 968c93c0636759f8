//! Recorded paths: a recording with noise and steps is filtered into a path
//! within every limit (checked by dense sampling), and a smooth recording
//! that the limits allow is reproduced closely and on time.

use crate::common::{self, Noise};

use servobus_trajectory::{track, JointLimits, JointState};

fn limits() -> Vec<JointLimits> {
    vec![
        JointLimits::new(3.0, 15.0, Some(150.0)).with_positions(-2.0, 2.0),
        JointLimits::new(2.0, 10.0, None).with_positions(-1.5, 1.5),
    ]
}

#[test]
fn noisy_recording_with_steps_is_played_within_every_limit() {
    let lim = limits();
    let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
    let (mut times, mut samples) = (Vec::new(), Vec::new());
    for i in 0..=1000 {
        // 10 s at 100 Hz: steps of 1 rad every 2 s, 0.05 rad of noise.
        let t = i as f64 * 0.01;
        let step = if ((t / 2.0) as u32).is_multiple_of(2) {
            -0.5
        } else {
            0.5
        };
        let a = step + 0.05 * noise.next();
        let b = (0.8 * (t * 3.0).sin() + 0.03 * noise.next()).clamp(-1.5, 1.5);
        times.push(t);
        samples.push(vec![a, b]);
    }
    let tracked = track(&lim, &times, &samples, 0.005).expect("filtered");
    let traj = &tracked.trajectory;
    let last = &samples[samples.len() - 1];
    common::check(traj, &lim, last, true);
    let mut s = vec![JointState::default(); 2];
    traj.sample(0.0, &mut s);
    for (j, st) in s.iter().enumerate() {
        assert!(
            (st.position - samples[0][j]).abs() < 1e-9 && st.velocity.abs() < 1e-9,
            "joint {j} starts at {st:?}, recording at {}",
            samples[0][j]
        );
    }
    // The steps are rounded off, not ignored: in the middle of each level
    // the path is there (within the noise), and on time.
    let lead = tracked.recording_start;
    for level in 0..5 {
        let t = 2.0 * level as f64 + 1.0;
        let want = if level % 2 == 0 { -0.5 } else { 0.5 };
        traj.sample(lead + t, &mut s);
        assert!(
            (s[0].position - want).abs() < 0.06,
            "level {level}: {:?}",
            s[0]
        );
    }
    println!(
        "noisy recording with steps: max deviation {:?}, rms {:?}",
        tracked.max_deviation, tracked.rms_deviation
    );
    // Joint 1 swings at up to 2.4 rad/s against a 2 rad/s limit: cut to it.
    assert!(
        tracked.max_deviation[1] < 0.15,
        "{:?}",
        tracked.max_deviation
    );
}

#[test]
fn smooth_recording_is_reproduced_closely_and_on_time() {
    let lim = limits();
    let (mut times, mut samples) = (Vec::new(), Vec::new());
    // Two swings out and back, from rest to rest, well within the limits
    // (peak speed 0.6 and 0.36 rad/s).
    let w = 1.2;
    let n = (4.0 * std::f64::consts::PI / w / 0.01).round() as usize;
    for i in 0..=n {
        let t = i as f64 * 0.01;
        samples.push(vec![
            0.5 * (1.0 - (w * t).cos()),
            -0.3 * (1.0 - (w * t).cos()),
        ]);
        times.push(t);
    }
    let tracked = track(&lim, &times, &samples, 0.005).expect("filtered");
    common::check(&tracked.trajectory, &lim, &samples[samples.len() - 1], true);
    println!(
        "smooth recording: max deviation {:?} rad, rms {:?} rad",
        tracked.max_deviation, tracked.rms_deviation
    );
    for j in 0..2 {
        assert!(
            tracked.max_deviation[j] < 0.005,
            "{:?}",
            tracked.max_deviation
        );
        assert!(
            tracked.rms_deviation[j] < 0.003,
            "{:?}",
            tracked.rms_deviation
        );
    }
}

#[test]
fn a_time_optimal_path_sampled_and_rounded_is_played_as_it_is_and_on_time() {
    use servobus_trajectory::{plan, track_with, Keyframe, PlanOptions, Quantity, TrackOptions};
    // Untimed keyframes ride every limit (jerk phases switching between
    // samples, cruises at full speed): the hardest recording to replay.
    let lim = limits();
    let keyframes = [
        Keyframe::new([0.0, 0.0]),
        Keyframe::new([1.5, -1.0]),
        Keyframe::new([-1.0, 0.5]),
        Keyframe::new([0.2, 0.0]),
    ];
    let path = plan(&lim, &keyframes, &PlanOptions::default()).expect("plan");
    let step = 0.005;
    let resolution = 0.5e-4;
    let round = |x: f64| (x / (2.0 * resolution)).round() * 2.0 * resolution;
    let (mut times, mut samples) = (Vec::new(), Vec::new());
    let mut s = vec![JointState::default(); 2];
    let n = (path.duration() / step).ceil() as usize;
    for i in 0..=n {
        let t = i as f64 * step;
        path.sample(t, &mut s);
        times.push(t);
        samples.push(s.iter().map(|x| round(x.position)).collect::<Vec<_>>());
    }
    let options = TrackOptions { step, resolution };
    let tracked = track_with(&lim, &times, &samples, &options).expect("played");
    println!(
        "time-optimal recording: max deviation {:?}, rms {:?}, {} departures",
        tracked.max_deviation,
        tracked.rms_deviation,
        tracked.departures.len()
    );
    assert_eq!(tracked.recording_start, 0.0, "not on time");
    // Off the samples only by the B-spline's a h^2 / 6 (15 * 25e-6 / 6).
    for j in 0..2 {
        assert!(
            tracked.max_deviation[j] < 1e-4,
            "{:?}",
            tracked.max_deviation
        );
    }
    assert!(tracked.departures.is_empty(), "{:?}", tracked.departures);
    // Within the limits as the rounding lets samples `h` apart show them.
    let shown = |h: f64| -> Vec<JointLimits> {
        lim.iter()
            .map(|l| JointLimits {
                max_velocity: l.max_velocity + 2.0 * resolution / h,
                max_acceleration: l.max_acceleration + 4.0 * resolution / (h * h),
                max_jerk: l.max_jerk.map(|j| j + 8.0 * resolution / (h * h * h)),
                ..*l
            })
            .collect()
    };
    common::check(&tracked.trajectory, &shown(step), &samples[n], true);

    // The same path played twice as fast breaks the speed limit: the
    // report says where and why.
    let fast: Vec<f64> = times.iter().map(|t| t / 2.0).collect();
    let tracked = track_with(&lim, &fast, &samples, &options).expect("played");
    common::check(&tracked.trajectory, &shown(step / 2.0), &samples[n], true);
    let worst = tracked
        .departures
        .iter()
        .max_by(|a, b| a.max_departure.total_cmp(&b.max_departure))
        .expect("a departure");
    assert_eq!(worst.quantity, Quantity::Velocity, "{worst:?}");
    assert!(
        worst.peak > lim[worst.joint].max_velocity * 1.5,
        "{worst:?}"
    );
    assert!(worst.start < worst.at && worst.at < worst.end, "{worst:?}");
}
