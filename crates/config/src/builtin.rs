//! The robots, motions and simulator examples (mountings, hands) shipped in
//! `configs/`, compiled into every program built on this crate, so that an
//! installed `servobus` (or a Python program) finds them from any directory
//! and by name. No registration: the table is this module's.
//!
//! A command-line argument that names a robot, motion, mounting or hand goes
//! through [`path_or_name`] (or [`robot_path_or_name`],
//! [`motion_path_or_name`]): an existing file wins;
//! otherwise a built-in name (`so101`, `arm-wave`) becomes the built-in file's
//! path (`<built-in>/robots/so101.yaml`), which the loaders of
//! this crate read like any file. A built-in motion's
//! `robot: ../robots/so101.yaml` thus resolves to the built-in robot.

use std::path::{Path, PathBuf};

use crate::files::{builtin_path, BuiltinFile};

/// What a built-in file describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A robot file (`configs/robots/`).
    Robot,
    /// A motion file (`configs/motions/`).
    Motion,
    /// How the simulator's servo horns sit on their joints
    /// (`configs/sim/*-mounting.yaml`, for `servobus sim --mounting`).
    Mounting,
    /// A hand that moves the simulator's torque-off joints
    /// (`configs/sim/*-hand.yaml`, for `servobus sim --hand`).
    Hand,
}

impl Kind {
    /// Every kind, in the order `servobus list` shows them.
    pub const ALL: [Kind; 4] = [Kind::Robot, Kind::Motion, Kind::Mounting, Kind::Hand];

    /// The kind in one word, as messages name it (`robot`, `motion`,
    /// `mounting`, `hand`).
    pub fn word(self) -> &'static str {
        match self {
            Kind::Robot => "robot",
            Kind::Motion => "motion",
            Kind::Mounting => "mounting",
            Kind::Hand => "hand",
        }
    }

    /// The kind of the shipped file `rel` (`sim/so101-hand.yaml`).
    fn of(rel: &str) -> Kind {
        match rel.split_once('/') {
            Some(("robots", _)) => Kind::Robot,
            Some(("sim", file)) if file.ends_with("-hand.yaml") => Kind::Hand,
            Some(("sim", _)) => Kind::Mounting,
            _ => Kind::Motion,
        }
    }
}

macro_rules! shipped {
    ($dir:literal, $name:literal) => {
        BuiltinFile {
            path: concat!($dir, "/", $name, ".yaml"),
            text: include_str!(concat!("../../../configs/", $dir, "/", $name, ".yaml")),
        }
    };
}

static FILES: [BuiltinFile; 15] = [
    shipped!("robots", "so101"),
    shipped!("robots", "lekiwi"),
    shipped!("robots", "hexapod"),
    shipped!("robots", "hexapod-2bus"),
    shipped!("robots", "scs-mini"),
    shipped!("motions", "arm-wave"),
    shipped!("motions", "arm-pick-place"),
    shipped!("motions", "arm-line"),
    shipped!("motions", "hexapod-dance"),
    shipped!("motions", "hexapod-tripod"),
    shipped!("motions", "hexapod-walk-turn"),
    shipped!("motions", "scs-mini-nod"),
    shipped!("sim", "so101-mounting"),
    shipped!("sim", "so101-hand"),
    shipped!("sim", "so101-first-arm-hand"),
];

/// One built-in robot or motion.
#[derive(Debug, Clone, Copy)]
pub struct Builtin {
    /// Its name on the command line (`so101`, `arm-wave`).
    pub name: &'static str,
    /// Robot, motion, mounting or hand.
    pub kind: Kind,
    /// The file's text.
    pub text: &'static str,
    rel: &'static str,
}

impl Builtin {
    /// The path the configuration loaders read it under.
    pub fn path(&self) -> PathBuf {
        builtin_path(self.rel)
    }

    /// The first sentence of its leading comment (what it is), whole.
    pub fn sentence(&self) -> String {
        let comment: Vec<&str> = self
            .text
            .lines()
            .map_while(|l| l.strip_prefix('#'))
            .map(str::trim)
            .take_while(|l| !l.is_empty())
            .collect();
        let text = comment.join(" ");
        // Up to the first full stop or colon: the name of the thing.
        let end = [text.find(". "), text.find(": ")]
            .into_iter()
            .flatten()
            .min();
        match end {
            Some(i) => text[..i].to_owned(),
            None => text.trim_end_matches(['.', ':']).to_owned(),
        }
    }

    /// [`Builtin::sentence`] in at most about 70 characters, cut at a
    /// word.
    pub fn summary(&self) -> String {
        let sentence = self.sentence();
        if sentence.len() <= 72 {
            return sentence;
        }
        let cut = sentence[..72].rfind(' ').unwrap_or(72);
        format!("{}...", &sentence[..cut])
    }

