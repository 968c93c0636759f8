//! One model of the servo's timing on both sides: on every shipped robot,
//! the simulator in virtual time runs the cycle `servobus budget` plans in
//! the time the budget says, so the budget's maximum rate and the rate the
//! simulator achieves agree (within 5 %, the bar; here within 1 %).

use crate::common;

use servobus_driver::Clock;
use servobus_protocol::registers::addr;

/// Free-running cycles per bus: SYNC WRITE of the goals, then the positions
/// read back, as `servobus bench` runs them.
const CYCLES: u32 = 200;

#[test]
fn every_shipped_robot_runs_on_the_simulator_at_the_budgets_maximum_rate() {
    for name in ["so101", "hexapod", "hexapod-2bus", "scs-mini"] {
        let robot = common::robot(&format!("{name}.yaml"));
        let (mut buses, _sims) = common::sim_buses(&robot);
        for (bus, config) in buses.iter_mut().zip(&robot.buses) {
            let ids: Vec<u8> = config.joints.iter().map(|j| j.id).collect();
            // Hold the servos where they are.
            let read = bus
                .sync_read_patiently(addr::PRESENT_POSITION, 2, &ids)
                .expect("the simulated servos answer");
            let mut goals = Vec::new();
            for r in read.iter() {
                goals.extend_from_slice(r.expect("every servo answers").data);
            }
            let start = bus.clock().now();
            let mut cycle = || {
                bus.sync_write(addr::GOAL_POSITION, &ids, &goals)
                    .expect("SYNC WRITE");
                let read = bus.sync_read(addr::PRESENT_POSITION, 2, &ids);
                read.expect("the read runs").missing()
            };
            let lost: usize = (0..CYCLES).map(|_| cycle()).sum();
            assert_eq!(lost, 0, "{name}: replies were lost");
            let achieved = f64::from(CYCLES) / (bus.clock().now() - start).as_secs_f64();
            // The budget of the wire and the servos: virtual time has no
            // pseudo-terminal, whose overhead `budget` charges on top.
            let budget = config
                .plan_on(&config.link(), 1.0)
                .expect("plans")
                .max_rate_hz();
            let ratio = achieved / budget;
            println!(
                "{name} bus {}: simulator {achieved:.1} Hz, budget {budget:.1} Hz",
                config.name
            );
            assert!(
                (0.99..=1.01).contains(&ratio),
                "{name} bus {}: simulator {achieved:.1} Hz vs budget {budget:.1} Hz",
                config.name
            );
        }
    }
}
