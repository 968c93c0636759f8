//! Numbers and hints as a person reads them: a calibration's pose ticks
//! are written as the integers they are (and a file with `2048.0` still
//! loads), a walk's jerk is said to 0.1 like every other limit, the plots'
//! font sizes have no 16 digits, and `servobus init` tells the user to run
//! what `docs/first-arm.md` runs.

use crate::common;

use std::path::{Path, PathBuf};

use common::{arg, exited, repo, scratch, servobus, servobus_in, servobus_ok, stdout};

/// A directory of its own for one test.
fn dir(name: &str) -> PathBuf {
    let dir = scratch("number-forms").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    dir
}

/// The values of every `pose_tick:` line of a calibration file's `text`.
fn pose_ticks(text: &str) -> Vec<&str> {
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("pose_tick:"))
        .map(str::trim)
        .collect()
}

#[test]
fn an_imported_calibration_writes_its_pose_ticks_as_integers_and_reads_old_floats() {
    let dir = dir("calibration");
    let lerobot = repo("crates/robot/tests/data/so101-lerobot.json");
    let file = dir.join("so101.calibration.yaml");
    let out = servobus(&[
        "calibrate",
        "--robot",
        "so101",
        "--from-lerobot",
        arg(&lerobot),
        "-o",
        arg(&file),
    ]);
    let (said, _) = exited(&out, 0);
    assert!(
        !said.contains("  `"),
        "no run of spaces in the hint: {said}"
    );
    let text = std::fs::read_to_string(&file).expect("the calibration");
    let ticks = pose_ticks(&text);
    assert_eq!(ticks.len(), 6, "{text}");
    // The gripper's range, 2031..3280, has its middle at half a tick: that
    // one is written as it is; every other is a whole tick.
    for tick in &ticks {
        let whole = tick.parse::<i64>().is_ok();
        assert!(whole || *tick == "2655.5", "pose_tick: {tick} in {text}");
    }
    assert_eq!(
        ticks.iter().filter(|t| t.contains('.')).count(),
        1,
        "{text}"
    );

    // A file written before, with `2035.0`, loads as it did: its export is
    // the LeRobot file it came from.
    let old = dir.join("old.calibration.yaml");
    let first = format!("pose_tick: {}\n", ticks[0]);
    assert!(!ticks[0].contains('.'));
    let floats = text.replacen(&first, &format!("pose_tick: {}.0\n", ticks[0]), 1);
    assert_ne!(floats, text);
    std::fs::write(&old, floats).expect("writes");
    let back = dir.join("back.json");
    servobus_ok(&[
        "calibrate",
        "--robot",
        "so101",
        "--calibration",
        arg(&old),
        "--to-lerobot",
        arg(&back),
    ]);
    assert_eq!(
        std::fs::read_to_string(&back).expect("the export"),
        std::fs::read_to_string(&lerobot).expect("the fixture")
    );
}

#[test]
fn a_walk_beyond_a_jerk_limit_says_it_to_a_tenth_like_the_other_limits() {
    let dir = dir("walk-jerk");
    let robot = std::fs::read_to_string(repo("configs/robots/hexapod.yaml")).expect("hexapod");
    assert!(robot.contains("max_jerk: 15000"));
    std::fs::write(
        dir.join("robot.yaml"),
        robot.replace("max_jerk: 15000", "max_jerk: 3000"),
    )
    .expect("writes");
    let motion = common::edited(
        "configs/motions/hexapod-tripod.yaml",
        &[("robot: ../robots/hexapod.yaml", "robot: robot.yaml")],
    );
    let walk = common::write_file(&dir, "walk.yaml", &motion);
    let out = servobus(&["plan", arg(&walk)]);
    let (_, err) = exited(&out, 2);
    let peak = err
        .split("needs a peak jerk of ")
        .nth(1)
        .and_then(|rest| rest.split_once(" deg/s^3, above the limit 3000.0 deg/s^3"))
        .map(|(peak, _)| peak)
        .unwrap_or_else(|| panic!("a jerk and its limit to 0.1: {err}"));
    let decimals = peak.split_once('.').map(|(_, d)| d.len());
    assert_eq!(decimals, Some(1), "the peak {peak} to 0.1: {err}");
    assert!(err.contains("the legs cannot keep this gait"), "{err}");
}

/// Each attribute of `svg` whose value is a number (`12`, `9.7`, `0.76em`)
/// with more than `max` decimals.
fn long_numbers(svg: &str, max: usize) -> Vec<String> {
    svg.split(['<', '>'])
        .filter(|tag| !tag.starts_with('/'))
        .flat_map(|tag| tag.split(' ').skip(1))
        .filter_map(|attr| {
            let (_, value) = attr.split_once("=\"")?;
            let value = value.trim_end_matches(['"', '/']);
            let number = value.trim_end_matches(|c: char| c.is_ascii_alphabetic());
            number.parse::<f64>().ok()?;
            let decimals = number.split_once('.').map_or(0, |(_, d)| d.len());
            (decimals > max).then(|| attr.to_owned())
        })
        .collect()
}

