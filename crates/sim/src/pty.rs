//! The wall-clock server: the simulated bus behind a pseudo-terminal, so that
//! any program that opens a serial port (Feetech's SDK, LeRobot, the
//! `servobus` commands) can talk to it.
//!
//! Bytes the client writes reach the servos as if sent at the baud rate;
//! replies are released to the client at the times the wire would deliver
//! them (or at once with pacing off). The baud rate the client sets on the
//! terminal is honoured: servos at another rate do not hear it.

use std::ffi::CStr;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use servobus_io::{Clock, SystemClock};
use servobus_timing::Link;

use crate::engine::{Engine, SimStats};
use crate::{Faults, SimServo};
pub use owner::Server;

/// Why the pty server could not start or stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PtyError {
    /// Creating or configuring the pseudo-terminal failed.
    #[error("cannot create a pseudo-terminal: {0}")]
    Open(#[source] io::Error),
    /// The link path exists and is not a symbolic link (it is never replaced).
    #[error("{0} exists and is not a symbolic link; refusing to replace it")]
    LinkOccupied(PathBuf),
    /// The link points at the pseudo-terminal of a simulator that is
    /// running in another process: it is not taken from it.
    #[error(
        "{link} is the link of a running simulator: {server} serves {} through it; stop that \
         simulator or choose another link",
        pty.display()
    )]
    LinkServed {
        /// The link path.
        link: PathBuf,
        /// The pseudo-terminal it points at.
        pty: PathBuf,
        /// The process serving it.
        server: Server,
    },
    /// Creating the symbolic link failed.
    #[error("cannot create the link {path}: {source}")]
    Link {
        /// The link path.
        path: PathBuf,
        /// The cause.
        #[source]
        source: io::Error,
    },
    /// Reading or writing the pseudo-terminal failed while serving.
    #[error("pseudo-terminal I/O failed: {0}")]
    Io(#[source] io::Error),
}

#[path = "owner.rs"]
mod owner;

/// Waits for a reply shorter than this are timed precisely (sleep, then spin).
const SHORT_WAIT: Duration = Duration::from_millis(2);
/// The spinning part of a precise wait.
const SPIN: Duration = Duration::from_micros(150);

/// A simulated bus served on a pseudo-terminal in wall-clock time.
///
/// The link (if any) is removed when the server is dropped, unless it
/// points elsewhere by then (another server took the path over).
#[derive(Debug)]
pub struct PtyServer {
    master: OwnedFd,
    /// Kept open so that the master never sees a hang-up between clients,
    /// and to read the baud rate the client sets.
    slave: OwnedFd,
    path: PathBuf,
    link: Option<PathBuf>,
    engine: Engine,
    clock: SystemClock,
    pacing: bool,
    configured_baud: u32,
    /// Step the servos at least this often, even when no client talks.
    tick: Option<Duration>,
}

fn last_error() -> io::Error {
    io::Error::last_os_error()
}

fn check(rc: libc::c_int) -> io::Result<libc::c_int> {
    if rc < 0 {
        Err(last_error())
    } else {
        Ok(rc)
    }
}

impl PtyServer {
    /// Creates a pseudo-terminal serving `servos` on a bus at `baud`, with
    /// pacing on.
    ///
    /// # Errors
    /// [`PtyError::Open`] when the system refuses a pseudo-terminal.
    pub fn open(
        baud: u32,
        servos: impl IntoIterator<Item = SimServo>,
    ) -> Result<PtyServer, PtyError> {
        let (master, slave, path) = open_pty(baud).map_err(PtyError::Open)?;
        let mut engine = Engine::new(baud);
        for s in servos {
            engine.add_servo(s);
        }
        Ok(PtyServer {
            master,
            slave,
            path,
            link: None,
            engine,
            clock: SystemClock::new(),
            pacing: true,
            configured_baud: baud,
            tick: None,
        })
    }

    /// Makes `link` a symbolic link to the terminal (replacing an old
    /// symbolic link there, never a file, nor the link of a simulator
    /// running in another process).
    ///
    /// # Errors
    /// [`PtyError::LinkOccupied`], [`PtyError::LinkServed`] or
    /// [`PtyError::Link`].
    pub fn link_to(&mut self, link: &Path) -> Result<(), PtyError> {
        if let Ok(meta) = std::fs::symlink_metadata(link) {
            if !meta.file_type().is_symlink() {
                return Err(PtyError::LinkOccupied(link.to_owned()));
            }
            if let Ok(pty) = std::fs::read_link(link) {
                if let Some(server) = owner::server_of(&pty) {
                    return Err(PtyError::LinkServed {
                        link: link.to_owned(),
                        pty,
                        server,
                    });
                }
            }
            let _ = std::fs::remove_file(link);
        }
        std::os::unix::fs::symlink(&self.path, link).map_err(|source| PtyError::Link {
            path: link.to_owned(),
            source,
        })?;
        self.link = Some(link.to_owned());
        Ok(())
    }

