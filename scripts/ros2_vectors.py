#!/usr/bin/env python3
"""Writes testdata/ros2/*.hex: CDR payloads of the ROS 2 messages servobus
reads and writes, serialized by rosbags (an implementation of ROS 2's CDR
independent of servobus), for the unit tests of crates/node/src/ros2.

Usage: eval "$(scripts/python_clients.sh)"
       "$SERVOBUS_ZENOH_PYTHON" scripts/ros2_vectors.py [OUT_DIR]

Each file holds one payload (the 4-byte encapsulation header first) as hex,
after comment lines starting with '#'. The sample values are written again,
by hand, in crates/node/src/ros2/vector_tests.rs: a change here needs the
same change there.

rosbags' ROS2_JAZZY store has builtin_interfaces, std_msgs, sensor_msgs,
trajectory_msgs, geometry_msgs, unique_identifier_msgs and action_msgs'
messages; control_msgs and the action's service types are registered here
from their Jazzy definitions (control_msgs 5.x). rosbags files them under
`<pkg>/msg/<Name>`: the names do not reach the bytes.
"""

import sys
from importlib.metadata import version
from pathlib import Path

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent / "testdata" / "ros2"

# Jazzy's control_msgs (5.x) and the action's own types, comments and
# constants aside (constants do not reach the bytes).
DEFINITIONS = {
    "control_msgs/msg/JointTolerance": """
string name
float64 position
float64 velocity
float64 acceleration
""",
    "control_msgs/msg/JointComponentTolerance": """
string joint_name
uint16 component
float64 position
float64 velocity
float64 acceleration
""",
    "control_msgs/msg/FjtGoal": """
trajectory_msgs/JointTrajectory trajectory
trajectory_msgs/MultiDOFJointTrajectory multi_dof_trajectory
control_msgs/JointTolerance[] path_tolerance
control_msgs/JointComponentTolerance[] component_path_tolerance
control_msgs/JointTolerance[] goal_tolerance
control_msgs/JointComponentTolerance[] component_goal_tolerance
builtin_interfaces/Duration goal_time_tolerance
""",
    "control_msgs/msg/FjtResult": """
int32 error_code
string error_string
""",
    "control_msgs/msg/FjtFeedback": """
std_msgs/Header header
string[] joint_names
trajectory_msgs/JointTrajectoryPoint desired
trajectory_msgs/JointTrajectoryPoint actual
trajectory_msgs/JointTrajectoryPoint error
string[] multi_dof_joint_names
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_desired
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_actual
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_error
""",
    "control_msgs/msg/FjtSendGoalRequest": """
unique_identifier_msgs/UUID goal_id
control_msgs/FjtGoal goal
""",
    "control_msgs/msg/FjtSendGoalResponse": """
bool accepted
builtin_interfaces/Time stamp
""",
    "control_msgs/msg/FjtGetResultRequest": """
unique_identifier_msgs/UUID goal_id
""",
    "control_msgs/msg/FjtGetResultResponse": """
int8 status
control_msgs/FjtResult result
""",
    "control_msgs/msg/FjtFeedbackMessage": """
unique_identifier_msgs/UUID goal_id
control_msgs/FjtFeedback feedback
""",
    "action_msgs/msg/CancelGoalRequest": """
action_msgs/GoalInfo goal_info
""",
    "action_msgs/msg/CancelGoalResponse": """
int8 return_code
action_msgs/GoalInfo[] goals_canceling
""",
}

store = get_typestore(Stores.ROS2_JAZZY)
for name, text in DEFINITIONS.items():
    store.register(get_types_from_msg(text, name))
T = store.types


def f64(*values):
    return np.array(values, dtype=np.float64)


def uuid(first):
    return T["unique_identifier_msgs/msg/UUID"](uuid=np.arange(first, first + 16, dtype=np.uint8))


def time(sec, nanosec):
    return T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)


