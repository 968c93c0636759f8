//! The wire formats, good and malformed.

use super::*;

#[test]
fn a_target_names_joints() {
    let m = parse_target(br#"{"t": 1.5, "joints": {"elbow_flex": 30, "gripper": 2.5}}"#)
        .expect("a target");
    assert_eq!(m.t, Some(1.5));
    assert_eq!(m.sent_ns, None);
    assert_eq!(
        m.joints,
        vec![
            ("elbow_flex".to_string(), 30.0),
            ("gripper".to_string(), 2.5)
        ]
    );
    let m = parse_target(br#"{"sent_ns": 17, "joints": {}}"#).expect("a target");
    assert_eq!(m.sent_ns, Some(17));
}

#[test]
fn malformed_targets_say_why() {
    for bad in [
        &b"\xff\xfe"[..],
        b"not json",
        b"[1, 2]",
        br#"{"t": 1}"#,
        br#"{"joints": {"elbow_flex": "far"}}"#,
        br#"{"t": "soon", "joints": {}}"#,
        br#"{"sent_ns": 1.5, "joints": {}}"#,
    ] {
        assert!(
            parse_target(bad).is_err(),
            "{:?}",
            String::from_utf8_lossy(bad)
        );
    }
}

#[test]
fn a_chunk_is_a_timed_list_per_joint() {
    let m = parse_live(
        br#"{"chunk": {"t0": 2.5, "dt": 0.02, "joints": {"elbow_flex": [30, 31.5, 33], "gripper": [2, 2, 2.5]}}}"#,
    )
    .expect("a chunk");
    assert_eq!(
        m,
        LiveMessage::Chunk(ChunkMessage {
            t0: Some(2.5),
            dt: 0.02,
            joints: vec![
                ("elbow_flex".to_string(), vec![30.0, 31.5, 33.0]),
                ("gripper".to_string(), vec![2.0, 2.0, 2.5]),
            ],
            sent_ns: None,
        })
    );
    // `t0` is optional (the points start on arrival), `sent_ns` too.
    let m = parse_chunk(
        br#"{"sent_ns": 9, "chunk": {"t0": null, "dt": 0.5, "joints": {"shoulder_pan": [-10]}}}"#,
    )
    .expect("a chunk");
    assert_eq!((m.t0, m.dt, m.sent_ns), (None, 0.5, Some(9)));
    assert_eq!(m.joints, vec![("shoulder_pan".to_string(), vec![-10.0])]);
    // Beside chunks, targets parse as they always did.
    let m = parse_live(br#"{"t": 1, "joints": {"elbow_flex": 30}}"#).expect("a target");
    assert_eq!(
        m,
        LiveMessage::Target(TargetMessage {
            t: Some(1.0),
            joints: vec![("elbow_flex".to_string(), 30.0)],
            base: None,
            grasps: Vec::new(),
            sent_ns: None,
        })
    );
}

#[test]
fn malformed_chunks_say_why() {
    let too_long = format!(
        r#"{{"chunk": {{"dt": 0.02, "joints": {{"elbow_flex": [{}]}}}}}}"#,
        vec!["1"; servobus_robot::MAX_CHUNK_POINTS + 1].join(",")
    );
    for (bad, why) in [
        (r#"{"chunk": 3}"#, "not a JSON object"),
        (r#"{"chunk": {"joints": {"elbow_flex": [1]}}}"#, "no `dt`"),
        (
            r#"{"chunk": {"dt": "fast", "joints": {"elbow_flex": [1]}}}"#,
            "`dt` is not",
        ),
        (
            r#"{"chunk": {"dt": 0, "joints": {"elbow_flex": [1]}}}"#,
            "positive",
        ),
        (
            r#"{"chunk": {"dt": -0.02, "joints": {"elbow_flex": [1]}}}"#,
            "positive",
        ),
        (
            r#"{"chunk": {"t0": "now", "dt": 0.02, "joints": {"elbow_flex": [1]}}}"#,
            "`t0`",
        ),
        (r#"{"chunk": {"dt": 0.02}}"#, "no `joints`"),
        (r#"{"chunk": {"dt": 0.02, "joints": {}}}"#, "no joint"),
        (
            r#"{"chunk": {"dt": 0.02, "joints": {"elbow_flex": 30}}}"#,
            "not a list",
        ),
        (
            r#"{"chunk": {"dt": 0.02, "joints": {"elbow_flex": []}}}"#,
            "1 to",
        ),
        (
            r#"{"chunk": {"dt": 0.02, "joints": {"elbow_flex": [1, "x"]}}}"#,
            "not a number",
        ),
        (
            r#"{"chunk": {"dt": 0.02, "joints": {"elbow_flex": [1, 2], "gripper": [1]}}}"#,
            "1 angles, the chunk's other joints 2",
        ),
        (
            r#"{"chunk": {"dt": 0.02, "joints": {"elbow_flex": [1]}}, "joints": {}}"#,
            "not both",
        ),
        (
            r#"{"sent_ns": "late", "chunk": {"dt": 0.02, "joints": {"elbow_flex": [1]}}}"#,
            "sent_ns",
        ),
        (too_long.as_str(), "1 to"),
    ] {
        match parse_live(bad.as_bytes()) {
            Err(e @ WireError::Chunk(_)) => {
                assert!(e.to_string().contains(why), "{bad}: {e}");
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
    // Not JSON at all: neither a target nor a chunk.
    assert!(matches!(parse_live(b"{chunk"), Err(WireError::Target(_))));
    assert_eq!(parse_live(b"\xff"), Err(WireError::NotText));
}

#[test]
fn commands_parse() {
    assert_eq!(parse_command(b" stop\n"), Ok(NodeCommand::Stop));
    assert_eq!(parse_command(b"torque_off"), Ok(NodeCommand::TorqueOff));
    assert_eq!(parse_command(b"shutdown\n"), Ok(NodeCommand::Shutdown));
    assert!(matches!(
        parse_command(b"shutdown now"),
        Err(WireError::UnknownCommand(_))
    ));
    assert_eq!(
        parse_command(b"play arm-wave"),
        Ok(NodeCommand::Play {
            motion: "arm-wave".into(),
            at: None
        })
    );
    let at = UNIX_EPOCH + Duration::from_millis(1_764_100_800_250);
    assert_eq!(
        parse_command(b"play arm-wave at 2025-11-25T20:00:00.250Z"),
        Ok(NodeCommand::Play {
            motion: "arm-wave".into(),
            at: Some(at)
        })
    );
    assert!(matches!(parse_command(b"play"), Err(WireError::NoMotion)));
    assert!(matches!(
        parse_command(b"stop now"),
        Err(WireError::UnknownCommand(_))
    ));
    assert!(matches!(
        parse_command(b"dance"),
        Err(WireError::UnknownCommand(_))
    ));
    assert!(matches!(
        parse_command(b"play arm-wave at tomorrow"),
        Err(WireError::BadTime(_))
    ));
}

#[test]
fn a_formatted_command_parses_back_to_itself() {
    let at = UNIX_EPOCH + Duration::from_micros(1_764_100_800_250_123);
    let yaml = "robot: so101\nkeyframes:\n  - pose: {elbow_flex: 10}\n".to_string();
    let commands = [
        NodeCommand::Stop,
        NodeCommand::Pause,
        NodeCommand::Resume,
        NodeCommand::TorqueOff,
        NodeCommand::Shutdown,
        NodeCommand::Play {
            motion: "arm-wave".into(),
            at: None,
        },
        NodeCommand::Play {
            motion: "arm-wave".into(),
            at: Some(at),
        },
        NodeCommand::Play {
            motion: yaml.clone(),
            at: Some(at),
        },
    ];
    for c in commands {
        let text = c.to_string();
        let back = parse_command(text.as_bytes()).expect("what is formatted parses");
        match (&c, &back) {
            (
                NodeCommand::Play {
                    motion: m0,
                    at: Some(a0),
                },
                NodeCommand::Play {
                    motion: m1,
                    at: Some(a1),
                },
            ) => {
                // YAML text keeps its lines (its trailing newline aside);
                // the time its microseconds.
                assert_eq!(m0.trim_end(), m1, "{text:?}");
                let d = a0
                    .duration_since(*a1)
                    .or_else(|e| Ok::<_, ()>(e.duration()));
                assert!(d.is_ok_and(|d| d < Duration::from_micros(1)), "{text:?}");
            }
            _ => assert_eq!(back, c, "{text:?}"),
        }
    }
}

#[test]
fn utc_times_by_hand() {
    // 2000-03-01T00:00:00Z is 951868800 s after the epoch.
    assert_eq!(
        parse_utc("2000-03-01T00:00:00Z"),
        Ok(UNIX_EPOCH + Duration::from_secs(951_868_800))
    );
    assert_eq!(
        parse_utc("12.5"),
        Ok(UNIX_EPOCH + Duration::from_millis(12_500))
    );
    for bad in [
        "2000-13-01T00:00:00Z",
        "2000-01-01T00:00:00",
        "-3",
        "NaN",
        "",
    ] {
        assert!(parse_utc(bad).is_err(), "{bad}");
    }
}

#[test]
fn a_base_velocity_parses_with_or_without_joints_and_says_what_is_wrong() {
    let m = parse_target(br#"{"base": {"x": 0.2, "theta": 30}}"#).expect("a base target");
    assert_eq!(
        m.base,
        Some(servobus_robot::config::BaseTarget {
            x: 0.2,
            y: 0.0,
            theta: 30.0
        })
    );
    assert!(m.joints.is_empty());
    let m = parse_target(br#"{"joints": {"gripper": 10}, "base": {"y": -0.1}}"#).expect("both");
    assert_eq!(m.joints, vec![("gripper".to_string(), 10.0)]);
    assert_eq!(m.base.map(|b| b.y), Some(-0.1));
    for (payload, says) in [
        (&br#"{"base": {"z": 1}}"#[..], "no field `z`"),
        (br#"{"base": {"x": "fast"}}"#, "`x` is not a number"),
        (br#"{"base": 2}"#, "not an object"),
    ] {
        let e = parse_target(payload).expect_err("malformed");
        assert!(e.to_string().contains(says), "{e}");
    }
}

#[test]
fn a_grasp_parses_alone_or_beside_joints_and_a_base_and_says_what_is_wrong() {
    let m = parse_target(br#"{"t": 4, "grasp": {"gripper": 40}}"#).expect("a grasp alone");
    assert_eq!(m.t, Some(4.0));
    assert!(m.joints.is_empty());
    assert_eq!(m.grasps, vec![("gripper".to_string(), 40.0)]);
    let m = parse_live(
        br#"{"joints": {"wrist_roll": 90}, "base": {"x": 0.1}, "grasp": {"gripper": 12.5}, "sent_ns": 5}"#,
    )
    .expect("all three");
    let LiveMessage::Target(m) = m else {
        panic!("a target: {m:?}");
    };
    assert_eq!(m.joints, vec![("wrist_roll".to_string(), 90.0)]);
    assert_eq!(m.base.map(|b| b.x), Some(0.1));
    assert_eq!(m.grasps, vec![("gripper".to_string(), 12.5)]);
    assert_eq!(m.sent_ns, Some(5));
    // Null is none; without `grasp` there is none either.
    let m = parse_target(br#"{"joints": {}, "grasp": null}"#).expect("a null grasp");
    assert!(m.grasps.is_empty());
    for (payload, says) in [
        (
            &br#"{"joints": {"gripper": 10}, "grasp": {"gripper": 40}}"#[..],
            "joint `gripper` is given an angle and a `grasp`",
        ),
        (
            br#"{"grasp": {"gripper": "firm"}}"#,
            "grasp `gripper`: the effort is not a number",
        ),
        (br#"{"grasp": 40}"#, "grasp: not an object"),
        (br#"{"grasp": ["gripper"]}"#, "grasp: not an object"),
    ] {
        let e = parse_target(payload).expect_err("malformed");
        assert!(matches!(e, WireError::Target(_)), "{e:?}");
        assert!(e.to_string().contains(says), "{e}");
    }
    let e = parse_live(br#"{"chunk": {"dt": 0.1, "joints": {"a": [1]}}, "grasp": {"a": 40}}"#)
        .expect_err("a grasp beside a chunk");
    assert!(matches!(e, WireError::Chunk(_)), "{e:?}");
    // Well formed: the efforts the joint cannot make are the stream's to refuse.
    assert!(parse_target(br#"{"grasp": {"gripper": 0, "elbow_flex": 150}}"#).is_ok());
}
