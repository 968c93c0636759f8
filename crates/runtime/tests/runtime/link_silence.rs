//! A silent bus against a silent servo, in virtual time. One servo that
//! stops answering while its neighbours answer is missing after 3 reads;
//! every servo of a bus silent at once is the link stalling (or the bus's
//! power), judged by how long it lasts: `FaultPolicy::bus_silence`, 100 ms.

use crate::common;

use servobus_runtime::{FaultKind, Finish, RunOptions, VirtualRun};
use servobus_sim::SimBus;

/// arm-wave at 200 Hz: one cycle is 5 ms.
const CYCLE_MS: u64 = 5;

fn arm() -> (VirtualRun<SimBus>, SimBus) {
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, mut sims) = common::sim_buses_at(&robot, &path);
    let run = VirtualRun::new(&robot, path, buses, RunOptions::default()).expect("starts");
    (run, sims.remove(0))
}

/// Every servo of the SO-101's bus (IDs 1 to 6) on or off the bus.
fn whole_bus(sim: &SimBus, offline: bool) {
    for id in 1..=6 {
        sim.servo(id, |s| s.set_offline(offline)).expect("servo");
    }
}

#[test]
fn a_whole_bus_silent_for_50_ms_is_a_stall_not_a_missing_servo() {
    let (mut run, sim) = arm();
    // 10 cycles of 5 ms: far more than the 3 reads that find one servo.
    let rec = common::record(&mut run, 5_000, |k| match k {
        300 => whole_bus(&sim, true),
        310 => whole_bus(&sim, false),
        _ => {}
    });
    assert!(rec.faults.is_empty(), "{:?}", rec.faults);
    assert_eq!(run.finished(), Some(Finish::Completed));
    // The stall is not hidden: every read in it counts as missed.
    let report = run.report();
    assert!(report.buses[0].missed_replies >= 6 * 9, "{report:?}");
}

#[test]
fn a_whole_bus_silent_for_good_stops_the_run_once_the_silence_passes_100_ms() {
    let (mut run, sim) = arm();
    let at = 300;
    common::record(&mut run, 5_000, |k| {
        if k == at {
            whole_bus(&sim, true);
        }
    });
    let f = run.fault().expect("the silent bus stops the run").clone();
    let FaultKind::Missing { reason, .. } = &f.kind else {
        panic!("{f:?}");
    };
    assert!(reason.contains("no servo of the bus answered"), "{reason}");
    // The documented default is 100 ms (README, `FaultPolicy::bus_silence`).
    // The last answer came in cycle at-1; 100 ms is 20 cycles of 5 ms. The
    // fault comes with the first read that is 100 ms or more after it,
    // give or take the read's position in its cycle.
    let cycles = 100 / CYCLE_MS;
    assert!(
        f.cycle >= at - 1 + cycles - 1 && f.cycle <= at + cycles + 1,
        "cycle {} vs silence from {at}",
        f.cycle
    );
}

#[test]
fn a_servo_lost_in_a_bus_stall_is_found_3_reads_after_the_bus_answers_again() {
    let (mut run, sim) = arm();
    common::record(&mut run, 5_000, |k| match k {
        300 => whole_bus(&sim, true),
        310 => {
            whole_bus(&sim, false);
            sim.servo(4, |s| s.set_offline(true)).expect("servo 4");
        }
        _ => {}
    });
    let f = run.fault().expect("servo 4 is found").clone();
    assert_eq!(f.servo_id, Some(4));
    let FaultKind::Missing { cycles, .. } = f.kind else {
        panic!("{f:?}");
    };
    assert_eq!(cycles, 3);
    assert!(f.cycle >= 310 && f.cycle < 313, "cycle {}", f.cycle);
}

#[test]
fn servos_read_in_turn_are_counted_one_by_one_even_when_a_turn_is_all_silent() {
    // 1000 Hz is above the arm's 847 Hz maximum: with `round_robin` each
    // cycle reads only some of the servos, so a read in which every servo
    // asked is silent says nothing about the bus while servo 6 answers in
    // its turn.
    let (path, mut robot) = common::motion("arm-wave.yaml");
    robot.buses[0].round_robin = true;
    let (buses, mut sims) = common::sim_buses_at(&robot, &path);
    let sim = sims.remove(0);
    let options = RunOptions {
        rate_hz: Some(1000.0),
        ..RunOptions::default()
    };
    let mut run = VirtualRun::new(&robot, path, buses, options).expect("starts");
    common::record(&mut run, 50_000, |k| {
        if k == 1000 {
            for id in 1..=5 {
                sim.servo(id, |s| s.set_offline(true)).expect("servo");
            }
        }
    });
    let f = run.fault().expect("the silent servos are found").clone();
    let FaultKind::Missing { cycles, reason } = &f.kind else {
        panic!("{f:?}");
    };
    assert!(f.servo_id.is_some_and(|id| (1..=5).contains(&id)), "{f:?}");
    assert_eq!((*cycles, reason.as_str()), (3, "no reply"), "{f:?}");
    // Found by its own count, well before a silence of the whole bus would
    // be judged (100 ms: 100 cycles at 1000 Hz).
    assert!(f.cycle >= 1000 && f.cycle < 1000 + 100, "cycle {}", f.cycle);
}
