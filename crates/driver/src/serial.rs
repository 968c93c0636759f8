//! The real serial port: [`SerialTransport`] over the `serialport` crate.
//!
//! 8 data bits, no parity, one stop bit, no flow control, raw mode. Reads
//! wait with nanosecond deadlines (`ppoll` on Linux) rather than the
//! tenth-of-a-second granularity of `VTIME`. Pseudo-terminals work too: the
//! simulator serves on one.
//!
//! USB adapters add latency of their own. FTDI chips hold received bytes
//! for up to their *latency timer* (16 ms by default) before sending them to
//! the host, which dwarfs the wire time of a reply at 1 Mbps. On Linux,
//! [`ftdi_latency_timer`] reads the timer from sysfs so that a tool can warn
//! (see [`FtdiLatency::warning`]) and a bus can take the latency into
//! account.
//!
//! Waiting for a reply normally blocks in the kernel, and waking from that
//! costs tens of microseconds (more on a virtual machine). With
//! [`SerialTransport::set_busy_poll`] the wait polls the port without
//! blocking instead: the control thread keeps its core for the whole wait
//! and sees each reply as soon as the kernel has it. It suits a control
//! thread pinned to a core of its own.

use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use serialport::{ClearBuffer, DataBits, FlowControl, Parity, SerialPort, StopBits};

use crate::{Clock, Transport, TransportError};

mod open_error;
pub use open_error::{Holder, NotSerial, OpenError, OpenProblem};

/// A serial port (or pseudo-terminal) as a [`Transport`], with deadlines on
/// the time base of `C`.
pub struct SerialTransport<C: Clock> {
    port: Box<dyn SerialPort>,
    clock: C,
    /// The rate the port was last set to.
    baud: u32,
    path: String,
    ftdi: Option<FtdiLatency>,
    busy_poll: bool,
}

impl<C: Clock> std::fmt::Debug for SerialTransport<C> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SerialTransport")
            .field("path", &self.path)
            .field("baud", &self.baud)
            .field("ftdi", &self.ftdi)
            .field("busy_poll", &self.busy_poll)
            .finish_non_exhaustive()
    }
}

impl<C: Clock> SerialTransport<C> {
    /// Opens `path` at `baud`, 8N1, raw, with exclusive access: the
    /// terminal's `TIOCEXCL` flag (further opens fail with `EBUSY`, except
    /// for root) and an exclusive `flock` (which binds root too), as other
    /// serial tools do. A second program, or a second servobus, is refused
    /// the port while this one has it.
    ///
    /// # Errors
    /// [`TransportError::Io`] carrying an [`OpenError`] (find it with
    /// [`OpenError::find`]) that says why and what to do: permission denied
    /// (the group to join), no such port (the ports present), busy (who has it),
    /// an empty path, the program's own terminal (`/dev/tty`) or a loop of
    /// symbolic links.
    pub fn open(path: &str, baud: u32, clock: C) -> Result<Self, TransportError> {
        // An empty path, the program's own terminal and a loop of links
        // are refused before they are opened (`/dev/tty` would open).
        if let Some(refused) = OpenError::before_open(path) {
            return Err(TransportError::Io(io::Error::new(refused.kind(), refused)));
        }
        let builder = serialport::new(path, baud)
            .data_bits(DataBits::Eight)
            .parity(Parity::None)
            .stop_bits(StopBits::One)
            .flow_control(FlowControl::None)
            .timeout(Duration::ZERO)
            .exclusive(true);
        let opened = open_low_latency(builder);
        let port = opened.map_err(|e| {
            // The crate says `NoDevice` for EBUSY (TIOCEXCL held) and for a
            // flock held by another program: both mean the port is taken.
            let (kind, locked) = match e.kind() {
                serialport::ErrorKind::Io(kind) => (kind, false),
                serialport::ErrorKind::NoDevice => (io::ErrorKind::NotFound, true),
                _ => (io::ErrorKind::Other, false),
            };
            let open = OpenError::classify(path, kind, locked, &e.to_string());
            TransportError::Io(io::Error::new(open.kind(), open))
        })?;
        let ftdi = ftdi_latency_timer(Path::new(path));
        Ok(SerialTransport {
            port,
            clock,
            baud,
            path: path.to_owned(),
            ftdi,
            busy_poll: false,
        })
    }

