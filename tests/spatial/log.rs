//! `servobus play --log` gives the named frames' positions (forward
//! kinematics of the measured angles) as columns of every row.

use std::path::PathBuf;

/// The rows of `play <motion> --fast --log`, header first.
fn logged(motion: &str) -> Vec<Vec<String>> {
    let path: PathBuf = std::env::temp_dir().join(format!(
        "servobus-spatial-log-{motion}-{}.csv",
        std::process::id()
    ));
    crate::servobus_ok(&[
        "play".as_ref(),
        motion.as_ref(),
        "--fast".as_ref(),
        "--log".as_ref(),
        path.as_ref(),
    ]);
    let text = std::fs::read_to_string(&path).expect("the log");
    let _ = std::fs::remove_file(&path);
    text.lines()
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

/// Column `name`'s index in the header.
fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

#[test]
fn an_arm_log_gives_the_tool_where_the_line_keyframes_put_it() {
    let rows = logged("arm-line");
    let header = &rows[0];
    // The joint columns first, as before; the tool's after them.
    assert_eq!(header[14], "skipped");
    assert_eq!(&header[15..], ["tool_x_mm", "tool_y_mm", "tool_z_mm"]);
    let x = column(header, "tool_x_mm");
    let tool: Vec<[f64; 3]> = rows[1..]
        .iter()
        .map(|r| {
            let v = |k: usize| r[x + k].parse::<f64>().expect("a number");
            [v(0), v(1), v(2)]
        })
        .collect();
    // The `tool:` targets of configs/motions/arm-line.yaml, each reached
    // (the run settles at every keyframe) within 1 mm.
    for target in [
        [220.0, 60.0, 120.0],
        [220.0, 60.0, 70.0],
        [220.0, -80.0, 120.0],
    ] {
        let closest = tool
            .iter()
            .map(|p| {
                p.iter()
                    .zip(target)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(closest < 1.0, "{target:?}: closest {closest:.3} mm");
    }
    // The straight-down line keeps x and y: every row between 75 and
    // 115 mm high over (220, 60) is within 1 mm of the line.
    let on_line = tool
        .iter()
        .filter(|p| (p[0] - 220.0).abs() < 5.0 && p[1] > 40.0 && (75.0..115.0).contains(&p[2]));
    let mut n = 0;
    for p in on_line {
        n += 1;
        let off = ((p[0] - 220.0).powi(2) + (p[1] - 60.0).powi(2)).sqrt();
        assert!(off < 1.0, "{p:?}: {off:.3} mm off the line");
    }
    assert!(n > 50, "{n} rows on the line down and up");
}

#[test]
fn a_hexapod_log_gives_every_foot() {
    let rows = logged("hexapod-dance");
    let header = &rows[0];
    let feet: Vec<&String> = header.iter().filter(|h| h.starts_with("foot_")).collect();
    assert_eq!(feet.len(), 6 * 3, "{header:?}");
    // The dance moves the body over planted feet: in the body's frame the
    // feet move, but the distance between any two of them stays (within
    // 2 mm, the tracking error of two legs).
    let x: Vec<usize> = header
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with("foot_") && h.ends_with("_x_mm"))
        .map(|(i, _)| i)
        .collect();
    let feet = |row: &[String]| -> Vec<[f64; 3]> {
        x.iter()
            .map(|&i| [0, 1, 2].map(|k| row[i + k].parse::<f64>().expect("a number")))
            .collect()
    };
    let gaps = |f: &[[f64; 3]]| -> Vec<f64> {
        let mut d = Vec::new();
        for a in 0..f.len() {
            for b in a + 1..f.len() {
                d.push(
                    (0..3)
                        .map(|k| (f[a][k] - f[b][k]).powi(2))
                        .sum::<f64>()
                        .sqrt(),
                );
            }
        }
        d
    };
    let first = gaps(&feet(&rows[1]));
    assert_eq!(first.len(), 15);
    let mut moved: f64 = 0.0;
    for row in &rows[1..] {
        let f = feet(row);
        moved = moved.max((f[0][2] - feet(&rows[1])[0][2]).abs());
        for (g, g0) in gaps(&f).iter().zip(&first) {
            assert!(
                (g - g0).abs() < 2.0,
                "at {} s: {g:.2} vs {g0:.2} mm",
                row[0]
            );
        }
    }
    // And the body did move over them.
    assert!(
        moved > 10.0,
        "a foot's height in the body frame moved {moved:.1} mm"
    );
}

#[test]
fn a_plot_of_a_run_shows_the_measured_tool_path_from_above_and_the_side() {
    let path: PathBuf =
        std::env::temp_dir().join(format!("servobus-spatial-plot-{}.svg", std::process::id()));
    crate::servobus_ok(&[
        "play".as_ref(),
        "arm-line".as_ref(),
        "--fast".as_ref(),
        "--plot".as_ref(),
        path.as_ref(),
    ]);
    let svg = std::fs::read_to_string(&path).expect("the plot");
    let _ = std::fs::remove_file(&path);
    for caption in [
        "Path in space, from above",
        "Path in space, from the side",
        "tracking error",
    ] {
        assert!(svg.contains(caption), "no `{caption}` in the plot");
    }
    // The tool's path is a legend entry of both views (a text element's
    // own line in the SVG).
    let labels = svg.lines().filter(|l| l.trim() == "tool").count();
    assert_eq!(labels, 2, "the tool's path in each view");
}
