//! No goal outside the joint limits is ever sent, over random motions
//! (replacement paths planned without position limits, so that they leave
//! the joint limits) and random faults: every SYNC WRITE frame on the wire
//! is decoded and checked.

use crate::common;

use common::Tapped;

use std::sync::{Arc, Mutex};

use proptest::prelude::*;
use servobus_driver::Bus;
use servobus_protocol::{parse_frame, registers::addr, Instruction};
use servobus_runtime::config::joint_limits;
use servobus_runtime::{Command, FaultPolicy, RunOptions, VirtualRun};
use servobus_sim::Faults;
use servobus_trajectory::{plan, JointLimits, Keyframe, PlanOptions};

/// Decodes every goal position in `bytes` (a SYNC WRITE of the goals)
/// into `goals`.
fn decode_goals(bytes: &[u8], goals: &Mutex<Vec<(u8, i32)>>) {
    if let Ok((p, _)) = parse_frame(bytes) {
        let params = p.params();
        if p.instruction() == Some(Instruction::SyncWrite)
            && params.first() == Some(&addr::GOAL_POSITION)
            && params.get(1) == Some(&2)
        {
            let mut g = goals.lock().unwrap_or_else(|e| e.into_inner());
            for item in params[2..].chunks_exact(3) {
                g.push((item[0], i32::from(u16::from_le_bytes([item[1], item[2]]))));
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn no_goal_outside_the_limits(
        poses in prop::collection::vec(prop::collection::vec(-1.3f64..1.3, 6), 2..5),
        replace_at in 20u64..300,
        stop_at in prop::option::of(100u64..600),
        drop in 0.0f64..0.2,
        corrupt in 0.0f64..0.1,
        block in prop::option::of(1u8..=6),
        seed in any::<u64>(),
    ) {
        let (path, robot) = common::motion("arm-wave.yaml");
        let (buses, sims) = common::sim_buses_at(&robot, &path);
        let goals = Arc::new(Mutex::new(Vec::new()));
        let buses: Vec<Bus<Tapped>> = buses
            .into_iter()
            .zip(&sims)
            .map(|(b, sim)| {
                let settings = *b.settings();
                let goals = Arc::clone(&goals);
                let t = Tapped::new(sim.clone(), move |_, bytes| decode_goals(bytes, &goals));
                Bus::new(t, settings)
            })
            .collect();
        // Random poses scaled beyond the joint limits (joint ranges are
        // about +-1.7 rad; poses reach +-1.3 rad around a random middle),
        // planned with the velocity limits but without position limits.
        let limits: Vec<JointLimits> = joint_limits(&robot)
            .into_iter()
            .map(|l| JointLimits::new(l.max_velocity, l.max_acceleration, l.max_jerk))
            .collect();
        let mut keyframes = vec![Keyframe::new(vec![0.0; 6])];
        for p in &poses {
            keyframes.push(Keyframe::new(p.iter().map(|x| x * 1.6).collect::<Vec<_>>()));
        }
        let wild = plan(&limits, &keyframes, &PlanOptions::default()).expect("plans");
        let options = RunOptions {
            faults: FaultPolicy::default(),
            telemetry_capacity: 0,
            ..RunOptions::default()
        };
        let mut run = VirtualRun::new(&robot, path, buses, options).expect("starts");
        // Faults from the first cycle on: start-up (which gives up on a
        // servo silent three times) is not what this property is about.
        sims[0].set_faults(Faults::seeded(seed).drop(drop).corrupt(corrupt));
        if let Some(id) = block {
            sims[0].servo(id, |s| s.set_blocked(true));
        }
        let tx = run.commands();
        let mut replacement = Some(Command::replace(wild));
        for _ in 0..3_000 {
            let k = run.cycle();
            if k == replace_at {
                if let Some(c) = replacement.take() {
                    let _ = tx.try_send(c);
                }
            }
            if Some(k) == stop_at {
                let _ = tx.try_send(Command::Stop);
            }
            if !run.step() {
                break;
            }
        }
        // Each joint's tick range by hand, from the robot file and the
        // mapping the file documents: the servo's angle is offset + position
        // (offset - position when inverted), in degrees from the middle
        // tick 2048 of an STS3215's 4096 ticks a turn; ticks inside the
        // limits round inwards.
        let ranges: Vec<(u8, f64, f64)> = robot
            .joints()
            .map(|j| {
                assert_eq!(j.model.name, "STS3215");
                let sign = if j.inverted { -1.0 } else { 1.0 };
                let tick = |deg: f64| 2048.0 + (j.offset + sign * deg) * 4096.0 / 360.0;
                let (a, b) = (tick(j.min), tick(j.max));
                (j.id, a.min(b).ceil(), a.max(b).floor())
            })
            .collect();
        let goals = goals.lock().unwrap_or_else(|e| e.into_inner());
        prop_assert!(!goals.is_empty());
        for &(id, tick) in goals.iter() {
            let &(_, lo, hi) = ranges.iter().find(|m| m.0 == id).expect("a joint of the arm");
            prop_assert!(f64::from(tick) >= lo && f64::from(tick) <= hi,
                "servo {id}: tick {tick} outside [{lo}, {hi}]");
        }
    }
}
