//! Helpers shared by the integration tests: invariant checks by dense
//! sampling, and the CSV files under testdata/trajectory.
#![allow(dead_code)]

use servobus_trajectory::{JointLimits, JointState, Keyframe, Trajectory};
use std::path::PathBuf;

/// Path of a file under the workspace's testdata/trajectory.
pub fn testdata(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/trajectory")
        .join(name)
}

/// Relative tolerance on limits (float rounding only).
pub const REL: f64 = 1e-6;

/// Samples `traj` densely and checks, between consecutive samples, that
/// position, velocity and acceleration change no faster than the velocity,
/// acceleration and jerk limits allow (which also proves continuity), that
/// every sample is within the limits, and that the end is `last` at rest.
/// `pos_slack` widens the position limits (for states starting outside).
pub fn check(traj: &Trajectory, limits: &[JointLimits], last: &[f64], check_positions: bool) {
    let n = limits.len();
    let steps = 4000;
    let dt = traj.duration() / steps as f64;
    let mut cursor = traj.cursor();
    let mut prev = vec![JointState::default(); n];
    let mut cur = vec![JointState::default(); n];
    traj.sample_with(&mut cursor, 0.0, &mut prev);
    for i in 1..=steps + 10 {
        let t = (i as f64 * dt).min(traj.duration() + 1.0);
        traj.sample_with(&mut cursor, t, &mut cur);
        let h = if i <= steps { dt } else { 1.0 };
        for (j, l) in limits.iter().enumerate() {
            let (a, b) = (prev[j], cur[j]);
            let ctx = || format!("joint {j} at t={t} (dt={h}): {a:?} -> {b:?}, limits {l:?}");
            assert!(
                b.velocity.abs() <= l.max_velocity * (1.0 + REL) + 1e-9,
                "velocity {}",
                ctx()
            );
            assert!(
                b.acceleration.abs() <= l.max_acceleration * (1.0 + REL) + 1e-9,
                "acceleration {}",
                ctx()
            );
            assert!(
                (b.position - a.position).abs() <= l.max_velocity * h * (1.0 + REL) + 1e-9,
                "position jump {}",
                ctx()
            );
            assert!(
                (b.velocity - a.velocity).abs() <= l.max_acceleration * h * (1.0 + REL) + 1e-9,
                "velocity jump {}",
                ctx()
            );
            if let Some(jm) = l.max_jerk {
                assert!(
                    (b.acceleration - a.acceleration).abs() <= jm * h * (1.0 + REL) + 1e-7,
                    "jerk {}",
                    ctx()
                );
            }
            if check_positions {
                let slack = 1e-9 * (1.0 + b.position.abs());
                assert!(
                    b.position >= l.min_position - slack && b.position <= l.max_position + slack,
                    "position {}",
                    ctx()
                );
            }
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    let mut end = vec![JointState::default(); n];
    traj.final_state(&mut end);
    for (j, (s, &q)) in end.iter().zip(last).enumerate() {
        assert!(
            (s.position - q).abs() <= 1e-9 * (1.0 + q.abs()),
            "joint {j} ends at {} not {q}",
            s.position
        );
        assert!(
            s.velocity.abs() <= 1e-9 && s.acceleration.abs() <= 1e-7,
            "joint {j} not at rest: {s:?}"
        );
    }
}

/// Checks that every joint is at its keyframe at each segment's end.
pub fn check_keyframes(traj: &Trajectory, keyframes: &[Keyframe]) {
    let mut out = vec![JointState::default(); traj.joints()];
    for s in traj.segments() {
        traj.sample(s.end, &mut out);
        for (j, (o, &q)) in out.iter().zip(&keyframes[s.keyframe].positions).enumerate() {
            assert!(
                (o.position - q).abs() <= 1e-7 * (1.0 + q.abs()),
                "keyframe {} joint {j}: {} != {q}",
                s.keyframe,
                o.position
            );
        }
    }
}

/// The benchmark choreography: `limits,...` and `keyframe,...` rows.
pub fn choreography() -> (Vec<JointLimits>, Vec<Keyframe>) {
    let text = std::fs::read_to_string(testdata("choreography.csv"))
        .expect("testdata/trajectory/choreography.csv");
    let mut limits = Vec::new();
    let mut keyframes = Vec::new();
    for line in text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
    {
        let mut f = line.split(',').map(str::trim);
        let kind = f.next().unwrap_or_default();
        let nums: Vec<f64> = f.map(|x| x.parse().expect("number")).collect();
        match kind {
            "limits" => limits.push(JointLimits {
                min_position: nums[0],
                max_position: nums[1],
                max_velocity: nums[2],
                max_acceleration: nums[3],
                max_jerk: nums.get(4).copied(),
            }),
            "keyframe" => keyframes.push(Keyframe::new(nums)),
            other => panic!("unknown row kind {other}"),
        }
    }
    (limits, keyframes)
}

/// A deterministic source of numbers in [-1, 1) (xorshift64*), for
/// recordings and noise that are the same on every run. Seed it with an
/// odd number.
pub struct Noise(pub u64);

impl Noise {
    /// The next number in [-1, 1).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        2.0 * (x as f64 / (1u64 << 53) as f64) - 1.0
    }
}
