//! Who serves a pseudo-terminal: a second simulator must not take the
//! link of one that is running.
//!
//! A [`PtyServer`](super::PtyServer) holds both ends of its terminal open:
//! the master (`/dev/ptmx`, whose `/proc/PID/fdinfo` gives the terminal's
//! number as `tty-index`) and the slave (`/dev/pts/N`). A terminal emulator
//! or `sshd` holds only the master, a shell or a client only the slave, so
//! a process holding both is a server. Linux only (and only processes the
//! user may inspect); elsewhere no server is ever found and links are
//! replaced as before.

use std::path::Path;

/// A process serving a pseudo-terminal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Server {
    /// Its process ID.
    pub pid: u32,
    /// Its name (`/proc/PID/comm`), when it can be read.
    pub name: Option<String>,
}

impl std::fmt::Display for Server {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.name {
            Some(name) => write!(f, "{name} (pid {})", self.pid),
            None => write!(f, "pid {}", self.pid),
        }
    }
}

/// The process other than this one that serves `pty` (`/dev/pts/N`),
/// holding both its ends; `None` when there is none, or `pty` is no
/// `/dev/pts` terminal.
pub(crate) fn server_of(pty: &Path) -> Option<Server> {
    let index: u32 = pty.strip_prefix("/dev/pts").ok()?.to_str()?.parse().ok()?;
    let me = std::process::id();
    let procs = std::fs::read_dir("/proc").ok()?;
    for entry in procs.flatten() {
        let Some(pid) = entry
            .file_name()
            .to_str()
            .and_then(|s| s.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != me && serves(&entry.path(), index, pty) {
            let comm = std::fs::read_to_string(entry.path().join("comm")).ok();
            let name = comm.map(|c| c.trim().to_owned()).filter(|c| !c.is_empty());
            return Some(Server { pid, name });
        }
    }
    None
}

/// Whether the process at `/proc/PID` (`proc`) holds the master of
/// terminal `index` and its slave `pty`.
fn serves(proc: &Path, index: u32, pty: &Path) -> bool {
    let Ok(fds) = std::fs::read_dir(proc.join("fd")) else {
        return false;
    };
    let (mut master, mut slave) = (false, false);
    for fd in fds.flatten() {
        let Ok(to) = std::fs::read_link(fd.path()) else {
            continue;
        };
        if to == pty {
            slave = true;
        } else if to == Path::new("/dev/ptmx") || to == Path::new("/dev/pts/ptmx") {
            let info = std::fs::read_to_string(proc.join("fdinfo").join(fd.file_name()));
            master |= info.is_ok_and(|text| tty_index(&text) == Some(index));
        }
        if master && slave {
            return true;
        }
    }
    false
}

/// The `tty-index:` of a pty master's `fdinfo`.
fn tty_index(fdinfo: &str) -> Option<u32> {
    fdinfo
        .lines()
        .find_map(|line| line.strip_prefix("tty-index:"))
        .and_then(|v| v.trim().parse().ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_terminal_number_is_read_from_fdinfo() {
        let text = "pos:\t0\nflags:\t02100002\nmnt_id:\t24\nino:\t91\ntty-index:\t7\n";
        assert_eq!(tty_index(text), Some(7));
        assert_eq!(tty_index("pos:\t0\n"), None);
        assert_eq!(server_of(Path::new("/dev/ttyUSB0")), None);
        assert_eq!(server_of(Path::new("/dev/pts/ptmx")), None);
    }
}
