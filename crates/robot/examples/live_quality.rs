//! How faithfully the live follower follows what users send, measured in
//! virtual time on the simulated SO-101: a table of overshoot beyond the
//! 0.5 s target envelope, lag, RMS error at that lag and RMS jerk of the
//! commanded pan, per input class (triangle wiggles with abrupt turns,
//! sine wiggles), target rate and limits (the servo model's, as `follow`
//! and the LeRobot plugin use, or the robot file's gentler ones).
//!
//! A measurement for working on the follower, not a test: run it before
//! and after a change and compare.
//!
//! ```text
//! cargo run --release -p servobus-robot --example live_quality
//! ```

use std::path::Path;

use servobus_robot::sim::SimRobot;
use servobus_runtime::config::{load_robot, Robot, RobotOptions};
use servobus_runtime::{Lead, LiveTarget, RunOptions, Telemetry, VirtualRun};

/// The loop's period, s (the SO-101's 200 Hz).
const PERIOD: f64 = 0.005;
/// Cycles run per case (4 s).
const CYCLES: u64 = 800;
/// Figures are taken from this time on, s: the inputs start at 0.2 s, and
/// a first move from rest (as a hand starts a wiggle) counts.
const FROM: f64 = 0.0;
/// The envelope window, s.
const WINDOW: f64 = 0.5;

/// One input class: its name and the pan's target at time t, deg.
struct Case {
    name: &'static str,
    source: fn(f64) -> f64,
}

fn triangle(t: f64, amplitude: f64, hz: f64) -> f64 {
    if t < 0.2 {
        return 0.0;
    }
    let p = ((t - 0.2) * hz).fract();
    let x = if p < 0.25 {
        4.0 * p
    } else if p < 0.75 {
        2.0 - 4.0 * p
    } else {
        4.0 * p - 4.0
    };
    amplitude * x
}

fn sine(t: f64, amplitude: f64, hz: f64) -> f64 {
    if t < 0.2 {
        0.0
    } else {
        amplitude * (2.0 * std::f64::consts::PI * hz * (t - 0.2)).sin()
    }
}

/// The hand's ease between keyframes (zero speed and acceleration at
/// each, as the simulator's scripted hand moves a leader arm).
fn ease(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)
}

/// Keyframes `(at, deg)` eased in turn; before the first, its position.
fn eased(t: f64, keys: &[(f64, f64)]) -> f64 {
    let mut last = keys[0];
    for &(at, q) in keys {
        if t < at {
            return last.1 + (q - last.1) * ease((t - last.0) / (at - last.0));
        }
        last = (at, q);
    }
    last.1
}

/// An eased wiggle between +-`amplitude`: from 0 at 0.2 s to the first
/// peak in a quarter period, then a peak every half period.
fn eased_wiggle(t: f64, amplitude: f64, hz: f64) -> f64 {
    let (start, half) = (0.2, 0.5 / hz);
    if t < start + 0.5 * half {
        return eased(t, &[(start, 0.0), (start + 0.5 * half, amplitude)]);
    }
    let k = ((t - start - 0.5 * half) / half).floor();
    let peak = |k: f64| {
        if k % 2.0 == 0.0 {
            amplitude
        } else {
            -amplitude
        }
    };
    let s = (t - start - 0.5 * half - k * half) / half;
    peak(k) + (peak(k + 1.0) - peak(k)) * ease(s)
}

