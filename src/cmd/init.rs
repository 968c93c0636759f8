//! `servobus init`: a starter robot file and motion to edit, written from a
//! built-in robot.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use servobus_config::{load_robot, Robot, RobotOptions};
use servobus_robot::files::AtomicFile;

use crate::shared::exit::input;
use crate::shared::out::outln;

/// Arguments of `servobus init`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Then: servobus plan DIR/motion.yaml; servobus play DIR/motion.yaml \
    (simulator); add --port /dev/ttyACM0 for real servos."
)]
pub struct Args {
    /// The robot to start from: a built-in name (`servobus list`) or a robot file.
    #[arg(long, default_value = "so101", value_parser = crate::shared::flags::robot_arg)]
    pub robot: PathBuf,
    /// Where to write `robot.yaml` and `motion.yaml` (created if missing).
    #[arg(default_value = ".")]
    pub dir: PathBuf,
    /// Overwrite `robot.yaml` and `motion.yaml` if they exist.
    #[arg(long)]
    pub force: bool,
}

/// Runs `servobus init`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let robot = load_robot(&args.robot, &RobotOptions::default())?;
    // The file as the user names it from here (`robot.yaml`, not
    // `./robot.yaml`): the commands in its comments name it so.
    let here = args.dir == Path::new(".");
    let robot_file = if here {
        PathBuf::from("robot.yaml")
    } else {
        args.dir.join("robot.yaml")
    };
    let dir_prefix = if here {
        String::new()
    } else {
        format!("{}/", args.dir.display().to_string().trim_end_matches('/'))
    };
    let original = robot_text(&args.robot)?;
    let robot_text = commands_for(&original, &robot_file.display().to_string(), &dir_prefix);
    let files = [
        (args.dir.join("robot.yaml"), robot_text),
        (args.dir.join("motion.yaml"), starter_motion(&robot)),
    ];
    if !args.force {
        if let Some((existing, _)) = files.iter().find(|(p, _)| p.exists()) {
            return Err(input(format!(
                "{} exists; not overwriting it (pass --force to replace it, or give another DIR)",
                existing.display()
            )));
        }
    }
    std::fs::create_dir_all(&args.dir).map_err(|e| {
        let why = crate::shared::os_error::os_text(&e);
        input(format!("cannot create {}: {why}", args.dir.display()))
    })?;
    // Both files are written in full (to temporaries) before either
    // replaces anything: a failure (a full disk) leaves neither, so that
    // `init` can simply be run again.
    let mut written = Vec::new();
    for (path, text) in &files {
        let mut file = AtomicFile::create(path)?;
        file.write_all(text.as_bytes())?;
        written.push(file);
    }
    for file in written {
        let path = file.path().to_path_buf();
        file.commit()?;
        outln!("wrote {}", path.display())?;
    }
    // `./motion.yaml` reads better as `motion.yaml`.
    let motion = if args.dir == Path::new(".") {
        PathBuf::from("motion.yaml")
    } else {
        files[1].0.clone()
    };
    let next = next_steps(
        &robot_file.display().to_string(),
        &motion.display().to_string(),
        &dir_prefix,
        servobus_config::builtin::commented_calibration(&original),
    );
    outln!("{next}")?;
    Ok(ExitCode::SUCCESS)
}

/// What to run next, with the paths of where `init` ran (`robot_file`,
/// `motion`; `dir_prefix` before a file beside them): the starter motion on
/// the simulator, then on real servos the steps of `docs/first-arm.md` up
/// to a calibrated robot: doctor, its fixes, calibrate, and the robot
/// file's `calibration:` line uncommented when it has one (`calibration`,
/// the file it names).
fn next_steps(
    robot_file: &str,
    motion: &str,
    dir_prefix: &str,
    calibration: Option<&str>,
) -> String {
    let on_port = format!("--robot {robot_file} --port /dev/ttyACM0");
    let mut text = format!(
        "Next, on the simulator:\n  servobus plan {motion}\n  servobus play {motion}\n\
         On real servos (`port:` in {robot_file}, or --port as here):\n  \
         servobus doctor {on_port}\n  servobus doctor {on_port} --fix\n  \
         servobus calibrate {on_port}"
    );
    if let Some(file) = calibration {
        let _ = write!(
            text,
            " -o {dir_prefix}{file}\n  then uncomment `calibration: {file}` in {robot_file}"
        );
    }
    text
}