    /// Waits for input by polling without blocking (`true`) or by blocking
    /// in the kernel until the deadline (`false`, the default). Busy polling
    /// takes a whole core while a reply is awaited, and saves the kernel's
    /// wake-up latency on every reply.
    pub fn set_busy_poll(&mut self, on: bool) {
        self.busy_poll = on;
    }

    /// Whether waits poll without blocking; see [`SerialTransport::set_busy_poll`].
    pub fn busy_poll(&self) -> bool {
        self.busy_poll
    }

    /// The path the port was opened with.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The FTDI latency timer of the adapter, when it is an FTDI adapter on
    /// Linux.
    pub fn ftdi_latency(&self) -> Option<&FtdiLatency> {
        self.ftdi.as_ref()
    }

    /// Whether the port is (a link to) a pseudo-terminal: a simulator such
    /// as `servobus sim`, not a USB adapter.
    pub fn is_pty(&self) -> bool {
        std::fs::canonicalize(&self.path).is_ok_and(|p| p.starts_with("/dev/pts"))
    }

    /// The adapter latency to allow for on this port when none is
    /// configured: an FTDI adapter's latency timer plus one USB frame,
    /// [`Link::PTY_LATENCY`](servobus_timing::Link::PTY_LATENCY) for a
    /// pseudo-terminal, [`Link::USB_LATENCY`](servobus_timing::Link::USB_LATENCY)
    /// for any other adapter. A real port never gets the pseudo-terminal's
    /// allowance.
    pub fn assumed_latency(&self) -> Duration {
        use servobus_timing::Link;
        match &self.ftdi {
            // The FTDI chip holds bytes up to its timer; add the USB frame.
            Some(f) => f.latency + Link::USB_LATENCY,
            None if self.is_pty() => Link::PTY_LATENCY,
            None => Link::USB_LATENCY,
        }
    }
}

/// Opens the port and, on Linux, asks the driver for low-latency mode
/// (`ASYNC_LOW_LATENCY`, what `setserial PORT low_latency` does): USB serial
/// drivers that honour it deliver received bytes without waiting for their
/// buffer timer. Ports that do not support it (ptys, CDC-ACM) are used as
/// they are.
#[cfg(target_os = "linux")]
fn open_low_latency(
    builder: serialport::SerialPortBuilder,
) -> Result<Box<dyn SerialPort>, serialport::Error> {
    use std::os::unix::io::AsRawFd;

    let port = builder.open_native()?;
    set_low_latency(port.as_raw_fd());
    Ok(Box::new(port))
}

#[cfg(not(target_os = "linux"))]
fn open_low_latency(
    builder: serialport::SerialPortBuilder,
) -> Result<Box<dyn SerialPort>, serialport::Error> {
    builder.open()
}

/// The kernel's `struct serial_struct` (include/uapi/linux/serial.h).
#[cfg(target_os = "linux")]
#[repr(C)]
struct SerialStruct {
    kind: libc::c_int,
    line: libc::c_int,
    port: libc::c_uint,
    irq: libc::c_int,
    flags: libc::c_int,
    xmit_fifo_size: libc::c_int,
    custom_divisor: libc::c_int,
    baud_base: libc::c_int,
    close_delay: libc::c_ushort,
    io_type: libc::c_char,
    reserved_char: libc::c_char,
    hub6: libc::c_int,
    closing_wait: libc::c_ushort,
    closing_wait2: libc::c_ushort,
    iomem_base: *mut libc::c_uchar,
    iomem_reg_shift: libc::c_ushort,
    port_high: libc::c_uint,
    iomap_base: libc::c_ulong,
}

/// Sets `ASYNC_LOW_LATENCY` on `fd`, best effort.
#[cfg(target_os = "linux")]
fn set_low_latency(fd: std::os::unix::io::RawFd) {
    const ASYNC_LOW_LATENCY: libc::c_int = 1 << 13;
    let mut ss = std::mem::MaybeUninit::<SerialStruct>::zeroed();
    // SAFETY: TIOCGSERIAL writes one `serial_struct` (whose layout
    // `SerialStruct` mirrors) into the buffer we own; `fd` is an open
    // descriptor owned by the port for the duration of the call.
    let got = unsafe { libc::ioctl(fd, libc::TIOCGSERIAL, ss.as_mut_ptr()) };
    if got != 0 {
        return;
    }
    // SAFETY: zero-initialised, then filled by a successful TIOCGSERIAL.
    let mut ss = unsafe { ss.assume_init() };
    if ss.flags & ASYNC_LOW_LATENCY != 0 {
        return;
    }
    ss.flags |= ASYNC_LOW_LATENCY;
    // SAFETY: TIOCSSERIAL reads one `serial_struct` from memory we own.
    // Failure (no permission, unsupported) leaves the port as it was.
    let _ = unsafe { libc::ioctl(fd, libc::TIOCSSERIAL, &ss as *const SerialStruct) };
}

