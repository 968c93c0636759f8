//! Every type's RIHS01 hash against the hash ROS 2 publishes.
//!
//! Where the expected values come from (rosidl's generated C,
//! `*__description.c`, whose `*__get_type_hash` and `*__EXPECTED_HASH`
//! arrays hold the hashes rosidl computed at build time):
//!
//! - [A] `saahu27/aprs`, `aprs_ws/build/control_msgs/rosidl_generator_c/
//!   control_msgs/action/detail/follow_joint_trajectory__description.c`:
//!   a build of control_msgs with the multi-DOF goal and feedback fields
//!   and without control_msgs 6.3's trajectory index, i.e. the
//!   FollowJointTrajectory of Jazzy's control_msgs 5.x; it lists the
//!   hashes of the action's own types and the expected hashes of every
//!   type they refer to (builtin_interfaces, std_msgs/Header,
//!   trajectory_msgs, geometry_msgs, unique_identifier_msgs/UUID,
//!   service_msgs/ServiceEventInfo, control_msgs tolerances).
//! - [K] `hpmicro/hpm_sdk`, `middleware/microros/kilted/include/<pkg>/<pkg>/
//!   <msg|srv>/detail/<type>__description.c` (ROS 2 Kilted), for
//!   `sensor_msgs/JointState`, `std_msgs/Float64MultiArray` (with its
//!   layout types), `action_msgs/msg/GoalStatusArray` (with GoalStatus,
//!   GoalInfo) and `action_msgs/srv/CancelGoal` (with its request,
//!   response and event). These interfaces are the same in Jazzy; for the
//!   messages among them, rosbags 0.10.11's `ROS2_JAZZY` store computes
//!   the same hashes from Jazzy's definitions.
//! - JointState is also what `ros2 topic info -v /joint_states` prints on
//!   Jazzy.

use super::types::*;
use super::TypeDescription;

fn check(t: &TypeDescription, expected: &str) {
    assert_eq!(t.rihs01(), expected, "the RIHS01 hash of {}", t.name());
}

#[test]
fn message_hashes_are_the_published_ones() {
    let published: [(&TypeDescription, &str); 17] = [
        // [A]
        (
            &TIME,
            "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197",
        ),
        (
            &DURATION,
            "RIHS01_e8d009f659816f758b75334ee1a9ca5b5c0b859843261f14c7f937349599d93b",
        ),
        (
            &HEADER,
            "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01",
        ),
        (
            &JOINT_TRAJECTORY,
            "RIHS01_179b33eba59d676f6d967ac71fe35e7ca2f64b2f3928f4a018cec115e213796e",
        ),
        (
            &JOINT_TRAJECTORY_POINT,
            "RIHS01_de8907036d8bd45aac6f30cc9044a3d4a329c42cbf719aff7d95a584cfa532d7",
        ),
        (
            &MULTI_DOF_TRAJECTORY,
            "RIHS01_3a18fd095292a65cfde8833c72985a30af981f3ec44494655c6267262b443a4a",
        ),
        (
            &MULTI_DOF_POINT,
            "RIHS01_6ada1085b5ee64eaa069b074968e69f0e27c8c5e6f5bb0586dd1c834ef0e32b8",
        ),
        (
            &VECTOR3,
            "RIHS01_cc12fe83e4c02719f1ce8070bfd14aecd40f75a96696a67a2a1f37f7dbb0765d",
        ),
        (
            &QUATERNION,
            "RIHS01_8a765f66778c8ff7c8ab94afcc590a2ed5325a1d9a076ffff38fbce36f458684",
        ),
        (
            &TRANSFORM,
            "RIHS01_beb83fbe698636351461f6f35d1abb20010c43d55374d81bd041f1ba2581fddc",
        ),
        (
            &TWIST,
            "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a",
        ),
        (
            &UUID,
            "RIHS01_1b8e8aca958cbea28fe6ef60bf6c19b683c97a9ef60bb34752067d0f2f7ab437",
        ),
        (
            &SERVICE_EVENT_INFO,
            "RIHS01_41bcbbe07a75c9b52bc96bfd5c24d7f0fc0a08c0cb7921b3373c5732345a6f45",
        ),
        // [K]
        (
            &JOINT_STATE,
            "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e",
        ),
        (
            &FLOAT64_MULTI_ARRAY,
            "RIHS01_1025ddc6b9552d191f89ef1a8d2f60f3d373e28b283d8891ddcc974e8c55397f",
        ),
        (
            &MULTI_ARRAY_LAYOUT,
            "RIHS01_4c66e6f78e740ac103a94cf63259f968e48c617e7699e829b63c21a5cb50dac6",
        ),
        (
            &MULTI_ARRAY_DIMENSION,
            "RIHS01_5e773a60a4c7fc8a54985f307c7837aa2994252a126c301957a24e31282c9cbe",
        ),
    ];
    for (t, expected) in published {
        check(t, expected);
    }
}