    /// Turns pacing at the wire rate on (default) or off (replies at once).
    pub fn set_pacing(&mut self, on: bool) {
        self.pacing = on;
    }

    /// Steps every servo at least every `period` (`None`: only when a
    /// request arrives, the default), so that bodies move and their truth
    /// is recorded while no client talks.
    pub fn set_tick(&mut self, period: Option<Duration>) {
        self.tick = period;
    }

    /// Steps every servo to the present time.
    pub fn settle(&mut self) {
        let now = self.clock.now();
        self.engine.advance_servos(now);
    }

    /// Injects `faults` (the random source is reseeded).
    pub fn set_faults(&mut self, faults: Faults) {
        self.engine.set_faults(faults);
    }

    /// The terminal's device path (e.g. `/dev/pts/3`).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The symbolic link, if one was made.
    pub fn link(&self) -> Option<&Path> {
        self.link.as_deref()
    }

    /// The path clients should open: the link if there is one.
    pub fn client_path(&self) -> &Path {
        self.link.as_deref().unwrap_or(&self.path)
    }

    /// Number of servos served.
    pub fn servo_count(&self) -> usize {
        self.engine.servos.len()
    }

    /// What happened on the bus so far.
    pub fn stats(&self) -> SimStats {
        self.engine.stats
    }

    /// Serves until `stop` becomes true (checked at least every 50 ms).
    ///
    /// # Errors
    /// [`PtyError::Io`] when the terminal fails.
    pub fn serve(&mut self, stop: &AtomicBool) -> Result<(), PtyError> {
        if self.pacing {
            stand_in_for_hardware();
        }
        let mut buf = [0u8; 4096];
        let mut last_tick = self.clock.now();
        while !stop.load(Ordering::SeqCst) {
            let now = self.clock.now();
            if let Some(period) = self.tick {
                if now >= last_tick + period {
                    self.engine.advance_servos(now);
                    last_tick = now;
                }
            }
            self.deliver(now)?;
            // Sleep until the next reply byte is due or input arrives.
            let now = self.clock.now();
            let wait = match self.engine.next_ready() {
                Some(_) if !self.pacing => Duration::ZERO,
                // A contiguous burst (a reply, or the replies of a SYNC READ
                // back to back) is handed over once its last byte is due, as
                // an adapter does when the line goes idle: one write, one
                // wake-up of the client.
                Some(_) => self
                    .engine
                    .burst_end(now, Duration::MAX, usize::MAX)
                    .saturating_sub(now),
                None => self.tick.unwrap_or(Duration::from_millis(50)),
            };
            if wait > Duration::ZERO && wait < SHORT_WAIT && self.engine.next_ready().is_some() {
                // Short waits: the client is waiting for this reply and sends
                // nothing meanwhile (half duplex); wait precisely.
                self.wait_precisely(now + wait);
                continue;
            }
            let longest = self.tick.unwrap_or(Duration::from_millis(50));
            if !self.poll_input(wait.min(longest).min(Duration::from_millis(50)))? {
                continue;
            }
            let n = match read_fd(&self.master, &mut buf) {
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => continue,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                // No client has the terminal open: wait for one.
                Err(e) if e.raw_os_error() == Some(libc::EIO) => {
                    std::thread::sleep(Duration::from_millis(10));
                    continue;
                }
                Err(e) => return Err(PtyError::Io(e)),
            };
            if n == 0 {
                continue;
            }
            self.follow_client_baud();
            let now = self.clock.now();
            self.engine.transmit(&buf[..n], now);
        }
        Ok(())
    }

    /// Sleeps until shortly before `due`, then spins: a sleep alone wakes
    /// tens of microseconds late, which would stretch every reply.
    fn wait_precisely(&self, due: Duration) {
        let now = self.clock.now();
        if due > now + SPIN {
            std::thread::sleep(due - now - SPIN);
        }
        while self.clock.now() < due {
            std::hint::spin_loop();
        }
    }

