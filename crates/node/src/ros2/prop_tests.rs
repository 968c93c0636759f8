//! Properties of the CDR codec: decode(encode(m)) == m for any message,
//! and no input (arbitrary, cut short, mutated) makes the reader panic;
//! each way a payload can be wrong is refused with the field it is in.

use proptest::collection::vec;
use proptest::prelude::*;

use super::vector_tests::uuid;
use super::*;

fn finite() -> impl Strategy<Value = f64> {
    -1e6f64..1e6
}

fn text() -> impl Strategy<Value = String> {
    "\\PC{0,12}"
}

fn values() -> impl Strategy<Value = Vec<f64>> {
    vec(finite(), 0..4)
}

fn header() -> impl Strategy<Value = Header> {
    (any::<i32>(), any::<u32>(), text()).prop_map(|(sec, nanosec, frame_id)| Header {
        stamp: RosTime { sec, nanosec },
        frame_id,
    })
}

fn duration() -> impl Strategy<Value = RosDuration> {
    (any::<i32>(), any::<u32>()).prop_map(|(sec, nanosec)| RosDuration { sec, nanosec })
}

fn point() -> impl Strategy<Value = JointTrajectoryPoint> {
    (values(), values(), values(), values(), duration()).prop_map(|(p, v, a, e, t)| {
        JointTrajectoryPoint {
            positions: p,
            velocities: v,
            accelerations: a,
            effort: e,
            time_from_start: t,
        }
    })
}

fn trajectory() -> impl Strategy<Value = JointTrajectory> {
    (header(), vec(text(), 0..4), vec(point(), 0..4)).prop_map(|(header, joint_names, points)| {
        JointTrajectory {
            header,
            joint_names,
            points,
        }
    })
}

fn vector3() -> impl Strategy<Value = RosVector3> {
    (finite(), finite(), finite()).prop_map(|(x, y, z)| RosVector3 { x, y, z })
}

fn multi_dof_point() -> impl Strategy<Value = MultiDofJointTrajectoryPoint> {
    let transform = (vector3(), vector3(), finite()).prop_map(|(t, q, w)| RosTransform {
        translation: t,
        rotation: RosQuaternion {
            x: q.x,
            y: q.y,
            z: q.z,
            w,
        },
    });
    let twist =
        || (vector3(), vector3()).prop_map(|(linear, angular)| RosTwist { linear, angular });
    (
        vec(transform, 0..2),
        vec(twist(), 0..2),
        vec(twist(), 0..2),
        duration(),
    )
        .prop_map(|(transforms, velocities, accelerations, time_from_start)| {
            MultiDofJointTrajectoryPoint {
                transforms,
                velocities,
                accelerations,
                time_from_start,
            }
        })
}

fn tolerance() -> impl Strategy<Value = JointTolerance> {
    (text(), finite(), finite(), finite()).prop_map(|(name, position, velocity, acceleration)| {
        JointTolerance {
            name,
            position,
            velocity,
            acceleration,
        }
    })
}

fn component_tolerance() -> impl Strategy<Value = JointComponentTolerance> {
    (text(), any::<u16>(), finite(), finite(), finite()).prop_map(
        |(joint_name, component, p, v, a)| JointComponentTolerance {
            joint_name,
            component,
            position: p,
            velocity: v,
            acceleration: a,
        },
    )
}

fn goal() -> impl Strategy<Value = FollowJointTrajectoryGoal> {
    let multi_dof = (header(), vec(text(), 0..2), vec(multi_dof_point(), 0..2)).prop_map(
        |(header, joint_names, points)| MultiDofJointTrajectory {
            header,
            joint_names,
            points,
        },
    );
    let tolerances = (
        vec(tolerance(), 0..3),
        vec(component_tolerance(), 0..2),
        vec(tolerance(), 0..3),
        vec(component_tolerance(), 0..2),
    );
    (trajectory(), multi_dof, tolerances, duration()).prop_map(|(t, m, (p, cp, g, cg), d)| {
        FollowJointTrajectoryGoal {
            trajectory: t,
            multi_dof_trajectory: m,
            path_tolerance: p,
            component_path_tolerance: cp,
            goal_tolerance: g,
            component_goal_tolerance: cg,
            goal_time_tolerance: d,
        }
    })
}

fn goal_info() -> impl Strategy<Value = GoalInfo> {
    (any::<[u8; 16]>(), any::<i32>(), any::<u32>()).prop_map(|(id, sec, nanosec)| GoalInfo {
        goal_id: Uuid(id),
        stamp: RosTime { sec, nanosec },
    })
}

