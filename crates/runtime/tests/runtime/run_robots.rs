//! End to end in virtual time: the arm within a stated tracking bound, the
//! 18-servo hexapod on one bus and on two buses in step, the SCS robot, and
//! stop / replace / pause commands mid-motion.

use crate::common;

use servobus_runtime::config::{load_motion, plan_motion, Robot};
use servobus_runtime::{Command, Finish, Report, RunOptions, VirtualRun};
use servobus_trajectory::Trajectory;

/// Plays `path` to its end on `robot`'s simulated buses (every servo at
/// mid-range) and prints the report.
fn play(robot: &Robot, path: Trajectory) -> Report {
    let (buses, _) = common::sim_buses(robot);
    let r = VirtualRun::new(robot, path, buses, common::quiet())
        .expect("starts")
        .run();
    show(&r);
    r
}

/// A run that completed at its planned rate with no overrun, clamp or
/// missed reply, every joint within 0.5 deg RMS and 2 deg at worst (the
/// stated bound).
fn assert_tracked(r: &Report) {
    assert_eq!(r.finish, Finish::Completed);
    assert_eq!(r.achieved_rate_hz, r.planned_rate_hz);
    assert_eq!((r.overruns, r.clamps, r.missed_replies), (0, 0, 0));
    assert!(r.worst_rms_error() < 0.5 && r.worst_max_error() < 2.0);
}

/// Options that keep the telemetry of a run driven by [`common::record`].
fn recorded() -> RunOptions {
    RunOptions {
        telemetry_capacity: 256,
        ..RunOptions::default()
    }
}

fn show(r: &Report) {
    println!(
        "{} cycles at {} Hz (planned {}), worst RMS {:.3} {}, worst max {:.3}, utilisation {:.3}, lead {:.1} ms",
        r.cycles,
        r.achieved_rate_hz,
        r.planned_rate_hz,
        r.worst_rms_error(),
        r.units,
        r.worst_max_error(),
        r.utilisation,
        r.lead_ms
    );
}

#[test]
fn the_arm_plays_pick_and_place_within_half_a_degree_rms() {
    let (path, robot) = common::motion("arm-pick-place.yaml");
    let r = play(&robot, path);
    assert_tracked(&r);
    assert_eq!(r.timeouts, 0);
}

#[test]
fn the_hexapod_walks_on_one_bus_and_on_two_buses_in_step() {
    let play_on = |robot_file: &str| {
        let (path, robot) = common::planned("motions/hexapod-tripod.yaml", Some(robot_file));
        let r = play(&robot, path);
        assert_tracked(&r);
        assert_eq!((r.achieved_rate_hz, r.joints.len()), (100.0, 18));
        r
    };
    let one = play_on("robots/hexapod.yaml");
    let two = play_on("robots/hexapod-2bus.yaml");
    // In step: both buses ran every cycle, and the same number as one bus.
    assert_eq!(two.buses.len(), 2);
    assert!(two.buses.iter().all(|b| b.cycles == two.cycles));
    assert_eq!(one.cycles, two.cycles);
    // Two wires in parallel: each bus is about half as busy.
    let (busy_one, busy_two) = (one.utilisation, two.utilisation);
    assert!(busy_two < 0.6 * busy_one, "{busy_two} vs {busy_one}");
}

#[test]
fn the_scs_robot_reads_servo_by_servo() {
    let (path, robot) = common::motion("scs-mini-nod.yaml");
    let r = play(&robot, path);
    assert_eq!(r.finish, Finish::Completed);
    assert_eq!(r.achieved_rate_hz, r.planned_rate_hz);
    assert_eq!((r.overruns, r.missed_replies), (0, 0));
    // The SCS0009's ticks are 0.29 deg: a coarser bound.
    for j in &r.joints {
        println!("{}: rms {:.3} max {:.3}", j.name, j.rms_error, j.max_error);
    }
    // Stated bound at 50 Hz: 2.5 deg RMS (measured 1.7 on the pan, which
    // sweeps at 300 deg/s with 20 ms between goals).
    assert!(r.worst_rms_error() < 2.5, "{}", r.worst_rms_error());
}