const CASES: [Case; 8] = [
    Case {
        name: "flick 50 deg out and back",
        source: |t| eased(t, &[(0.2, 0.0), (0.35, 50.0), (0.5, 0.0)]),
    },
    Case {
        name: "eased 12 deg at 2 Hz",
        source: |t| eased_wiggle(t, 12.0, 2.0),
    },
    Case {
        name: "eased 20 deg at 1 Hz",
        source: |t| eased_wiggle(t, 20.0, 1.0),
    },
    Case {
        name: "swing -100/+100 deg",
        source: |t| {
            eased(
                t,
                &[
                    (0.2, 0.0),
                    (0.9, -100.0),
                    (1.2, -100.0),
                    (2.1, 100.0),
                    (2.4, 100.0),
                    (3.1, 0.0),
                ],
            )
        },
    },
    Case {
        name: "triangle 12 deg at 2 Hz",
        source: |t| triangle(t, 12.0, 2.0),
    },
    Case {
        name: "triangle 20 deg at 1 Hz",
        source: |t| triangle(t, 20.0, 1.0),
    },
    Case {
        name: "sine 20 deg at 1 Hz",
        source: |t| sine(t, 20.0, 1.0),
    },
    Case {
        name: "sine 20 deg at 0.5 Hz",
        source: |t| sine(t, 20.0, 0.5),
    },
];

/// How a sender's targets are timed.
#[derive(Clone, Copy)]
enum Timing {
    /// Sampled and stamped at each slot's time.
    Exact,
    /// As a Python loop such as LeRobot's sends them: each slot's read
    /// takes 1-7 ms (pseudo-random), the positions are those of the read's
    /// middle and the stamp is taken when the read is done.
    Python,
    /// As `servobus follow` reads a leader arm: each slot's read takes
    /// 1.5-3 ms, one in 20 a stall of 10-40 ms (a loaded machine), after
    /// which the loop starts its next slot at once on a moved schedule;
    /// one read in 30 misses and sends nothing.
    Leader,
}

/// A pseudo-random number in [0, 1) for slot `k` and stream `salt`.
fn unit(k: u32, salt: u64) -> f64 {
    let mut x = (u64::from(k) ^ salt.wrapping_mul(0xA24B_AED4_963E_E407))
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ 0xD1B5_4A32_D192_ED03;
    x ^= x >> 29;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 32;
    (x % 1_000_000) as f64 / 1e6
}

/// The reads of [`Timing::Leader`] at `hz` over `seconds`: (sample time,
/// stamp), the missed ones left out.
fn leader_reads(hz: f64, seconds: f64) -> Vec<(f64, f64)> {
    let period = 1.0 / hz;
    let (mut t, mut k, mut out) = (period, 0u32, Vec::new());
    while t < seconds && k < 1_000_000 {
        k += 1;
        let mut read = 0.0015 + 0.0015 * unit(k, 1);
        if unit(k, 2) < 0.05 {
            read += 0.010 + 0.030 * unit(k, 3);
        }
        if unit(k, 4) >= 1.0 / 30.0 {
            out.push((t + 0.5 * read, t + read));
        }
        t = (t + period).max(t + read + 0.0002);
    }
    out
}

/// The targets sent: (arrival time, deg).
type Sent = Vec<(f64, f64)>;

/// The read time of slot `k` in [`Timing::Python`], s.
fn read_time(k: u32) -> f64 {
    let mut x = u64::from(k).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
    x ^= x >> 29;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 32;
    0.001 + 0.006 * (x % 1000) as f64 / 1000.0
}

/// The commanded pan (the robot file's units: degrees), one per cycle,
/// following `source` sent at `hz` and timed by `timing`, and the targets
/// sent: (arrival time, deg).
fn follow(
    robot: &Robot,
    hz: f64,
    source: fn(f64) -> f64,
    timing: Timing,
) -> Result<(Vec<f64>, Sent), String> {
    let sim = SimRobot::builder(robot)
        .build()
        .map_err(|e| e.to_string())?;
    let options = RunOptions {
        lead: Lead::None,
        approach: None,
        ..RunOptions::default()
    };
    let mut run =
        VirtualRun::live(robot, sim.driver_buses(), options).map_err(|e| e.to_string())?;
    let tx = run.targets();
    let telemetry = run.telemetry();
    let mut pan = Vec::new();
    let mut sent = Vec::new();
    let mut slot = 1u32;
    let reads = leader_reads(hz, CYCLES as f64 * PERIOD + 1.0);
    for _ in 0..CYCLES {
        let now = run.cycle() as f64 * PERIOD;
        loop {
            let s = f64::from(slot) / hz;
            let (sample, stamp) = match timing {
                Timing::Exact => (s, s),
                Timing::Python => (s + 0.5 * read_time(slot), s + read_time(slot)),
                Timing::Leader => match reads.get(slot as usize - 1) {
                    Some(&r) => r,
                    None => break,
                },
            };
            if stamp > now + 1e-9 {
                break;
            }
            let q = source(sample);
            tx.send(LiveTarget::named(
                stamp,
                vec![("shoulder_pan".into(), q.to_radians())],
            ))
            .map_err(|e| e.to_string())?;
            sent.push((now, q));
            slot += 1;
        }
        let going = run.step();
        while let Ok(m) = telemetry.try_recv() {
            if let Telemetry::Cycle(c) = m {
                if let Some(j) = c.joints().iter().find(|j| j.joint == 0) {
                    pan.push(j.commanded);
                }
            }
        }
        if !going {
            break;
        }
    }
    Ok((pan, sent))
}

