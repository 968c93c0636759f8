//! Virtual time and threads run the same cycle code: the same motion with
//! the same faults (injected at the same cycle, by the bus itself) played
//! through [`VirtualRun`] and through [`spawn`] (its bus threads on the
//! simulator's manual clocks) gives the same report, fault and reaction
//! included, the same telemetry cycle by cycle, and leaves the servos in
//! the same state (where they hold, whether their torque is on).

use crate::common;

use common::Tapped;

use std::sync::mpsc;

use servobus_driver::Bus;
use servobus_protocol::registers::addr;
use servobus_protocol::{parse_frame, Instruction, StatusFlags};
use servobus_runtime::config::Robot;
use servobus_runtime::{
    spawn, Command, FaultKind, FaultPolicy, Finish, Lead, Reaction, Report, RunOptions, Telemetry,
    VirtualRun,
};
use servobus_sim::SimBus;
use servobus_trajectory::Trajectory;

type Action = fn(&SimBus);

/// What a simulated bus does to itself just before the goals of a given
/// cycle go out (the bus's own frame count, so both runners inject at the
/// same point of the same cycle); it can hold the first cycle back until
/// the test has sent its commands.
struct Scripted {
    goal_frames: u64,
    inject: Option<(u64, Action)>,
    gate: Option<mpsc::Receiver<()>>,
}

/// Start-up sends one goal frame; cycle `k` sends frame `k + 2`.
const STARTUP_GOAL_FRAMES: u64 = 1;

impl Scripted {
    /// Sees the frame `bytes` about to be written to `sim`.
    fn on_write(&mut self, sim: &SimBus, bytes: &[u8]) {
        let goals = parse_frame(bytes).is_ok_and(|(p, _)| {
            p.instruction() == Some(Instruction::SyncWrite)
                && p.params().first() == Some(&addr::GOAL_POSITION)
        });
        if !goals {
            return;
        }
        self.goal_frames += 1;
        let cycle = self.goal_frames.checked_sub(STARTUP_GOAL_FRAMES + 1);
        if cycle == Some(0) {
            if let Some(gate) = self.gate.take() {
                // A closed gate (the test gone) opens it too.
                let _ = gate.recv();
            }
        }
        if let Some((at, action)) = self.inject {
            if cycle == Some(at) {
                action(sim);
                self.inject = None;
            }
        }
    }
}

/// A run to play twice.
struct Scenario {
    motion: &'static str,
    robot: Option<&'static str>,
    policy: FaultPolicy,
    lead: Lead,
    /// Bus, cycle and what to do to the bus then.
    inject: Option<(usize, u64, Action)>,
    /// Commands, each stamped with its cycle.
    commands: Vec<(u64, Command)>,
}

impl Scenario {
    fn arm() -> Self {
        Scenario {
            motion: "motions/arm-wave.yaml",
            robot: None,
            policy: FaultPolicy::default(),
            lead: Lead::default(),
            inject: None,
            commands: Vec::new(),
        }
    }

    /// The arm with `action` done to its bus just before cycle `at`.
    fn arm_with(at: u64, action: Action) -> Self {
        Scenario {
            inject: Some((0, at, action)),
            ..Scenario::arm()
        }
    }

    fn load(&self) -> (Trajectory, Robot) {
        common::planned(self.motion, self.robot)
    }

    /// The scenario's buses (the servos at the path's start), their
    /// simulators, and the gate that holds back cycle 0.
    #[allow(clippy::type_complexity)]
    fn buses(
        &self,
        robot: &Robot,
        path: &Trajectory,
    ) -> (Vec<Bus<Tapped>>, Vec<SimBus>, mpsc::Sender<()>) {
        let (buses, sims) = common::sim_buses_at(robot, path);
        let (open, gate) = mpsc::channel();
        let mut gate = Some(gate);
        let buses = buses
            .into_iter()
            .zip(&sims)
            .enumerate()
            .map(|(i, (b, sim))| {
                let settings = *b.settings();
                let mut script = Scripted {
                    goal_frames: 0,
                    inject: self.inject.filter(|s| s.0 == i).map(|s| (s.1, s.2)),
                    gate: if i == 0 { gate.take() } else { None },
                };
                let t = Tapped::new(sim.clone(), move |sim, bytes| script.on_write(sim, bytes));
                Bus::new(t, settings)
            })
            .collect();
        (buses, sims, open)
    }

