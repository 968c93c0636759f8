//! A log played again (issue #37): `play arm-wave --log take.csv`, then
//! `play take.csv`, is the take again, its planned path and what the
//! servos did within half a degree of the take's and on time. A recording
//! that breaks a limit is played within it, and the report says where and
//! why.

use crate::common;

use std::collections::BTreeMap;
use std::path::Path;

use common::{num, scratch, servobus_json, servobus_ok, stdout};

/// A `(time, value)` series.
type Series = Vec<(f64, f64)>;

/// Per joint, the series of `column` in a `play --log` file.
fn column(log: &Path, column: &str) -> BTreeMap<String, Series> {
    let text = std::fs::read_to_string(log).expect("log");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let find = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (t, joint, value) = (find("time_s"), find("joint"), find(column));
    let mut out: BTreeMap<String, Series> = BTreeMap::new();
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let (Ok(time), Ok(v)) = (f[t].parse(), f[value].parse()) else {
            continue;
        };
        out.entry(f[joint].to_owned()).or_default().push((time, v));
    }
    out
}

/// Series `s` at `t`, linearly interpolated (held beyond its ends).
fn at(s: &[(f64, f64)], t: f64) -> f64 {
    let i = s.partition_point(|p| p.0 <= t);
    if i == 0 {
        return s[0].1;
    }
    if i == s.len() {
        return s[s.len() - 1].1;
    }
    let ((ta, a), (tb, b)) = (s[i - 1], s[i]);
    a + (b - a) * (t - ta) / (tb - ta)
}

/// The largest and the RMS distance of `b`, shifted by `shift` s, from
/// `a` at `a`'s samples.
fn distance(a: &[(f64, f64)], b: &[(f64, f64)], shift: f64) -> (f64, f64) {
    let (mut max, mut sum) = (0.0f64, 0.0);
    for &(t, v) in a {
        let e = at(b, t + shift) - v;
        max = max.max(e.abs());
        sum += e * e;
    }
    (max, (sum / a.len() as f64).sqrt())
}

/// How late `b` is against `a`, s: the shift within 20 ms (in steps of
/// 0.25 ms) with the least RMS distance.
fn lateness(a: &[(f64, f64)], b: &[(f64, f64)]) -> f64 {
    (-80..=80)
        .map(|k| k as f64 * 0.000_25)
        .min_by(|&x, &y| distance(a, b, x).1.total_cmp(&distance(a, b, y).1))
        .expect("shifts")
}

#[test]
fn a_log_played_again_is_the_take_again_and_on_time() {
    let dir = scratch("replay_log");
    let (take, replay) = (dir.join("take.csv"), dir.join("replay.csv"));
    let (take_s, replay_s) = (
        take.to_str().expect("utf-8"),
        replay.to_str().expect("utf-8"),
    );
    let first = servobus_json(&["play", "arm-wave", "--fast", "--json", "--log", take_s]);
    assert_eq!(first["finish"], "completed", "{first}");
    let again = servobus_json(&[
        "play", take_s, "--robot", "so101", "--fast", "--json", "--log", replay_s,
    ]);
    assert_eq!(again["finish"], "completed", "{again}");

    // The report: the take's planned path, played through its samples,
    // nowhere off it, starting when it starts.
    let r = &again["recording"];
    assert_eq!(r["column"], "planned_deg", "{r}");
    assert_eq!(num(r, "lead_s"), 0.0, "{r}");
    assert_eq!(r["departures"].as_array().map(Vec::len), Some(0), "{r}");
    for j in r["joints"].as_array().expect("joints") {
        assert!(num(j, "max_departure") < 0.05, "{j}");
    }

    // The logs: the path played and what the servos did, against the
    // take's. (The planned column is the path at the reading, 0.4 ms into
    // the cycle on the simulator: the replay's is that much ahead of the
    // take's, 0.1 deg at the wrist's 240 deg/s.)
    for name in ["planned_deg", "measured_deg"] {
        let (a, b) = (column(&take, name), column(&replay, name));
        assert_eq!(a.len(), 6, "{name}: {:?}", a.keys());
        for (joint, sa) in &a {
            let sb = &b[joint];
            let (max, rms) = distance(sa, sb, 0.0);
            println!("{name} {joint}: max {max:.3} deg, rms {rms:.3} deg");
            assert!(max <= 0.5, "{name} {joint}: departs by {max} deg");
            let late = lateness(sa, sb);
            assert!(late.abs() <= 0.001, "{name} {joint}: {late} s late");
        }
    }
}