/// Finite differences of a path within its limits stay within them up to
/// float rounding (relative).
const WITHIN: f64 = 1.0 + 1e-6;
/// How far a ramp of the identified lead may take the goals past a path's
/// limits (the runtime's `LEAD_EXCESS`).
const LEAD_EXCESS: f64 = 0.01;

/// Plays arm-wave from its start, sends `command` at cycle `at`, and checks
/// the commands of every joint stay within the arm's limits around it.
///
/// The limits hold exactly for finite differences too: the k-th difference
/// of a sampled path over k periods is a weighted mean of its k-th
/// derivative over them (mean value theorem for divided differences), so
/// it cannot exceed a bound the path keeps; [`WITHIN`] is float rounding,
/// and [`LEAD_EXCESS`] what a ramp of the identified lead may add.
fn command_mid_motion(command: Command, at: u64, jerk_limited: bool) -> (Report, common::Recorded) {
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, _) = common::sim_buses_at(&robot, &path);
    let mut run = VirtualRun::new(&robot, path, buses, recorded()).expect("starts");
    let tx = run.commands();
    let rec = common::record_acting_at(&mut run, 20_000, at, || {
        tx.try_send(command).expect("room for a command");
    });
    let limits: Vec<(f64, f64, f64)> = robot
        .joints()
        .map(|j| {
            (
                j.max_velocity,
                j.max_acceleration,
                j.max_jerk.unwrap_or(f64::INFINITY),
            )
        })
        .collect();
    for (i, (v_max, a_max, j_max)) in limits.into_iter().enumerate() {
        let (v, a, j) = rec.peaks(i, at - 20, 0.005);
        println!("joint {i}: {v:.1} deg/s, {a:.0} deg/s^2, {j:.0} deg/s^3");
        // The run identifies its lead: a ramp of it may add LEAD_EXCESS.
        let within = WITHIN + LEAD_EXCESS;
        assert!(
            v <= v_max * within && a <= a_max * within,
            "joint {i}: {v} {a}"
        );
        if jerk_limited {
            assert!(j <= j_max * within, "joint {i}: {j}");
        }
    }
    (run.report(), rec)
}

#[test]
fn a_stop_mid_motion_is_jerk_limited_and_ends_the_run() {
    let (r, rec) = command_mid_motion(Command::Stop, 300, true);
    assert_eq!(r.finish, Finish::Stopped);
    assert!(r.fault.is_none());
    // It stopped early (arm-wave lasts about 1600 cycles).
    let last = rec.rows.last().map_or(0, |r| r.0);
    assert!((300..600).contains(&last), "{last}");
}

/// A stop may come at any cycle (a Ctrl-C, a closed stdout): wherever it
/// comes, the goals keep every limit: exactly (to float rounding) with no
/// lead, and within [`LEAD_EXCESS`] while the identified lead ramps (the
/// goals are the path sampled that far ahead; see the runtime's
/// `busloop/lead.rs`). It used to be 1.6 % in jerk and 0.8 % in
/// acceleration in the first second, and more on a loaded host.
#[test]
fn a_stop_at_any_cycle_keeps_every_limit() {
    let (path, robot) = common::motion("arm-wave.yaml");
    for (lead, within) in [
        (servobus_runtime::Lead::None, WITHIN),
        (servobus_runtime::Lead::default(), WITHIN + LEAD_EXCESS),
    ] {
        for at in (40..1050).step_by(37) {
            let (buses, _) = common::sim_buses_at(&robot, &path);
            let options = RunOptions { lead, ..recorded() };
            let mut run = VirtualRun::new(&robot, path.clone(), buses, options).expect("starts");
            let tx = run.commands();
            let rec = common::record_acting_at(&mut run, 20_000, at, || {
                tx.try_send(Command::Stop).expect("room for a command");
            });
            assert_eq!(run.report().finish, Finish::Stopped, "stop at {at}");
            for (i, joint) in robot.joints().enumerate() {
                let (v, a, j) = rec.peaks(i, 0, 0.005);
                let j_max = joint.max_jerk.unwrap_or(f64::INFINITY);
                assert!(
                    v <= joint.max_velocity * within
                        && a <= joint.max_acceleration * within
                        && j <= j_max * within,
                    "{lead:?}, stop at cycle {at}, joint {i}: {v} deg/s, {a} deg/s^2, {j} deg/s^3"
                );
            }
        }
    }
}