/// The robot file's text: the built-in text, or the file as it is.
fn robot_text(path: &Path) -> anyhow::Result<String> {
    if let Some(b) = servobus::builtin::all().find(|b| b.path() == path) {
        return Ok(b.text.to_owned());
    }
    std::fs::read_to_string(path).map_err(|e| input(format!("cannot read {}: {e}", path.display())))
}

/// `text` with the `servobus` commands in its comments made for the copy
/// written at `robot_file`: the `--robot` of each names `robot_file`, and
/// its `-o` file goes beside it (`dir_prefix`, empty for the current
/// directory), where the copy's `calibration: ... # relative to this file`
/// looks. A command may wrap onto the next comment line; the YAML itself
/// is not touched.
fn commands_for(text: &str, robot_file: &str, dir_prefix: &str) -> String {
    /// What the previous token of the comment asked for.
    #[derive(Clone, Copy, PartialEq)]
    enum Next {
        Word,
        Robot,
        Output,
    }
    let mut out = String::with_capacity(text.len());
    let mut next = Next::Word;
    // Inside a `servobus ...` command whose robot has been renamed.
    let mut command = false;
    for line in text.split_inclusive('\n') {
        let Some(start) = line.find('#').filter(|&i| line[..i].trim().is_empty()) else {
            // Not a comment line: a command does not go on past it.
            (next, command) = (Next::Word, false);
            out.push_str(line);
            continue;
        };
        out.push_str(&line[..start]);
        let mut rest = &line[start..];
        while !rest.is_empty() {
            let gap = rest
                .find(|c: char| !c.is_whitespace())
                .unwrap_or(rest.len());
            out.push_str(&rest[..gap]);
            rest = &rest[gap..];
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            let (token, after) = rest.split_at(end);
            rest = after;
            if token.is_empty() {
                continue;
            }
            // A token may close a parenthesis or a sentence: `file.yaml)`.
            let word = token.trim_end_matches([')', ',', ';']);
            let tail = &token[word.len()..];
            match next {
                Next::Robot if word != "#" => {
                    out.push_str(robot_file);
                    out.push_str(tail);
                    (next, command) = (Next::Word, true);
                    continue;
                }
                Next::Output if word != "#" => {
                    out.push_str(dir_prefix);
                    out.push_str(token);
                    next = Next::Word;
                    continue;
                }
                _ => {}
            }
            match word {
                "servobus" => command = false,
                "--robot" => next = Next::Robot,
                "-o" | "--output" if command => next = Next::Output,
                _ => {}
            }
            out.push_str(token);
        }
    }
    out
}

/// Joints the starter motion moves one at a time (the rest stay still), so
/// that it stays short for a robot with many joints.
const MOVED_JOINTS: usize = 6;

/// A motion for `robot`: from rest, each of the first joints moves a quarter
/// of the way toward its farther limit and back, then all rest.
fn starter_motion(robot: &Robot) -> String {
    let units = robot.units.name();
    let mut text = format!(
        "# A starter motion for `{name}`: from rest, each of the first joints in turn moves\n\
         # a quarter of the way toward a limit and back. Edit the poses and keyframes.\n\
         # Check it:        servobus plan motion.yaml\n\
         # Simulate it:     servobus play motion.yaml\n\
         # On real servos:  servobus play motion.yaml --port /dev/ttyACM0\n\
         robot: robot.yaml      # relative to this file; --robot overrides\n\
         units: {units}             # unit of every angle below\n\
         poses:\n  rest: {{",
        name = robot.name
    );
    let rest: Vec<String> = robot
        .joints()
        .map(|j| format!("{}: {}", j.name, number(j.rest())))
        .collect();
    text.push_str(&rest.join(", "));
    text.push_str(
        "}\nkeyframes:\n  - pose: rest          # the first keyframe is the start, t = 0\n",
    );
    for (i, j) in robot.joints().take(MOVED_JOINTS).enumerate() {
        let rest = j.rest();
        let toward = if j.max - rest >= rest - j.min {
            j.max
        } else {
            j.min
        };
        let goal = rest + (toward - rest) / 4.0;
        let note = if i == 0 {
            "    # joints not named keep their value"
        } else {
            ""
        };
        let _ = writeln!(text, "  - pose: {{{}: {}}}{note}", j.name, number(goal));
        let _ = writeln!(text, "  - pose: rest");
    }
    text.push_str("repeat: 1              # play the keyframes this many times\n");
    text
}

/// A number as a person would write it: at most one decimal.
fn number(v: f64) -> String {
    let r = (v * 10.0).round() / 10.0 + 0.0; // no `-0`
    if r.fract() == 0.0 {
        format!("{r:.0}")
    } else {
        format!("{r:.1}")
    }
}
