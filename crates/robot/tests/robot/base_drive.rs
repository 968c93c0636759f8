//! The shipped `lekiwi` (an SO-101 arm on three omni wheels) driven as a
//! mobile base by live base velocities at 30 Hz, as a keyboard teleop or a
//! policy sends them, in virtual time on the simulator. The odometry from
//! the wheels' measured speeds is compared with the simulator's truth (the
//! pose integrated from the wheels' true turns), and the wheels' commanded
//! speeds with their limits.

use crate::common;

use common::robot;
use servobus_robot::config::{BaseTarget, Robot};
use servobus_robot::odometry::{truth_poses, Odometer, Odometry};
use servobus_robot::sim::{new_truth, SimRobot};
use servobus_runtime::{Command, Lead, LiveTarget, RunOptions, Telemetry, VirtualRun};
use servobus_sim::Truth;

const PERIOD: f64 = 0.005;

/// A base velocity held from `from` s to `to` s.
struct Leg {
    from: f64,
    to: f64,
    target: BaseTarget,
}

/// What a drive gave: the odometry's pose at the end, the truth's poses
/// (every 10 ms), and per wheel the commanded speeds of every cycle
/// (deg/s).
struct Drive {
    odometry: Odometry,
    truth: Vec<Odometry>,
    commanded: Vec<Vec<f64>>,
}

fn options() -> RunOptions {
    RunOptions {
        lead: Lead::None,
        approach: None,
        ..RunOptions::default()
    }
}

/// Drives `robot`'s base through `legs` (targets sent at 30 Hz while a leg
/// lasts, a zero velocity between legs until `stop_sending` s, then none)
/// for `seconds`, then stops the run.
fn drive(robot: &Robot, legs: &[Leg], stop_sending: f64, seconds: f64) -> Drive {
    let truth = new_truth(robot);
    let sim = SimRobot::builder(robot)
        .truth(&truth)
        .build()
        .expect("the robot simulates");
    let mut run = VirtualRun::live(robot, sim.driver_buses(), options()).expect("a live run");
    let (tx, telemetry) = (run.targets(), run.telemetry());
    let mut odometer = Odometer::of(robot, robot.units).expect("lekiwi has a base");
    let wheels: Vec<usize> = robot.base.as_ref().expect("a base").wheels().to_vec();
    let mut commanded = vec![Vec::new(); wheels.len()];
    let mut slot = 1u32;
    let cycles = (seconds / PERIOD) as u64;
    while run.cycle() < cycles {
        let now = run.cycle() as f64 * PERIOD;
        while f64::from(slot) / 30.0 <= now {
            let s = f64::from(slot) / 30.0;
            slot += 1;
            let target = match legs.iter().find(|l| l.from <= s && s < l.to) {
                Some(leg) => Some(leg.target),
                // Between legs the sender stops the base (keys let go);
                // after the last it sends nothing (a lost stream) unless
                // told to stop.
                None if s < stop_sending => Some(base(0.0, 0.0, 0.0)),
                None => None,
            };
            if let Some(target) = target {
                let speeds = robot.wheel_targets(&target).expect("a base velocity");
                tx.send(LiveTarget::named(s, speeds.wheels))
                    .expect("a good target");
            }
        }
        assert!(run.step(), "the run goes on");
        take(&telemetry, &mut odometer, &wheels, &mut commanded);
    }
    run.commands().send(Command::Stop).expect("the run listens");
    while run.step() {
        take(&telemetry, &mut odometer, &wheels, &mut commanded);
    }
    sim.settle();
    Drive {
        odometry: odometer.pose(),
        truth: poses(robot, &truth),
        commanded,
    }
}

fn take(
    telemetry: &crossbeam_channel::Receiver<Telemetry>,
    odometer: &mut Odometer,
    wheels: &[usize],
    commanded: &mut [Vec<f64>],
) {
    while let Ok(m) = telemetry.try_recv() {
        if let Telemetry::Cycle(c) = m {
            odometer.take(&c);
            for j in c.joints() {
                if let Some(w) = wheels.iter().position(|&i| i == j.joint) {
                    commanded[w].push(j.commanded);
                }
            }
        }
    }
}

fn poses(robot: &Robot, truth: &Truth) -> Vec<Odometry> {
    truth_poses(robot, &truth.names(), &truth.rows()).expect("every wheel in the truth")
}

/// Every wheel's commanded speed within its `max_velocity` and changing
/// by no more than its `max_acceleration` allows in a cycle.
fn within_limits(robot: &Robot, commanded: &[Vec<f64>]) {
    let joints: Vec<_> = robot.joints().collect();
    for (&w, speeds) in robot
        .base
        .as_ref()
        .expect("a base")
        .wheels()
        .iter()
        .zip(commanded)
    {
        let j = joints[w];
        assert!(!speeds.is_empty(), "no telemetry of {}", j.name);
        let top = speeds.iter().fold(0.0f64, |a, s| a.max(s.abs()));
        assert!(top <= j.max_velocity + 1e-9, "{}: {top}", j.name);
        for p in speeds.windows(2) {
            let a = (p[1] - p[0]).abs() / PERIOD;
            assert!(a <= j.max_acceleration * (1.0 + 1e-9), "{}: {a}", j.name);
        }
    }
}

