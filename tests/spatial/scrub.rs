//! The shipped hexapod motions do not scrub: over every stretch of time two
//! feet are both on the ground, their distance apart changes by less than
//! 1 mm. Measured on the planned path at 200 Hz. A walking foot is on the
//! ground at the standing height (40 mm below its hip); a dancing hexapod
//! keeps every foot on the ground throughout.

use servobus_kinematics::{Legs, Point3, Poses};
use servobus_runtime::config::{load_motion, plan_motion};
use servobus_trajectory::JointState;

use crate::config;

/// The largest change of distance between two feet over a stretch of time
/// when both are down, mm, on the planned path of `name` (every foot down
/// throughout when `planted`).
pub fn worst_slide(name: &str, planted: bool) -> f64 {
    let (motion, robot) = load_motion(&config(&format!("motions/{name}")), None).expect("loads");
    let path = plan_motion(&motion, &robot).expect("plans");
    let legs = Legs::new(&robot.geometry().expect("geometry")).expect("legs");
    let mut poses = Poses::new(legs.model());
    let mut state = vec![JointState::default(); path.joints()];
    let mut q = vec![0.0; path.joints()];
    let mut feet = vec![Point3::origin(); legs.len()];
    let n = legs.len();
    let mut reference: Vec<Option<f64>> = vec![None; n * n];
    let mut worst: f64 = 0.0;
    let steps = (path.duration() * 200.0).ceil() as usize;
    for k in 0..=steps {
        path.sample(k as f64 / 200.0, &mut state);
        for (v, s) in q.iter_mut().zip(&state) {
            *v = s.position;
        }
        legs.feet(&q, &mut poses, &mut feet);
        let down: Vec<bool> = feet.iter().map(|p| planted || p.z < -40.0 + 0.05).collect();
        for a in 0..n {
            for b in a + 1..n {
                let slot = &mut reference[a * n + b];
                if !(down[a] && down[b]) {
                    *slot = None;
                    continue;
                }
                let d = (feet[a] - feet[b]).norm();
                worst = worst.max((d - *slot.get_or_insert(d)).abs());
            }
        }
    }
    worst
}

#[test]
fn shipped_hexapod_motions_keep_planted_feet_within_1_mm() {
    for (name, planted) in [
        ("hexapod-dance.yaml", true),
        ("hexapod-tripod.yaml", false),
        ("hexapod-walk-turn.yaml", false),
    ] {
        let slide = worst_slide(name, planted);
        println!("{name}: planted feet move {slide:.3} mm apart at most");
        assert!(slide < 1.0, "{name}: planted feet slide {slide} mm");
    }
}