    /// For a motion, the robot its `robot:` names: a built-in robot's name
    /// (`so101`) where it is one, else the path as written. `None` for the
    /// other kinds, or a motion that names no robot.
    pub fn robot(&self) -> Option<String> {
        if self.kind != Kind::Motion {
            return None;
        }
        let doc: serde_yaml::Value = serde_yaml::from_str(self.text).ok()?;
        let named = doc.get("robot")?.as_str()?;
        let stem = Path::new(named).file_stem().and_then(|s| s.to_str());
        match stem.and_then(|s| find(Kind::Robot, s)) {
            Some(robot) => Some(robot.name.to_owned()),
            None => Some(named.to_owned()),
        }
    }
}

/// The text of the shipped file `rel` (`robots/so101.yaml`).
pub(crate) fn text(rel: &str) -> Option<&'static str> {
    FILES.iter().find(|f| f.path == rel).map(|f| f.text)
}

/// Every built-in file, robots first, then motions, mountings and hands.
pub fn all() -> impl Iterator<Item = Builtin> {
    FILES.iter().filter_map(|f| {
        let (_, file) = f.path.split_once('/')?;
        let name = file.strip_suffix(".yaml")?;
        Some(Builtin {
            name,
            kind: Kind::of(f.path),
            text: f.text,
            rel: f.path,
        })
    })
}

/// The built-in of `kind` called `name` (with or without `.yaml`).
pub fn find(kind: Kind, name: &str) -> Option<Builtin> {
    let name = name.strip_suffix(".yaml").unwrap_or(name);
    all().find(|b| b.kind == kind && b.name == name)
}

/// The built-in whose name is nearest to `arg` (a mistyped name: `so100`,
/// `arm_wave`), when one is within two edits and `arg` is not already a
/// path with a directory; the first of equally near ones.
pub fn nearest(arg: &str) -> Option<Builtin> {
    if arg.contains('/') {
        return None;
    }
    let name = arg.strip_suffix(".yaml").unwrap_or(arg);
    all()
        .map(|b| (edits(name, b.name), b))
        .filter(|(d, _)| *d <= 2 && *d < name.chars().count())
        .min_by_key(|(d, _)| *d)
        .map(|(_, b)| b)
}

/// The Levenshtein distance between `a` and `b` (by characters, case
/// and `_`/`-` alike).
fn edits(a: &str, b: &str) -> usize {
    let norm = |c: char| {
        if c == '_' {
            '-'
        } else {
            c.to_ascii_lowercase()
        }
    };
    let b: Vec<char> = b.chars().map(norm).collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().map(norm).enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (k, cb) in b.iter().enumerate() {
            let up = row[k + 1];
            row[k + 1] = (diag + usize::from(ca != *cb)).min(up + 1).min(row[k] + 1);
            diag = up;
        }
    }
    row[b.len()]
}

