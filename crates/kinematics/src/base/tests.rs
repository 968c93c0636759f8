//! Wheel maps, speed limits, odometry and the checks of a `base:` section.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use proptest::prelude::*;
use servobus_alloc_count::{allocations_during, Counting};

use super::*;

mod checks;

#[global_allocator]
static GLOBAL: Counting = Counting;

const JOINTS: &[&str] = &[
    "wheel_left",
    "wheel_back",
    "wheel_right",
    "wheel_l",
    "wheel_r",
];

fn joint_index(name: &str) -> Option<usize> {
    JOINTS.iter().position(|j| *j == name)
}

fn parse(yaml: &str) -> BaseSpec {
    serde_yaml::from_str(yaml).expect("a base section the test wrote")
}

fn check(yaml: &str) -> Result<Base, BaseError> {
    Base::new(&parse(yaml), joint_index)
}

fn refused(yaml: &str) -> String {
    check(yaml)
        .expect_err("a base the test made wrong")
        .to_string()
}

const LEKIWI: &str = "omni3:
  wheel_radius_mm: 50.8
  base_radius_mm: 125
  wheels:
    - {joint: wheel_left, angle_deg: 150}
    - {joint: wheel_back, angle_deg: 270}
    - {joint: wheel_right, angle_deg: 30}
";

const DIFF: &str =
    "differential: {wheel_radius_mm: 50, track_mm: 160, left: wheel_l, right: wheel_r}";

fn lekiwi() -> Base {
    check(LEKIWI).expect("LeKiwi's base")
}

fn diff() -> Base {
    check(DIFF).expect("a differential base")
}

fn omni(angles: [f64; 3], r_mm: f64, big_r_mm: f64) -> Result<Base, BaseError> {
    check(&format!(
        "omni3: {{wheel_radius_mm: {r_mm}, base_radius_mm: {big_r_mm}, wheels: [\
         {{joint: wheel_left, angle_deg: {}}}, {{joint: wheel_back, angle_deg: {}}}, \
         {{joint: wheel_right, angle_deg: {}}}]}}",
        angles[0], angles[1], angles[2]
    ))
}

