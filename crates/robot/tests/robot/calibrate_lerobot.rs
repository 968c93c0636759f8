//! LeRobot calibration files: a round trip, and the same raw positions
//! meaning the same angles as LeRobot's normalisation.
//!
//! LeRobot's documented normalisation of a present position `val`, with
//! `min`, `max` from its file and `max_res` = 4095 for an STS3215:
//! - `DEGREES`: `(val - (min + max) / 2) * 360 / max_res`, not clamped, no
//!   drive mode;
//! - `RANGE_M100_100`: `val` clamped to `[min, max]`, then
//!   `(val - min) / (max - min) * 200 - 100`, negated when `drive_mode` is 1.
//!
//! Both are written out below from that description, not taken from
//! servobus.

use crate::common;

use std::path::{Path, PathBuf};

use servobus_robot::calibrate::{from_lerobot, lerobot_value, to_lerobot, NormMode};
use servobus_runtime::config::{load_calibration, save_calibration, JointMap};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn temp(name: &str) -> PathBuf {
    common::temp_path("calibrate_lerobot", name)
}

fn lerobot_degrees(val: f64, min: f64, max: f64) -> f64 {
    (val - (min + max) / 2.0) * 360.0 / 4095.0
}

fn lerobot_m100(val: f64, min: f64, max: f64, drive_mode: bool) -> f64 {
    let v = val.clamp(min, max);
    let n = (v - min) / (max - min) * 200.0 - 100.0;
    if drive_mode {
        -n
    } else {
        n
    }
}

#[test]
fn a_lerobot_file_imported_then_exported_is_identical() {
    let robot = common::robot("so101.yaml");
    let json = std::fs::read_to_string(data("so101-lerobot.json")).expect("fixture");
    let cal = from_lerobot(&robot, &json, "imported").expect("imports");
    // Through a servobus calibration file and back.
    let path = temp("so101.calibration.yaml");
    save_calibration(&cal, &path).expect("saves");
    let back = load_calibration(&path).expect("loads");
    assert_eq!(back, cal);
    assert_eq!(to_lerobot(&back), json);
}

#[test]
fn a_seam_crossing_range_is_exported_in_its_centred_frame() {
    let robot = common::robot("so101.yaml");
    let json = std::fs::read_to_string(data("so101-lerobot.json")).expect("fixture");
    let mut cal = from_lerobot(&robot, &json, "imported").expect("imports");
    // A range measured across the seam without an offset: 3900..4296.
    cal.joints[0].homing_offset = 0;
    cal.joints[0].range = [3900, 4296];
    cal.joints[0].pose_tick = 4098.0;
    let out: serde_json::Value = serde_json::from_str(&to_lerobot(&cal)).expect("json");
    let pan = &out["shoulder_pan"];
    let (min, max) = (pan["range_min"].as_i64(), pan["range_max"].as_i64());
    // LeRobot needs min < max inside 0..4095: the centring offset gives it.
    assert_eq!((min, max), (Some(1850), Some(2246)));
    assert_eq!(pan["homing_offset"].as_i64(), Some(-2046));
}

#[test]
fn the_same_raw_positions_give_lerobots_degrees_and_range_values() {
    let json = std::fs::read_to_string(data("so101-lerobot.json")).expect("fixture");
    let motors: serde_json::Value = serde_json::from_str(&json).expect("json");
    let robot = common::robot("so101.yaml");
    let cal = from_lerobot(&robot, &json, "imported").expect("imports");
    let path = temp("so101-deg.calibration.yaml");
    save_calibration(&cal, &path).expect("saves");
    let robot = common::calibrated("so101.yaml", &path);
    let mut checked = 0;
    for (joint, jc) in robot.joints().zip(&cal.joints) {
        let m = &motors[&joint.name];
        let min = m["range_min"].as_f64().expect("min");
        let max = m["range_max"].as_f64().expect("max");
        let drive = m["drive_mode"].as_i64() == Some(1);
        let map = JointMap::new(joint, robot.units);
        for k in 0..=20 {
            let val = (min + (max - min) * f64::from(k) / 20.0).round();
            let ours = map.from_ticks(val as i32).to_degrees();
            let theirs = lerobot_degrees(val, min, max);
            // Same sign convention for drive_mode 0; the opposite for 1,
            // which LeRobot's DEGREES ignores.
            let ours_as_theirs = if drive { -ours } else { ours };
            assert!(
                (ours_as_theirs - theirs).abs() <= theirs.abs() / 4095.0 + 1e-9,
                "{} at {val}: {ours} vs LeRobot {theirs}",
                joint.name
            );
            let m100 = lerobot_value(jc, ours, NormMode::RangeM100To100).expect("known model");
            let expect = lerobot_m100(val, min, max, drive);
            assert!(
                (m100 - expect).abs() < 1e-9,
                "{}: {m100} vs {expect}",
                joint.name
            );
            let deg = lerobot_value(jc, ours, NormMode::Degrees).expect("known model");
            assert!(
                (deg - theirs).abs() < 1e-9,
                "{}: {deg} vs {theirs}",
                joint.name
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 6 * 21);
}
