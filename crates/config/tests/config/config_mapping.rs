//! Joint angle <-> tick mapping and the last-step clamp.

use servobus_config::{
    JointCalibration, JointConfig, JointMap, PlayFrame, Units, RANGE_MARGIN_DEG,
};
use servobus_protocol::registers::model_by_name;

fn joint(model: &str, min: f64, max: f64, offset: f64, inverted: bool) -> JointConfig {
    JointConfig {
        name: "j".into(),
        id: 1,
        model: model_by_name(model).expect("known model"),
        // A position joint (`JointMode::Position`, the default).
        mode: Default::default(),
        min,
        max,
        max_velocity: 100.0,
        max_acceleration: 100.0,
        max_jerk: None,
        offset,
        inverted,
        home: None,
        calibration: None,
        servo: None,
        faults: Default::default(),
    }
}

/// An STS3215 joint's calibration: the pose (0 deg) reads `pose_tick`,
/// ticks run `direction`, measured over `range`; no homing offset.
fn sts3215_calibration(range: [i64; 2], pose_tick: f64, direction: i8) -> JointCalibration {
    JointCalibration {
        name: "j".into(),
        id: 1,
        model: "STS3215".into(),
        firmware: None,
        homing_offset: 0,
        pose_deg: 0.0,
        pose_tick,
        direction,
        range,
    }
}

/// A calibrated STS3215 joint: pose at 0 deg reads `pose_tick`, range `range`.
fn calibrated(pose_tick: f64, direction: i8, range: [i64; 2]) -> JointConfig {
    JointConfig {
        calibration: Some(sts3215_calibration(range, pose_tick, direction)),
        ..joint("sts3215", -30.0, 30.0, 0.0, false)
    }
}

#[test]
fn a_range_across_the_seam_plays_in_a_centred_frame() {
    let j = sts3215_calibration([3900, 4296], 4100.0, -1);
    assert!(j.crosses_seam());
    let f = j.play_frame();
    let moved = j.in_frame(f);
    assert!(!moved.crosses_seam());
    assert_eq!(moved.range, [1850, 2246]);
    // Angles do not change with the frame.
    let m = j.servo_model().expect("known");
    for t in [3900.0, 4100.0, 4296.0] {
        let d = j.degrees_at(m, t);
        assert!((moved.degrees_at(m, t - f.shift as f64) - d).abs() < 1e-9);
    }
    // 396 ticks = 34.8 deg, reversed: from pose 0 the limits are
    // -(4296-4100) and +(4100-3900) ticks, less the margin.
    let (lo, hi) = j.limits_deg(m);
    let tick = 360.0 / 4096.0;
    assert!((lo - (-196.0 * tick + RANGE_MARGIN_DEG)).abs() < 1e-9);
    assert!((hi - (200.0 * tick - RANGE_MARGIN_DEG)).abs() < 1e-9);
}

#[test]
fn the_calibration_pose_stays_inside_the_limits_at_an_end_stop() {
    // A gripper held closed against its stop: pose 0 deg at tick 3100, and
    // swept 1137 ticks (99.93 deg) open from there.
    let j = sts3215_calibration([3100, 4237], 3100.0, 1);
    let m = j.servo_model().expect("known");
    let (lo, hi) = j.limits_deg(m);
    // No margin on the closed side: 0 deg ("closed") can be played.
    assert_eq!(lo, 0.0);
    assert!((hi - (1137.0 * 360.0 / 4096.0 - RANGE_MARGIN_DEG)).abs() < 1e-9);
    // A pose 1 deg inside an end: the limit there is the pose, not the margin.
    let j = sts3215_calibration([3089, 4237], 3100.0, 1);
    let (lo, _) = j.limits_deg(m);
    assert_eq!(lo, 0.0);
    let measured = j.range_deg(m).0;
    assert!((measured - (-11.0 * 360.0 / 4096.0)).abs() < 1e-9);
}

#[test]
fn a_range_on_one_side_keeps_its_frame() {
    let j = sts3215_calibration([1000, 3000], 2000.0, 1);
    assert_eq!(
        j.play_frame(),
        PlayFrame {
            homing_offset: 0,
            shift: 0
        }
    );
}

#[test]
fn a_calibrated_joint_across_the_seam_maps_through_its_centred_frame() {
    // Sensor range 3900..4296 (3900..4095 then 0..200), pose at 4100
    // (sensor tick 4), reversed.
    let j = calibrated(4100.0, -1, [3900, 4296]);
    let frame = j.calibration.as_ref().expect("calibrated").play_frame();
    let m = JointMap::new(&j, Units::Deg);
    // In the play frame every tick is the calibration's minus the shift:
    // pose 4100 - 2050 = 2050.
    assert_eq!(frame.shift, 2050);
    assert_eq!(m.to_ticks(0.0), 2050);
    // Reversed: +10 deg is 10 / (360/4096) = 113.8 ticks lower.
    assert_eq!(m.to_ticks(10f64.to_radians()), 2050 - 114);
    // Readings come back exactly, on both sides of the old seam.
    for deg in [-15.0f64, -5.0, 0.0, 5.0, 15.0] {
        let t = m.to_ticks(deg.to_radians());
        assert!((m.from_ticks(t).to_degrees() - deg).abs() < 0.05, "{deg}");
    }
}