/// Sorts an error of the serialport crate (a failed `ioctl` or `tcflush`)
/// as [`io_error`] sorts a read's: EIO ("I/O error") is a port that is
/// gone, as is `NoDevice`.
fn serial_error(e: serialport::Error) -> TransportError {
    let text = e.to_string();
    match e.kind() {
        serialport::ErrorKind::NoDevice => TransportError::Disconnected(text),
        serialport::ErrorKind::Io(kind) => io_error(io::Error::new(kind, text)),
        _ if text.contains("I/O error") => TransportError::Disconnected(text),
        _ => TransportError::Io(io::Error::other(text)),
    }
}

/// Sorts an I/O error into timeout, disconnection or other.
fn io_error(e: io::Error) -> TransportError {
    // EIO is what Linux returns on a pty whose other side closed, and on an
    // unplugged USB adapter.
    const EIO: i32 = 5;
    match e.kind() {
        io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock => TransportError::TimedOut,
        io::ErrorKind::BrokenPipe
        | io::ErrorKind::NotConnected
        | io::ErrorKind::UnexpectedEof
        | io::ErrorKind::ConnectionReset => TransportError::Disconnected(e.to_string()),
        _ if e.raw_os_error() == Some(EIO) || e.to_string().contains("I/O error") => {
            TransportError::Disconnected(e.to_string())
        }
        _ => TransportError::Io(e),
    }
}

impl<C: Clock> Transport for SerialTransport<C> {
    type Clock = C;

    fn clock(&self) -> &C {
        &self.clock
    }

    fn baud(&self) -> u32 {
        self.baud
    }

    /// Sets the port to `baud` (a bus changes its rate through
    /// [`Bus::set_baud`](crate::Bus::set_baud), which calls this).
    fn set_baud(&mut self, baud: u32) -> Result<(), TransportError> {
        match self.port.set_baud_rate(baud) {
            Ok(()) => {
                self.baud = baud;
                Ok(())
            }
            // The driver refusing the rate is not a broken port.
            Err(e) if matches!(e.kind(), serialport::ErrorKind::InvalidInput) => {
                Err(TransportError::BaudRefused {
                    requested: baud,
                    current: self.baud,
                })
            }
            Err(e) => Err(serial_error(e)),
        }
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        // Not a reply deadline: a liveness bound for a port that stopped
        // draining (a frame takes at most 27 ms on the wire even at 9600
        // baud), so that a wedged adapter is an error rather than a hang.
        self.port
            .set_timeout(Duration::from_secs(1))
            .map_err(serial_error)?;
        self.port.write_all(bytes).map_err(io_error)
    }

    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        if !self.busy_poll {
            let wait = deadline.saturating_sub(self.clock.now());
            self.port.set_timeout(wait).map_err(serial_error)?;
            return self.read_once(buf);
        }
        self.port
            .set_timeout(Duration::ZERO)
            .map_err(serial_error)?;
        loop {
            match self.read_once(buf) {
                Err(TransportError::TimedOut) if self.clock.now() < deadline => {
                    std::hint::spin_loop();
                }
                other => return other,
            }
        }
    }

    fn discard_input(&mut self) -> Result<(), TransportError> {
        self.port.clear(ClearBuffer::Input).map_err(serial_error)
    }
}

impl<C: Clock> SerialTransport<C> {
    /// One read with the timeout already set on the port.
    fn read_once(&mut self, buf: &mut [u8]) -> Result<usize, TransportError> {
        match self.port.read(buf) {
            Ok(0) if !buf.is_empty() => Err(TransportError::Disconnected(format!(
                "{}: end of file",
                self.path
            ))),
            Ok(n) => Ok(n),
            Err(e) => Err(io_error(e)),
        }
    }
}