fn feedback() -> impl Strategy<Value = FeedbackMessage> {
    let names = (vec(text(), 0..3), vec(text(), 0..2));
    let points = (point(), point(), point());
    let multi = (multi_dof_point(), multi_dof_point(), multi_dof_point());
    (any::<[u8; 16]>(), header(), names, points, multi).prop_map(
        |(id, header, (joint_names, multi_names), (desired, actual, error), (md, ma, me))| {
            FeedbackMessage {
                goal_id: Uuid(id),
                feedback: FollowJointTrajectoryFeedback {
                    header,
                    joint_names,
                    desired,
                    actual,
                    error,
                    multi_dof_joint_names: multi_names,
                    multi_dof_desired: md,
                    multi_dof_actual: ma,
                    multi_dof_error: me,
                },
            }
        },
    )
}

/// decode(encode(m)) == m, and every strict prefix of the payload is an
/// error rather than a panic or a shorter message.
fn round_trip<T: CdrMessage + PartialEq + std::fmt::Debug>(m: &T) -> Result<(), TestCaseError> {
    let bytes = m.encode();
    prop_assert_eq!(&T::decode(&bytes).expect("its own encoding"), m);
    for len in 0..bytes.len() {
        prop_assert!(T::decode(&bytes[..len]).is_err(), "cut at {}", len);
    }
    Ok(())
}

/// Decodes `bytes` as every message type; none may panic.
fn decode_all(bytes: &[u8]) {
    let _ = JointStateMessage::decode(bytes);
    let _ = Float64MultiArray::decode(bytes);
    let _ = JointTrajectory::decode(bytes);
    let _ = SendGoalRequest::decode(bytes);
    let _ = SendGoalResponse::decode(bytes);
    let _ = GetResultRequest::decode(bytes);
    let _ = GetResultResponse::decode(bytes);
    let _ = CancelGoalRequest::decode(bytes);
    let _ = CancelGoalResponse::decode(bytes);
    let _ = FeedbackMessage::decode(bytes);
    let _ = GoalStatusArray::decode(bytes);
}

proptest! {
    #[test]
    fn trajectories_round_trip(m in trajectory()) {
        round_trip(&m)?;
    }

    #[test]
    fn joint_states_and_arrays_round_trip(
        h in header(),
        n in vec(text(), 0..4),
        v in (values(), values(), values()),
        label in text(),
        dims in any::<(u32, u32, u32)>(),
    ) {
        let state = JointStateMessage { header: h, name: n, position: v.0, velocity: v.1, effort: v.2.clone() };
        round_trip(&state)?;
        let dim = MultiArrayDimension { label, size: dims.0, stride: dims.1 };
        let layout = MultiArrayLayout { dim: vec![dim], data_offset: dims.2 };
        round_trip(&Float64MultiArray { layout, data: v.2 })?;
    }

    #[test]
    fn goals_round_trip(id in any::<[u8; 16]>(), goal in goal()) {
        round_trip(&SendGoalRequest { goal_id: Uuid(id), goal })?;
    }

    #[test]
    fn feedback_round_trips(m in feedback()) {
        round_trip(&m)?;
    }

    #[test]
    fn service_replies_and_status_round_trip(
        accepted in any::<bool>(),
        status in any::<i8>(),
        code in any::<i32>(),
        why in text(),
        infos in vec(goal_info(), 0..4),
        statuses in vec(any::<i8>(), 0..4),
    ) {
        round_trip(&SendGoalResponse { accepted, stamp: RosTime { sec: code, nanosec: 7 } })?;
        let result = FollowJointTrajectoryResult { error_code: code, error_string: why };
        round_trip(&GetResultResponse { status, result })?;
        round_trip(&CancelGoalResponse { return_code: status, goals_canceling: infos.clone() })?;
        if let Some(first) = infos.first() {
            round_trip(&CancelGoalRequest { goal_info: *first })?;
        }
        let status_list = infos.iter().zip(&statuses)
            .map(|(goal_info, status)| GoalStatus { goal_info: *goal_info, status: *status })
            .collect();
        round_trip(&GoalStatusArray { status_list })?;
    }

    #[test]
    fn arbitrary_bytes_never_panic(body in vec(any::<u8>(), 0..400)) {
        decode_all(&body);
        let mut payload = cdr::ENCAPSULATION.to_vec();
        payload.extend_from_slice(&body);
        decode_all(&payload);
    }

    #[test]
    fn mutated_payloads_never_panic(goal in goal(), at in any::<prop::sample::Index>(), byte in any::<u8>()) {
        let mut bytes = SendGoalRequest { goal_id: uuid(1), goal }.encode();
        let i = at.index(bytes.len());
        bytes[i] = byte;
        decode_all(&bytes);
        if let Ok(m) = SendGoalRequest::decode(&bytes) {
            let _ = m.encode();
        }
    }
}

