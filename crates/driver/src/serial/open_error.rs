//! Why a serial port could not be opened, with what to do about it.
//!
//! The three common failures each have a remedy the user can act on: a port
//! they may not open (join the group that owns the device), a port that is
//! not there (these ports are), a port another program holds (this one).

use std::fmt;
use std::io;
use std::path::Path;

/// A serial port that could not be opened. Carried inside the
/// [`TransportError::Io`](crate::TransportError::Io) that
/// [`SerialTransport::open`](crate::SerialTransport::open) returns (as the
/// `io::Error`'s inner error), so a program can find it with
/// [`OpenError::find`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OpenError {
    /// The port as given.
    pub path: String,
    /// What went wrong.
    pub problem: OpenProblem,
}

/// What went wrong opening a port.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum OpenProblem {
    /// The user may not open the device.
    PermissionDenied {
        /// The group that owns the device (`dialout`, `uucp`), when known.
        group: Option<String>,
    },
    /// No such port.
    NotFound {
        /// The serial ports that are present.
        present: Vec<String>,
    },
    /// Another program has the port open.
    Busy {
        /// The programs holding it (`minicom (pid 1234)`), when they can be found.
        holders: Vec<String>,
    },
    /// Anything else, in the operating system's words.
    Other(String),
}

impl OpenError {
    /// Sorts a failure to open `path`: `kind` and `errno` as the operating
    /// system reported them, `text` its message.
    pub(crate) fn classify(
        path: &str,
        kind: io::ErrorKind,
        errno: Option<i32>,
        text: &str,
    ) -> Self {
        const EBUSY: i32 = 16;
        const ENOENT: i32 = 2;
        const ENODEV: i32 = 19;
        const EACCES: i32 = 13;
        let lower = text.to_ascii_lowercase();
        let problem = if kind == io::ErrorKind::PermissionDenied
            || errno == Some(EACCES)
            || lower.contains("permission denied")
        {
            OpenProblem::PermissionDenied {
                group: owning_group(Path::new(path)),
            }
        } else if errno == Some(EBUSY) || lower.contains("busy") {
            OpenProblem::Busy {
                holders: holders(Path::new(path)),
            }
        } else if kind == io::ErrorKind::NotFound
            || matches!(errno, Some(ENOENT | ENODEV))
            || !Path::new(path).exists()
        {
            OpenProblem::NotFound {
                present: present_ports(),
            }
        } else {
            OpenProblem::Other(text.to_owned())
        };
        OpenError {
            path: path.to_owned(),
            problem,
        }
    }

    /// The `io::ErrorKind` that best matches the problem.
    pub(crate) fn kind(&self) -> io::ErrorKind {
        match self.problem {
            OpenProblem::PermissionDenied { .. } => io::ErrorKind::PermissionDenied,
            OpenProblem::NotFound { .. } => io::ErrorKind::NotFound,
            OpenProblem::Busy { .. } | OpenProblem::Other(_) => io::ErrorKind::Other,
        }
    }

    /// The `OpenError` inside `error` or any of its sources.
    pub fn find<'a>(error: &'a (dyn std::error::Error + 'static)) -> Option<&'a OpenError> {
        let mut next = Some(error);
        while let Some(e) = next {
            if let Some(open) = e.downcast_ref::<OpenError>() {
                return Some(open);
            }
            if let Some(inner) = e
                .downcast_ref::<io::Error>()
                .and_then(|io| io.get_ref())
                .and_then(|inner| inner.downcast_ref::<OpenError>())
            {
                return Some(inner);
            }
            next = e.source();
        }
        None
    }
}

impl fmt::Display for OpenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot open {}: ", self.path)?;
        match &self.problem {
            OpenProblem::PermissionDenied { group: Some(group) } => write!(
                f,
                "permission denied. Add your user to the `{group}` group, which owns the port \
                 (`sudo usermod -aG {group} $USER`), then log out and back in"
            ),
            OpenProblem::PermissionDenied { group: None } => f.write_str(
                "permission denied. Add your user to the group of serial ports, `dialout` \
                 (`uucp` on Arch): `sudo usermod -aG dialout $USER`, then log out and back in",
            ),
            OpenProblem::NotFound { present } if present.is_empty() => f.write_str(
                "no such port, and no serial ports are present (is the adapter plugged in?)",
            ),
            OpenProblem::NotFound { present } => {
                write!(f, "no such port; ports present: {}", present.join(", "))
            }
            OpenProblem::Busy { holders } if holders.is_empty() => {
                f.write_str("the port is busy: another program has it open; close it and retry")
            }
            OpenProblem::Busy { holders } => write!(
                f,
                "the port is busy: {} has it open; close it and retry",
                holders.join(", ")
            ),
            OpenProblem::Other(text) => f.write_str(text),
        }
    }
}