/// The latency timer of an FTDI USB serial adapter (Linux).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FtdiLatency {
    /// The sysfs file holding it, e.g.
    /// `/sys/bus/usb-serial/devices/ttyUSB0/latency_timer`.
    pub sysfs_path: PathBuf,
    /// Its value.
    pub latency: Duration,
}

impl FtdiLatency {
    /// The best value: 1 ms.
    pub const BEST: Duration = Duration::from_millis(1);

    /// Whether the timer is above 1 ms (every reply is held that long).
    pub fn is_too_high(&self) -> bool {
        self.latency > Self::BEST
    }

    /// A one-line warning with the fix, when the timer is too high.
    pub fn warning(&self) -> Option<String> {
        self.is_too_high().then(|| {
            format!(
                "FTDI latency timer is {} ms: every reply waits that long; set it to 1 with \
                 `echo 1 | sudo tee {}`",
                self.latency.as_millis(),
                self.sysfs_path.display()
            )
        })
    }
}

/// Reads the FTDI latency timer of the adapter behind `port` (a device path
/// or a symbolic link to one), on Linux. `None` for anything that is not a
/// USB serial adapter with a latency timer (CDC-ACM adapters, ptys, other
/// systems).
pub fn ftdi_latency_timer(port: &Path) -> Option<FtdiLatency> {
    let dev = std::fs::canonicalize(port).ok()?;
    let name = dev.file_name()?.to_str()?;
    if !name.starts_with("ttyUSB") {
        return None;
    }
    let sysfs_path = Path::new("/sys/bus/usb-serial/devices")
        .join(name)
        .join("latency_timer");
    let text = std::fs::read_to_string(&sysfs_path).ok()?;
    let ms: u64 = text.trim().parse().ok()?;
    Some(FtdiLatency {
        sysfs_path,
        latency: Duration::from_millis(ms),
    })
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use crate::SystemClock;

    #[test]
    fn a_pty_is_a_serial_port() {
        let Ok((mut master, slave)) = serialport::TTYPort::pair() else {
            // No pty support in this environment: nothing to test.
            return;
        };
        let Some(name) = slave.name() else { return };
        let clock = SystemClock::new();
        let mut port = SerialTransport::open(&name, 1_000_000, clock)
            .or_else(|_| {
                // The pair's slave holds the exclusive lock; drop it and reopen.
                drop(slave);
                SerialTransport::open(&name, 1_000_000, clock)
            })
            .expect("open pty");
        assert!(port.ftdi_latency().is_none());
        port.write_all(&[1, 2, 3]).expect("write");
        let mut got = [0u8; 8];
        master.set_timeout(Duration::from_secs(5)).expect("timeout");
        let n = master.read(&mut got).expect("master read");
        assert_eq!(&got[..n], &[1, 2, 3]);
        // Nothing to read: a timeout, not an error.
        let err = port.read(&mut got, clock.now()).unwrap_err();
        assert!(err.is_timeout(), "{err}");
        master.write_all(&[9, 8]).expect("master write");
        let deadline = clock.now() + Duration::from_secs(5);
        let n = port.read(&mut got, deadline).expect("read");
        assert_eq!(&got[..n], &[9, 8][..n]);

        // Busy polling: the same answers, without blocking in the kernel.
        port.set_busy_poll(true);
        assert!(port.busy_poll());
        while port.read(&mut got, clock.now()).is_ok() {}
        let before = clock.now();
        let err = port
            .read(&mut got, before + Duration::from_millis(2))
            .unwrap_err();
        assert!(err.is_timeout(), "{err}");
        assert!(clock.now() >= before + Duration::from_millis(2));
        master.write_all(&[7]).expect("master write");
        let n = port
            .read(&mut got, clock.now() + Duration::from_secs(5))
            .expect("busy read");
        assert_eq!(&got[..n], &[7]);
    }

    #[test]
    fn ftdi_warning_names_the_sysfs_file() {
        let f = FtdiLatency {
            sysfs_path: PathBuf::from("/sys/bus/usb-serial/devices/ttyUSB0/latency_timer"),
            latency: Duration::from_millis(16),
        };
        let w = f.warning().unwrap_or_default();
        assert!(
            w.contains("16 ms") && w.contains("ttyUSB0/latency_timer"),
            "{w}"
        );
        let ok = FtdiLatency {
            latency: FtdiLatency::BEST,
            ..f
        };
        assert_eq!(ok.warning(), None);
        assert_eq!(ftdi_latency_timer(Path::new("/dev/null")), None);
    }
}
