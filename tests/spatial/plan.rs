//! `servobus plan --json`'s spatial figures for the shipped spatial
//! motions.

fn plan_json(motion: &str) -> serde_json::Value {
    let out = crate::servobus_ok(&["plan".as_ref(), motion.as_ref(), "--json".as_ref()]);
    serde_json::from_slice(&out).expect("JSON")
}

fn num(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} in {v}"))
}

#[test]
fn a_walk_reports_its_distance_turn_lift_and_margin() {
    let v = plan_json("hexapod-walk-turn");
    let s = &v["spatial"];
    // 300 mm forward and 100 mm sideways, 90 deg of turn, 25 mm lift
    // (configs/motions/hexapod-walk-turn.yaml).
    assert!((num(s, "body_distance_mm") - 400.0).abs() < 12.0, "{s}");
    assert!((num(s, "body_turn") - 90.0).abs() < 2.7, "{s}");
    assert!((num(s, "max_foot_lift_mm") - 25.0).abs() < 0.01, "{s}");
    // A tripod keeps the body inside its three feet.
    assert!(num(s, "min_stability_margin_mm") > 10.0, "{s}");
    assert_eq!(s["low_margin_at_s"], serde_json::json!([]));
    assert!(s.get("tool_peak_speed_mm_s").is_none());
}

#[test]
fn a_tool_line_motion_reports_the_tool_and_its_dexterity() {
    let v = plan_json("arm-line");
    let s = &v["spatial"];
    // Two 50 mm lines and a 140 mm one, and the joint moves to and from
    // them: more than 240 mm of path.
    assert!(num(s, "tool_path_mm") > 240.0, "{s}");
    assert!(num(s, "tool_peak_speed_mm_s") > 80.0, "{s}");
    // The lines refuse a dexterity under 10 mm/rad.
    assert!(num(s, "min_dexterity_mm_per_rad") > 10.0, "{s}");
    assert!(s.get("body_distance_mm").is_none());
}