#[test]
fn follow_joint_trajectory_hashes_are_the_published_ones() {
    // [A], the action's own types, and its tolerances.
    let published: [(&TypeDescription, &str); 15] = [
        (
            &FOLLOW_JOINT_TRAJECTORY,
            "RIHS01_738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6",
        ),
        (
            &FJT_GOAL,
            "RIHS01_8a9060704b269608f5a340934cc26e66869dd14bdac29e2e7fd9ec8b9882d205",
        ),
        (
            &FJT_RESULT,
            "RIHS01_8002e99ed2c14c6faa522f2a93c26d744c5982f254f9e98ff9c6f19789bdb220",
        ),
        (
            &FJT_FEEDBACK,
            "RIHS01_3fd0aaecf71725121ae1ff7f01098a5e0da581e672be18a6b2c286cb43d96b49",
        ),
        (
            &FJT_SEND_GOAL,
            "RIHS01_b13789dddc325a7a962825c45e28c77d37237ec129dd0c34dc5994562938c57f",
        ),
        (
            &FJT_SEND_GOAL_REQUEST,
            "RIHS01_179c93691f1f6d1d115881ff88c3917b7cc6eac2ba4bf56766cc7c4389e19ef1",
        ),
        (
            &FJT_SEND_GOAL_RESPONSE,
            "RIHS01_e6a48ba740ae254500129a877f0b071be8663a115da1a539b74599cc97921fbf",
        ),
        (
            &FJT_SEND_GOAL_EVENT,
            "RIHS01_906dd566308db02673c73c654f69bdd84738589629c1bc2841ddb49059ed1c6f",
        ),
        (
            &FJT_GET_RESULT,
            "RIHS01_e3ceb38e3e1867c8dc0f46014df26e90eb93422f27e9e97f936e07f94be4bc8b",
        ),
        (
            &FJT_GET_RESULT_REQUEST,
            "RIHS01_ecf7ea8463d3beec7084bca75216d0b01b87b6e1e4e09679bb26093041efcbe9",
        ),
        (
            &FJT_GET_RESULT_RESPONSE,
            "RIHS01_08eefbaa146ce02ba45898d5e99160afd6c4c54a30d159aee0f2ca6035b1580f",
        ),
        (
            &FJT_GET_RESULT_EVENT,
            "RIHS01_43161a489e52daaa5bbc2fa74f73f1804d099574fcf8f819170807d75472662a",
        ),
        (
            &FJT_FEEDBACK_MESSAGE,
            "RIHS01_80398fcb9674a79081a9906e2ccf0c804dd7cb15e22e362e606ee87186beab71",
        ),
        (
            &JOINT_TOLERANCE,
            "RIHS01_c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648",
        ),
        (
            &JOINT_COMPONENT_TOLERANCE,
            "RIHS01_739ea7566931944d33830fa10f1bf5e7a7fbdc3172bce7a7eaac642bd6e3ffa4",
        ),
    ];
    for (t, expected) in published {
        check(t, expected);
    }
}

#[test]
fn action_msgs_hashes_are_the_published_ones() {
    // [K], cancel_goal__description.c and goal_status_array__description.c.
    let published: [(&TypeDescription, &str); 7] = [
        (
            &CANCEL_GOAL,
            "RIHS01_573d8b0a534451d7bc2ac8c5ffde8ac14b8593b7001175d0cd6516dcbeb8689a",
        ),
        (
            &CANCEL_GOAL_REQUEST,
            "RIHS01_3d3c84653c1f96918086887e1dcb236faec88b81a5b14fd4cf4840065bcdf8af",
        ),
        (
            &CANCEL_GOAL_RESPONSE,
            "RIHS01_35e682cf3f510e83c70a82a4aac888496dedee56773bf9d8e5e0aa81f9e1c960",
        ),
        (
            &CANCEL_GOAL_EVENT,
            "RIHS01_178f81615ce6be41ad328211d7a56b08b00e73f41f0b8aec256b2f3ff97a5e7e",
        ),
        (
            &GOAL_INFO,
            "RIHS01_6398fe763154554353930716b225947f93b672f0fb2e49fdd01bb7a7e37933e9",
        ),
        (
            &GOAL_STATUS,
            "RIHS01_32f4cfd717735d17657e1178f24431c1ce996c878c515230f6c5b3476819dbb9",
        ),
        (
            &GOAL_STATUS_ARRAY,
            "RIHS01_6c1684b00f177d37438febe6e709fc4e2b0d4248dca4854946f9ed8b30cda83e",
        ),
    ];
    for (t, expected) in published {
        check(t, expected);
    }
}

#[test]
fn dds_names_follow_rmw_zenoh() {
    // rmw_zenoh's type names: `<namespace>::dds_::<name>_`; a service is
    // named by its response type with `Response_` cut off.
    assert_eq!(
        JOINT_TRAJECTORY.dds_name(),
        "trajectory_msgs::msg::dds_::JointTrajectory_"
    );
    assert_eq!(JOINT_STATE.dds_name(), super::JOINT_STATE_TYPE);
    assert_eq!(
        FJT_SEND_GOAL.dds_name(),
        "control_msgs::action::dds_::FollowJointTrajectory_SendGoal_"
    );
    assert_eq!(
        FJT_SEND_GOAL_REQUEST.dds_name(),
        "control_msgs::action::dds_::FollowJointTrajectory_SendGoal_Request_"
    );
    assert_eq!(
        FJT_GET_RESULT_RESPONSE.dds_name(),
        "control_msgs::action::dds_::FollowJointTrajectory_GetResult_Response_"
    );
    assert_eq!(
        CANCEL_GOAL.dds_name(),
        "action_msgs::srv::dds_::CancelGoal_"
    );
    assert_eq!(
        FJT_FEEDBACK_MESSAGE.dds_name(),
        "control_msgs::action::dds_::FollowJointTrajectory_FeedbackMessage_"
    );
    assert_eq!(
        GOAL_STATUS_ARRAY.dds_name(),
        "action_msgs::msg::dds_::GoalStatusArray_"
    );
}

#[test]
fn a_changed_field_changes_the_hash() {
    // The hash sees field names, types and nesting: a description that
    // differed from ROS's in any of them would fail the tests above.
    static RENAMED: TypeDescription = TypeDescription::new(
        "builtin_interfaces/msg/Time",
        &[
            super::hash::field("sec", super::hash::field_type::INT32),
            super::hash::field("nanosecs", super::hash::field_type::UINT32),
        ],
    );
    assert_ne!(RENAMED.rihs01(), TIME.rihs01());
}
