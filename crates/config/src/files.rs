//! Built-in files: robot and motion texts compiled into a program and read
//! through the same loaders as files on disk.
//!
//! The shipped robots, motions and simulator examples
//! ([`builtin`](crate::builtin)) are addressed by paths under
//! [`BUILTIN_DIR`] (`<built-in>/robots/so101.yaml`). A built-in motion's
//! `robot: ../robots/so101.yaml` therefore resolves to the built-in robot
//! exactly as it would next to the file on disk, and errors point into the
//! built-in text with the same `file:line:column` as for any file.

use std::path::{Component, Path, PathBuf};

/// The first component of every built-in file's path. It cannot be a real
/// directory name by accident (the angle brackets are unusual in paths).
pub const BUILTIN_DIR: &str = "<built-in>";

/// One built-in file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BuiltinFile {
    /// Path below [`BUILTIN_DIR`], with `/` separators (`robots/so101.yaml`).
    pub path: &'static str,
    /// The file's text.
    pub text: &'static str,
}

/// The path under which the built-in file `rel` (`robots/so101.yaml`) is read.
pub fn builtin_path(rel: &str) -> PathBuf {
    Path::new(BUILTIN_DIR).join(rel)
}

/// Whether `path` names a built-in file (one that exists or not).
pub fn is_builtin_path(path: &Path) -> bool {
    path.components().next() == Some(Component::Normal(BUILTIN_DIR.as_ref()))
}

/// `path` with `.` and `..` resolved, when it is a built-in path (so that
/// `<built-in>/motions/../robots/so101.yaml` prints as
/// `<built-in>/robots/so101.yaml`); other paths are returned as they are,
/// since on disk `..` after a symbolic link is not lexical.
pub(crate) fn tidy(path: PathBuf) -> PathBuf {
    if !is_builtin_path(&path) {
        return path;
    }
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir if out.components().count() > 1 => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

/// The text of the built-in file at `path`, after resolving `..` and `.`
/// lexically (a built-in motion's `robot:` is relative to it).
pub(crate) fn builtin_text(path: &Path) -> Option<&'static str> {
    if !is_builtin_path(path) {
        return None;
    }
    let mut parts: Vec<&str> = Vec::new();
    for c in path.components().skip(1) {
        match c {
            Component::Normal(s) => parts.push(s.to_str()?),
            Component::ParentDir => {
                parts.pop()?;
            }
            Component::CurDir => {}
            Component::RootDir | Component::Prefix(_) => return None,
        }
    }
    crate::builtin::text(&parts.join("/"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_between_builtin_files_resolve() {
        let motion = builtin_path("motions/arm-wave.yaml");
        assert!(builtin_text(&motion).is_some_and(|t| t.contains("keyframes:")));
        let robot = motion.parent().map(|d| d.join("../robots/./so101.yaml"));
        assert!(robot
            .as_deref()
            .and_then(builtin_text)
            .is_some_and(|t| t.contains("name: so101")));
        assert_eq!(builtin_text(&builtin_path("robots/none.yaml")), None);
        assert_eq!(builtin_text(&builtin_path("../../etc/passwd")), None);
        assert_eq!(builtin_text(Path::new("robots/so101.yaml")), None);
        let tidy_robot = tidy(builtin_path("motions/../robots/./so101.yaml"));
        assert_eq!(tidy_robot, builtin_path("robots/so101.yaml"));
    }
}
