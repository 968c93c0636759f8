//! Benches of servobus-trajectory: sampling 18 joints (target <= 100 ns),
//! planning 18 joints x 100 untimed keyframes (<= 1 ms), the same keyframes
//! timed (with room to spare, and too close together so that most segments
//! are stretched), retargeting 18 joints from a moving state (<= 30 us),
//! one cycle of following a new goal for 18 joints (<= 2 us).

use criterion::{black_box, Criterion};
use servobus_trajectory::{
    follow_steps, plan, retarget, stop, Follower, Goal, JointLimits, JointState, Keyframe, OnLimit,
    PlanOptions,
};

const JOINTS: usize = 18;

/// Hexapod-like limits (rad): 18 joints, jerk limited.
fn limits() -> Vec<JointLimits> {
    (0..JOINTS)
        .map(|j| {
            JointLimits::new(
                4.0 + (j % 3) as f64,
                20.0 + (j % 4) as f64 * 5.0,
                Some(300.0),
            )
            .with_positions(-2.0, 2.0)
        })
        .collect()
}

/// A deterministic pseudo-random choreography: smooth sweeps with turns.
fn keyframes(n: usize) -> Vec<Keyframe> {
    (0..n)
        .map(|k| {
            Keyframe::new(
                (0..JOINTS)
                    .map(|j| 1.5 * ((k as f64) * (0.45 + 0.05 * j as f64) + j as f64).sin())
                    .collect::<Vec<_>>(),
            )
        })
        .collect()
}

/// Registers the benches of this module.
pub fn benches(c: &mut Criterion) {
    let limits = limits();
    let kfs = keyframes(100);
    let options = PlanOptions::default();

    c.bench_function("trajectory/plan_18x100", |b| {
        b.iter(|| plan(black_box(&limits), black_box(&kfs), &options).map(|t| t.duration()))
    });

    // Timed: 1 s apart (every segment fits); tight: 50 ms apart, most
    // segments too short and lengthened (`on_limit: stretch`).
    let timed = |spacing: f64| -> Vec<Keyframe> {
        let later = kfs.iter().enumerate().skip(1);
        let timed = later.map(|(k, f)| f.clone().at(spacing * k as f64));
        kfs.iter().take(1).cloned().chain(timed).collect()
    };
    let (spaced, tight) = (timed(1.0), timed(0.05));
    c.bench_function("trajectory/plan_timed_18x100", |b| {
        b.iter(|| plan(black_box(&limits), black_box(&spaced), &options).map(|t| t.duration()))
    });
    let stretch = PlanOptions {
        on_limit: OnLimit::Stretch,
        ..PlanOptions::default()
    };
    c.bench_function("trajectory/plan_stretch_18x100", |b| {
        b.iter(|| plan(black_box(&limits), black_box(&tight), &stretch).map(|t| t.duration()))
    });

    let traj = match plan(&limits, &kfs, &options) {
        Ok(t) => t,
        Err(e) => panic!("bench choreography does not plan: {e}"),
    };
    let mut cursor = traj.cursor();
    let mut out = [JointState::default(); JOINTS];
    // A 1 kHz control loop: one sample per call, time moving forward and
    // wrapping at the end.
    let mut t = 0.0;
    c.bench_function("trajectory/sample_18", |b| {
        b.iter(|| {
            traj.sample_with(&mut cursor, black_box(t), &mut out);
            t += 0.001;
            if t > traj.duration() {
                t = 0.0;
            }
            out[0].position
        })
    });

    // Retarget from a moving state: the middle of the choreography.
    let mut state = [JointState::default(); JOINTS];
    traj.sample(traj.duration() * 0.37, &mut state);
    let target = &kfs[10].positions;
    c.bench_function("trajectory/retarget_18", |b| {
        b.iter(|| {
            retarget(black_box(&limits), black_box(&state), black_box(target)).map(|t| t.duration())
        })
    });
    // One cycle of following for 18 joints, each with a new goal (the
    // costly case: every joint plans anew from a moving state).
    let mut followers: Vec<Follower> = state.iter().map(|s| Follower::new(*s)).collect();
    let mut flip = 1.0;
    c.bench_function("trajectory/follow_step_18", |b| {
        b.iter(|| {
            flip = -flip;
            let goals: [Goal; JOINTS] = std::array::from_fn(|j| Goal {
                position: target[j] + 0.01 * flip,
                velocity: 0.1 * flip,
                acceleration: 0.5 * flip,
                horizon: 0.033,
            });
            follow_steps(black_box(&limits), &mut followers, black_box(&goals), 0.005);
            followers[0].state().position
        })
    });
    // The same cycle as the live loop runs it: each step kept within the
    // places its reference was told to go (here tight enough that the
    // bound steps in and the blend is searched, the costly case).
    let mut bounded: Vec<Follower> = state.iter().map(|s| Follower::new(*s)).collect();
    let mut flip = 1.0;
    c.bench_function("trajectory/follow_within_18", |b| {
        b.iter(|| {
            flip = -flip;
            for ((f, lim), t) in bounded.iter_mut().zip(&limits).zip(target.iter()) {
                let goal = Goal {
                    position: t + 0.01 * flip,
                    velocity: 0.1 * flip,
                    acceleration: 0.5 * flip,
                    horizon: 0.033,
                };
                let here = f.state().position;
                f.step_within(
                    lim,
                    black_box(goal),
                    0.005,
                    (here - 1e-4, here + 1e-4),
                    (f64::NEG_INFINITY, f64::INFINITY),
                );
            }
            bounded[0].state().position
        })
    });
    // The same cycle with the goal held (the plan is kept): most cycles of
    // a 30 Hz stream followed at 200 Hz.
    let goals: [Goal; JOINTS] = std::array::from_fn(|j| Goal {
        position: target[j],
        velocity: 0.0,
        acceleration: 0.0,
        horizon: 0.033,
    });
    let mut held: Vec<Follower> = state.iter().map(|s| Follower::new(*s)).collect();
    c.bench_function("trajectory/follow_hold_18", |b| {
        b.iter(|| {
            follow_steps(black_box(&limits), &mut held, black_box(&goals), 1e-9);
            held[0].state().position
        })
    });
    c.bench_function("trajectory/stop_18", |b| {
        b.iter(|| stop(black_box(&limits), black_box(&state)).map(|t| t.duration()))
    });
}
