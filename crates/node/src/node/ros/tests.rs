//! ROS 2 trajectories through the stream of a virtual-time run of the
//! simulated SO-101 ([`crate::node::virtual_node`]): the stream clock is
//! the run's, so each point's time is exact.

use std::time::Instant;

use servobus_robot::config::Robot;

use super::topics::send_planned;
use super::trajectory::{plan, Planned, Start};
use super::{ros_robot, RobotInfo};
use crate::node::virtual_node::{Node, PAN};
use crate::ros2::{JointTrajectory, JointTrajectoryPoint, RosDuration};

const ELBOW: usize = 2;

fn info(robot: &Robot) -> RobotInfo {
    RobotInfo {
        name: robot.name.clone(),
        joints: robot.joints().map(|j| j.name.clone()).collect(),
        units: robot.units,
        rate_hz: robot.rate_hz,
        config: Some(robot.clone()),
    }
}

/// A trajectory of `joints` through `points` (deg) at `times` (s).
fn trajectory(joints: &[&str], points: &[&[f64]], times: &[f64]) -> JointTrajectory {
    JointTrajectory {
        joint_names: joints.iter().map(|s| s.to_string()).collect(),
        points: points
            .iter()
            .zip(times)
            .map(|(q, &t)| JointTrajectoryPoint {
                positions: q.iter().map(|d| d.to_radians()).collect(),
                time_from_start: RosDuration::from_secs_f64(t),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    }
}

/// Plans `traj` arriving at run time `now` (starting then) from the
/// commanded state, and sends it as the node does.
fn send(node: &Node, traj: &JointTrajectory, now: f64) -> Planned {
    let robot = ros_robot(&info(&node.robot));
    let last = node.commanded.last().cloned();
    let heading = |j: usize| last.as_ref().map(|r| r[j].to_radians());
    let from = Start {
        now,
        start: now,
        position: &heading,
    };
    let planned = plan(traj, &robot, &from).expect("a trajectory the arm can follow");
    send_planned(
        &planned,
        now,
        Instant::now(),
        (&node.to, &node.shared, &robot),
    )
    .expect("the stream takes it");
    planned
}

#[test]
fn a_trajectory_of_four_points_is_followed_through_them_at_their_times() {
    let mut node = Node::new();
    let dt = node.period();
    assert!(node.run_for(40, |_, _| {}));
    let before = node.commanded.last().expect("cycles").clone();
    let pan = [20.0, -10.0, 30.0, 0.0];
    let elbow = [-15.0, 25.0, 10.0, 40.0];
    let times = [0.8, 1.6, 2.4, 3.2];
    let points: Vec<[f64; 2]> = pan.iter().zip(&elbow).map(|(&p, &e)| [p, e]).collect();
    let points: Vec<&[f64]> = points.iter().map(|p| &p[..]).collect();
    let traj = trajectory(&["shoulder_pan", "elbow_flex"], &points, &times);
    let k0: usize = 40;
    assert!(node.run_for(800, |node, k| {
        if k == k0 as u64 {
            send(node, &traj, k as f64 * dt);
        }
    }));
    for (i, &t) in times.iter().enumerate() {
        let k = k0 + (t / dt).round() as usize;
        let row = &node.commanded[k];
        for (j, want) in [(PAN, pan[i]), (ELBOW, elbow[i])] {
            let off = (row[j] - want).abs();
            assert!(
                off < 1.0,
                "point {i} at {t} s, joint {j}: {} deg, {off} off",
                row[j]
            );
        }
    }
    // The other joints never moved; the path kept to the limits.
    for j in [1, 3, 4, 5] {
        assert!(node
            .joint(j, 0)
            .iter()
            .all(|q| (q - before[j]).abs() < 1e-9));
    }
    let end = *node.joint(ELBOW, 0).last().expect("cycles");
    assert!((end - 40.0).abs() < 0.1, "held at the last point: {end}");
    node.assert_within_limits();
}

#[test]
fn a_trajectory_replaced_mid_way_joins_it_without_a_jump() {
    let mut node = Node::new();
    let dt = node.period();
    assert!(node.run_for(40, |_, _| {}));
    let first = trajectory(&["shoulder_pan"], &[&[20.0], &[40.0]], &[1.0, 2.0]);
    let second = trajectory(&["shoulder_pan"], &[&[10.0], &[-20.0]], &[1.0, 2.0]);
    let (k0, k1): (u64, usize) = (40, 240);
    assert!(node.run_for(800, |node, k| {
        let t = k as f64 * dt;
        if k == k0 {
            send(node, &first, t);
        }
        if k == k1 as u64 {
            send(node, &second, t);
        }
    }));
    let pan = node.joint(PAN, 0);
    // Moving up at 20 deg/s when replaced, and on the first one's path.
    let v = (pan[k1] - pan[k1 - 10]) / (10.0 * dt);
    assert!(
        (v - 20.0).abs() < 2.0 && (pan[k1] - 20.0).abs() < 1.0,
        "{v} deg/s at {}",
        pan[k1]
    );
    // Then the second one's points at their times, from there.
    assert!((pan[k1 + 200] - 10.0).abs() < 1.0, "{}", pan[k1 + 200]);
    assert!((pan[k1 + 400] + 20.0).abs() < 1.0, "{}", pan[k1 + 400]);
    // No jump: the velocity and acceleration stay within the pan's limits
    // across the join (finite differences of the commanded path).
    node.assert_within_limits();
}
