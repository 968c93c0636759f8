//! Live targets and the rest of the loop, in virtual time on the simulated
//! SO-101: a run playing a path switches to following at the first target
//! with no limit broken, and Pause and Resume stop and restart the
//! following as they pause and resume a path.

use crate::common;

use common::{motion, record, sim_buses_at};
use servobus_runtime::{Command, Lead, LiveTarget, RunOptions, VirtualRun};

const PERIOD: f64 = 0.005;

fn options() -> RunOptions {
    RunOptions {
        lead: Lead::None,
        approach: None,
        ..RunOptions::default()
    }
}

#[test]
fn a_target_sent_while_a_path_plays_takes_over_smoothly() {
    let (path, robot) = motion("arm-wave.yaml");
    let (buses, _) = sim_buses_at(&robot, &path);
    let mut run = VirtualRun::new(&robot, path, buses, options()).expect("the run starts");
    let tx = run.targets();
    // At 1 s, in the middle of the wave, the pan is sent to -40 deg (and
    // again at 20 Hz, so that the stream does not time out).
    let rec = record(&mut run, 800, |k| {
        if k >= 200 && k % 10 == 0 {
            let t = LiveTarget::named(
                k as f64 * PERIOD,
                vec![("shoulder_pan".into(), (-40f64).to_radians())],
            );
            tx.send(t).expect("a good target");
        }
    });
    assert!(rec.faults.is_empty(), "{:?}", rec.faults);
    rec.assert_within_so101_limits(0, PERIOD);
    let pan = rec.commanded(0);
    assert_eq!(pan.len(), 800, "the run goes on following");
    assert!((pan[799] + 40.0).abs() < 1e-6, "{}", pan[799]);
    let live = run.report().live.expect("targets counted");
    assert_eq!(live.received, 60);
}

#[test]
fn pause_stops_the_following_and_resume_restarts_it() {
    let (path, robot) = motion("arm-wave.yaml");
    let (buses, _) = sim_buses_at(&robot, &path);
    let mut run = VirtualRun::live(&robot, buses, options()).expect("the run starts");
    let tx = run.targets();
    let commands = run.commands();
    // The pan target ramps at 30 deg/s for 3 s; paused from 1 s to 2 s.
    let rec = record(&mut run, 700, |k| {
        let t = k as f64 * PERIOD;
        if k % 6 == 0 && t < 3.0 {
            let q: f64 = 30.0 * t;
            let target = LiveTarget::named(t, vec![("shoulder_pan".into(), q.to_radians())]);
            tx.send(target).expect("a good target");
        }
        if k == 200 {
            commands.send(Command::Pause).expect("the run listens");
        }
        if k == 400 {
            commands.send(Command::Resume).expect("the run listens");
        }
    });
    rec.assert_within_so101_limits(0, PERIOD);
    let pan = rec.commanded(0);
    // Held still in the second half of the pause.
    let held = pan[300];
    assert!(
        pan[300..400].iter().all(|p| (p - held).abs() < 1e-9),
        "{held}"
    );
    assert!(held < 40.0, "stopped soon after 1 s: {held}");
    // Following again: the last target (2.97 s) is at 89.1 deg; the pan
    // stops within its extrapolation and its stop distance beyond it.
    assert!(pan[699] > 89.0 && pan[699] < 95.0, "{}", pan[699]);
}

#[test]
fn a_path_played_in_a_live_run_ends_in_a_hold_and_the_run_goes_on() {
    let (path, robot) = motion("arm-wave.yaml");
    let (buses, _) = sim_buses_at(&robot, &path);
    let wave = path.duration();
    let mut run = VirtualRun::live(&robot, buses, options()).expect("the run starts");
    let tx = run.targets();
    let commands = run.commands();
    let mut path = Some(path);
    // The wave (about 5.7 s) is played at once; from 6.5 s the pan is
    // sent to -30 deg at 20 Hz.
    let rec = record(&mut run, 1600, |k| {
        if let Some(p) = path.take() {
            commands.send(Command::replace(p)).expect("the run listens");
        }
        if k >= 1300 && k % 10 == 0 {
            let t = LiveTarget::named(
                k as f64 * PERIOD,
                vec![("shoulder_pan".into(), (-30f64).to_radians())],
            );
            tx.send(t).expect("a good target");
        }
    });
    assert!(rec.faults.is_empty(), "{:?}", rec.faults);
    rec.assert_within_so101_limits(0, PERIOD);
    let pan = rec.commanded(0);
    assert_eq!(pan.len(), 1600, "the run went on after the wave");
    // Held still where the wave ended, until the targets came.
    let end = (wave / PERIOD) as usize + 20;
    assert!(end < 1250, "the wave lasts {wave} s");
    let held = pan[end];
    assert!(
        pan[end..1300].iter().all(|p| (p - held).abs() < 1e-9),
        "{held}"
    );
    // Then following again.
    assert!((pan[1599] + 30.0).abs() < 1e-6, "{}", pan[1599]);
}