/// A payload: the header, then `body`.
fn payload(body: &[u8]) -> Vec<u8> {
    [&cdr::ENCAPSULATION[..], body].concat()
}

#[test]
fn a_huge_count_is_refused_before_anything_is_allocated() {
    // Time, then a frame_id claiming 4 GiB.
    let bytes = payload(&[0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0xff]);
    let e = JointTrajectory::decode(&bytes).expect_err("4 GiB in 12 bytes");
    assert_eq!(e.field, "header.frame_id");
    assert_eq!(
        e.kind,
        CdrErrorKind::Count {
            count: u32::MAX,
            remaining: 0
        }
    );
    // Header, then 1e6 joint names in 4 bytes: each takes at least 5.
    let mut body = vec![0u8; 8];
    body.extend_from_slice(&[1, 0, 0, 0, 0, 0, 0, 0]);
    body.extend_from_slice(&1_000_000u32.to_le_bytes());
    body.extend_from_slice(&[0; 4]);
    let e = JointTrajectory::decode(&payload(&body)).expect_err("1e6 names in 4 bytes");
    assert_eq!(e.field, "joint_names");
    assert!(
        matches!(
            e.kind,
            CdrErrorKind::Count {
                count: 1_000_000,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn bad_strings_and_booleans_name_their_field() {
    let mut bad_utf8 = payload(&[0; 8]);
    bad_utf8.extend_from_slice(&[2, 0, 0, 0, 0xff, 0]);
    let e = Header::decode(&bad_utf8).expect_err("not UTF-8");
    assert_eq!(
        (e.field.as_str(), &e.kind),
        ("frame_id", &CdrErrorKind::NotUtf8)
    );
    let mut no_nul = payload(&[0; 8]);
    no_nul.extend_from_slice(&[2, 0, 0, 0, b'a', b'b']);
    let e = Header::decode(&no_nul).expect_err("no NUL");
    assert_eq!(e.kind, CdrErrorKind::NoNul);
    // A length of 0 is the empty string, as Fast-CDR reads it.
    let mut empty = payload(&[0; 8]);
    empty.extend_from_slice(&[0, 0, 0, 0]);
    assert_eq!(
        Header::decode(&empty).map(|h| h.frame_id),
        Ok(String::new())
    );
    let not_bool = payload(&[2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    let e = SendGoalResponse::decode(&not_bool).expect_err("2 is no boolean");
    assert_eq!(e.field, "accepted");
    assert_eq!(e.kind, CdrErrorKind::NotBool { value: 2 });
}

#[test]
fn an_element_error_names_its_index() {
    let mut m = JointTrajectory {
        joint_names: vec!["a".into(), "b".into()],
        points: vec![JointTrajectoryPoint::default(); 3],
        ..Default::default()
    };
    m.points[2].positions = vec![1.0; 4];
    let bytes = m.encode();
    // Cut in the third position of point 2: what is left still holds
    // three points' worth of bytes, so the count is not what fails.
    let e = JointTrajectory::decode(&bytes[..bytes.len() - 28]).expect_err("cut in point 2");
    assert_eq!(e.field, "points[2].positions");
    let names = JointTrajectory::decode(&bytes[..37]).expect_err("cut in the second name");
    assert_eq!(names.field, "joint_names[1]");
}

#[test]
fn only_little_endian_cdr_is_read() {
    // The options (the header's last two bytes) are not checked.
    let mut options = Header::default().encode();
    options[3] = 3;
    assert_eq!(Header::decode(&options), Ok(Header::default()));
    let e = JointTrajectory::decode(&[0x00, 0x00, 0x00, 0x00, 1]).expect_err("big endian");
    assert_eq!(
        e.kind,
        CdrErrorKind::Encapsulation {
            found: vec![0, 0, 0, 0]
        }
    );
    let e = JointTrajectory::decode(&[0x00]).expect_err("one byte");
    assert_eq!(e.kind, CdrErrorKind::Encapsulation { found: vec![0] });
    assert!(e.to_string().contains("00 01 00 00"), "{e}");
}
