//! Property tests: random limits and keyframes; sampled motion never
//! exceeds a limit, is continuous, passes every keyframe and ends at rest.

mod common;

use proptest::prelude::*;
use servobus_trajectory::{
    plan, retarget, stop, JointLimits, JointState, Keyframe, OnLimit, PlanOptions, TimedShape,
};

fn limits_strategy() -> impl Strategy<Value = JointLimits> {
    (
        0.2f64..5.0,
        0.5f64..40.0,
        prop::option::weighted(0.8, 5.0f64..500.0),
    )
        .prop_map(|(v, a, j)| JointLimits::new(v, a, j).with_positions(-2.0, 2.0))
}

/// Joints, then keyframes with positions in the limits; some positions
/// repeat the previous one (a joint that pauses).
fn case() -> impl Strategy<Value = (Vec<JointLimits>, Vec<Vec<f64>>)> {
    (1usize..5, 2usize..8).prop_flat_map(|(nj, nk)| {
        (
            prop::collection::vec(limits_strategy(), nj),
            prop::collection::vec(
                prop::collection::vec(prop_oneof![3 => -2.0f64..2.0, 1 => Just(0.5)], nj),
                nk,
            ),
        )
    })
}

proptest! {
    // 64 cases by default (PROPTEST_CASES=N for a longer run).
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(64),
        ..ProptestConfig::default()
    })]

    #[test]
    fn untimed_within_limits((limits, kfs) in case(), stop_each in any::<bool>()) {
        let keyframes: Vec<Keyframe> = kfs.iter().cloned().map(Keyframe::new).collect();
        let options = PlanOptions { stop_at_keyframes: stop_each, ..PlanOptions::default() };
        let traj = plan(&limits, &keyframes, &options).expect("plan");
        common::check(&traj, &limits, &kfs[kfs.len() - 1], true);
        common::check_keyframes(&traj, &keyframes);
        // Untimed motion stays within the keyframes' range.
        for j in 0..limits.len() {
            let s = traj.joint_summary(j).expect("joint");
            let lo = kfs.iter().map(|k| k[j]).fold(f64::INFINITY, f64::min);
            let hi = kfs.iter().map(|k| k[j]).fold(f64::NEG_INFINITY, f64::max);
            prop_assert!(s.min_position >= lo - 1e-9 && s.max_position <= hi + 1e-9);
        }
    }

    #[test]
    fn timed_stretched_within_limits(
        (limits, kfs) in case(),
        gaps in prop::collection::vec(0.05f64..2.0, 8),
        timed in prop::collection::vec(any::<bool>(), 8),
        shape in prop_oneof![Just(TimedShape::Cubic), Just(TimedShape::Monotone), Just(TimedShape::MinimumJerk)],
        repeat in 1u32..3,
    ) {
        // Mixed timed and untimed keyframes; the cubic spline may leave
        // the position limits, which stretching cannot fix: widen them.
        let limits: Vec<JointLimits> = limits.into_iter().map(|l| l.with_positions(-50.0, 50.0)).collect();
        let mut t = 0.0;
        let keyframes: Vec<Keyframe> = kfs.iter().enumerate().map(|(k, p)| {
            t += gaps[k];
            let kf = Keyframe::new(p.clone());
            if k > 0 && timed[k] { kf.at(t) } else { kf }
        }).collect();
        let options = PlanOptions { shape, on_limit: OnLimit::Stretch, repeat, ..PlanOptions::default() };
        let traj = plan(&limits, &keyframes, &options).expect("plan");
        common::check(&traj, &limits, &kfs[kfs.len() - 1], true);
        common::check_keyframes(&traj, &keyframes);
        let segs = traj.segments();
        prop_assert_eq!(segs.len(), if kfs[0] == kfs[kfs.len() - 1] { (kfs.len() - 1) * repeat as usize } else { kfs.len() * repeat as usize - 1 });
        for w in segs.windows(2) {
            prop_assert!(w[0].end == w[1].start && w[0].start <= w[0].end);
        }
    }

    #[test]
    fn retarget_and_stop_within_limits(
        (limits, kfs) in case(),
        fv in prop::collection::vec(-1.0f64..1.0, 5),
        fa in prop::collection::vec(-1.0f64..1.0, 5),
    ) {
        // A state within the limits whose speed stays within the limit
        // while the acceleration is ramped to zero (otherwise exceeding it
        // is unavoidable).
        let states: Vec<JointState> = limits.iter().enumerate().map(|(j, l)| {
            let vm = l.max_velocity;
            let (a, ramp) = match l.max_jerk {
                Some(jm) => {
                    let a = fa[j] * l.max_acceleration.min(0.99 * (2.0 * jm * vm).sqrt());
                    (a, a.signum() * a * a / (2.0 * jm))
                }
                None => (0.0, 0.0),
            };
            // Speeds whose value after the ramp, v + ramp, is within +-vm.
            let (lo, hi) = ((-vm).max(-vm - ramp), vm.min(vm - ramp));
            let v = lo + 0.5 * (fv[j] + 1.0) * (hi - lo);
            JointState { position: kfs[0][j] * 0.5, velocity: v, acceleration: a }
        }).collect();
        let target = &kfs[kfs.len() - 1];
        let free: Vec<JointLimits> = limits.iter().map(|l| l.with_positions(-1e3, 1e3)).collect();
        let traj = retarget(&limits, &states, target).expect("retarget");
        common::check(&traj, &free, target, true);
        let mut s0 = vec![JointState::default(); limits.len()];
        traj.sample(0.0, &mut s0);
        // Continuous from the given state (acceleration only jumps for a
        // joint without a jerk limit).
        for ((a, b), l) in s0.iter().zip(&states).zip(&limits) {
            prop_assert!((a.position - b.position).abs() < 1e-12 && (a.velocity - b.velocity).abs() < 1e-12);
            if traj.duration() > 0.0 && l.max_jerk.is_some() {
                prop_assert!((a.acceleration - b.acceleration).abs() < 1e-9);
            }
        }
        let halt = stop(&limits, &states).expect("stop");
        let mut end = vec![JointState::default(); limits.len()];
        halt.final_state(&mut end);
        let ends: Vec<f64> = end.iter().map(|s| s.position).collect();
        common::check(&halt, &free, &ends, true);
    }
}