def duration(sec, nanosec):
    return T["builtin_interfaces/msg/Duration"](sec=sec, nanosec=nanosec)


def header(sec, nanosec, frame_id):
    return T["std_msgs/msg/Header"](stamp=time(sec, nanosec), frame_id=frame_id)


def point(positions=(), velocities=(), accelerations=(), effort=(), sec=0, nanosec=0):
    return T["trajectory_msgs/msg/JointTrajectoryPoint"](
        positions=f64(*positions),
        velocities=f64(*velocities),
        accelerations=f64(*accelerations),
        effort=f64(*effort),
        time_from_start=duration(sec, nanosec),
    )


def multi_dof_point(transforms=(), velocities=(), sec=0):
    return T["trajectory_msgs/msg/MultiDOFJointTrajectoryPoint"](
        transforms=list(transforms), velocities=list(velocities), accelerations=[], time_from_start=duration(sec, 0)
    )


def vector3(x, y, z):
    return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def trajectory(frame_id):
    return T["trajectory_msgs/msg/JointTrajectory"](
        header=header(0, 0, frame_id),
        joint_names=["shoulder_pan", "elbow_flex"],
        points=[
            point(positions=(0.0, 0.5), velocities=(0.1, 0.2), sec=1, nanosec=500_000_000),
            point(positions=(0.25, -0.75), accelerations=(0.0, 1.0), sec=3),
        ],
    )


def tolerance(name, position, velocity, acceleration):
    return T["control_msgs/msg/JointTolerance"](
        name=name, position=position, velocity=velocity, acceleration=acceleration
    )


def goal(multi_dof):
    if multi_dof:
        transform = T["geometry_msgs/msg/Transform"](
            translation=vector3(1.0, 2.0, 3.0),
            rotation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
        )
        twist = T["geometry_msgs/msg/Twist"](linear=vector3(0.5, 0.0, 0.0), angular=vector3(0.0, 0.0, -0.25))
        mdt = T["trajectory_msgs/msg/MultiDOFJointTrajectory"](
            header=header(5, 6, "odom"),
            joint_names=["base"],
            points=[multi_dof_point([transform], [twist], sec=2)],
        )
    else:
        mdt = T["trajectory_msgs/msg/MultiDOFJointTrajectory"](header=header(0, 0, ""), joint_names=[], points=[])
    component = T["control_msgs/msg/JointComponentTolerance"](
        joint_name="base", component=4, position=0.1, velocity=0.2, acceleration=0.3
    )
    return T["control_msgs/msg/FjtGoal"](
        trajectory=trajectory(""),
        multi_dof_trajectory=mdt,
        path_tolerance=[tolerance("elbow_flex", 0.05, 0.0, 0.0)],
        component_path_tolerance=[],
        goal_tolerance=[tolerance("shoulder_pan", 0.01, -1.0, 0.0)],
        component_goal_tolerance=[component] if multi_dof else [],
        goal_time_tolerance=duration(0, 250_000_000),
    )


def goal_info(first, sec, nanosec):
    return T["action_msgs/msg/GoalInfo"](goal_id=uuid(first), stamp=time(sec, nanosec))


def feedback_message():
    feedback = T["control_msgs/msg/FjtFeedback"](
        header=header(100, 200, ""),
        joint_names=["shoulder_pan", "elbow_flex"],
        desired=point(positions=(0.1, 0.2), velocities=(0.3, -0.4), sec=1),
        actual=point(positions=(0.11, 0.19)),
        error=point(positions=(-0.01, 0.01)),
        multi_dof_joint_names=[],
        multi_dof_desired=multi_dof_point(),
        multi_dof_actual=multi_dof_point(),
        multi_dof_error=multi_dof_point(),
    )
    return T["control_msgs/msg/FjtFeedbackMessage"](goal_id=uuid(0), feedback=feedback)