/// The names of the built-ins of `kind`, comma-separated (for messages).
pub fn names(kind: Kind) -> String {
    all()
        .filter(|b| b.kind == kind)
        .map(|b| b.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The robot file to load for a `--robot` argument: `arg` itself when it is
/// an existing file (or not a built-in name), else the built-in robot of
/// that name.
pub fn robot_path_or_name(arg: &Path) -> PathBuf {
    path_or_name(Kind::Robot, arg)
}

/// The motion file to load for a motion argument: `arg` itself when it is an
/// existing file (or not a built-in name), else the built-in motion of that
/// name.
pub fn motion_path_or_name(arg: &Path) -> PathBuf {
    path_or_name(Kind::Motion, arg)
}

/// The robot file a motion file at `motion` names with `robot: <robot>`,
/// by the rule of a `--robot` argument ([`robot_path_or_name`]), taken
/// beside the motion: the file `robot` relative to the motion's directory
/// when it exists (a built-in motion's `../robots/so101.yaml` included),
/// else the built-in robot of that name (`robot: so101`), else that
/// relative path (whose absence the loader then reports).
pub fn motion_robot_path(motion: &Path, robot: &str) -> PathBuf {
    let beside = crate::files::tidy(motion.parent().unwrap_or(Path::new("")).join(robot));
    if beside.exists() || crate::files::builtin_text(&beside).is_some() {
        return beside;
    }
    match find(Kind::Robot, robot) {
        Some(b) => b.path(),
        None => beside,
    }
}

/// How a motion file written at `motion` names the robot file `robot` in
/// its `robot:`, so that [`motion_robot_path`] finds it again: a built-in
/// robot by its name (`so101`), any other file by its path relative to the
/// motion's directory (a folder holding both can be moved), or, when no
/// such path can be made (the motion's directory cannot be resolved, or is
/// on another drive), by its absolute path.
pub fn motion_robot_field(robot: &Path, motion: &Path) -> PathBuf {
    if let Some(name) = builtin_name(robot) {
        return PathBuf::from(name);
    }
    let Ok(target) = robot.canonicalize() else {
        return robot.to_owned();
    };
    let dir = motion.parent().filter(|d| !d.as_os_str().is_empty());
    let from = dir.unwrap_or(Path::new(".")).canonicalize();
    match from.ok().and_then(|from| relative_path(&from, &target)) {
        Some(rel) => rel,
        None => target,
    }
}

/// The path of `target` seen from the directory `from`, both absolute and
/// free of `.`, `..` and symbolic links (canonical); `None` when they share
/// no root (two Windows drives).
fn relative_path(from: &Path, target: &Path) -> Option<PathBuf> {
    let mut from_parts = from.components().peekable();
    let mut target_parts = target.components().peekable();
    match (from_parts.peek(), target_parts.peek()) {
        (Some(a), Some(b)) if a == b => {}
        _ => return None,
    }
    while let (Some(a), Some(b)) = (from_parts.peek(), target_parts.peek()) {
        if a != b {
            break;
        }
        from_parts.next();
        target_parts.next();
    }
    let mut rel = PathBuf::new();
    for _ in from_parts {
        rel.push("..");
    }
    for part in target_parts {
        rel.push(part);
    }
    Some(rel)
}

/// The file to load for an argument that takes a file or a built-in of
/// `kind`: `arg` itself when it is an existing file (or not a built-in
/// name), else the built-in of that name.
pub fn path_or_name(kind: Kind, arg: &Path) -> PathBuf {
    if arg.exists() {
        return arg.to_owned();
    }
    match arg.to_str().and_then(|s| find(kind, s)) {
        Some(b) => b.path(),
        None => arg.to_owned(),
    }
}

/// The name of the built-in file at `path` (`so101` for
/// `<built-in>/robots/so101.yaml`), when it is one.
pub fn builtin_name(path: &Path) -> Option<&'static str> {
    all().find(|b| b.path() == path).map(|b| b.name)
}

/// `path` as a command line takes it: a built-in file's name, any other
/// file's path.
pub fn argument(path: &Path) -> String {
    builtin_name(path).map_or_else(|| path.display().to_string(), str::to_owned)
}

/// The calibration file a robot file's `text` names in a commented-out
/// `# calibration: FILE` line (as the shipped robots and `servobus init`'s
/// copies do): the line to uncomment once the robot is calibrated.
pub fn commented_calibration(text: &str) -> Option<&str> {
    text.lines()
        .find_map(|line| line.trim_start().strip_prefix("# calibration:"))
        .and_then(|rest| rest.split_whitespace().next())
}

/// The text of the robot (or any) file at `path`: a built-in's own text,
/// else the file as it is on disk (`None` when it cannot be read).
pub fn file_text(path: &Path) -> Option<std::borrow::Cow<'static, str>> {
    match crate::files::builtin_text(path) {
        Some(text) => Some(std::borrow::Cow::Borrowed(text)),
        None => std::fs::read_to_string(path)
            .ok()
            .map(std::borrow::Cow::Owned),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{load_motion, load_robot, RobotOptions};

    #[test]
    fn a_shipped_robot_names_its_calibration_in_a_comment() {
        let text = file_text(&crate::files::builtin_path("robots/so101.yaml")).expect("built in");
        assert_eq!(
            commented_calibration(&text),
            Some("my-arm.calibration.yaml")
        );
        assert_eq!(commented_calibration("joints: []\n"), None);
        assert_eq!(
            commented_calibration("  # calibration: a.yaml   # relative\n"),
            Some("a.yaml")
        );
    }

    #[test]
    fn a_mistyped_name_finds_the_nearest_built_in() {
        let name = |arg: &str| nearest(arg).map(|b| b.name);
        assert_eq!(name("so100"), Some("so101"));
        assert_eq!(name("SO101.yaml"), Some("so101"));
        assert_eq!(name("arm_wave"), Some("arm-wave"));
        assert_eq!(name("hexapd"), Some("hexapod"));
        // Far from every name, or a path: no guess.
        assert_eq!(name("quadruped"), None);
        assert_eq!(name("configs/so100"), None);
        assert_eq!(name("x"), None);
    }

    #[test]
    fn every_shipped_file_is_built_in_and_loads() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
        let mut on_disk = 0;
        for sub in ["robots", "motions", "sim"] {
            for entry in std::fs::read_dir(dir.join(sub)).expect("configs dir") {
                let path = entry.expect("entry").path();
                let name = path.file_stem().and_then(|s| s.to_str()).expect("name");
                let b = all()
                    .find(|b| b.name == name)
                    .unwrap_or_else(|| panic!("{name} is not built in"));
                assert_eq!(b.text, std::fs::read_to_string(&path).expect("read"));
                on_disk += 1;
            }
        }
        assert_eq!(on_disk, all().count());
        // (The simulator's mountings and hands load in the facade's
        // `sim_body` tests.)
        for b in all() {
            match b.kind {
                Kind::Robot => {
                    drop(load_robot(&b.path(), &RobotOptions::default()).expect("robot loads"))
                }
                Kind::Motion => drop(load_motion(&b.path(), None).expect("motion loads")),
                Kind::Mounting | Kind::Hand => {}
            }
        }
        assert_eq!(
            find(Kind::Mounting, "so101-mounting").map(|b| b.kind),
            Some(Kind::Mounting)
        );
        assert_eq!(
            find(Kind::Hand, "so101-hand").map(|b| b.kind),
            Some(Kind::Hand)
        );
    }

    #[test]
    fn a_builtin_motion_uses_the_builtin_robot() {
        let (motion, robot) = load_motion(&motion_path_or_name(Path::new("arm-wave")), None)
            .expect("built-in motion");
        assert_eq!(robot.name, "so101");
        assert!(
            motion.robot_path.starts_with("<built-in>"),
            "{:?}",
            motion.robot_path
        );
    }

    #[test]
    fn summaries_are_one_short_sentence() {
        for b in all() {
            let s = b.summary();
            assert!(!s.is_empty() && s.len() <= 75, "{}: {s:?}", b.name);
            let full_stop = s.ends_with('.') && !s.ends_with("...");
            assert!(!full_stop && !s.contains(". "), "{}: {s:?}", b.name);
        }
        let arm = find(Kind::Robot, "so101").expect("so101");
        assert_eq!(arm.summary(), "SO-101-style 6-joint arm");
    }

    #[test]
    fn every_motion_names_its_built_in_robot() {
        for b in all() {
            let robot = b.robot();
            if b.kind == Kind::Motion {
                let name = robot.unwrap_or_default();
                assert!(find(Kind::Robot, &name).is_some(), "{}: {name:?}", b.name);
            } else {
                assert_eq!(robot, None, "{}", b.name);
            }
        }
        let walk = find(Kind::Motion, "hexapod-walk-turn").expect("walk");
        assert_eq!(walk.robot().as_deref(), Some("hexapod"));
    }

    #[test]
    fn names_resolve_and_paths_stay() {
        // The command-line test `a_file_named_like_a_builtin_wins` runs
        // this with a file called `so101` in the working directory.
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/robots/so101.yaml");
        assert_eq!(robot_path_or_name(&file), file);
        assert!(robot_path_or_name(Path::new("so101")).starts_with("<built-in>"));
        assert_eq!(robot_path_or_name(Path::new("nope")), Path::new("nope"));
    }

    #[test]
    fn relative_paths_climb_to_the_common_directory() {
        let rel = |from: &str, to: &str| relative_path(Path::new(from), Path::new(to));
        assert_eq!(rel("/a/b", "/a/b/r.yaml"), Some("r.yaml".into()));
        assert_eq!(rel("/a/b/m", "/a/b/r.yaml"), Some("../r.yaml".into()));
        assert_eq!(rel("/a/x/y", "/a/b/r.yaml"), Some("../../b/r.yaml".into()));
        assert_eq!(rel("/", "/a/r.yaml"), Some("a/r.yaml".into()));
        assert_eq!(rel("a", "/a/r.yaml"), None);
    }

    #[test]
    fn a_motion_names_a_builtin_robot_by_name_and_a_file_relative_to_it() {
        let so101 = robot_path_or_name(Path::new("so101"));
        let motion = Path::new("anywhere/taught.yaml");
        assert_eq!(motion_robot_field(&so101, motion), Path::new("so101"));
        // A file: relative to the motion's directory, which finds it again.
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
        let robot = dir.join("../../configs/robots/so101.yaml");
        let motion = dir.join("src/taught.yaml");
        let field = motion_robot_field(&robot, &motion);
        assert_eq!(field, Path::new("../../../configs/robots/so101.yaml"));
        let found = motion_robot_path(&motion, field.to_str().expect("UTF-8"));
        assert_eq!(
            found.canonicalize().expect("found"),
            robot.canonicalize().expect("the robot")
        );
    }

    #[test]
    fn a_builtin_is_named_by_its_name_and_a_file_by_its_path() {
        assert_eq!(argument(&robot_path_or_name(Path::new("so101"))), "so101");
        assert_eq!(argument(Path::new("arm/robot.yaml")), "arm/robot.yaml");
        let hand = path_or_name(Kind::Hand, Path::new("so101-hand"));
        assert_eq!(argument(&hand), "so101-hand");
        // A built-in of another kind is not found under that name.
        assert_eq!(
            path_or_name(Kind::Mounting, Path::new("so101-hand")),
            Path::new("so101-hand")
        );
    }
}
