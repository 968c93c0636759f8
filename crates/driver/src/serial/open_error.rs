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
        /// The programs holding it, when they can be found.
        holders: Vec<Holder>,
    },
    /// The path is there but is no serial port.
    NotSerial {
        /// What it is instead.
        what: NotSerial,
    },
    /// The port was given as an empty string (`--port ''`).
    Empty,
    /// `/dev/tty`: the terminal of the program itself, never the servos'
    /// adapter (opening it would send packets to the user's screen).
    OwnTerminal,
    /// A symbolic link that leads back to itself (`ELOOP`).
    LinkLoop,
    /// Anything else, in the operating system's words.
    Other(String),
}

/// A program that has a port open.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Holder {
    /// Its process ID.
    pub pid: u32,
    /// Its name (`/proc/PID/comm`), when it can be read.
    pub name: Option<String>,
}

impl fmt::Display for Holder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.name {
            Some(name) => write!(f, "{name} (pid {})", self.pid),
            None => write!(f, "pid {}", self.pid),
        }
    }
}

/// What a path given as a port is, when it is no serial port.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum NotSerial {
    /// A directory.
    Directory,
    /// A regular file.
    RegularFile,
    /// Something else that is no character device (a socket, a pipe).
    NotCharDevice,
    /// A character device that is not a terminal (`/dev/null`).
    NotTerminal,
}

impl fmt::Display for NotSerial {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NotSerial::Directory => "a directory",
            NotSerial::RegularFile => "a regular file",
            NotSerial::NotCharDevice => "not a character device",
            NotSerial::NotTerminal => "a device that is not a terminal",
        })
    }
}

impl OpenError {
    /// Sorts a failure to open `path`: `kind` as the operating system
    /// reported it, `locked` when the port refused exclusive access (the
    /// `TIOCEXCL` flag or the `flock` of another program), `text` the
    /// message. The path itself is looked at too, since the `errno` of a
    /// failed open is not always carried this far.
    pub(crate) fn classify(path: &str, kind: io::ErrorKind, locked: bool, text: &str) -> Self {
        if let Some(refused) = Self::before_open(path) {
            return refused;
        }
        let lower = text.to_ascii_lowercase();
        let file = Path::new(path);
        let problem =
            if kind == io::ErrorKind::PermissionDenied || lower.contains("permission denied") {
                OpenProblem::PermissionDenied {
                    group: owning_group(file),
                }
            } else if !file.exists() {
                OpenProblem::NotFound {
                    present: present_ports(),
                }
            } else if let Some(what) = not_a_device(file) {
                OpenProblem::NotSerial { what }
            } else if locked || lower.contains("busy") {
                OpenProblem::Busy {
                    holders: holders(file),
                }
            } else if lower.contains("typewriter") || lower.contains("inappropriate ioctl") {
                OpenProblem::NotSerial {
                    what: NotSerial::NotTerminal,
                }
            } else if kind == io::ErrorKind::NotFound || lower.contains("no such device") {
                OpenProblem::NotFound {
                    present: present_ports(),
                }
            } else {
                OpenProblem::Other(plain_os_text(text))
            };
        OpenError {
            path: path.to_owned(),
            problem,
        }
    }

    /// A path refused before it is opened: an empty one, the program's own
    /// terminal (`/dev/tty`, or a link to it), or a symbolic link loop.
    /// Opening `/dev/tty` would succeed and write packets to the screen;
    /// the other two would fail with a misleading "no such port".
    pub(crate) fn before_open(path: &str) -> Option<Self> {
        let problem = if path.is_empty() {
            OpenProblem::Empty
        } else if is_own_terminal(Path::new(path)) {
            OpenProblem::OwnTerminal
        } else if is_link_loop(Path::new(path)) {
            OpenProblem::LinkLoop
        } else {
            return None;
        };
        Some(OpenError {
            path: path.to_owned(),
            problem,
        })
    }

