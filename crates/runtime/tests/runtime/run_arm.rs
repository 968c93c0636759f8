//! The 6-joint arm plays a choreography end to end in virtual time.

use crate::common;

use servobus_runtime::{Finish, VirtualRun};
use servobus_sim::addr;

#[test]
fn arm_wave_plays_end_to_end_at_exactly_the_requested_rate() {
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, _sims) = common::sim_buses(&robot);
    let report = VirtualRun::new(&robot, path, buses, common::quiet())
        .expect("starts")
        .run();
    println!("{}", serde_json::to_string_pretty(&report).unwrap());
    assert_eq!(report.finish, Finish::Completed);
    assert_eq!(report.achieved_rate_hz, 200.0);
    assert_eq!(report.overruns, 0);
    assert_eq!(report.clamps, 0);
}

#[test]
fn the_servos_own_ramps_are_turned_off_so_they_follow_the_path_without_trailing() {
    // Left by another program (LeRobot sets the ramp to 254, a speed cap
    // is a common leftover): servobus's path is already limited, and the
    // firmware's ramp on top of it would make every joint trail the path.
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, sims) = common::sim_buses(&robot);
    let ids: Vec<u8> = robot.joints().map(|j| j.id).collect();
    for &id in &ids {
        sims[0].servo(id, |s| {
            s.poke(addr::ACCELERATION, &[254]);
            s.poke(addr::GOAL_SPEED, &200u16.to_le_bytes());
        });
    }
    let report = VirtualRun::new(&robot, path, buses, common::quiet())
        .expect("starts")
        .run();
    assert_eq!(report.finish, Finish::Completed);
    for &id in &ids {
        assert_eq!(
            sims[0].register(id, addr::ACCELERATION),
            Some(0),
            "servo {id}"
        );
        assert_eq!(
            sims[0].register(id, addr::GOAL_SPEED),
            Some(0),
            "servo {id}"
        );
        assert_eq!(
            sims[0].register(id, addr::GOAL_SPEED + 1),
            Some(0),
            "servo {id}"
        );
    }
    // Tracked as closely as servos that never had a ramp (a speed cap of
    // 200 steps/s would have left the joints tens of degrees behind).
    assert!(
        report.worst_max_error() < 3.0,
        "{}",
        report.worst_max_error()
    );
}