/// Overshoot beyond the envelope of the targets sent in the last
/// [`WINDOW`], best lag, RMS error at it, RMS jerk (k deg/s^3).
fn figures(pan: &[f64], sent: &[(f64, f64)], source: fn(f64) -> f64) -> (f64, f64, f64, f64) {
    let mut over = 0.0f64;
    for (k, &q) in pan.iter().enumerate() {
        let t = k as f64 * PERIOD;
        if t < FROM {
            continue;
        }
        // The targets sent in the window, and the one in force at its start.
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let in_force = sent.iter().rev().find(|(at, _)| *at <= t - WINDOW);
        let recent = sent.iter().filter(|(at, _)| *at > t - WINDOW && *at <= t);
        for &(_, v) in in_force.into_iter().chain(recent) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if lo > hi {
            lo = 0.0;
            hi = 0.0;
        }
        over = over.max(q - hi).max(lo - q);
    }
    let rms = |lag: f64| {
        let (mut sum, mut n) = (0.0, 0.0);
        for (k, &q) in pan.iter().enumerate() {
            let t = k as f64 * PERIOD;
            if t >= FROM {
                let e = q - source(t - lag);
                sum += e * e;
                n += 1.0;
            }
        }
        (sum / f64::max(n, 1.0)).sqrt()
    };
    let lag = (0..300)
        .map(|ms| f64::from(ms) * 1e-3)
        .min_by(|a, b| rms(*a).total_cmp(&rms(*b)))
        .unwrap_or(0.0);
    let from = (FROM / PERIOD) as usize;
    let (mut sum, mut n) = (0.0, 0.0);
    for w in pan.get(from..).unwrap_or(&[]).windows(4) {
        let j = (w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0]) / PERIOD.powi(3);
        sum += j * j;
        n += 1.0;
    }
    (over, lag, rms(lag), (sum / f64::max(n, 1.0)).sqrt() / 1e3)
}

fn main() -> Result<(), String> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/robots/so101.yaml");
    let gentle = load_robot(&file, &RobotOptions::default()).map_err(|e| e.to_string())?;
    let model = gentle.clone().with_model_limits();
    println!(
        "{:<26}{:>6}{:>8}{:>8}{:>8}{:>8}{:>10}",
        "input (pan)", "Hz", "limits", "over", "lag ms", "rms", "jerk k/s3"
    );
    for case in &CASES {
        for (hz, limits, robot, timing) in [
            (50.0, "model", &model, Timing::Exact),
            (30.0, "model", &model, Timing::Exact),
            (30.0, "python", &model, Timing::Python),
            (50.0, "leader", &model, Timing::Leader),
            (30.0, "file", &gentle, Timing::Exact),
        ] {
            let (pan, sent) = follow(robot, hz, case.source, timing)?;
            let (over, lag, rms, jerk) = figures(&pan, &sent, case.source);
            println!(
                "{:<26}{hz:>6.0}{limits:>8}{over:>8.1}{:>8.0}{rms:>8.2}{jerk:>10.0}",
                case.name,
                lag * 1e3
            );
        }
    }
    Ok(())
}