    /// The `io::ErrorKind` that best matches the problem.
    pub(crate) fn kind(&self) -> io::ErrorKind {
        match self.problem {
            OpenProblem::PermissionDenied { .. } => io::ErrorKind::PermissionDenied,
            OpenProblem::NotFound { .. } => io::ErrorKind::NotFound,
            OpenProblem::NotSerial { .. }
            | OpenProblem::Empty
            | OpenProblem::OwnTerminal
            | OpenProblem::LinkLoop => io::ErrorKind::InvalidInput,
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
        if self.problem == OpenProblem::Empty {
            return f.write_str(
                "the port is empty: give the servos' adapter, e.g. --port /dev/ttyUSB0, or no \
                 --port for the simulator",
            );
        }
        write!(f, "cannot open {}: ", self.path)?;
        match &self.problem {
            OpenProblem::Empty => Ok(()),
            OpenProblem::OwnTerminal => f.write_str(
                "that is this program's own terminal, not a serial port; give the servos' \
                 adapter, e.g. /dev/ttyUSB0",
            ),
            OpenProblem::LinkLoop => f.write_str(
                "the symbolic link leads back to itself (a loop of links); point it at the \
                 servos' adapter, e.g. /dev/ttyUSB0",
            ),
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
            OpenProblem::Busy { holders } => {
                f.write_str("the port is busy: ")?;
                for (i, holder) in holders.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{holder}")?;
                }
                f.write_str(" has it open; close it and retry")
            }
            OpenProblem::NotSerial { what } => {
                write!(
                    f,
                    "not a serial port ({what}); give the servos' adapter, e.g. /dev/ttyUSB0"
                )
            }
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

/// What `path` is when it is no character device; `None` for a device, or
/// when it cannot be told.
fn not_a_device(path: &Path) -> Option<NotSerial> {
    let meta = std::fs::metadata(path).ok()?;
    if meta.is_dir() {
        return Some(NotSerial::Directory);
    }
    if meta.is_file() {
        return Some(NotSerial::RegularFile);
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if !meta.file_type().is_char_device() {
            return Some(NotSerial::NotCharDevice);
        }
    }
    None
}

/// Whether `path` is, or links to, `/dev/tty`: the controlling terminal of
/// whichever process opens it.
fn is_own_terminal(path: &Path) -> bool {
    let tty = Path::new("/dev/tty");
    path == tty || std::fs::canonicalize(path).is_ok_and(|p| p == tty)
}

/// Whether `path` is a symbolic link that cannot be followed because the
/// links loop (`ELOOP`, or more than 40 links in a row where that error
/// cannot be read).
fn is_link_loop(path: &Path) -> bool {
    let Ok(link) = std::fs::symlink_metadata(path) else {
        return false;
    };
    if !link.file_type().is_symlink() {
        return false;
    }
    match std::fs::metadata(path) {
        Ok(_) => false,
        #[cfg(unix)]
        Err(e) => e.raw_os_error() == Some(libc::ELOOP),
        #[cfg(not(unix))]
        Err(_) => false,
    }
}

/// An operating system's message without its `(os error N)` suffix.
fn plain_os_text(text: &str) -> String {
    match text.find(" (os error ") {
        Some(at) => text[..at].to_owned(),
        None => text.to_owned(),
    }
}

/// Programs holding `path`, as `name (pid N)`: the holder of its `flock`
/// (from `/proc/locks`) when there is one, else every program with it open
/// (from the `/proc/*/fd` links). Linux only (and only processes the user
/// may inspect); none elsewhere.
fn holders(path: &Path) -> Vec<Holder> {
    let lockers = lock_holders(path);
    if !lockers.is_empty() {
        return lockers;
    }
    let Ok(target) = std::fs::canonicalize(path) else {
        return Vec::new();
    };
    let Ok(procs) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    let mut found = Vec::new();
    for entry in procs.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(|s| s.parse::<u32>().ok()) else {
            continue;
        };
        let Ok(fds) = std::fs::read_dir(entry.path().join("fd")) else {
            continue;
        };
        let holds = fds
            .flatten()
            .any(|fd| std::fs::read_link(fd.path()).is_ok_and(|link| link == target));
        if holds && pid != std::process::id() {
            found.push(holder(pid));
        }
    }
    found
}

/// The process `pid`, named when its name can be read.
fn holder(pid: u32) -> Holder {
    let comm = std::fs::read_to_string(Path::new("/proc").join(pid.to_string()).join("comm"));
    let name = comm
        .ok()
        .map(|c| c.trim().to_owned())
        .filter(|c| !c.is_empty());
    Holder { pid, name }
}

/// The processes holding a `flock` on `path`, from `/proc/locks`, whose
/// lines read `1: FLOCK ADVISORY WRITE <pid> <major>:<minor>:<inode> 0 EOF`
/// (major and minor of the file system's device, in hex).
fn lock_holders(path: &Path) -> Vec<Holder> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let Ok(meta) = std::fs::metadata(path) else {
            return Vec::new();
        };
        let Ok(locks) = std::fs::read_to_string("/proc/locks") else {
            return Vec::new();
        };
        let (major, minor) = split_dev(meta.dev());
        let me = std::process::id();
        let mut found = Vec::new();
        for line in locks.lines() {
            let fields: Vec<&str> = line.split_whitespace().collect();
            // A blocked waiter's line has a `->` field more; skip it.
            let (Some(&"FLOCK"), Some(pid), Some(file)) =
                (fields.get(1), fields.get(4), fields.get(5))
            else {
                continue;
            };
            let mut parts = file.split(':');
            let (Some(maj), Some(min), Some(ino)) = (parts.next(), parts.next(), parts.next())
            else {
                continue;
            };
            let same = u64::from_str_radix(maj, 16).ok() == Some(major)
                && u64::from_str_radix(min, 16).ok() == Some(minor)
                && ino.parse::<u64>().ok() == Some(meta.ino());
            match pid.parse::<u32>() {
                Ok(pid) if same && pid != me => found.push(holder(pid)),
                _ => {}
            }
        }
        found.dedup();
        found
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        Vec::new()
    }
}

