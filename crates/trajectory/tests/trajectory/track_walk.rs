//! Random recordings played by `track`: a recording is outside data (a CSV
//! given to `servobus play`), so whatever it holds, tracking it never
//! panics, and the path keeps the velocity and acceleration limits (and
//! the jerk limit where there is one), checked by finite differences of
//! its positions as well as by its sampled states.
//!
//! The regressions: a recording whose length is a whole number of steps
//! but for rounding (`0.28 / 0.005 = 56.00000000000001`) gave the passes
//! a last step of zero length, over which the pursuit's bounds were
//! `0 / 0` when the joint was exactly at a limit: `f64::clamp` panicked
//! on the NaN ("min > max, or either was NaN").

use crate::common::{self, Noise};

use proptest::prelude::*;
use servobus_trajectory::{track, track_with, JointLimits, TrackOptions, Trajectory};

/// A one-joint recording of `n` samples `h` apart, `q(i)` at sample `i`.
fn recording(n: usize, h: f64, q: impl Fn(usize) -> f64) -> (Vec<f64>, Vec<Vec<f64>>) {
    let times = (0..n).map(|i| i as f64 * h).collect();
    let samples = (0..n).map(|i| vec![q(i)]).collect();
    (times, samples)
}

/// A random walk of `n` samples `h` apart from `seed`, steps of up to
/// `scale` (clamped to `[-bound, bound]`), on every joint of `joints`.
fn walk(
    seed: u64,
    n: usize,
    h: f64,
    scale: f64,
    joints: usize,
    bound: f64,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut rng = Noise(seed | 1);
    let mut q = vec![0.0f64; joints];
    let times = (0..n).map(|i| i as f64 * h).collect();
    let samples = (0..n)
        .map(|_| {
            for x in q.iter_mut() {
                *x = (*x + scale * rng.next()).clamp(-bound, bound);
            }
            q.clone()
        })
        .collect();
    (times, samples)
}

/// Relative tolerance on a limit in the finite-difference check: float
/// rounding of the path's pieces only.
const REL: f64 = 1e-6;

/// The sampling period of the finite-difference check, s.
const DT: f64 = 1e-3;

/// Checks by finite differences of the positions, `DT` apart, that the
/// speed, acceleration and (where limited) jerk keep within `limits`:
/// over a path with `|v| <= vm` the first difference over `DT` is within
/// `vm`, with `|a| <= am` the second within `am`, with `|j| <= jm` the
/// third within `jm` (mean value theorem). Tolerance: `REL` of the limit
/// plus the rounding of a k-th difference of positions up to `|p|`,
/// `2^k * 1e-15 * (1 + |p|) / DT^k`.
fn check_by_differences(traj: &Trajectory, limits: &[JointLimits]) {
    let n = (traj.duration() / DT).ceil() as usize + 4;
    let mut state = vec![Default::default(); limits.len()];
    let mut cursor = traj.cursor();
    let mut p: Vec<Vec<f64>> = vec![Vec::with_capacity(n + 1); limits.len()];
    for i in 0..=n {
        traj.sample_with(&mut cursor, i as f64 * DT, &mut state);
        for (pj, s) in p.iter_mut().zip(&state) {
            pj.push(s.position);
        }
    }
    for (j, (l, pj)) in limits.iter().zip(&p).enumerate() {
        let size = 1.0 + pj.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let round = |k: i32| 2f64.powi(k) * 1e-15 * size / DT.powi(k);
        let orders = [
            (1, Some(l.max_velocity), "velocity"),
            (2, Some(l.max_acceleration), "acceleration"),
            (3, l.max_jerk, "jerk"),
        ];
        for (k, limit, what) in orders {
            let Some(limit) = limit else { continue };
            let mut d = pj.clone();
            for _ in 0..k {
                d = d.windows(2).map(|w| (w[1] - w[0]) / DT).collect();
            }
            let bound = limit * (1.0 + REL) + round(k);
            for (i, x) in d.iter().enumerate() {
                assert!(
                    x.abs() <= bound,
                    "joint {j}: {what} {x} by differences at t={} beyond {limit} ({l:?})",
                    i as f64 * DT
                );
            }
        }
    }
}

/// Tracks and checks: the path starts and ends at the recording's ends at
/// rest and keeps every limit, by sampled states and by differences.
fn track_and_check(limits: &[JointLimits], times: &[f64], samples: &[Vec<f64>], step: f64) {
    let tracked = track(limits, times, samples, step).expect("tracked");
    let last = &samples[samples.len() - 1];
    common::check(&tracked.trajectory, limits, last, true);
    check_by_differences(&tracked.trajectory, limits);
}