    /// Writes every reply byte due at `now` (all of them without pacing).
    fn deliver(&mut self, now: Duration) -> Result<(), PtyError> {
        let until = if self.pacing { now } else { Duration::MAX };
        let mut out = [0u8; 1024];
        loop {
            let n = self.engine.take_ready(until, &mut out);
            if n == 0 {
                return Ok(());
            }
            let mut sent = 0;
            while sent < n {
                match write_fd(&self.master, &out[sent..n]) {
                    Ok(k) => sent += k,
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                        // The client is not reading: its input queue is full.
                        // Real adapters drop bytes then; so do we.
                        break;
                    }
                    Err(e) if e.raw_os_error() == Some(libc::EIO) => break,
                    Err(e) => return Err(PtyError::Io(e)),
                }
            }
        }
    }

    /// Waits up to `timeout` for input; true when some is ready.
    fn poll_input(&self, timeout: Duration) -> Result<bool, PtyError> {
        let mut pfd = libc::pollfd {
            fd: self.master.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        let ts = libc::timespec {
            tv_sec: timeout.as_secs() as libc::time_t,
            tv_nsec: libc::c_long::from(timeout.subsec_nanos() as i32),
        };
        // SAFETY: `pfd` is one valid pollfd, `ts` a valid timespec, and the
        // signal mask pointer may be null.
        let rc = unsafe { libc::ppoll(&mut pfd, 1, &ts, std::ptr::null()) };
        if rc < 0 {
            let e = last_error();
            if e.kind() == io::ErrorKind::Interrupted {
                return Ok(false);
            }
            return Err(PtyError::Io(e));
        }
        if rc > 0 && pfd.revents & libc::POLLHUP != 0 && pfd.revents & libc::POLLIN == 0 {
            // No client: avoid spinning on the hang-up.
            std::thread::sleep(Duration::from_millis(10));
            return Ok(false);
        }
        Ok(rc > 0 && pfd.revents & libc::POLLIN != 0)
    }

    /// Adopts the baud rate the client set on the terminal, when it is one
    /// termios can name (otherwise the robot file's rate stays).
    fn follow_client_baud(&mut self) {
        let baud = termios_baud(&self.slave).unwrap_or(self.configured_baud);
        if baud != self.engine.link.baud {
            self.engine.link = Link::new(baud);
        }
    }
}

impl Drop for PtyServer {
    fn drop(&mut self) {
        // Only a link that still points at this server's terminal: another
        // server may have taken the path over since.
        if let Some(link) = &self.link {
            if std::fs::read_link(link).is_ok_and(|to| to == self.path) {
                let _ = std::fs::remove_file(link);
            }
        }
    }
}

/// Asks, best effort, that the serving thread be scheduled as the hardware it
/// stands in for: servos answer on time whatever the host is doing. On a
/// loaded machine a server at normal priority waits behind every other task
/// each time it wakes (for a request, then for the reply's time), and its
/// replies come milliseconds late: reads that a client counts as lost,
/// though the servo is healthy. So the thread asks for the lowest
/// real-time priority (SCHED_FIFO 1: above every normal task, below any
/// real-time one, such as a control thread given `rt` priority) and the
/// smallest timer slack. It only ever blocks or waits out a reply's wire
/// time, and the kernel's real-time throttling bounds it anyway. Where the
/// system refuses (no permission), it serves at normal priority as before.
#[cfg(target_os = "linux")]
fn stand_in_for_hardware() {
    /// `PR_SET_TIMERSLACK` (include/uapi/linux/prctl.h).
    const PR_SET_TIMERSLACK: libc::c_int = 29;
    let param = libc::sched_param { sched_priority: 1 };
    // SAFETY: plain system calls on the calling thread with a valid
    // `sched_param`; failure leaves the thread as it was.
    unsafe {
        let _ = libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param);
        let _ = libc::prctl(PR_SET_TIMERSLACK, 1 as libc::c_ulong);
    }
}

#[cfg(not(target_os = "linux"))]
fn stand_in_for_hardware() {}

pub(crate) fn read_fd(fd: &OwnedFd, buf: &mut [u8]) -> io::Result<usize> {
    // SAFETY: `buf` is valid for `buf.len()` writable bytes.
    let n = unsafe { libc::read(fd.as_raw_fd(), buf.as_mut_ptr().cast(), buf.len()) };
    if n < 0 {
        Err(last_error())
    } else {
        Ok(n as usize)
    }
}

pub(crate) fn write_fd(fd: &OwnedFd, buf: &[u8]) -> io::Result<usize> {
    // SAFETY: `buf` is valid for `buf.len()` readable bytes.
    let n = unsafe { libc::write(fd.as_raw_fd(), buf.as_ptr().cast(), buf.len()) };
    if n < 0 {
        Err(last_error())
    } else {
        Ok(n as usize)
    }
}

const SPEEDS: &[(libc::speed_t, u32)] = &[
    (libc::B1200, 1_200),
    (libc::B2400, 2_400),
    (libc::B4800, 4_800),
    (libc::B9600, 9_600),
    (libc::B19200, 19_200),
    (libc::B38400, 38_400),
    (libc::B57600, 57_600),
    (libc::B115200, 115_200),
    (libc::B230400, 230_400),
    (libc::B460800, 460_800),
    (libc::B500000, 500_000),
    (libc::B576000, 576_000),
    (libc::B921600, 921_600),
    (libc::B1000000, 1_000_000),
    (libc::B1152000, 1_152_000),
    (libc::B1500000, 1_500_000),
    (libc::B2000000, 2_000_000),
];

