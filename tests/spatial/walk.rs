//! `hexapod-walk-turn.yaml`: forward 30 cm, a 90 deg turn to the left,
//! 10 cm to the right, in a tripod gait with a 25 mm lift.

use servobus_kinematics::{planar_motion, Legs, Point3, Poses, Vector2};

use crate::play;

/// Every foot (body frame, mm) for each row of angles.
fn feet(legs: &Legs, rows: &[Vec<f64>]) -> Vec<Vec<Point3<f64>>> {
    let mut poses = Poses::new(legs.model());
    rows.iter()
        .map(|q| {
            let mut f = vec![Point3::origin(); legs.len()];
            legs.feet(q, &mut poses, &mut f);
            f
        })
        .collect()
}

#[test]
fn stance_feet_do_not_slip_swing_feet_lift_and_the_body_goes_where_told() {
    let played = play("hexapod-walk-turn.yaml");
    let legs = Legs::new(&played.model).expect("six legs");
    let truth = feet(&legs, &played.rows);
    let plan = feet(&legs, &played.planned);
    // Standing (femur 30, tibia -60): every foot 40 mm below its hip.
    let ground = -40.0;
    let down = |p: &Point3<f64>| p.z < ground + 0.05;
    // 1. Feet down in the plan keep their distances to each other within
    //    1 mm, and their height within 1 mm, in the truth.
    let mut reference: Vec<Vec<Option<f64>>> = vec![vec![None; legs.len()]; legs.len()];
    let mut worst_slip: f64 = 0.0;
    let mut worst_height: f64 = 0.0;
    for (planned, real) in plan.iter().zip(&truth) {
        for a in 0..legs.len() {
            if down(&planned[a]) {
                worst_height = worst_height.max((real[a].z - ground).abs());
            }
            for b in a + 1..legs.len() {
                if !(down(&planned[a]) && down(&planned[b])) {
                    reference[a][b] = None;
                    continue;
                }
                let d = (real[a] - real[b]).norm();
                let d0 = *reference[a][b].get_or_insert(d);
                worst_slip = worst_slip.max((d - d0).abs());
            }
        }
    }
    // 2. Each swing rises to the lift, 25 mm, within 2 mm.
    let mut swings = 0;
    for leg in 0..legs.len() {
        let mut peak: Option<f64> = None;
        for (planned, real) in plan.iter().zip(&truth) {
            if down(&planned[leg]) {
                if let Some(h) = peak.take() {
                    swings += 1;
                    assert!(
                        (h - ground - 25.0).abs() < 2.0,
                        "leg {leg} rose {} mm",
                        h - ground
                    );
                }
            } else {
                peak = Some(peak.map_or(real[leg].z, |h: f64| h.max(real[leg].z)));
            }
        }
    }
    // 3. The body's path, from the feet down in consecutive rows (the
    //    feet move by the inverse of the body's move).
    let (mut yaw, mut x, mut y) = (0.0f64, 0.0f64, 0.0f64);
    let mut track = vec![Vector2::new(0.0, 0.0)];
    for k in 0..plan.len().saturating_sub(1) {
        let common: Vec<usize> = (0..legs.len())
            .filter(|&l| down(&plan[k][l]) && down(&plan[k + 1][l]))
            .collect();
        if common.len() >= 3 {
            let flat = |r: usize| -> Vec<Vector2<f64>> {
                common
                    .iter()
                    .map(|&l| Vector2::new(truth[r][l].x, truth[r][l].y))
                    .collect()
            };
            let (angle, shift) = planar_motion(&flat(k + 1), &flat(k));
            let (s, c) = yaw.sin_cos();
            x += c * shift.x - s * shift.y;
            y += s * shift.x + c * shift.y;
            yaw += angle;
        }
        if k % 50 == 0 {
            track.push(Vector2::new(x, y));
        }
    }
    track.push(Vector2::new(x, y));
    let length: f64 = track.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    println!(
        "slip {worst_slip:.3} mm, height {worst_height:.3} mm, {swings} swings; body to \
         ({x:.1}, {y:.1}) mm, {:.2} deg, path {length:.1} mm",
        yaw.to_degrees()
    );
    assert!(worst_slip < 1.0, "stance feet slip {worst_slip} mm");
    assert!(
        worst_height < 1.0,
        "stance feet leave the ground by {worst_height} mm"
    );
    assert!(swings > 20, "only {swings} swings");
    // 300 mm forward and 100 mm sideways: 400 mm of path; 90 deg of turn.
    assert!((length - 400.0).abs() < 12.0, "the body went {length} mm");
    assert!(
        (yaw.to_degrees() - 90.0).abs() < 2.7,
        "the body turned {yaw} rad"
    );
}
