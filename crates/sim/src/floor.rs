//! The fastest request/reply cycle a pseudo-terminal allows on this machine.
//!
//! `servobus bench` on the simulator measures the whole stack: the driver,
//! the simulated servos and the pseudo-terminal between them. [`pty_floor`]
//! keeps only the last: a client writes a request of the bus's size (a SYNC
//! WRITE then a SYNC READ) and waits for a reply of the bus's size; a server
//! thread answers when the wire would have carried every byte at the baud
//! rate, timed from the moment it read the request, as the simulator does.
//! No protocol, no servo, no allocation in the loop. What is lost against the
//! wire is the kernel's hand-over of bytes between the two ends (a wake-up
//! each way), which the simulator pays too: its rate is the floor of what
//! `bench` can achieve.

use std::io;
use std::os::fd::{AsRawFd, OwnedFd};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::pty::{open_pty, read_fd, write_fd};

/// The server starts spinning this long before a reply is due.
const SPIN: Duration = Duration::from_micros(150);

/// How long the client waits for a reply before giving up.
const REPLY_WAIT_MS: i32 = 100;

/// The byte counts of one cycle: a write, then `trips` request/reply
/// exchanges (one SYNC READ, or one READ per servo on buses without it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FloorCycle {
    /// Baud rate the server paces the wire at.
    pub baud: u32,
    /// Bytes written before the first request (the SYNC WRITE).
    pub write: usize,
    /// Bytes of each request (the SYNC READ, or one READ).
    pub read: usize,
    /// Bytes of each reply (its status packets).
    pub reply: usize,
    /// Request/reply exchanges per cycle (at least 1).
    pub trips: usize,
    /// What the servos add to each exchange beside the wire: their
    /// turnarounds and return delays, which the simulator waits too. With
    /// it, the floor is the simulator's own timing on this pty, so that
    /// `bench` can be held to it.
    pub servo: Duration,
}

impl FloorCycle {
    /// Wire time of every byte of the cycle (10 bits each), rounded up to
    /// the nanosecond.
    pub fn wire_time(&self) -> Duration {
        let total = self.write + self.trips.max(1) * (self.read + self.reply);
        servobus_timing::Link::new(self.baud).wire_time(total)
    }
}

/// What [`pty_floor`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Floor {
    /// Cycles completed.
    pub cycles: u64,
    /// Time from the start of the first cycle to the end of the last.
    pub elapsed: Duration,
    /// Each cycle's period, in order.
    pub periods: Vec<Duration>,
}

impl Floor {
    /// The mean rate: cycles per second of elapsed time (the statistic
    /// `bench` reports as its achieved rate), Hz; 0 when nothing ran.
    pub fn rate_hz(&self) -> f64 {
        if self.elapsed.is_zero() {
            0.0
        } else {
            self.cycles as f64 / self.elapsed.as_secs_f64()
        }
    }
}

/// Runs request/reply cycles of `cycle`'s sizes through a fresh
/// pseudo-terminal for `duration` and returns what it achieved.
///
/// # Errors
///
/// The pseudo-terminal cannot be opened or used, or the server does not
/// answer within 100 ms.
pub fn pty_floor(cycle: FloorCycle, duration: Duration) -> io::Result<Floor> {
    if cycle.read == 0 || cycle.reply == 0 || cycle.trips == 0 {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "the request and the reply must not be empty",
        ));
    }
    let (server, client, _) = open_pty(cycle.baud)?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let handle = std::thread::spawn(move || serve(&server, cycle, &flag));
    let measured = measure(&client, cycle, duration);
    stop.store(true, Ordering::SeqCst);
    // Wake the server from its wait so that it sees the flag.
    write_all(&client, &[0])?;
    match handle.join() {
        Ok(served) => served?,
        Err(_) => return Err(io::Error::other("the floor's server thread panicked")),
    }
    measured
}

