//! Passing through untimed keyframes against stopping at each one, on the
//! benchmark choreography kept in testdata/trajectory/choreography.csv.

use crate::common;

use servobus_trajectory::{plan, PlanOptions};

#[test]
fn untimed_pass_through_beats_stopping() {
    let (limits, keyframes) = common::choreography();
    assert_eq!(limits.len(), 6);
    assert!(keyframes.len() >= 20);
    let through = plan(&limits, &keyframes, &PlanOptions::default()).expect("plan");
    let stopping = plan(
        &limits,
        &keyframes,
        &PlanOptions {
            stop_at_keyframes: true,
            ..PlanOptions::default()
        },
    )
    .expect("plan with stops");
    let last = &keyframes[keyframes.len() - 1].positions;
    common::check(&through, &limits, last, true);
    common::check(&stopping, &limits, last, true);
    common::check_keyframes(&through, &keyframes);
    let saving = 1.0 - through.duration() / stopping.duration();
    println!(
        "benchmark choreography ({} keyframes): stopping at each {:.3} s, passing through {:.3} s, {:.1} % shorter",
        keyframes.len(),
        stopping.duration(),
        through.duration(),
        100.0 * saving
    );
    assert!(saving >= 0.20, "only {:.1} % shorter", 100.0 * saving);
}

#[test]
fn no_overshoot_beyond_keyframe_range() {
    let (limits, keyframes) = common::choreography();
    let traj = plan(&limits, &keyframes, &PlanOptions::default()).expect("plan");
    for (j, l) in limits.iter().enumerate() {
        let s = traj.joint_summary(j).expect("joint");
        let lo = keyframes
            .iter()
            .map(|k| k.positions[j])
            .fold(f64::INFINITY, f64::min);
        let hi = keyframes
            .iter()
            .map(|k| k.positions[j])
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            s.min_position >= lo - 1e-9 && s.max_position <= hi + 1e-9,
            "joint {j}: {s:?} vs [{lo}, {hi}]"
        );
        assert!(s.peak_velocity <= l.max_velocity * (1.0 + 1e-9));
        assert!(s.peak_acceleration <= l.max_acceleration * (1.0 + 1e-9));
        assert!(s.peak_jerk <= l.max_jerk.unwrap_or(f64::INFINITY) * (1.0 + 1e-9));
    }
}
