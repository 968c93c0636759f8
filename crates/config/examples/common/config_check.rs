//! What the YAML fuzzers check on one input, shared by the cargo-fuzz
//! target (`fuzz/fuzz_targets/config_yaml.rs`), the stable fuzzer
//! (`examples/fuzz_config.rs`) and the regression test that replays
//! `testdata/fuzz-config/`.
//!
//! The input goes through the real loaders, as files on disk: as a robot
//! file, as a motion file (whose `robot:` resolves next to the shipped
//! robots), as the robot of a shipped motion, and as a calibration file.
//! Every motion that loads is planned. Beyond "no panic", it checks that a
//! refusal names a file, speaks in the file's terms (no Rust type names,
//! no number of more than 20 digits outside the echoed text) and that a
//! plan that succeeds is within the duration limit.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use servobus_config::{
    limits, load_calibration, load_motion, load_robot, plan_motion, ConfigError, RobotOptions,
};

/// Inputs longer than this are not tried (the fuzz target's size cap):
/// the shipped files are under 10 KB, and the loaders' own limit is 1 MiB.
pub const MAX_LEN: usize = 16 * 1024;

/// A scratch directory with the shipped robots and motions, where each
/// input is written before it is loaded.
pub struct Workspace {
    dir: PathBuf,
}

impl Workspace {
    /// Copies `configs/robots/*.yaml` and `configs/motions/*.yaml` of the
    /// repository at `repo` into a new scratch directory.
    pub fn new(repo: &Path) -> std::io::Result<Workspace> {
        // Memory-backed where there is one: every input is written twice.
        let shm = Path::new("/dev/shm");
        let base = if shm.is_dir() {
            shm.to_owned()
        } else {
            std::env::temp_dir()
        };
        let dir = base.join(format!(
            "servobus-fuzz-config-{}-{:x}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos())
        ));
        for sub in ["robots", "motions"] {
            std::fs::create_dir_all(dir.join(sub))?;
            for entry in std::fs::read_dir(repo.join("configs").join(sub))? {
                let path = entry?.path();
                if let Some(name) = path.file_name() {
                    std::fs::copy(&path, dir.join(sub).join(name))?;
                }
            }
        }
        Ok(Workspace { dir })
    }

    /// Loads `input` every way there is and checks every outcome; returns
    /// one feature per load (its outcome's kind), for the fuzzer to keep
    /// inputs that do something new.
    ///
    /// # Panics
    /// When a check fails (that is the point).
    pub fn check(&self, input: &[u8]) -> Vec<String> {
        let robot = self.dir.join("robots/fuzz.yaml");
        let motion = self.dir.join("motions/fuzz.yaml");
        let write = |p: &Path| std::fs::write(p, input).expect("the scratch directory is writable");
        write(&robot);
        write(&motion);
        let text = String::from_utf8_lossy(input);
        let feature = |load: &str, outcome| feature(load, outcome, &text);
        let wave = self.dir.join("motions/arm-wave.yaml");
        vec![
            feature(
                "robot",
                load_robot(&robot, &RobotOptions::default()).map(|_| ()),
            ),
            feature("motion", load_and_plan(&motion, None)),
            feature("robot-of-wave", load_and_plan(&wave, Some(&robot))),
            feature("calibration", load_calibration(&robot).map(|_| ())),
        ]
    }
}

impl Drop for Workspace {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Loads the motion at `path` and plans it; a plan that succeeds must be
/// within the duration limit.
fn load_and_plan(path: &Path, robot: Option<&Path>) -> Result<(), ConfigError> {
    let (motion, robot) = load_motion(path, robot)?;
    let trajectory = plan_motion(&motion, &robot)?;
    let duration = trajectory.duration();
    assert!(
        duration.is_finite() && duration <= limits::MAX_MOTION_DURATION_S,
        "a plan of {duration} s was accepted"
    );
    Ok(())
}

/// The outcome's kind, after checking a refusal's message (`input`: the
/// text that was loaded).
fn feature(load: &str, outcome: Result<(), ConfigError>, input: &str) -> String {
    let e = match outcome {
        Ok(()) => return format!("{load}:ok"),
        Err(e) => e,
    };
    let text = e.to_string();
    check_message(&e, &text, input);
    let kind = match &e {
        ConfigError::Invalid { field, reason, .. } => {
            // The message's own first words, not the file's text it echoes.
            let words: Vec<&str> = reason
                .split_whitespace()
                .take_while(|w| {
                    w.chars()
                        .all(|c| c.is_ascii_alphabetic() || ",;:".contains(c))
                })
                .take(3)
                .collect();
            // The field's depth, not its names (a file's own keys would
            // make every input new).
            let depth = field.matches(['.', '[']).count();
            format!("{depth}:{}", shape(&words.join(" ")))
        }
        ConfigError::Read { error, .. } => format!("read:{:?}", error.kind()),
        other => format!("{:?}", std::mem::discriminant(other)),
    };
    format!("{load}:{kind}")
}

/// `text` without digits (`keyframe 3:` and `keyframe 12:` are one
/// feature).
fn shape(text: &str) -> String {
    text.chars().filter(|c| !c.is_ascii_digit()).collect()
}

/// A refusal names its file and speaks in the file's terms: what it says
/// beyond the file's own text (`input`) has no Rust type and no number of
/// more than 20 digits.
fn check_message(e: &ConfigError, text: &str, input: &str) {
    let file = e.file().display().to_string();
    assert!(
        text.starts_with(&file),
        "the message does not name the file: {text}"
    );
    if servobus_config::is_builtin_path(e.file()) {
        return;
    }
    // The field path (`poses.<name>`) and the echoed text are the file's own.
    let said = match e {
        ConfigError::Invalid { reason, .. } => reason.as_str(),
        _ => &text[file.len()..],
    };
    let own = outside_echoes(said);
    for rust in [
        "expected struct",
        "untagged enum",
        "expected enum",
        "expected f64",
        "expected f32",
        "expected u8",
        "expected u16",
        "expected u32",
        "expected u64",
        "expected i64",
        "expected i32",
        "expected path string",
    ] {
        let echoed = input.contains(rust);
        assert!(
            echoed || !own.contains(rust),
            "a Rust type in the message: {text}"
        );
    }
    for digits in own.split(|c: char| !c.is_ascii_digit()) {
        let echoed = input.contains(digits);
        assert!(
            echoed || digits.len() <= 20,
            "a number of {} digits in the message: {text}",
            digits.len()
        );
    }
}

/// `text` without the parts that echo the file: `backticked`, "quoted",
/// and the lists of names after `(poses:`, `(joints:`, `(known:`.
fn outside_echoes(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut inside: Option<char> = None;
    for c in text.chars() {
        match inside {
            Some(end) if c == end => inside = None,
            Some(_) => {}
            None if c == '`' || c == '"' => inside = Some(c),
            None if c == '(' => inside = Some(')'),
            None => out.push(c),
        }
    }
    out
}