fn speeds(base: &Base, t: Twist) -> Vec<f64> {
    let mut out = vec![0.0; base.wheels().len()];
    base.wheel_speeds(&t, &mut out).expect("a drivable twist");
    out
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn same_twist(a: Twist, b: Twist, tol: f64) -> bool {
    close(a.x, b.x, tol) && close(a.y, b.y, tol) && close(a.theta, b.theta, tol)
}

fn twist(x: f64, y: f64, theta: f64) -> Twist {
    Twist { x, y, theta }
}

#[test]
fn the_spec_order_and_kind_are_kept() {
    let b = lekiwi();
    assert_eq!((b.kind(), b.wheels()), (BaseKind::Omni3, &[0, 1, 2][..]));
    let d = diff();
    assert_eq!(
        (d.kind(), d.wheels()),
        (BaseKind::Differential, &[3, 4][..])
    );
    assert_eq!(d.wheel_joints(), ["wheel_l", "wheel_r"]);
}

#[test]
fn known_wheel_speeds() {
    let (r, big_r) = (0.0508, 0.125);
    // Turning in place: every rim moves at R w, counter-clockwise.
    let spin = speeds(&lekiwi(), twist(0.0, 0.0, 2.0));
    assert!(
        spin.iter().all(|&s| close(s, big_r * 2.0 / r, 1e-12)),
        "{spin:?}"
    );
    // Forward: -sin(a) / r, i.e. -0.5, 1, -0.5 over r.
    let fwd = speeds(&lekiwi(), twist(1.0, 0.0, 0.0));
    for (s, want) in fwd.iter().zip([-0.5 / r, 1.0 / r, -0.5 / r]) {
        assert!(close(*s, want, 1e-12), "{fwd:?}");
    }
    // Left: cos(a) / r.
    let left = speeds(&lekiwi(), twist(0.0, 1.0, 0.0));
    let c = 3f64.sqrt() / 2.0;
    for (s, want) in left.iter().zip([-c / r, 0.0, c / r]) {
        assert!((s - want).abs() < 1e-12, "{left:?}");
    }
    assert_eq!(speeds(&diff(), twist(1.0, 0.0, 0.0)), [20.0, 20.0]);
    let turn = speeds(&diff(), twist(0.0, 0.0, 1.0));
    assert!(
        close(turn[0], -1.6, 1e-12) && close(turn[1], 1.6, 1e-12),
        "{turn:?}"
    );
}

proptest! {
    #[test]
    fn omni3_twist_inverts_wheel_speeds(x in -3.0..3.0f64, y in -3.0..3.0f64, w in -12.0..12.0f64) {
        let b = lekiwi();
        let t = twist(x, y, w);
        let back = b.twist(&speeds(&b, t)).expect("finite speeds");
        prop_assert!(same_twist(back, t, 1e-12), "{t:?} -> {back:?}");
    }

    #[test]
    fn any_omni3_geometry_inverts(
        a0 in 0.0..360.0f64, gap1 in 5.0..175.0f64, gap2 in 5.0..175.0f64,
        r_mm in 10.0..200.0f64, big_r_mm in 30.0..500.0f64,
        x in -3.0..3.0f64, y in -3.0..3.0f64, w in -12.0..12.0f64,
    ) {
        let b = omni([a0, a0 + gap1, a0 + gap1 + gap2 + 5.0], r_mm, big_r_mm)
            .expect("three distinct angles");
        let t = twist(x, y, w);
        let back = b.twist(&speeds(&b, t)).expect("finite speeds");
        prop_assert!(same_twist(back, t, 1e-9), "{t:?} -> {back:?}");
    }

    #[test]
    fn differential_twist_inverts_wheel_speeds(x in -3.0..3.0f64, w in -12.0..12.0f64) {
        let b = diff();
        let t = twist(x, 0.0, w);
        let back = b.twist(&speeds(&b, t)).expect("finite speeds");
        prop_assert!(same_twist(back, t, 1e-12), "{t:?} -> {back:?}");
    }

    #[test]
    fn limited_keeps_the_direction_and_the_limits(
        x in -3.0..3.0f64, y in -3.0..3.0f64, w in -12.0..12.0f64,
        limits in proptest::collection::vec(0.5..40.0f64, 3),
    ) {
        let b = lekiwi();
        let t = twist(x, y, w);
        let mut out = [0.0; 3];
        let factor = b.limited(&t, &limits, &mut out).expect("valid limits");
        prop_assert!(factor > 0.0 && factor <= 1.0);
        let use_of_limit = out.iter().zip(&limits).map(|(s, m)| s.abs() / m);
        prop_assert!(use_of_limit.clone().all(|u| u <= 1.0), "{out:?} over {limits:?}");
        if factor < 1.0 {
            // The fastest wheel (for its limit) is exactly at it.
            prop_assert_eq!(use_of_limit.fold(0.0, f64::max), 1.0);
        }
        let moved = b.twist(&out).expect("finite speeds");
        let want = twist(x * factor, y * factor, w * factor);
        prop_assert!(same_twist(moved, want, 1e-9), "{moved:?} != {want:?}");
    }

    #[test]
    fn odometry_heading_stays_in_range(
        steps in proptest::collection::vec((-2.0..2.0f64, -2.0..2.0f64, -20.0..20.0f64, 0.0..0.5f64), 1..40),
    ) {
        let mut odo = Odometry::default();
        for (x, y, w, dt) in steps {
            odo.integrate(&twist(x, y, w), dt).expect("a valid step");
            prop_assert!(odo.theta_rad > -PI && odo.theta_rad <= PI, "{odo:?}");
        }
    }
}

#[test]
fn limited_names_a_figure_and_leaves_a_slow_twist_alone() {
    let b = lekiwi();
    let mut out = [0.0; 3];
    // Forward 1 m/s needs 1 / 0.0508 rad/s on the back wheel.
    let factor = b
        .limited(&twist(1.0, 0.0, 0.0), &[10.0; 3], &mut out)
        .expect("limits");
    assert!(close(factor, 10.0 * 0.0508, 1e-12), "{factor}");
    assert_eq!(out[1], 10.0);
    assert!(
        close(out[0], -5.0, 1e-12) && close(out[2], -5.0, 1e-12),
        "{out:?}"
    );
    let slow = twist(0.1, -0.05, 0.3);
    let factor = b.limited(&slow, &[10.0; 3], &mut out).expect("limits");
    assert_eq!((factor, out.to_vec()), (1.0, speeds(&b, slow)));
    // A negative wheel at its limit keeps its sign.
    let mut two = [0.0; 2];
    let factor = diff()
        .limited(&twist(0.0, 0.0, -5.0), &[4.0, 8.0], &mut two)
        .expect("limits");
    assert!(close(factor, 4.0 / 8.0, 1e-12), "{factor}");
    assert_eq!(two, [4.0, -4.0]);
}

#[test]
fn the_per_cycle_methods_allocate_nothing() {
    let (b, d) = (lekiwi(), diff());
    let (mut three, mut two, mut odo) = ([0.0; 3], [0.0; 2], Odometry::default());
    let t = twist(0.3, 0.1, 1.0);
    let (n, ok) = allocations_during(|| {
        b.wheel_speeds(&t, &mut three)?;
        b.limited(&t, &[1.0; 3], &mut three)?;
        let back = b.twist(&three)?;
        odo.integrate(&back, 0.01)?;
        d.limited(&twist(0.3, 0.0, 1.0), &[1.0; 2], &mut two)?;
        d.twist(&two).map(|_| ())
    });
    assert_eq!((n, ok), (0, Ok(())));
}

fn run(odo: &mut Odometry, t: Twist, total_s: f64, steps: u32) {
    for _ in 0..steps {
        odo.integrate(&t, total_s / f64::from(steps))
            .expect("a valid step");
    }
}

#[test]
fn odometry_goes_straight_and_round() {
    let mut odo = Odometry::default();
    odo.integrate(&twist(1.0, 0.0, 0.0), 1.0).expect("a step");
    assert_eq!(
        odo,
        Odometry {
            x_m: 1.0,
            y_m: 0.0,
            theta_rad: 0.0
        }
    );
    // A quarter circle of radius 1 m (pi/2 m/s at pi/2 rad/s), to the left.
    let mut quarter = Odometry::default();
    quarter
        .integrate(&twist(FRAC_PI_2, 0.0, FRAC_PI_2), 1.0)
        .expect("a step");
    assert!(
        close(quarter.x_m, 1.0, 1e-15) && close(quarter.y_m, 1.0, 1e-15),
        "{quarter:?}"
    );
    assert!(close(quarter.theta_rad, FRAC_PI_2, 1e-15), "{quarter:?}");
    // Sideways while facing +y world moves along -x world.
    let mut side = Odometry {
        x_m: 0.0,
        y_m: 0.0,
        theta_rad: FRAC_PI_2,
    };
    side.integrate(&twist(0.0, 1.0, 0.0), 1.0).expect("a step");
    assert!(
        close(side.x_m, -1.0, 1e-15) && side.y_m.abs() < 1e-15,
        "{side:?}"
    );
}

#[test]
fn a_full_circle_returns_to_the_start() {
    let period = 7.0;
    let mut odo = Odometry::default();
    run(&mut odo, twist(0.4, 0.1, TAU / period), period, 100);
    assert!(odo.x_m.abs() < 1e-9 && odo.y_m.abs() < 1e-9, "{odo:?}");
    assert!(odo.theta_rad.abs() < 1e-9, "{odo:?}");
}

#[test]
fn an_arc_ends_at_the_same_pose_in_any_number_of_steps() {
    for t in [
        twist(0.7, -0.2, 1.3),
        twist(0.5, 0.0, -3e-5),
        twist(0.5, 0.0, 0.0),
    ] {
        let (mut one, mut many) = (Odometry::default(), Odometry::default());
        run(&mut one, t, 2.0, 1);
        run(&mut many, t, 2.0, 1000);
        assert!(
            close(one.x_m, many.x_m, 1e-9) && close(one.y_m, many.y_m, 1e-9),
            "{one:?} {many:?}"
        );
        assert!(
            close(one.theta_rad, many.theta_rad, 1e-9),
            "{one:?} {many:?}"
        );
    }
}

#[test]
fn rotation_in_place_wraps_the_heading() {
    let mut odo = Odometry::default();
    run(&mut odo, twist(0.0, 0.0, 1.0), 4.0, 8);
    assert_eq!((odo.x_m, odo.y_m), (0.0, 0.0));
    assert!(close(odo.theta_rad, 4.0 - TAU, 1e-12), "{odo:?}");
    let mut half = Odometry::default();
    run(&mut half, twist(0.0, 0.0, -PI), 1.0, 1);
    assert_eq!(half.theta_rad, PI, "-pi is written as pi");
}

#[test]
fn small_turns_follow_the_arc_on_both_sides_of_the_series() {
    // The series below the threshold and the closed form above it agree
    // with the arc written out here.
    for turn in [0.0, 1e-12, 0.999e-4, 1.001e-4, -0.999e-4] {
        let mut odo = Odometry::default();
        odo.integrate(&twist(1.0, 0.5, turn), 1.0).expect("a step");
        let (s, c) = if turn == 0.0 {
            (1.0, 0.0)
        } else {
            (turn.sin() / turn, 2.0 * (turn / 2.0).sin().powi(2) / turn)
        };
        assert!(close(odo.x_m, s - 0.5 * c, 1e-15), "{turn}: {odo:?}");
        assert!(close(odo.y_m, c + 0.5 * s, 1e-15), "{turn}: {odo:?}");
    }
}

#[test]
fn bad_steps_leave_the_pose_alone() {
    let start = Odometry {
        x_m: 1.0,
        y_m: 2.0,
        theta_rad: 0.5,
    };
    let mut odo = start;
    let nan = twist(f64::NAN, 0.0, 0.0);
    assert!(matches!(
        odo.integrate(&nan, 0.1),
        Err(BaseError::TwistNotFinite { field: "x", .. })
    ));
    for dt in [-0.1, f64::NAN, f64::INFINITY] {
        let e = odo
            .integrate(&twist(1.0, 0.0, 0.0), dt)
            .expect_err("a bad dt");
        assert!(
            e.to_string().starts_with("odometry step: dt must be"),
            "{e}"
        );
    }
    assert_eq!(odo, start);
}