fn base(x: f64, y: f64, theta: f64) -> BaseTarget {
    BaseTarget { x, y, theta }
}

#[test]
fn a_square_driven_by_stream_ends_where_the_truth_does_and_no_wheel_exceeds_its_limits() {
    let robot = robot("lekiwi.yaml");
    // 1 m forward, 1 m to the left, a quarter turn in place; a second's
    // rest between (a zero velocity sent).
    let legs = [
        Leg {
            from: 0.0,
            to: 5.0,
            target: base(0.2, 0.0, 0.0),
        },
        Leg {
            from: 6.0,
            to: 11.0,
            target: base(0.0, 0.2, 0.0),
        },
        Leg {
            from: 12.0,
            to: 14.0,
            target: base(0.0, 0.0, 45.0),
        },
    ];
    let d = drive(&robot, &legs, 15.0, 15.0);
    let truth = *d.truth.last().expect("a truth");
    let (o, t) = (d.odometry, truth);
    println!(
        "odometry x {:.4} m y {:.4} m theta {:.2} deg; truth x {:.4} m y {:.4} m theta {:.2} deg",
        o.x_m,
        o.y_m,
        o.theta_rad.to_degrees(),
        t.x_m,
        t.y_m,
        t.theta_rad.to_degrees()
    );
    // The base went where it was told: 1 m, 1 m and 90 degrees (the ramp
    // into each leg loses what the ramp out of it gains), within 2 %.
    assert!((t.x_m - 1.0).abs() < 0.02, "{t:?}");
    assert!((t.y_m - 1.0).abs() < 0.02, "{t:?}");
    assert!((t.theta_rad.to_degrees() - 90.0).abs() < 1.8, "{t:?}");
    // The odometry within 2 % of the truth: of the 2 m driven, and of the
    // turn.
    let off = (o.x_m - t.x_m).hypot(o.y_m - t.y_m);
    assert!(off <= 0.02 * 2.0, "{off} m off");
    let turn = (o.theta_rad - t.theta_rad).to_degrees().abs();
    assert!(turn <= 0.02 * 90.0, "{turn} deg off");
    within_limits(&robot, &d.commanded);
}

#[test]
fn a_lost_stream_stops_the_base_ramped_within_what_its_acceleration_allows() {
    let robot = robot("lekiwi.yaml");
    let v = 0.25;
    let legs = [Leg {
        from: 0.0,
        to: 2.0,
        target: base(v, 0.0, 0.0),
    }];
    let d = drive(&robot, &legs, 0.0, 4.0);
    // The last target was sent at 2 s less one slot; from there the base
    // runs on until the target timeout (0.25 s), then brakes at the wheels'
    // acceleration: the slowest of them sets the base's.
    let last = ((2.0 * 30.0f64).ceil() - 1.0) / 30.0;
    let timeout = options().target_timeout.as_secs_f64();
    let joints: Vec<_> = robot.joints().collect();
    let wheels = robot.base.as_ref().expect("a base").wheels();
    let speeds = robot.wheel_targets(&base(v, 0.0, 0.0)).expect("a velocity");
    // Braking time: the wheel whose speed takes longest to ramp to 0.
    let brake = speeds
        .wheels
        .iter()
        .zip(wheels)
        .map(|((_, s), &w)| s.abs() / joints[w].max_acceleration.to_radians())
        .fold(0.0f64, f64::max);
    let allowed = v * (timeout + 0.5 * brake + 2.0 * PERIOD);
    // What the commands drove: the base's x from the commanded wheel
    // speeds, from the cycle of the last target on.
    let base_of = robot.base.as_ref().expect("a base");
    let from = (last / PERIOD).round() as usize;
    let commanded_run_on: f64 = (from..d.commanded[0].len())
        .map(|k| {
            let w: Vec<f64> = d.commanded.iter().map(|c| c[k].to_radians()).collect();
            base_of.twist(&w).expect("finite speeds").x * PERIOD
        })
        .sum();
    let at = |t: f64| d.truth[(t / 0.01).round() as usize];
    let (stopped_from, end) = (at(last), at(3.9));
    let run_on = end.x_m - stopped_from.x_m;
    println!(
        "ran on {run_on:.3} m after the last target, commanded {commanded_run_on:.3} m \
         (allowed {allowed:.3} m)"
    );
    assert!(
        commanded_run_on > v * timeout * 0.9,
        "it stopped before the timeout: {commanded_run_on}"
    );
    assert!(
        commanded_run_on <= allowed,
        "{commanded_run_on} m > {allowed} m"
    );
    // The shafts follow their commanded speeds a little behind (the
    // simulated motor's response, some 50 ms): the base itself runs on
    // by no more than 0.1 s of its speed more.
    assert!(
        run_on <= commanded_run_on + v * 0.1,
        "{run_on} m, commanded {commanded_run_on} m"
    );
    // At rest well before the end, and commanded to rest.
    let still = at(3.5);
    assert!((end.x_m - still.x_m).abs() < 1e-3, "{still:?} {end:?}");
    for c in &d.commanded {
        assert_eq!(c.last().copied(), Some(0.0));
    }
    within_limits(&robot, &d.commanded);
}