impl std::error::Error for OpenError {}

/// The name of the group that owns the device file.
fn owning_group(path: &Path) -> Option<String> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let gid = std::fs::metadata(path).ok()?.gid();
        let groups = std::fs::read_to_string("/etc/group").ok()?;
        groups.lines().find_map(|line| {
            let mut fields = line.split(':');
            let name = fields.next()?;
            let id = fields.nth(1)?.parse::<u32>().ok()?;
            (id == gid && id != 0).then(|| name.to_owned())
        })
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        None
    }
}

/// The serial ports present, by name.
fn present_ports() -> Vec<String> {
    let mut ports: Vec<String> = serialport::available_ports()
        .map(|v| v.into_iter().map(|p| p.port_name).collect())
        .unwrap_or_default();
    ports.sort();
    ports.dedup();
    ports
}

/// Programs with `path` open, as `name (pid N)`: found through `/proc` on
/// Linux (only processes the user may inspect), none elsewhere.
fn holders(path: &Path) -> Vec<String> {
    let Ok(target) = std::fs::canonicalize(path) else {
        return Vec::new();
    };
    let Ok(procs) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    let mut found = Vec::new();
    for entry in procs.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .filter(|s| s.bytes().all(|b| b.is_ascii_digit()))
        else {
            continue;
        };
        let Ok(fds) = std::fs::read_dir(entry.path().join("fd")) else {
            continue;
        };
        let holds = fds
            .flatten()
            .any(|fd| std::fs::read_link(fd.path()).is_ok_and(|link| link == target));
        if holds && pid != std::process::id().to_string() {
            let comm = std::fs::read_to_string(entry.path().join("comm")).unwrap_or_default();
            found.push(format!("{} (pid {pid})", comm.trim()));
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_problem_says_what_to_do_once() {
        let denied = OpenError {
            path: "/dev/ttyUSB0".into(),
            problem: OpenProblem::PermissionDenied {
                group: Some("dialout".into()),
            },
        }
        .to_string();
        assert!(
            denied.contains("sudo usermod -aG dialout $USER"),
            "{denied}"
        );
        assert_eq!(denied.matches("permission denied").count(), 1, "{denied}");
        let missing = OpenError {
            path: "/dev/ttyUSB9".into(),
            problem: OpenProblem::NotFound {
                present: vec!["/dev/ttyACM0".into()],
            },
        }
        .to_string();
        assert_eq!(
            missing,
            "cannot open /dev/ttyUSB9: no such port; ports present: /dev/ttyACM0"
        );
    }

    #[test]
    fn a_missing_path_is_not_found() {
        let e = OpenError::classify("/dev/servobus-none", io::ErrorKind::Other, None, "x");
        assert!(matches!(e.problem, OpenProblem::NotFound { .. }), "{e:?}");
        let e = OpenError::classify("/dev/null", io::ErrorKind::Other, Some(16), "x");
        assert!(matches!(e.problem, OpenProblem::Busy { .. }), "{e:?}");
    }
}
