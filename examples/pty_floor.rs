//! The fastest cycle a pseudo-terminal allows on this machine.
//!
//! `servobus bench` on the simulator measures the whole stack: the driver,
//! the simulated servos and the pseudo-terminal between them. This program
//! keeps only the last ([`servobus_sim::pty_floor`], which `bench` also runs
//! and reports as `floor_rate_hz`): a client writes a request of the arm's
//! size (a SYNC WRITE then a SYNC READ, 26 + 14 bytes) and waits for a reply
//! of 48 bytes; a server thread answers when the wire would have carried all
//! 88 bytes at the baud rate, as the simulator does.
//!
//! Its rate is the mean, cycles per second, the same statistic as bench's
//! achieved rate, so the two compare directly.
//!
//! ```text
//! cargo run --release --example pty_floor -- --seconds 5
//! cargo run --release -- bench --seconds 5
//! ```

use std::time::Duration;

use clap::Parser;
use servobus_sim::{pty_floor, FloorCycle};

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
    if args.baud == 0 {
        return Err("--baud must not be 0".into());
    }
    let cycle = FloorCycle {
        baud: args.baud,
        write: args.write,
        read: args.read,
        reply: args.reply,
        trips: 1,
        // The bare pseudo-terminal: no servo time on top of the wire.
        servo: Duration::ZERO,
    };
    let floor = pty_floor(cycle, Duration::from_secs_f64(args.seconds))?;
    let us = |d: Duration| d.as_secs_f64() * 1e6;
    let wire_us = us(cycle.wire_time());
    let mut periods = floor.periods.clone();
    periods.sort_unstable();
    let at = |q: f64| {
        let i = ((periods.len() as f64 - 1.0) * q).round() as usize;
        periods.get(i).map_or(0.0, |d| us(*d))
    };
    println!(
        "{} cycles of {} bytes at {} baud: wire time {wire_us:.0} us ({:.1} Hz)",
        floor.cycles,
        args.write + args.read + args.reply,
        args.baud,
        1e6 / wire_us
    );
    println!(
        "mean rate {:.1} Hz, {:.1} % of the wire-limited rate; period p50 {:.0} us, \
         p99 {:.0} us, max {:.0} us",
        floor.rate_hz(),
        100.0 * floor.rate_hz() * wire_us / 1e6,
        at(0.5),
        at(0.99),
        at(1.0)
    );
    Ok(())
}
