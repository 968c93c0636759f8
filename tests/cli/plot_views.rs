//! What the plots show (issue 37), read from their SVG: `follow --plot`
//! says which line is the leader and which the follower; the hexapod's
//! `plan --plot` draws its joints leg by leg; its views in space show the
//! body walking and turning in the world; and a walk's 800 samples are no
//! solid bar of keyframe ticks.

use crate::common;

use std::path::PathBuf;

use common::{arg, scratch, servobus_ok};

/// The SVG written by `servobus ARGS --plot FILE` (FILE `name` in a
/// scratch directory).
fn plot(name: &str, args: &[&str]) -> String {
    let file: PathBuf = scratch("plot-views").join(name);
    let _ = std::fs::remove_file(&file);
    servobus_ok(&[args, &["--plot", arg(&file)]].concat());
    std::fs::read_to_string(&file).expect("the plot was written")
}

/// The text of every `<text>` element of `svg`, its XML escapes read.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t.split_once('>')?.1.split("</text>").next()?.trim()))
        .map(|t| {
            t.replace("&apos;", "'")
                .replace("&quot;", "\"")
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&amp;", "&")
        })
        .collect()
}

/// `svg` has a text element saying each of `wanted` (whole).
fn shows(svg: &str, wanted: &[&str]) {
    let texts = texts(svg);
    for w in wanted {
        assert!(
            texts.iter().any(|t| t == w),
            "no text `{w}` in the plot; its texts: {texts:?}"
        );
    }
}

/// `svg` has a text element containing each of `wanted`.
fn says_in_text(svg: &str, wanted: &[&str]) {
    let texts = texts(svg);
    for w in wanted {
        assert!(
            texts.iter().any(|t| t.contains(w)),
            "no `{w}` in the plot's texts: {texts:?}"
        );
    }
}

/// Every `<polyline>` of `svg` whose attributes include `attrs`: its
/// points, in pixels.
fn polylines(svg: &str, attrs: &str) -> Vec<Vec<(f64, f64)>> {
    svg.split("<polyline")
        .skip(1)
        .filter_map(|element| {
            let element = &element[..element.find("/>")?];
            if !element.contains(attrs) {
                return None;
            }
            let points = element.split("points=\"").nth(1)?.split('"').next()?;
            let points = points
                .split_whitespace()
                .filter_map(|p| {
                    let (x, y) = p.split_once(',')?;
                    Some((x.parse().ok()?, y.parse().ok()?))
                })
                .collect();
            Some(points)
        })
        .collect()
}

#[test]
fn the_follow_plot_says_which_line_is_the_leader_and_which_the_follower() {
    let svg = plot("follow.svg", &common::follow_hand("2", &["--json"]));
    shows(
        &svg,
        &["shoulder_pan  (blue dashes: leader, red line: follower)"],
    );
    says_in_text(&svg, &["the follower's error against its leader"]);
    // Nothing of a planned run is said of a follower.
    for t in texts(&svg) {
        for word in ["planned", "measured", "keyframe"] {
            assert!(!t.contains(word), "`{word}` in the follow plot: `{t}`");
        }
    }
}

#[test]
fn the_hexapods_plan_plot_has_a_panel_per_leg_in_one_key_of_coxa_femur_and_tibia() {
    let svg = plot("walk-turn.svg", &["plan", "hexapod-walk-turn"]);
    for leg in [
        "front_left",
        "middle_left",
        "rear_left",
        "front_right",
        "middle_right",
        "rear_right",
    ] {
        shows(
            &svg,
            &[
                &format!("Position, leg {leg}"),
                &format!("Velocity, leg {leg}"),
            ],
        );
        // No panel keys its joints by their full names: the key names the
        // parts, once for every leg.
        let full = format!("{leg}_coxa");
        assert!(!texts(&svg).contains(&full), "`{full}` in a key");
    }
    shows(
        &svg,
        &[
            "Position of each leg's joints:",
            "Velocity of each leg's joints:",
            "coxa",
            "femur",
            "tibia",
        ],
    );
    // Three parts, said once per quantity: no legend box per panel.
    let coxa = texts(&svg).iter().filter(|t| *t == "coxa").count();
    assert_eq!(coxa, 2, "`coxa` said {coxa} times");
    // An arm keeps one chart of every joint.
    let arm = plot("wave.svg", &["plan", "arm-wave"]);
    shows(&arm, &["Position of every joint", "shoulder_pan"]);
    assert!(
        !texts(&arm).iter().any(|t| t.contains("leg")),
        "an arm has no legs"
    );
}