fn speed_of(baud: u32) -> Option<libc::speed_t> {
    SPEEDS.iter().find(|s| s.1 == baud).map(|s| s.0)
}

/// The output rate the client set on the terminal, in bits per second.
///
/// On Linux the kernel's own figure (`TCGETS2`), which also names the
/// non-standard rates that a client sets with `BOTHER` (pyserial does, for
/// 14400 or 250000 baud); elsewhere the standard rates of [`SPEEDS`].
#[cfg(target_os = "linux")]
fn termios_baud(fd: &OwnedFd) -> Option<u32> {
    // SAFETY: termios2 is plain data.
    let mut t: libc::termios2 = unsafe { std::mem::zeroed() };
    // SAFETY: `fd` is an open terminal; TCGETS2 fills the termios2 it is given.
    if unsafe { libc::ioctl(fd.as_raw_fd(), libc::TCGETS2, &mut t) } != 0 {
        return None;
    }
    Some(t.c_ospeed)
}

#[cfg(not(target_os = "linux"))]
fn termios_baud(fd: &OwnedFd) -> Option<u32> {
    // SAFETY: termios is plain data; tcgetattr fills it for a valid fd.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    // SAFETY: `fd` is an open terminal and `t` a valid termios.
    if unsafe { libc::tcgetattr(fd.as_raw_fd(), &mut t) } != 0 {
        return None;
    }
    // SAFETY: `t` was filled by tcgetattr.
    let speed = unsafe { libc::cfgetospeed(&t) };
    SPEEDS.iter().find(|s| s.0 == speed).map(|s| s.1)
}

/// Opens a pseudo-terminal pair: master (non-blocking), slave (raw, at
/// `baud`), and the slave's path.
pub(crate) fn open_pty(baud: u32) -> io::Result<(OwnedFd, OwnedFd, PathBuf)> {
    // SAFETY: posix_openpt has no memory preconditions.
    let m = check(unsafe { libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY) })?;
    // SAFETY: `m` is a fresh descriptor nobody else owns.
    let master = unsafe { OwnedFd::from_raw_fd(m) };
    // SAFETY: `master` is an open pty master.
    check(unsafe { libc::grantpt(master.as_raw_fd()) })?;
    // SAFETY: as above.
    check(unsafe { libc::unlockpt(master.as_raw_fd()) })?;
    let mut name = [0 as libc::c_char; 128];
    // SAFETY: `name` is writable for its whole length.
    let rc = unsafe { libc::ptsname_r(master.as_raw_fd(), name.as_mut_ptr(), name.len()) };
    if rc != 0 {
        return Err(io::Error::from_raw_os_error(rc));
    }
    // SAFETY: ptsname_r wrote a NUL-terminated string into `name`.
    let path = unsafe { CStr::from_ptr(name.as_ptr()) };
    let path = PathBuf::from(path.to_string_lossy().into_owned());
    // SAFETY: `name` is a NUL-terminated path.
    let s = check(unsafe { libc::open(name.as_ptr(), libc::O_RDWR | libc::O_NOCTTY) })?;
    // SAFETY: `s` is a fresh descriptor nobody else owns.
    let slave = unsafe { OwnedFd::from_raw_fd(s) };
    // SAFETY: termios is plain data; zeroed is a valid start for tcgetattr.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    // SAFETY: `slave` is an open terminal; `t` is valid.
    check(unsafe { libc::tcgetattr(slave.as_raw_fd(), &mut t) })?;
    // SAFETY: `t` is a valid termios.
    unsafe { libc::cfmakeraw(&mut t) };
    if let Some(speed) = speed_of(baud) {
        // SAFETY: `t` is a valid termios; the speed is a termios constant.
        unsafe {
            libc::cfsetispeed(&mut t, speed);
            libc::cfsetospeed(&mut t, speed);
        }
    }
    // SAFETY: `slave` is open; `t` is valid.
    check(unsafe { libc::tcsetattr(slave.as_raw_fd(), libc::TCSANOW, &t) })?;
    // SAFETY: fcntl on an open descriptor.
    let flags = check(unsafe { libc::fcntl(master.as_raw_fd(), libc::F_GETFL) })?;
    // SAFETY: as above.
    check(unsafe { libc::fcntl(master.as_raw_fd(), libc::F_SETFL, flags | libc::O_NONBLOCK) })?;
    Ok((master, slave, path))
}
