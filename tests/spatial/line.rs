//! `arm-line.yaml`: the SO-101's tool goes straight down 5 cm from A to B,
//! straight back up, then straight 14 cm sideways to C.

use servobus_kinematics::{Poses, Vector3};

use crate::play;

/// The distance from `p` to the segment `a`-`b`, mm.
fn to_segment(p: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>) -> f64 {
    let d = b - a;
    let s = ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
    (p - (a + d * s)).norm()
}

#[test]
fn the_tool_keeps_within_1_mm_of_its_lines_from_the_true_angles() {
    let played = play("arm-line.yaml");
    // The keyframes' tool positions, mm (configs/motions/arm-line.yaml).
    let a = Vector3::new(220.0, 60.0, 120.0);
    let b = Vector3::new(220.0, 60.0, 70.0);
    let c = Vector3::new(220.0, -80.0, 120.0);
    let tool = played.model.frame_index("tool").expect("a tool frame");
    let mut poses = Poses::new(&played.model);
    let at: Vec<Vector3<f64>> = played
        .rows
        .iter()
        .map(|q| {
            played.model.forward(q, &mut poses);
            poses.frame(tool).expect("tool").translation.vector
        })
        .collect();
    let near = |p: &Vector3<f64>, to: Vector3<f64>| (p - to).norm() < 1.0;
    let first = at.iter().position(|p| near(p, a)).expect("reaches A");
    let last = at.iter().rposition(|p| near(p, c)).expect("reaches C");
    assert!(
        at[first..=last].iter().any(|p| near(p, b)),
        "the tool comes within 1 mm of B"
    );
    let worst = at[first..=last]
        .iter()
        .map(|&p| to_segment(p, a, b).min(to_segment(p, a, c)))
        .fold(0.0, f64::max);
    println!(
        "{} rows on the lines; worst distance {worst:.3} mm",
        last - first + 1
    );
    assert!(worst < 1.0, "the tool strays {worst} mm from its lines");
    // It ends each line at rest on its target: the closest rows to B and C.
    for (name, target) in [("B", b), ("C", c)] {
        let closest = at[first..=last]
            .iter()
            .map(|p| (p - target).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(closest < 1.0, "{name}: {closest} mm short");
    }
}