#[test]
fn a_recording_beyond_a_limit_is_played_within_it_and_the_report_says_where_and_why() {
    let dir = scratch("replay_log_fast_swing");
    let rec = dir.join("swing.csv");
    // shoulder_pan at rest, then 60 deg in 0.3 s (a half cosine: 314 deg/s
    // at its fastest, so101 allows 180), then at rest again.
    let mut text = String::from("time_s,shoulder_pan\n");
    for i in 0..=200 {
        let t = i as f64 * 0.01;
        let x = ((t - 0.5) / 0.3).clamp(0.0, 1.0);
        let q = 30.0 * (1.0 - (std::f64::consts::PI * x).cos());
        text += &format!("{t:.2},{q:.4}\n");
    }
    std::fs::write(&rec, text).expect("recording");
    let (rec_s, log) = (rec.to_str().expect("utf-8"), dir.join("log.csv"));
    let log_s = log.to_str().expect("utf-8");
    let v = servobus_json(&[
        "play", rec_s, "--robot", "so101", "--fast", "--json", "--log", log_s,
    ]);
    assert_eq!(v["finish"], "completed", "{v}");
    let departures = v["recording"]["departures"].as_array().expect("departures");
    let d = &departures[0];
    assert_eq!(d["joint"], "shoulder_pan", "{d}");
    assert_eq!(d["limit"], "velocity", "{d}");
    assert_eq!(d["unit"], "deg/s", "{d}");
    // The recording's own peak, as its samples show it (smoothed a little).
    assert!((num(d, "peak") - 314.2).abs() < 2.0, "{d}");
    assert_eq!(num(d, "max"), 180.0, "{d}");
    // Where: around the swing (0.5 to 0.8 s), its fastest part inside; the
    // path leaves the recording earlier and rejoins it later, to be there
    // on time on average.
    assert!(num(d, "start_s") < 0.65 && num(d, "end_s") > 0.65, "{d}");
    assert!(num(d, "start_s") > 0.0 && num(d, "end_s") < 1.5, "{d}");
    assert!(num(d, "max_departure") > 1.0, "{d}");
    // And played within the limit: what was sent never faster than 180
    // deg/s (the log rounds to 1e-4 deg).
    let sent = &column(&log, "commanded_deg")["shoulder_pan"];
    for w in sent.windows(2) {
        let speed = (w[1].1 - w[0].1).abs() / (w[1].0 - w[0].0);
        assert!(speed <= 180.0 * 1.001 + 0.02, "{speed} deg/s at {}", w[0].0);
    }

    // The text report says it in words.
    let out = servobus_ok(&["play", rec_s, "--robot", "so101", "--fast"]);
    let text = stdout(&out);
    assert!(
        text.contains("where it breaks a limit: shoulder_pan")
            && text.contains("velocity 31")
            && text.contains("beyond its limit 180.0 deg/s"),
        "{text}"
    );
}

#[test]
fn the_plot_of_a_replay_draws_the_recording_beside_it_and_a_motion_s_does_not() {
    let dir = scratch("replay_log_plot");
    let (take, replay_svg, plain_svg) =
        (dir.join("take.csv"), dir.join("x.svg"), dir.join("y.svg"));
    let path = |p: &Path| p.to_str().expect("utf-8").to_owned();
    let take_s = path(&take);
    servobus_ok(&["play", "arm-wave", "--fast", "--log", &take_s]);
    servobus_ok(&[
        "play",
        &take_s,
        "--robot",
        "so101",
        "--fast",
        "--plot",
        &path(&replay_svg),
    ]);
    servobus_ok(&["play", "arm-wave", "--fast", "--plot", &path(&plain_svg)]);

    // The recording's grey line (a wide one) per joint, and the key says it.
    let replay = std::fs::read_to_string(&replay_svg).expect("replay plot");
    assert!(
        replay.contains("shoulder_pan  (blue dashes: planned, red: measured, grey: recording)"),
        "no recording in the key"
    );
    let line = "stroke=\"#808080\" stroke-width=\"4\"";
    assert_eq!(
        replay.matches(line).count(),
        6,
        "a recording line per joint"
    );
    // A motion's plot is as it was: no recording.
    let plain = std::fs::read_to_string(&plain_svg).expect("plain plot");
    assert!(
        !plain.contains("recording"),
        "a recording in a motion's plot"
    );
    assert!(!plain.contains(line), "a recording line in a motion's plot");
    assert!(plain.contains("shoulder_pan  (blue dashes: planned, red line: measured)"));
}