    fn options(&self) -> RunOptions {
        RunOptions {
            faults: self.policy,
            lead: self.lead,
            autoplay: self.commands.is_empty(),
            // Room for every sample of the run: nothing is dropped, in
            // either runner, whenever the test reads.
            telemetry_capacity: 8192,
            ..RunOptions::default()
        }
    }
}

/// A servo at the end: its ID, and its goal, position (ticks) and torque.
type ServoState = (u8, Option<(i32, i32, bool)>);

/// What a run left: its report, its telemetry in a canonical order, and
/// every servo's goal, position and torque at the end.
#[derive(Debug, PartialEq)]
struct Outcome {
    report: Report,
    rows: Vec<(u64, usize, usize, f64, Option<f64>)>,
    faults: Vec<servobus_runtime::Fault>,
    finished: Vec<Finish>,
    servos: Vec<ServoState>,
}

fn outcome(report: Report, telemetry: Vec<Telemetry>, sims: &[SimBus], robot: &Robot) -> Outcome {
    let mut o = Outcome {
        report,
        rows: Vec::new(),
        faults: Vec::new(),
        finished: Vec::new(),
        servos: Vec::new(),
    };
    for m in telemetry {
        match m {
            Telemetry::Cycle(c) => o.rows.extend(
                c.joints()
                    .iter()
                    .map(|j| (c.cycle, c.bus, j.joint, j.commanded, j.measured)),
            ),
            Telemetry::Fault(f) => o.faults.push(f),
            Telemetry::Finished(f) => o.finished.push(f),
            _ => {}
        }
    }
    // Bus threads interleave their samples: order them by cycle and joint.
    o.rows
        .sort_by(|a, b| (a.0, a.2).cmp(&(b.0, b.2)).then(a.3.total_cmp(&b.3)));
    for (b, sim) in robot.buses.iter().zip(sims) {
        for j in &b.joints {
            let state = sim.servo(j.id, |s| {
                (s.goal_position(), s.present_position(), s.torque_enabled())
            });
            o.servos.push((j.id, state));
        }
    }
    o
}

fn play_virtual(s: &Scenario) -> Outcome {
    let (path, robot) = s.load();
    let (buses, sims, open) = s.buses(&robot, &path);
    let run = VirtualRun::new(&robot, path, buses, s.options()).expect("starts");
    let tx = run.commands();
    for (at, c) in &s.commands {
        tx.send_at(*at, c.clone()).expect("room for the commands");
    }
    drop(tx);
    open.send(()).expect("the gate is there");
    let telemetry = run.telemetry();
    let report = run.run();
    outcome(report, telemetry.try_iter().collect(), &sims, &robot)
}

fn play_threaded(s: &Scenario) -> Outcome {
    let (path, robot) = s.load();
    let (buses, sims, open) = s.buses(&robot, &path);
    let runner = spawn(&robot, path, buses, s.options()).expect("starts");
    // Cycle 0 is held back until the commands are in, so that they are
    // received before their cycle however the threads are scheduled.
    for (at, c) in &s.commands {
        runner.send_at(*at, c.clone()).expect("running");
    }
    open.send(()).expect("the gate is there");
    let telemetry = runner.telemetry();
    let report = runner.join().expect("joins");
    outcome(report, telemetry.try_iter().collect(), &sims, &robot)
}

/// Plays `s` both ways and checks they agree; returns the outcome.
fn same_both_ways(s: &Scenario) -> Outcome {
    let v = play_virtual(s);
    let t = play_threaded(s);
    println!(
        "{:?} after {} cycles; fault: {:?}",
        v.report.finish, v.report.cycles, v.report.fault
    );
    assert_eq!(v.report.telemetry_dropped, 0);
    assert!(!v.rows.is_empty());
    assert_eq!(v.report, t.report);
    assert_eq!(v.faults, t.faults);
    assert_eq!(v.finished, t.finished);
    assert_eq!(v.servos, t.servos);
    // Last: the longest comparison, cycle by cycle.
    assert_eq!(v.rows.len(), t.rows.len());
    assert!(v.rows == t.rows, "the telemetry differs");
    v
}

