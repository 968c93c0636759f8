//! Lag compensation: commanding the path ahead by the servos' lag cuts the
//! tracking error of the simulated arm.
//!
//! Measured on `arm-wave.yaml` (200 Hz, six STS3215 in the simulator,
//! whose servos trail their goal by a 10 ms first-order lag plus their own
//! motion profile): mean RMS error over the joints 0.715 deg without lead,
//! 0.066 deg with the lead identified while the arm moves (14.45 ms,
//! starting from the servo model's prior: its 10 ms response lag plus half
//! the 5 ms cycle), and 0.063 deg with that lead fixed from the start; worst
//! maximum error 3.66 / 0.32 / 0.21 deg. Without the prior (no lead until
//! the first estimate) the first second cost 0.46 deg. Starting at the
//! path's first keyframe (no approach), the auto lead is refined during the
//! first moves: mean RMS 0.078 deg (0.071 deg with the final lead fixed from
//! the start).

use crate::common;

use std::time::Duration;

use servobus_runtime::{Finish, Lead, Report, RunOptions, VirtualRun};

fn play(lead: Lead) -> Report {
    play_from(lead, false)
}

/// Plays the arm wave with the servos at rest wherever the simulator puts
/// them (an approach comes first), or already at the path's start.
fn play_from(lead: Lead, at_start: bool) -> Report {
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, _) = if at_start {
        common::sim_buses_at(&robot, &path)
    } else {
        common::sim_buses(&robot)
    };
    let options = RunOptions {
        lead,
        telemetry_capacity: 0,
        ..RunOptions::default()
    };
    let r = VirtualRun::new(&robot, path, buses, options)
        .expect("starts")
        .run();
    assert_eq!(r.finish, Finish::Completed);
    r
}

fn mean_rms(r: &Report) -> f64 {
    r.joints.iter().map(|j| j.rms_error).sum::<f64>() / r.joints.len() as f64
}

#[test]
fn the_lead_cuts_the_rms_tracking_error_of_the_arm_wave() {
    let none = play(Lead::None);
    let auto = play(Lead::default());
    let fixed = play(Lead::Fixed(Duration::from_secs_f64(auto.lead_ms / 1e3)));
    for (name, r) in [("no lead", &none), ("auto", &auto), ("fixed", &fixed)] {
        println!(
            "{name:8} lead {:5.2} ms: mean RMS {:.3} deg, worst RMS {:.3} deg, worst max {:.3} deg",
            r.lead_ms,
            mean_rms(r),
            r.worst_rms_error(),
            r.worst_max_error()
        );
        for j in &r.joints {
            println!(
                "    {:14} rms {:.3} max {:.3}",
                j.name, j.rms_error, j.max_error
            );
        }
    }
    // The identified lag, by hand: the simulated servo's first-order lag
    // (10 ms: a ramp trails by exactly its time constant), plus the goals
    // held for a 5 ms cycle (on average half of it, 2.5 ms), plus at most
    // the rest of the cycle and the cycle's 1180 us on the bus. So between
    // 10 + 2.5 = 12.5 and 10 + 5 + 1.18 = 16.18 ms (13.84 measured).
    assert!((12.5..16.18).contains(&auto.lead_ms), "{}", auto.lead_ms);
    // Either lead cuts the mean RMS error at least fivefold (about elevenfold
    // measured); the auto lead starts from the model's prior and refines it,
    // so it is a little behind the fixed one.
    assert!(mean_rms(&fixed) * 5.0 < mean_rms(&none));
    assert!(mean_rms(&auto) * 5.0 < mean_rms(&none));
    assert!(fixed.worst_max_error() * 5.0 < none.worst_max_error());
}

/// Issue 26: the README's `play arm-wave`, with no `lead_ms` in the robot
/// file, tracks from the first cycle: worst error at most 0.5 deg over the
/// whole run and RMS at most 0.2 deg on every joint. Held with a margin
/// (measured from the first keyframe 0.420 deg worst, 0.150 deg worst RMS;
/// after an approach 0.293 and 0.092). Before the prior was in force from
/// the first cycle (it was ramped in over 0.5 s) the README's run had
/// 1.51 deg worst on the elbow.
#[test]
fn the_arm_wave_tracks_from_the_first_cycle_without_a_lead_in_the_robot_file() {
    // As the README's `play` runs it: the simulated arm starts at the
    // path's first keyframe (no approach to learn the lag during), and as
    // a test that starts elsewhere, after an approach.
    for at_start in [true, false] {
        let auto = play_from(Lead::default(), at_start);
        for j in &auto.joints {
            println!(
                "at start {at_start}: {:14} rms {:.3} max {:.3}",
                j.name, j.rms_error, j.max_error
            );
            assert!(j.max_error < 0.47, "{}: max {} deg", j.name, j.max_error);
            assert!(j.rms_error < 0.15, "{}: rms {} deg", j.name, j.rms_error);
        }
    }
}

#[test]
fn the_auto_lead_is_refined_while_the_arm_moves() {
    // No approach: the first estimate comes from the first, accelerating
    // cycles, where the error understates the lag; later readings correct it.
    let auto = play_from(Lead::default(), true);
    let fixed = play_from(
        Lead::Fixed(Duration::from_secs_f64(auto.lead_ms / 1e3)),
        true,
    );
    let steady = play(Lead::default());
    println!(
        "from the start: auto lead {:.2} ms mean RMS {:.3} deg; fixed mean RMS {:.3} deg; \
         lead identified with an approach {:.2} ms",
        auto.lead_ms,
        mean_rms(&auto),
        mean_rms(&fixed),
        steady.lead_ms
    );
    // The lead ends where a long identification puts it.
    assert!(
        (auto.lead_ms - steady.lead_ms).abs() < 1.0,
        "{} vs {}",
        auto.lead_ms,
        steady.lead_ms
    );
    // And the first moves cost little: within 3 times the RMS error of the
    // lead known from the start (measured 2.7 times; keeping the first
    // estimate, 9.9 ms, gave 0.44 deg, over 6 times).
    assert!(mean_rms(&auto) < 3.0 * mean_rms(&fixed));
}