fn measure(client: &OwnedFd, cycle: FloorCycle, duration: Duration) -> io::Result<Floor> {
    let first = vec![0u8; cycle.write];
    let second = vec![0u8; cycle.read];
    let mut buf = vec![0u8; 4096];
    let mut periods = Vec::with_capacity(1 << 14);
    let start = Instant::now();
    let end = start + duration;
    let mut last = start;
    while Instant::now() < end {
        write_all(client, &first)?;
        for _ in 0..cycle.trips {
            write_all(client, &second)?;
            let mut got = 0;
            while got < cycle.reply {
                if !wait_readable(client, REPLY_WAIT_MS)? {
                    return Err(io::Error::new(
                        io::ErrorKind::TimedOut,
                        "the floor's server did not answer within 100 ms",
                    ));
                }
                got += read_fd(client, &mut buf)?;
            }
        }
        let now = Instant::now();
        periods.push(now - last);
        last = now;
    }
    Ok(Floor {
        cycles: periods.len() as u64,
        elapsed: last - start,
        periods,
    })
}

/// Answers every complete request with the reply's bytes once the wire
/// time of the exchange (the write too, on the cycle's first) has passed
/// since its first byte was read.
fn serve(port: &OwnedFd, cycle: FloorCycle, stop: &AtomicBool) -> io::Result<()> {
    let link = servobus_timing::Link::new(cycle.baud);
    let mut trip = 0;
    let answer = vec![0u8; cycle.reply];
    let mut buf = vec![0u8; 4096];
    let mut got = 0;
    let mut started = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        if !wait_readable(port, 50)? {
            continue;
        }
        if got == 0 {
            started = Instant::now();
        }
        got += match read_fd(port, &mut buf) {
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => 0,
            Err(e) => return Err(e),
        };
        let request = if trip == 0 {
            cycle.write + cycle.read
        } else {
            cycle.read
        };
        if got < request {
            continue;
        }
        got = 0;
        let due = started + link.wire_time(request + cycle.reply) + cycle.servo;
        trip = (trip + 1) % cycle.trips;
        if let Some(nap) = due.checked_duration_since(Instant::now() + SPIN) {
            std::thread::sleep(nap);
        }
        while Instant::now() < due {
            std::hint::spin_loop();
        }
        write_all(port, &answer)?;
    }
    Ok(())
}

/// Waits up to `ms` milliseconds for input; true when some is ready.
fn wait_readable(fd: &OwnedFd, ms: i32) -> io::Result<bool> {
    let mut pfd = libc::pollfd {
        fd: fd.as_raw_fd(),
        events: libc::POLLIN,
        revents: 0,
    };
    // SAFETY: one valid pollfd for the duration of the call.
    let rc = unsafe { libc::poll(&mut pfd, 1, ms) };
    if rc < 0 {
        let e = io::Error::last_os_error();
        return if e.kind() == io::ErrorKind::Interrupted {
            Ok(false)
        } else {
            Err(e)
        };
    }
    Ok(rc > 0)
}

/// Writes every byte; the server's end is non-blocking, so a full buffer
/// is waited out.
fn write_all(fd: &OwnedFd, mut bytes: &[u8]) -> io::Result<()> {
    while !bytes.is_empty() {
        match write_fd(fd, bytes) {
            Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
            Ok(k) => bytes = &bytes[k..],
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => std::thread::yield_now(),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wire_time_of_the_arms_cycle_is_880_us_at_1_mbps() {
        let arm = FloorCycle {
            baud: 1_000_000,
            write: 26,
            read: 14,
            reply: 48,
            trips: 1,
            servo: Duration::ZERO,
        };
        assert_eq!(arm.wire_time(), Duration::from_micros(880));
    }

    #[test]
    fn the_floor_is_slower_than_the_wire_and_counts_every_cycle() {
        // 120 us of wire at 1 Mbps: a real pty cannot beat the wire.
        let tiny = FloorCycle {
            baud: 1_000_000,
            write: 4,
            read: 2,
            reply: 2,
            trips: 2,
            servo: Duration::ZERO,
        };
        let floor = pty_floor(tiny, Duration::from_millis(100)).expect("a pty");
        assert!(floor.cycles > 0);
        assert_eq!(floor.periods.len() as u64, floor.cycles);
        let sum: Duration = floor.periods.iter().sum();
        assert_eq!(sum, floor.elapsed);
        assert_eq!(tiny.wire_time(), Duration::from_micros(120));
        assert!(floor.rate_hz() <= 1e6 / 120.0, "{}", floor.rate_hz());
    }
}