/// The SVG `servobus ARGS --plot FILE` writes (FILE `name` in `dir`).
fn plot(dir: &Path, name: &str, args: &[&str]) -> String {
    let file = dir.join(name);
    servobus_ok(&[args, &["--plot", arg(&file)]].concat());
    std::fs::read_to_string(&file).expect("the plot")
}

#[test]
fn the_plots_font_sizes_are_said_to_a_tenth_of_a_pixel() {
    let dir = dir("plots");
    for (name, args) in [
        ("plan.svg", &["plan", "arm-wave"][..]),
        ("plan-walk.svg", &["plan", "hexapod-walk-turn"][..]),
        ("play.svg", &["play", "arm-wave", "--fast"][..]),
    ] {
        let svg = plot(&dir, name, args);
        assert!(svg.contains("font-size=\""), "{name} has text");
        let long = long_numbers(&svg, 2);
        assert!(long.is_empty(), "{name}: {:?}", &long[..long.len().min(5)]);
        for size in svg.split("font-size=\"").skip(1) {
            let size = size.split('"').next().unwrap_or_default();
            let decimals = size.split_once('.').map_or(0, |(_, d)| d.len());
            assert!(decimals <= 1, "{name}: font-size=\"{size}\"");
        }
    }
}

/// The commands of `docs/first-arm.md`'s shell blocks that start with
/// `prefix`, each once.
fn doc_commands(prefix: &str) -> Vec<String> {
    let doc = std::fs::read_to_string(repo("docs/first-arm.md")).expect("the walkthrough");
    let mut commands: Vec<String> = Vec::new();
    for block in doc.split("```sh\n").skip(1) {
        let block = block.split("```").next().unwrap_or_default();
        for line in block.lines().filter(|l| l.starts_with(prefix)) {
            if !commands.iter().any(|c| c == line) {
                commands.push(line.to_owned());
            }
        }
    }
    commands
}

#[test]
fn inits_next_steps_are_the_commands_the_first_arm_walkthrough_runs() {
    // As the walkthrough runs them: in the directory of robot.yaml.
    let here = dir("init-here");
    let out = servobus_in(&here, &["init"]);
    let (said, _) = exited(&out, 0);
    let lines: Vec<&str> = said.lines().map(str::trim).collect();
    let mut commands = doc_commands("servobus doctor");
    commands.extend(doc_commands("servobus calibrate"));
    assert!(
        commands.len() >= 3,
        "doctor, doctor --fix, calibrate: {commands:?}"
    );
    for command in &commands {
        assert!(
            lines.contains(&command.as_str()),
            "init says `{command}`: {said}"
        );
    }
    assert!(
        lines.contains(&"servobus plan motion.yaml"),
        "the simulator's first step: {said}"
    );

    // Step 3's file is the one the commented line names, and step 4's sed
    // makes that line the robot file's `calibration:`.
    let calibrate = doc_commands("servobus calibrate").remove(0);
    let (_, file) = calibrate.split_once(" -o ").expect("calibrate -o FILE");
    let sed = doc_commands("sed -i").remove(0);
    let expr = sed.split('\'').nth(1).expect("sed 's/FROM/TO/'");
    let parts: Vec<&str> = expr.split('/').collect();
    let (from, to) = (parts[1].trim_start_matches('^'), parts[2]);
    let robot = std::fs::read_to_string(here.join("robot.yaml")).expect("robot.yaml");
    let named: Vec<String> = robot
        .lines()
        .filter_map(|l| l.strip_prefix(from).map(|rest| format!("{to}{rest}")))
        .collect();
    assert_eq!(named.len(), 1, "one line for the sed of step 4: {robot}");
    let wanted = format!("calibration: {file}");
    assert!(named[0].starts_with(&wanted), "{}", named[0]);
    assert!(
        said.contains(&format!("`{wanted}`")),
        "init says to uncomment it: {said}"
    );

    // From the directory above, with the paths from there.
    let above = dir("init-above");
    let out = servobus_in(&above, &["init", "arm"]);
    let said = stdout(&out);
    for command in &commands {
        let from_above = command
            .replace("robot.yaml", "arm/robot.yaml")
            .replace(&format!("-o {file}"), &format!("-o arm/{file}"));
        assert!(
            said.contains(&from_above),
            "init says `{from_above}`: {said}"
        );
    }
}
