//! Byte vectors from an independent serializer: `testdata/ros2/*.hex`,
//! written by rosbags (`scripts/ros2_vectors.py`). Each is decoded and
//! compared field by field with the values the script used (written here
//! again by hand), and those values are encoded and compared byte for byte.

use super::*;

/// The payload of a fixture: its hex, comment lines aside.
fn fixture(text: &str) -> Vec<u8> {
    let hex: String = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .flat_map(|l| l.split_whitespace())
        .collect();
    assert!(hex.len().is_multiple_of(2), "an odd number of hex digits");
    (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).expect("hex digits"))
        .collect()
}

/// Decodes `bytes` into `expected`'s type, compares, and encodes back.
fn both_ways<T: CdrMessage + PartialEq + std::fmt::Debug>(bytes: &[u8], expected: &T) {
    let decoded = T::decode(bytes).expect("the fixture decodes");
    assert_eq!(&decoded, expected);
    assert_eq!(expected.encode(), bytes, "servobus's bytes are rosbags'");
}

macro_rules! vector {
    ($name:literal) => {
        fixture(include_str!(concat!(
            "../../../../testdata/ros2/",
            $name,
            ".hex"
        )))
    };
}

pub(super) fn uuid(first: u8) -> Uuid {
    let mut id = [0u8; 16];
    for (i, b) in id.iter_mut().enumerate() {
        *b = first + i as u8;
    }
    Uuid(id)
}