const WRIST_FLEX_ID: u8 = 4;

/// The cycle at which wrist_flex (joint 3) of arm-wave moves fastest, at
/// 200 Hz.
fn fastest_wrist_cycle() -> u64 {
    let (path, _) = Scenario::arm().load();
    common::fastest_cycle(&path, 3, 0.005)
}

#[test]
fn a_vanished_servo_stops_the_arm_alike_in_both_runners() {
    let at = fastest_wrist_cycle();
    let o = same_both_ways(&Scenario::arm_with(at, |sim| {
        sim.servo(WRIST_FLEX_ID, |s| s.set_offline(true));
    }));
    let f = o.report.fault.expect("a fault");
    assert!(matches!(f.kind, FaultKind::Missing { cycles: 3, .. }));
    assert_eq!(
        (f.reaction, o.report.finish),
        (Reaction::Stop, Finish::Fault)
    );
    assert!(f.cycle >= at && f.cycle < at + 3);
}

#[test]
fn a_blocked_joint_is_held_alike_in_both_runners() {
    let at = fastest_wrist_cycle() - 10;
    let o = same_both_ways(&Scenario::arm_with(at, |sim| {
        sim.servo(WRIST_FLEX_ID, |s| s.set_blocked(true));
    }));
    let f = o.report.fault.expect("a fault");
    assert!(matches!(f.kind, FaultKind::Stall { cycles: 3, .. }));
    assert_eq!(f.reaction, Reaction::Hold);
    // Held where it stands, in both (the servo states are equal).
    let wrist = o.servos.iter().find(|s| s.0 == WRIST_FLEX_ID);
    let (goal, present, torque) = wrist.and_then(|s| s.1).expect("the servo");
    assert!((goal - present).abs() <= 1 && torque, "{goal} vs {present}");
}

#[test]
fn a_status_flag_stops_and_a_following_error_turns_torque_off_alike() {
    let at = fastest_wrist_cycle();
    let o = same_both_ways(&Scenario::arm_with(at, |sim| {
        sim.servo(2, |s| s.inject_status(StatusFlags::OVERHEAT));
    }));
    let f = o.report.fault.expect("a fault");
    assert_eq!((f.cycle, f.reaction), (at, Reaction::Stop));

    // Without lead the arm trails its path by more than 1.5 deg.
    let s = Scenario {
        policy: FaultPolicy {
            following_error: 1.5f64.to_radians(),
            on_following_error: Reaction::TorqueOff,
            stall_error: f64::INFINITY,
            ..FaultPolicy::default()
        },
        lead: Lead::None,
        ..Scenario::arm()
    };
    let o = same_both_ways(&s);
    let f = o.report.fault.expect("a fault");
    assert!(matches!(
        f.kind,
        FaultKind::FollowingError { cycles: 3, .. }
    ));
    assert!(o.servos.iter().all(|s| s.1.is_some_and(|st| !st.2)));
}

#[test]
fn commands_stamped_to_cycles_act_alike_in_both_runners() {
    let s = Scenario {
        commands: vec![
            (10, Command::Play),
            (200, Command::Pause),
            (800, Command::Resume),
            (1000, Command::Stop),
        ],
        ..Scenario::arm()
    };
    let o = same_both_ways(&s);
    assert_eq!(o.report.finish, Finish::Stopped);
    // Nothing moved before Play took effect; the pause held still.
    let wrist = |k: u64| {
        o.rows
            .iter()
            .find(|r| r.0 == k && r.2 == 3)
            .map(|r| r.3)
            .expect("a sample")
    };
    assert_eq!(wrist(0), wrist(9));
    assert_ne!(wrist(9), wrist(100));
    assert!((wrist(700) - wrist(790)).abs() < 1e-9);
}

#[test]
fn the_two_bus_hexapod_walks_alike_in_both_runners() {
    let s = Scenario {
        motion: "motions/hexapod-tripod.yaml",
        robot: Some("robots/hexapod-2bus.yaml"),
        ..Scenario::arm()
    };
    let o = same_both_ways(&s);
    assert_eq!(o.report.finish, Finish::Completed);
    assert_eq!(o.report.buses.len(), 2);
}