/// The major and minor numbers of a Linux device number (glibc's
/// `gnu_dev_major` and `gnu_dev_minor`).
#[cfg(unix)]
fn split_dev(dev: u64) -> (u64, u64) {
    let major = ((dev >> 8) & 0xfff) | ((dev >> 32) & !0xfff);
    let minor = (dev & 0xff) | ((dev >> 12) & !0xff);
    (major, minor)
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
    fn the_holders_of_a_busy_port_are_named_with_their_pids() {
        let busy = OpenError {
            path: "/dev/ttyACM0".into(),
            problem: OpenProblem::Busy {
                holders: vec![
                    Holder {
                        pid: 1234,
                        name: Some("minicom".into()),
                    },
                    Holder {
                        pid: 99,
                        name: None,
                    },
                ],
            },
        };
        assert_eq!(
            busy.to_string(),
            "cannot open /dev/ttyACM0: the port is busy: minicom (pid 1234), pid 99 has it \
             open; close it and retry"
        );
    }

    #[test]
    #[cfg(unix)]
    fn an_empty_port_the_own_terminal_and_a_link_loop_say_what_they_are() {
        let empty = OpenError::before_open("").expect("refused");
        assert_eq!(empty.problem, OpenProblem::Empty);
        assert_eq!(
            empty.to_string(),
            "the port is empty: give the servos' adapter, e.g. --port /dev/ttyUSB0, or no \
             --port for the simulator"
        );
        let tty = OpenError::before_open("/dev/tty").expect("refused");
        assert_eq!(
            tty.to_string(),
            "cannot open /dev/tty: that is this program's own terminal, not a serial port; \
             give the servos' adapter, e.g. /dev/ttyUSB0"
        );
        assert_eq!(tty.kind(), io::ErrorKind::InvalidInput);
        let dir = std::env::temp_dir().join(format!("servobus-open-loop-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("a scratch directory");
        let (a, b) = (dir.join("a"), dir.join("b"));
        std::os::unix::fs::symlink(&b, &a).expect("a -> b");
        std::os::unix::fs::symlink(&a, &b).expect("b -> a");
        let own = dir.join("own");
        std::os::unix::fs::symlink("/dev/tty", &own).expect("own -> /dev/tty");
        let looped = OpenError::classify(
            &a.to_string_lossy(),
            io::ErrorKind::Other,
            false,
            "Too many levels of symbolic links (os error 40)",
        );
        assert_eq!(looped.problem, OpenProblem::LinkLoop);
        assert!(
            looped.to_string().ends_with(
                "the symbolic link leads back to itself (a loop of links); point it at the \
                 servos' adapter, e.g. /dev/ttyUSB0"
            ),
            "{looped}"
        );
        let own = OpenError::before_open(&own.to_string_lossy()).expect("refused");
        assert_eq!(own.problem, OpenProblem::OwnTerminal);
        // An ordinary missing path and a device are not refused early.
        assert_eq!(OpenError::before_open("/dev/servobus-none"), None);
        assert_eq!(OpenError::before_open("/dev/null"), None);
        std::fs::remove_dir_all(&dir).expect("cleaned up");
    }

    #[test]
    fn a_missing_path_is_not_found() {
        let e = OpenError::classify("/dev/servobus-none", io::ErrorKind::Other, false, "x");
        assert!(matches!(e.problem, OpenProblem::NotFound { .. }), "{e:?}");
    }

    #[test]
    fn a_locked_device_is_busy_not_missing() {
        // What the serialport crate says when another program holds the
        // port's flock: `NoDevice`, with no errno.
        let text = "Unable to acquire exclusive lock on serial port";
        let e = OpenError::classify("/dev/null", io::ErrorKind::NotFound, true, text);
        assert!(matches!(e.problem, OpenProblem::Busy { .. }), "{e:?}");
        assert!(
            e.to_string()
                .starts_with("cannot open /dev/null: the port is busy"),
            "{e}"
        );
    }

    #[test]
    fn a_file_or_directory_is_not_a_serial_port() {
        let dir = std::env::temp_dir();
        let e = OpenError::classify(
            &dir.to_string_lossy(),
            io::ErrorKind::Other,
            false,
            "EISDIR",
        );
        assert_eq!(
            e.problem,
            OpenProblem::NotSerial {
                what: NotSerial::Directory
            }
        );
        let e = OpenError::classify("/dev/null", io::ErrorKind::Other, false, "Not a typewriter");
        assert_eq!(e.to_string(), "cannot open /dev/null: not a serial port (a device that is not a terminal); give the servos' adapter, e.g. /dev/ttyUSB0");
        assert_eq!(split_dev(0x0000_0000_0000_1a01), (0x1a, 0x01));
        assert_eq!(split_dev(136 << 8 | 4), (136, 4));
    }
}
