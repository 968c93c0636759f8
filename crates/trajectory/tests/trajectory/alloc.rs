//! Sampling allocates nothing: a counting global allocator around the
//! control-loop calls.

use servobus_alloc_count::{allocations_during, Counting};
use servobus_trajectory::{plan, JointLimits, JointState, Keyframe, PlanOptions};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn sampling_allocates_nothing() {
    let limits = vec![JointLimits::new(3.0, 20.0, Some(200.0)); 18];
    let keyframes: Vec<Keyframe> = (0..20)
        .map(|k| {
            Keyframe::new(
                (0..18)
                    .map(|j| ((k * 7 + j * 3) % 11) as f64 * 0.1)
                    .collect::<Vec<_>>(),
            )
        })
        .collect();
    let traj = plan(&limits, &keyframes, &PlanOptions::default()).expect("plan");
    let mut cursor = traj.cursor();
    let mut out = [JointState::default(); 18];
    let (count, checksum) = allocations_during(|| {
        let mut t = -0.1;
        let mut checksum = 0.0;
        while t < traj.duration() + 0.1 {
            traj.sample_with(&mut cursor, t, &mut out);
            checksum += out[0].position;
            traj.sample(t * 0.5, &mut out);
            checksum += out[17].velocity;
            t += 0.001;
        }
        traj.final_state(&mut out);
        checksum
    });
    assert!(checksum.is_finite());
    assert_eq!(count, 0, "sampling allocated {count} times");
}
