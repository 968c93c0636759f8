//! Rest-to-rest durations against Ruckig's time-optimal ones.
//!
//! testdata/trajectory/ruckig.csv is written by scripts/ruckig_compare.py
//! (random multi-joint cases solved by the `ruckig` PyPI package).

use crate::common;

use servobus_trajectory::{plan, JointLimits, Keyframe, PlanOptions};

#[test]
fn durations_within_a_thousandth_of_ruckig() {
    let text = std::fs::read_to_string(common::testdata("ruckig.csv")).expect("ruckig.csv");
    let mut rows: Vec<Vec<String>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    rows.retain(|r| r.len() == 8);
    let num = |s: &str| -> f64 { s.parse().expect("number") };
    let mut worst: f64 = 0.0;
    let mut cases = 0;
    let mut i = 0;
    while i < rows.len() {
        let case = rows[i][0].clone();
        let mut limits = Vec::new();
        let (mut from, mut to) = (Vec::new(), Vec::new());
        let expected = num(&rows[i][7]);
        while i < rows.len() && rows[i][0] == case {
            let r = &rows[i];
            from.push(num(&r[2]));
            to.push(num(&r[3]));
            let jerk = if r[6].is_empty() {
                None
            } else {
                Some(num(&r[6]))
            };
            limits.push(JointLimits::new(num(&r[4]), num(&r[5]), jerk));
            i += 1;
        }
        let traj = plan(
            &limits,
            &[Keyframe::new(from), Keyframe::new(to.clone())],
            &PlanOptions::default(),
        )
        .expect("plan");
        let rel = (traj.duration() - expected).abs() / expected.max(1e-12);
        assert!(
            rel <= 1e-3,
            "case {case}: {} s vs ruckig {expected} s",
            traj.duration()
        );
        common::check(&traj, &limits, &to, false);
        worst = worst.max(rel);
        cases += 1;
    }
    assert!(cases >= 100, "only {cases} cases");
    println!("{cases} cases, worst relative difference to ruckig: {worst:.3e}");
}
