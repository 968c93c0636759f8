//! Keys, tokens and attachments, as rmw_zenoh forms them.

use super::*;

const SEND_GOAL_HASH: &str =
    "RIHS01_b13789dddc325a7a962825c45e28c77d37237ec129dd0c34dc5994562938c57f";

#[test]
fn the_joint_state_type_hash_is_the_one_ros_2_publishes() {
    // As `ros2 topic info -v /joint_states` prints it on Jazzy.
    assert_eq!(
        joint_state_type_hash(),
        "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e"
    );
}

#[test]
fn the_key_follows_the_domain_topic_type_hash_layout() {
    let key = joint_states_key(7, "so101");
    assert!(
        key.starts_with("7/so101/joint_states/sensor_msgs::msg::dds_::JointState_/RIHS01_a13ee3"),
        "{key}"
    );
    assert_eq!(
        joint_states_key(0, "my-arm").split('/').nth(1),
        Some("my_arm")
    );
}

#[test]
fn namespaces_are_made_absolute_and_valid() {
    assert_eq!(ros_namespace(""), "");
    assert_eq!(ros_namespace("/"), "");
    assert_eq!(ros_namespace("so101"), "/so101");
    assert_eq!(ros_namespace("/left arm//2nd/"), "/left_arm/_2nd");
    assert_eq!(
        name_in("/so101", "joint_trajectory"),
        "/so101/joint_trajectory"
    );
    assert_eq!(name_in("", "joint_trajectory"), "/joint_trajectory");
}

#[test]
fn subscribed_topics_have_their_keys() {
    assert_eq!(
        joint_trajectory_key(3, "so101"),
        "3/so101/joint_trajectory/trajectory_msgs::msg::dds_::JointTrajectory_/\
         RIHS01_179b33eba59d676f6d967ac71fe35e7ca2f64b2f3928f4a018cec115e213796e"
    );
    let [state, array] = joint_commands_keys(0, "");
    assert!(state.starts_with("0/joint_commands/sensor_msgs::msg::dds_::JointState_/RIHS01_a13ee3"));
    assert!(array
        .starts_with("0/joint_commands/std_msgs::msg::dds_::Float64MultiArray_/RIHS01_1025ddc6"));
}

#[test]
fn the_action_maps_to_three_services_and_two_topics() {
    let keys = follow_joint_trajectory_keys(0, "/so101");
    let base = "0/so101/follow_joint_trajectory/_action";
    assert_eq!(
        keys.send_goal,
        format!(
            "{base}/send_goal/control_msgs::action::dds_::FollowJointTrajectory_SendGoal_/{SEND_GOAL_HASH}"
        )
    );
    assert!(keys.cancel_goal.starts_with(&format!(
        "{base}/cancel_goal/action_msgs::srv::dds_::CancelGoal_/RIHS01_573d8b0a"
    )));
    assert!(keys.get_result.starts_with(&format!(
        "{base}/get_result/control_msgs::action::dds_::FollowJointTrajectory_GetResult_/RIHS01_e3ceb38e"
    )));
    assert!(keys.feedback.starts_with(&format!(
        "{base}/feedback/control_msgs::action::dds_::FollowJointTrajectory_FeedbackMessage_/RIHS01_80398fcb"
    )));
    assert!(keys.status.starts_with(&format!(
        "{base}/status/action_msgs::msg::dds_::GoalStatusArray_/RIHS01_6c1684b0"
    )));
}

#[test]
fn liveliness_tokens_name_the_node_and_its_publisher() {
    let [node, publisher] = liveliness_tokens(0, "abc", "so101");
    assert_eq!(node, "@ros2_lv/0/abc/0/0/NN/%/%/servobus_so101");
    assert!(publisher.starts_with(
        "@ros2_lv/0/abc/0/10/MP/%/%/servobus_so101/%so101%joint_states/sensor_msgs::msg::dds_::JointState_/RIHS01_"
    ));
    assert!(publisher.ends_with("/::,10:,:,:,,"), "{publisher}");
}

fn node() -> RosNode<'static> {
    RosNode {
        domain: 2,
        session_id: "a1b2",
        namespace: "/so101",
        name: "servobus_so101",
    }
}

