//! The 6-joint arm plays a choreography end to end in virtual time.

use crate::common;

use servobus_runtime::{Finish, VirtualRun};

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