#[test]
fn a_reading_past_the_register_end_unwraps_next_to_the_range() {
    // Range 10..1000 in a frame that does not cross the seam; pose at 500.
    let m = JointMap::new(&calibrated(500.0, 1, [10, 1000]), Units::Deg);
    // Tick 4090 is 6 ticks below 0, just under the range: not 3590 above it.
    let deg = m.from_ticks(4090).to_degrees();
    let expect = (-6.0 - 500.0) * 360.0 / 4096.0;
    assert!((deg - expect).abs() < 1e-9, "{deg} vs {expect}");
}

#[test]
fn sts3215_zero_is_the_middle_tick_and_90_deg_is_a_quarter_turn() {
    let m = JointMap::new(&joint("sts3215", -180.0, 179.0, 0.0, false), Units::Deg);
    assert_eq!(m.to_ticks(0.0), 2048);
    assert_eq!(m.to_ticks(90f64.to_radians()), 3072);
    assert_eq!(m.to_ticks(-90f64.to_radians()), 1024);
    // One tick is 360/4096 deg = 0.087890625 deg; half a tick rounds to nearest.
    assert_eq!(m.to_ticks(0.04f64.to_radians()), 2048);
    assert_eq!(m.to_ticks(0.05f64.to_radians()), 2049);
    assert!((m.from_ticks(3072) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
}

#[test]
fn scs0009_has_1024_ticks_over_300_deg() {
    let m = JointMap::new(&joint("scs0009", -150.0, 149.0, 0.0, false), Units::Deg);
    assert_eq!(m.to_ticks(0.0), 512);
    // 150 deg = 512 ticks; the register tops out at 1023.
    assert_eq!(m.to_ticks(-150f64.to_radians()), 0);
    assert_eq!(m.to_ticks(150f64.to_radians()), 1023);
    assert_eq!(m.to_ticks(75f64.to_radians()), 768);
}

#[test]
fn inversion_and_offset() {
    // Servo angle = offset - position: joint 0 sits 30 deg below the middle.
    let m = JointMap::new(&joint("sts3215", -90.0, 90.0, -30.0, true), Units::Deg);
    let per_deg: f64 = 4096.0 / 360.0;
    assert_eq!(m.to_ticks(0.0), (2048.0 - 30.0 * per_deg).round() as i32);
    assert_eq!(
        m.to_ticks(10f64.to_radians()),
        (2048.0 - 40.0 * per_deg).round() as i32
    );
    // Reading back inverts the mapping to within half a tick.
    for deg in [-90.0f64, -12.5, 0.0, 33.3, 90.0] {
        let rad = deg.to_radians();
        let back = m.from_ticks(m.to_ticks(rad));
        assert!((back - rad).abs() <= 0.5 / per_deg * std::f64::consts::PI / 180.0 + 1e-12);
    }
}

#[test]
fn radians_robot_units() {
    let m = JointMap::new(&joint("sts3215", -1.0, 1.0, 0.0, false), Units::Rad);
    assert_eq!(m.min_rad, -1.0);
    assert_eq!(m.max_rad, 1.0);
    assert_eq!(m.to_ticks(std::f64::consts::PI / 2.0), 3072);
}

#[test]
fn clamp_reports_whether_it_clamped() {
    let m = JointMap::new(&joint("sts3215", -45.0, 45.0, 0.0, false), Units::Deg);
    let inside = m.goal(10f64.to_radians());
    assert!(!inside.clamped);
    let above = m.goal(50f64.to_radians());
    assert!(above.clamped);
    // Clamped to the 45 deg limit: 45 x 4096 / 360 = 512 ticks above 2048.
    assert_eq!(above.value, 2560);
    let below = m.clamp(-1.0);
    assert!(below.clamped);
    assert_eq!(below.value, m.min_rad);
    let nan = m.goal(f64::NAN);
    assert!(nan.clamped);
    assert_eq!(nan.value, 2048);
    // The register range holds even for absurd inputs without limits applied.
    assert_eq!(m.to_ticks(1e12), 4095);
    assert_eq!(m.to_ticks(-1e12), 0);
}

#[test]
fn unit_conversions() {
    assert!((Units::Deg.to_rad(180.0) - std::f64::consts::PI).abs() < 1e-15);
    assert_eq!(Units::Rad.to_rad(1.25), 1.25);
    assert!((Units::Rad.convert(std::f64::consts::PI, Units::Deg) - 180.0).abs() < 1e-12);
    assert_eq!(Units::Deg.convert(12.0, Units::Deg), 12.0);
}