#[test]
fn a_subscription_and_a_service_server_have_tokens() {
    let n = node();
    assert_eq!(n.token(), "@ros2_lv/2/a1b2/0/0/NN/%/%so101/servobus_so101");
    let sub = n.subscription_token(11, "/so101/joint_trajectory", &types::JOINT_TRAJECTORY);
    assert_eq!(
        sub,
        "@ros2_lv/2/a1b2/0/11/MS/%/%so101/servobus_so101/%so101%joint_trajectory/\
         trajectory_msgs::msg::dds_::JointTrajectory_/\
         RIHS01_179b33eba59d676f6d967ac71fe35e7ca2f64b2f3928f4a018cec115e213796e/::,10:,:,:,,"
    );
    let srv = n.service_token(12, "/so101/x/_action/send_goal", &types::FJT_SEND_GOAL);
    assert_eq!(
        srv,
        format!(
            "@ros2_lv/2/a1b2/0/12/SS/%/%so101/servobus_so101/%so101%x%_action%send_goal/\
             control_msgs::action::dds_::FollowJointTrajectory_SendGoal_/{SEND_GOAL_HASH}/::,10:,:,:,,"
        )
    );
}

#[test]
fn an_action_server_announces_five_entities() {
    let tokens = node().action_server_tokens(20, "/so101/follow_joint_trajectory");
    let kinds: Vec<&str> = tokens
        .iter()
        .map(|t| t.split('/').nth(5).unwrap_or(""))
        .collect();
    assert_eq!(kinds, ["SS", "SS", "SS", "MP", "MP"]);
    let ids: Vec<&str> = tokens
        .iter()
        .map(|t| t.split('/').nth(4).unwrap_or(""))
        .collect();
    assert_eq!(ids, ["20", "21", "22", "23", "24"]);
    let names: Vec<&str> = tokens
        .iter()
        .map(|t| t.split('/').nth(9).unwrap_or(""))
        .collect();
    assert_eq!(
        names,
        [
            "%so101%follow_joint_trajectory%_action%send_goal",
            "%so101%follow_joint_trajectory%_action%cancel_goal",
            "%so101%follow_joint_trajectory%_action%get_result",
            "%so101%follow_joint_trajectory%_action%feedback",
            "%so101%follow_joint_trajectory%_action%status",
        ]
    );
    assert!(tokens[3].ends_with("/::,10:,:,:,,"));
    assert!(tokens[4].ends_with("/:1:,1:,:,:,,"), "{}", tokens[4]);
    assert!(
        tokens.iter().all(|t| t.split('/').count() == 13),
        "{tokens:?}"
    );
}

#[test]
fn the_attachment_is_sequence_stamp_and_gid() {
    let gid = [9u8; 16];
    let a = attachment(3, 0x0102, &gid);
    assert_eq!(a.len(), 33);
    assert_eq!(&a[..8], &[3, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(&a[8..16], &[2, 1, 0, 0, 0, 0, 0, 0]);
    assert_eq!(a[16], 16);
    assert_eq!(&a[17..], &gid);
    assert_eq!(
        Attachment::decode(&a),
        Ok(Attachment {
            sequence: 3,
            stamp_ns: 0x0102,
            gid
        })
    );
}

#[test]
fn a_bad_attachment_is_refused() {
    let mut a = attachment(-1, 5, &[1; 16]);
    assert_eq!(
        Attachment::decode(&a[..32]),
        Err(AttachmentError::Length { found: 32 })
    );
    a[16] = 8;
    assert_eq!(
        Attachment::decode(&a),
        Err(AttachmentError::GidLength { found: 8 })
    );
}

#[test]
fn a_joint_state_encodes_as_cdr_by_hand() {
    let names = vec!["a".to_string()];
    let msg = JointState {
        stamp_ns: 1_500_000_000,
        frame_id: "",
        names: &names,
        position: &[1.0],
        velocity: &[],
        effort: &[],
    };
    let bytes = msg.encode();
    let expected: Vec<u8> = [
        &[0x00, 0x01, 0x00, 0x00][..],   // encapsulation: CDR little endian
        &[1, 0, 0, 0],                   // sec
        &[0x00, 0x65, 0xcd, 0x1d],       // nanosec 500_000_000
        &[1, 0, 0, 0, 0, 0, 0, 0],       // frame_id: length 1, NUL, pad
        &[1, 0, 0, 0],                   // one name
        &[2, 0, 0, 0, b'a', 0, 0, 0],    // "a", NUL, pad to 4
        &[1, 0, 0, 0],                   // one position (offset 28)
        &[0, 0, 0, 0, 0, 0, 0xf0, 0x3f], // 1.0 at offset 32
        &[0, 0, 0, 0],                   // no velocities
        &[0, 0, 0, 0],                   // no efforts
    ]
    .concat();
    assert_eq!(bytes, expected);
    let owned = JointStateMessage::decode(&bytes).expect("its own encoding");
    assert_eq!(
        owned.header.stamp,
        RosTime {
            sec: 1,
            nanosec: 500_000_000
        }
    );
    assert_eq!(owned.encode(), bytes);
}