SAMPLES = {
    "joint_state": (
        "sensor_msgs/msg/JointState",
        T["sensor_msgs/msg/JointState"](
            header=header(1_700_000_000, 123_456_789, ""),
            name=["shoulder_pan", "elbow_flex", "gripper"],
            position=f64(0.1, -1.25, 0.5),
            velocity=f64(),
            effort=f64(0.0, 2.5, -3.0),
        ),
    ),
    "float64_multi_array": (
        "std_msgs/msg/Float64MultiArray",
        T["std_msgs/msg/Float64MultiArray"](
            layout=T["std_msgs/msg/MultiArrayLayout"](
                dim=[T["std_msgs/msg/MultiArrayDimension"](label="joints", size=3, stride=3)], data_offset=0
            ),
            data=f64(0.25, -0.5, 1.0),
        ),
    ),
    "joint_trajectory": ("trajectory_msgs/msg/JointTrajectory", trajectory("base")),
    "send_goal_request": (
        "control_msgs/action/FollowJointTrajectory_SendGoal_Request",
        T["control_msgs/msg/FjtSendGoalRequest"](goal_id=uuid(0), goal=goal(False)),
    ),
    "send_goal_request_multi_dof": (
        "control_msgs/action/FollowJointTrajectory_SendGoal_Request (multi-DOF)",
        T["control_msgs/msg/FjtSendGoalRequest"](goal_id=uuid(100), goal=goal(True)),
    ),
    "send_goal_response": (
        "control_msgs/action/FollowJointTrajectory_SendGoal_Response",
        T["control_msgs/msg/FjtSendGoalResponse"](accepted=True, stamp=time(1_700_000_001, 5)),
    ),
    "get_result_request": (
        "control_msgs/action/FollowJointTrajectory_GetResult_Request",
        T["control_msgs/msg/FjtGetResultRequest"](goal_id=uuid(0)),
    ),
    "get_result_response": (
        "control_msgs/action/FollowJointTrajectory_GetResult_Response",
        T["control_msgs/msg/FjtGetResultResponse"](
            status=6,
            result=T["control_msgs/msg/FjtResult"](
                error_code=-4, error_string="elbow_flex left its path tolerance by 0.2 rad"
            ),
        ),
    ),
    "cancel_goal_request": (
        "action_msgs/srv/CancelGoal_Request",
        T["action_msgs/msg/CancelGoalRequest"](goal_info=goal_info(16, 12, 34)),
    ),
    "cancel_goal_response": (
        "action_msgs/srv/CancelGoal_Response",
        T["action_msgs/msg/CancelGoalResponse"](
            return_code=0, goals_canceling=[goal_info(0, 7, 8), goal_info(32, 9, 10)]
        ),
    ),
    "feedback_message": ("control_msgs/action/FollowJointTrajectory_FeedbackMessage", feedback_message()),
    "goal_status_array": (
        "action_msgs/msg/GoalStatusArray",
        T["action_msgs/msg/GoalStatusArray"](
            status_list=[
                T["action_msgs/msg/GoalStatus"](goal_info=goal_info(0, 1, 2), status=2),
                T["action_msgs/msg/GoalStatus"](goal_info=goal_info(48, 3, 4), status=4),
            ]
        ),
    ),
}


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    rosbags = version("rosbags")
    for stem, (ros_type, message) in SAMPLES.items():
        payload = bytes(store.serialize_cdr(message, message.__msgtype__))
        lines = [payload[i : i + 16].hex(" ") for i in range(0, len(payload), 16)]
        text = "\n".join(
            [
                f"# {ros_type}, {len(payload)} bytes",
                f"# written by scripts/ros2_vectors.py with rosbags {rosbags} (ROS2_JAZZY); do not edit",
                *lines,
            ]
        )
        (OUT / f"{stem}.hex").write_text(text + "\n")
        print(f"{stem}.hex: {len(payload)} bytes")


if __name__ == "__main__":
    main()