fn header(sec: i32, nanosec: u32, frame_id: &str) -> Header {
    Header {
        stamp: RosTime { sec, nanosec },
        frame_id: frame_id.into(),
    }
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

fn trajectory(frame_id: &str) -> JointTrajectory {
    JointTrajectory {
        header: header(0, 0, frame_id),
        joint_names: names(&["shoulder_pan", "elbow_flex"]),
        points: vec![
            JointTrajectoryPoint {
                positions: vec![0.0, 0.5],
                velocities: vec![0.1, 0.2],
                time_from_start: RosDuration {
                    sec: 1,
                    nanosec: 500_000_000,
                },
                ..Default::default()
            },
            JointTrajectoryPoint {
                positions: vec![0.25, -0.75],
                accelerations: vec![0.0, 1.0],
                time_from_start: RosDuration { sec: 3, nanosec: 0 },
                ..Default::default()
            },
        ],
    }
}

fn tolerance(name: &str, position: f64, velocity: f64, acceleration: f64) -> JointTolerance {
    JointTolerance {
        name: name.into(),
        position,
        velocity,
        acceleration,
    }
}

fn goal() -> FollowJointTrajectoryGoal {
    FollowJointTrajectoryGoal {
        trajectory: trajectory(""),
        path_tolerance: vec![tolerance("elbow_flex", 0.05, 0.0, 0.0)],
        goal_tolerance: vec![tolerance("shoulder_pan", 0.01, -1.0, 0.0)],
        goal_time_tolerance: RosDuration {
            sec: 0,
            nanosec: 250_000_000,
        },
        ..Default::default()
    }
}

fn multi_dof_goal() -> FollowJointTrajectoryGoal {
    let v = |x, y, z| RosVector3 { x, y, z };
    let point = MultiDofJointTrajectoryPoint {
        transforms: vec![RosTransform {
            translation: v(1.0, 2.0, 3.0),
            rotation: RosQuaternion::default(),
        }],
        velocities: vec![RosTwist {
            linear: v(0.5, 0.0, 0.0),
            angular: v(0.0, 0.0, -0.25),
        }],
        accelerations: vec![],
        time_from_start: RosDuration { sec: 2, nanosec: 0 },
    };
    FollowJointTrajectoryGoal {
        multi_dof_trajectory: MultiDofJointTrajectory {
            header: header(5, 6, "odom"),
            joint_names: names(&["base"]),
            points: vec![point],
        },
        component_goal_tolerance: vec![JointComponentTolerance {
            joint_name: "base".into(),
            component: JointComponentTolerance::TRANSLATION,
            position: 0.1,
            velocity: 0.2,
            acceleration: 0.3,
        }],
        ..goal()
    }
}

fn goal_info(first: u8, sec: i32, nanosec: u32) -> GoalInfo {
    GoalInfo {
        goal_id: uuid(first),
        stamp: RosTime { sec, nanosec },
    }
}

#[test]
fn joint_state() {
    let expected = JointStateMessage {
        header: header(1_700_000_000, 123_456_789, ""),
        name: names(&["shoulder_pan", "elbow_flex", "gripper"]),
        position: vec![0.1, -1.25, 0.5],
        velocity: vec![],
        effort: vec![0.0, 2.5, -3.0],
    };
    let bytes = vector!("joint_state");
    both_ways(&bytes, &expected);
    // The borrowed form servobus publishes writes the same bytes.
    let published = JointState {
        stamp_ns: 1_700_000_000_123_456_789,
        frame_id: "",
        names: &expected.name,
        position: &expected.position,
        velocity: &expected.velocity,
        effort: &expected.effort,
    };
    assert_eq!(published.encode(), bytes);
}

#[test]
fn float64_multi_array() {
    let expected = Float64MultiArray {
        layout: MultiArrayLayout {
            dim: vec![MultiArrayDimension {
                label: "joints".into(),
                size: 3,
                stride: 3,
            }],
            data_offset: 0,
        },
        data: vec![0.25, -0.5, 1.0],
    };
    both_ways(&vector!("float64_multi_array"), &expected);
}

#[test]
fn joint_trajectory() {
    both_ways(&vector!("joint_trajectory"), &trajectory("base"));
}

#[test]
fn send_goal_request() {
    let expected = SendGoalRequest {
        goal_id: uuid(0),
        goal: goal(),
    };
    both_ways(&vector!("send_goal_request"), &expected);
    assert!(!expected.goal.has_multi_dof());
}

#[test]
fn send_goal_request_with_multi_dof_joints() {
    let expected = SendGoalRequest {
        goal_id: uuid(100),
        goal: multi_dof_goal(),
    };
    both_ways(&vector!("send_goal_request_multi_dof"), &expected);
    assert!(expected.goal.has_multi_dof());
}

#[test]
fn send_goal_response() {
    let expected = SendGoalResponse {
        accepted: true,
        stamp: RosTime {
            sec: 1_700_000_001,
            nanosec: 5,
        },
    };
    both_ways(&vector!("send_goal_response"), &expected);
}

#[test]
fn get_result_request_and_response() {
    let request = GetResultRequest { goal_id: uuid(0) };
    both_ways(&vector!("get_result_request"), &request);
    let response = GetResultResponse {
        status: GoalStatus::STATUS_ABORTED,
        result: FollowJointTrajectoryResult {
            error_code: FollowJointTrajectoryResult::PATH_TOLERANCE_VIOLATED,
            error_string: "elbow_flex left its path tolerance by 0.2 rad".into(),
        },
    };
    both_ways(&vector!("get_result_response"), &response);
}

#[test]
fn cancel_goal_request_and_response() {
    let request = CancelGoalRequest {
        goal_info: goal_info(16, 12, 34),
    };
    both_ways(&vector!("cancel_goal_request"), &request);
    let response = CancelGoalResponse {
        return_code: CancelGoalResponse::ERROR_NONE,
        goals_canceling: vec![goal_info(0, 7, 8), goal_info(32, 9, 10)],
    };
    both_ways(&vector!("cancel_goal_response"), &response);
}

#[test]
fn feedback_message() {
    let point = |positions: Vec<f64>, velocities: Vec<f64>, sec| JointTrajectoryPoint {
        positions,
        velocities,
        time_from_start: RosDuration { sec, nanosec: 0 },
        ..Default::default()
    };
    let expected = FeedbackMessage {
        goal_id: uuid(0),
        feedback: FollowJointTrajectoryFeedback {
            header: header(100, 200, ""),
            joint_names: names(&["shoulder_pan", "elbow_flex"]),
            desired: point(vec![0.1, 0.2], vec![0.3, -0.4], 1),
            actual: point(vec![0.11, 0.19], vec![], 0),
            error: point(vec![-0.01, 0.01], vec![], 0),
            ..Default::default()
        },
    };
    both_ways(&vector!("feedback_message"), &expected);
}

#[test]
fn goal_status_array() {
    let expected = GoalStatusArray {
        status_list: vec![
            GoalStatus {
                goal_info: goal_info(0, 1, 2),
                status: GoalStatus::STATUS_EXECUTING,
            },
            GoalStatus {
                goal_info: goal_info(48, 3, 4),
                status: GoalStatus::STATUS_SUCCEEDED,
            },
        ],
    };
    both_ways(&vector!("goal_status_array"), &expected);
}

#[test]
fn every_prefix_of_a_fixture_is_refused_with_its_field() {
    let bytes = vector!("send_goal_request");
    for len in 0..bytes.len() {
        match SendGoalRequest::decode(&bytes[..len]) {
            Ok(_) => panic!("a payload cut at {len} bytes decoded"),
            Err(e) => assert!(!e.field.is_empty(), "{e}"),
        }
    }
    let cut = SendGoalRequest::decode(&bytes[..40]).expect_err("cut short");
    assert!(cut.field.starts_with("goal.trajectory."), "{cut}");
}