/// The body's path in the world view of `svg`: the longest black line 3
/// px wide (its key's sample is 2 points), in pixels.
fn body_path(svg: &str) -> Vec<(f64, f64)> {
    polylines(svg, r##"stroke="#000000" stroke-width="3""##)
        .into_iter()
        .max_by_key(Vec::len)
        .expect("the body's path")
}

#[test]
fn the_hexapods_views_in_space_show_the_body_walking_and_turning_in_the_world() {
    // Planned (plan) and measured (play): 300 mm forward, a quarter turn
    // to the left on the spot, 100 mm to its right (towards the start's
    // +x after the turn), seen from above in the world at one scale for x
    // and y: 400 mm across, none up or down.
    let planned = plot("plan-walk.svg", &["plan", "hexapod-walk-turn"]);
    let played = plot("play-walk.svg", &["play", "hexapod-walk-turn", "--fast"]);
    for svg in [&planned, &played] {
        shows(
            svg,
            &[
                "Path in space, from above, in the world",
                "body (arrows: its heading)",
                "Path in space, from above, body frame",
                "Path in space, from the side, body frame",
            ],
        );
        let body = body_path(svg);
        let span = |f: fn(&(f64, f64)) -> f64| {
            let v: Vec<f64> = body.iter().map(f).collect();
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - v.iter().copied().fold(f64::INFINITY, f64::min)
        };
        let (across, up) = (span(|p| p.0), span(|p| p.1));
        assert!(
            across > 60.0 && up < across / 10.0,
            "the body's path spans {across} px across and {up} px up"
        );
        // The body stays longest where it turns on the spot (6 s of 16),
        // after 300 mm of the 400: three quarters of the way across.
        let mut dwell: std::collections::BTreeMap<i64, usize> = Default::default();
        for p in &body {
            *dwell.entry(p.0.round() as i64).or_default() += 1;
        }
        let turn = dwell.iter().max_by_key(|(_, n)| **n).map_or(0, |(x, _)| *x);
        let x0 = body.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
        let share = (turn as f64 - x0) / across;
        assert!(
            (share - 0.75).abs() < 0.05,
            "the turn at {share:.2} of the body's path"
        );
    }
}

#[test]
fn a_walks_samples_are_marked_by_a_bracket_not_a_solid_bar_of_ticks() {
    let svg = plot("play-ticks.svg", &["play", "hexapod-walk-turn", "--fast"]);
    // The keyframes' grey marks, vertical ones, by the chart row they
    // stand in (their top and bottom): none closer than 3 px to the next.
    let marks = polylines(&svg, r##"stroke="#969696""##);
    let mut rows: std::collections::BTreeMap<(i64, i64), Vec<f64>> = Default::default();
    for m in &marks {
        if let [a, b] = m[..] {
            if a.0 == b.0 {
                rows.entry((a.1 as i64, b.1 as i64)).or_default().push(a.0);
            }
        }
    }
    assert!(!rows.is_empty(), "no keyframe marks");
    for (row, xs) in &mut rows {
        xs.sort_by(f64::total_cmp);
        for w in xs.windows(2) {
            assert!(
                w[1] - w[0] >= 3.0,
                "marks {} px apart at {w:?} in the charts at {row:?} ({} marks)",
                w[1] - w[0],
                xs.len()
            );
        }
    }
    // 19 charts (18 joints and the error), each a bracket of 3 lines.
    assert!(marks.len() <= 19 * 3, "{} marks", marks.len());
    says_in_text(&svg, &["grey bracket on top"]);
}