#[test]
fn a_recording_ending_a_rounding_short_of_a_step_is_played_within_its_limits() {
    // 28 intervals of 10 ms: 0.28 s, 56.00000000000001 steps of 5 ms.
    // A ramp at 10 rad/s against 2 rad/s, no jerk limit: the pass ends at
    // the speed limit exactly.
    let lim = [JointLimits::new(2.0, 10.0, None)];
    let (times, samples) = recording(29, 0.01, |i| 0.1 * i as f64);
    track_and_check(&lim, &times, &samples, 0.005);
    // 7 intervals: 0.07 s, 14.000000000000002 steps. A jump of 0.1 at the
    // last sample with a jerk limit: the pass ends at the acceleration
    // limit exactly.
    let lim = [JointLimits::new(2.0, 10.0, Some(150.0))];
    let (times, samples) = recording(8, 0.01, |i| if i == 7 { 0.1 } else { 0.0 });
    track_and_check(&lim, &times, &samples, 0.005);
}

#[test]
fn seeded_random_walks_are_played_within_their_limits() {
    // The case as reported: a random walk, no jerk limit (it panicked in
    // `track::pass::pursue`).
    let lim = [JointLimits::new(2.0, 10.0, None)];
    let (times, samples) = walk(9, 29, 0.01, 0.2, 1, f64::INFINITY);
    track_and_check(&lim, &times, &samples, 0.005);
    let lim = [
        JointLimits::new(2.0, 10.0, None),
        JointLimits::new(3.0, 15.0, Some(150.0)),
    ];
    let (times, samples) = walk(0x9e37_79b9_7f4a_7c15, 205, 0.01, 0.3, 2, f64::INFINITY);
    track_and_check(&lim, &times, &samples, 0.005);
}

/// Limits of one joint: speed, acceleration, and a jerk limit or none.
fn joint_limits() -> impl Strategy<Value = JointLimits> {
    (
        0.5f64..5.0,
        2.0f64..50.0,
        prop_oneof![Just(None), (50.0f64..2000.0).prop_map(Some)],
    )
        .prop_map(|(v, a, j)| JointLimits::new(v, a, j))
}

/// A recording's spacing, tracking step and number of samples: often a
/// length of a whole number of steps but for rounding (the case that
/// panicked), else any.
fn timing() -> impl Strategy<Value = (f64, f64, usize)> {
    let h = prop_oneof![
        3 => Just(0.01),
        1 => Just(0.02),
        1 => Just(0.005),
        1 => Just(1.0 / 30.0),
        2 => 0.002f64..0.05,
    ];
    let step =
        prop_oneof![3 => Just(0.005), 1 => Just(0.01), 1 => Just(0.002), 2 => 0.001f64..0.02];
    (h, step).prop_flat_map(|(h, step)| {
        let rounded: Vec<usize> = (2usize..250)
            .filter(|&n| {
                let steps = (n - 1) as f64 * h / step;
                steps > steps.floor() && steps - steps.floor() < 1e-6
            })
            .collect();
        let n = if rounded.is_empty() {
            (2usize..250).boxed()
        } else {
            prop_oneof![2usize..250, prop::sample::select(rounded)].boxed()
        };
        (Just(h), Just(step), n)
    })
}

proptest! {
    // 64 cases by default (PROPTEST_CASES=N for a longer run).
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(64),
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_walks_are_played_within_every_limit(
        limits in prop::collection::vec(joint_limits(), 1..3),
        seed in any::<u64>(),
        (h, step, n) in timing(),
        scale in prop_oneof![0.0f64..0.05, 0.05f64..1.0],
        bound in prop_oneof![Just(f64::INFINITY), 0.2f64..3.0],
        resolution in prop_oneof![Just(0.0), Just(0.00005)],
    ) {
        // With a rounding of the samples, near the position limits the
        // path may leave them by about the rounding, which `track_with`
        // refuses (a separate matter): position limits without rounding.
        let bound = if resolution > 0.0 { f64::INFINITY } else { bound };
        let limits: Vec<JointLimits> = limits
            .into_iter()
            .map(|l| l.with_positions(-bound, bound))
            .collect();
        let (times, samples) = walk(seed, n, h, scale, limits.len(), bound);
        let options = TrackOptions { step, resolution };
        let tracked = track_with(&limits, &times, &samples, &options)
            .map_err(|e| TestCaseError::fail(format!("refused: {e}")))?;
        // With a rounding of the samples, the recording is followed where
        // it keeps within the limits widened by what the rounding makes of
        // its differences (`TrackOptions::resolution`): those are kept.
        // The differences are those of the samples' grid, of at least
        // four intervals.
        let r = resolution;
        let h = (n - 1) as f64 * h / (n - 1).max(4) as f64;
        let kept: Vec<JointLimits> = limits
            .iter()
            .map(|l| JointLimits {
                max_velocity: l.max_velocity + 2.0 * r / h,
                max_acceleration: l.max_acceleration + 4.0 * r / (h * h),
                max_jerk: l.max_jerk.map(|jm| jm + 8.0 * r / (h * h * h)),
                ..*l
            })
            .collect();
        common::check(&tracked.trajectory, &kept, &samples[n - 1], true);
        check_by_differences(&tracked.trajectory, &kept);
    }
}
