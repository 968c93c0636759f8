//! The fastest cycle a pseudo-terminal allows on this machine.
//!
//! `servobus bench` on the simulator measures the whole stack: the driver,
//! the simulated servos and the pseudo-terminal between them. This program
//! keeps only the last: a client thread writes a request of the arm's size
//! (a SYNC WRITE then a SYNC READ, 26 + 14 bytes) and waits for a reply of
//! 48 bytes; a server thread answers when the wire would have carried all
//! 88 bytes at the baud rate, timed from the moment it read the request, as
//! the simulator does. No protocol, no servo, no allocation in the loop.
//!
//! The period it achieves is the ceiling for the simulator on this machine:
//! what is lost against the wire here is the kernel's hand-over of bytes
//! between the two ends (a wake-up each way), which `servobus bench` pays
//! too. Compare the two percentages.
//!
//! ```text
//! cargo run --release --example pty_floor -- --seconds 5
//! cargo run --release -- bench --seconds 5
//! ```

use std::io;
use std::os::fd::{AsRawFd, RawFd};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use clap::Parser;
use serialport::TTYPort;
use servobus_runtime::stats::Histogram;

/// Measure the fastest request/reply cycle through a pseudo-terminal.
#[derive(Parser, Debug)]
struct Args {
    /// Baud rate the server paces the wire at.
    #[arg(long, default_value_t = 1_000_000)]
    baud: u32,
    /// Bytes of the first request write (the SYNC WRITE).
    #[arg(long, default_value_t = 26)]
    write: usize,
    /// Bytes of the second request write (the SYNC READ).
    #[arg(long, default_value_t = 14)]
    read: usize,
    /// Bytes of the reply (6 status packets of 8 bytes).
    #[arg(long, default_value_t = 48)]
    reply: usize,
    /// How long to run, s.
    #[arg(long, default_value_t = 3.0)]
    seconds: f64,
}

/// The server starts spinning this long before a reply is due.
const SPIN: Duration = Duration::from_micros(150);

fn main() -> std::process::ExitCode {
    // Errors print in words (`error: ...`), not in their `Debug` form.
    match run(Args::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> Result<(), Box<dyn std::error::Error>> {
    if !(args.seconds > 0.0 && args.seconds <= 3600.0) {
        return Err("--seconds must be in (0, 3600]".into());
    }
    if args.baud == 0 || args.write + args.read == 0 || args.reply == 0 {
        return Err("--baud, the request and the reply must not be empty".into());
    }
    let total = args.write + args.read + args.reply;
    // 10 bits per byte (8N1), rounded up to the nanosecond.
    let wire =
        Duration::from_nanos((total as u64 * 10 * 1_000_000_000).div_ceil(u64::from(args.baud)));

    let (server, client) = TTYPort::pair()?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let request = args.write + args.read;
    let reply = args.reply;
    let handle = std::thread::spawn(move || serve(&server, request, reply, wire, &flag));

    let fd = client.as_raw_fd();
    let first = vec![0u8; args.write];
    let second = vec![0u8; args.read];
    let mut buf = vec![0u8; 4096];
    let mut periods = Histogram::new(Duration::from_millis(100));
    let end = Instant::now() + Duration::from_secs_f64(args.seconds);
    let mut last = Instant::now();
    let mut cycles = 0u64;
    while Instant::now() < end {
        write_all(fd, &first)?;
        write_all(fd, &second)?;
        let mut got = 0;
        while got < reply {
            if !wait_readable(fd, 100)? {
                return Err("the server did not answer within 100 ms".into());
            }
            got += read_some(fd, &mut buf)?;
        }
        let now = Instant::now();
        periods.record(now - last);
        last = now;
        cycles += 1;
    }
    stop.store(true, Ordering::SeqCst);
    // Wake the server from its wait so that it sees the flag.
    write_all(fd, &[0])?;
    match handle.join() {
        Ok(served) => served?,
        Err(_) => return Err("the server thread panicked".into()),
    }

    let us = |d: Duration| d.as_secs_f64() * 1e6;
    let (p50, p99, max) = (
        us(periods.quantile(0.5)),
        us(periods.quantile(0.99)),
        us(periods.max()),
    );
    let wire_us = us(wire);
    println!(
        "{cycles} cycles of {total} bytes at {} baud: wire time {wire_us:.0} us ({:.1} Hz)",
        args.baud,
        1e6 / wire_us
    );
    println!(
        "period p50 {:.0} us, p99 {:.0} us, max {:.0} us; p50 rate {:.1} % of the wire-limited rate",
        p50,
        p99,
        max,
        100.0 * wire_us / p50
    );
    Ok(())
}

/// Answers every complete request with `reply` bytes once `wire` has passed
/// since its first byte was read.
fn serve(
    port: &TTYPort,
    request: usize,
    reply: usize,
    wire: Duration,
    stop: &AtomicBool,
) -> io::Result<()> {
    let fd = port.as_raw_fd();
    let answer = vec![0u8; reply];
    let mut buf = vec![0u8; 4096];
    let mut got = 0;
    let mut started = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        if !wait_readable(fd, 50)? {
            continue;
        }
        if got == 0 {
            started = Instant::now();
        }
        got += read_some(fd, &mut buf)?;
        if got < request {
            continue;
        }
        got = 0;
        let due = started + wire;
        if let Some(nap) = due.checked_duration_since(Instant::now() + SPIN) {
            std::thread::sleep(nap);
        }
        while Instant::now() < due {
            std::hint::spin_loop();
        }
        write_all(fd, &answer)?;
    }
    Ok(())
}

/// Waits up to `ms` milliseconds for input; true when some is ready.
fn wait_readable(fd: RawFd, ms: i32) -> io::Result<bool> {
    let mut pfd = libc::pollfd {
        fd,
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

fn read_some(fd: RawFd, buf: &mut [u8]) -> io::Result<usize> {
    // SAFETY: `buf` is valid for writes of its length.
    let n = unsafe { libc::read(fd, buf.as_mut_ptr().cast(), buf.len()) };
    usize::try_from(n).map_err(|_| io::Error::last_os_error())
}

fn write_all(fd: RawFd, mut bytes: &[u8]) -> io::Result<()> {
    while !bytes.is_empty() {
        // SAFETY: `bytes` is valid for reads of its length.
        let n = unsafe { libc::write(fd, bytes.as_ptr().cast(), bytes.len()) };
        match usize::try_from(n) {
            Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
            Ok(k) => bytes = &bytes[k..],
            Err(_) => {
                let e = io::Error::last_os_error();
                if e.kind() != io::ErrorKind::Interrupted {
                    return Err(e);
                }
            }
        }
    }
    Ok(())
}