#[test]
fn a_replacement_mid_motion_is_continuous() {
    let (m, robot) =
        load_motion(&common::config("motions/arm-pick-place.yaml"), None).expect("loads");
    let other = plan_motion(&m, &robot).expect("plans");
    let duration = other.duration();
    let (r, rec) = command_mid_motion(Command::replace(other), 300, true);
    assert_eq!(r.finish, Finish::Completed);
    // The run went on for the transition and the whole new path.
    let last = rec.rows.last().map_or(0, |r| r.0) as f64 * 0.005;
    assert!(last > 1.5 + duration, "{last}");
}

#[test]
fn pause_holds_on_the_path_and_resume_continues() {
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, _) = common::sim_buses_at(&robot, &path);
    let plain = (path.duration() / 0.005) as u64;
    let mut run = VirtualRun::new(&robot, path, buses, recorded()).expect("starts");
    let tx = run.commands();
    let rec = common::record(&mut run, 20_000, |k| {
        if k == 300 {
            let _ = tx.try_send(Command::Pause);
        }
        if k == 900 {
            let _ = tx.try_send(Command::Resume);
        }
    });
    let r = run.report();
    assert_eq!(r.finish, Finish::Completed);
    // Paused: between the end of the ramp and the resume nothing moves.
    for j in 0..6 {
        let c = rec.commanded(j);
        assert!((c[800] - c[700]).abs() < 1e-9, "joint {j}");
        let (v, a, _) = rec.peaks(j, 0, 0.005);
        let limit = robot.joints().nth(j).expect("six joints");
        // Known and not yet fixed: pause and resume go past the limits,
        // by 4.4 % in velocity and 10.9 % in acceleration on elbow_flex
        // (188.0 deg/s against 180, 998 deg/s^2 against 900; the ramp of
        // the time scale adds the path's velocity times the ramp's rate of
        // change to the path's own acceleration, and the goals, sampled a
        // lead ahead, see the ramp's change that much early: 3.7 % and
        // 7.1 % while the lead started at 0 instead of the servo model's
        // prior). Held here to what is true, so it cannot get worse unseen;
        // the exact limit is the goal.
        assert!(
            v <= limit.max_velocity * 1.05 && a <= limit.max_acceleration * 1.12,
            "joint {j}: {v} {a}"
        );
    }
    // It played the whole path, about 600 cycles late (the ramps take back
    // a little).
    assert!(r.cycles > plain + 450, "{} vs {plain}", r.cycles);
}

#[test]
fn play_during_the_approach_starts_the_path_where_the_approach_ends() {
    // The servos start wherever the simulator puts them: an approach of
    // about two seconds comes first, and Play arrives early in it.
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, _) = common::sim_buses(&robot);
    let options = RunOptions {
        autoplay: false,
        ..recorded()
    };
    let mut run = VirtualRun::new(&robot, path, buses, options).expect("starts");
    let tx = run.commands();
    tx.send_at(20, Command::Play).expect("room for a command");
    let rec = common::record(&mut run, 20_000, |_| {});
    let r = run.report();
    assert_eq!(r.finish, Finish::Completed, "{:?}", r.fault);
    // No jump to the path's start: every joint within its limits (exactly,
    // see `command_mid_motion`).
    for (i, j) in robot.joints().enumerate() {
        let (v, a, _) = rec.peaks(i, 0, 0.005);
        println!("{}: {v:.1} deg/s, {a:.0} deg/s^2", j.name);
        assert!(v <= j.max_velocity * WITHIN && a <= j.max_acceleration * WITHIN);
    }
}
