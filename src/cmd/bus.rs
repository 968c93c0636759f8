//! The bus tools: `servobus scan`, `ping`, `read`, `write` and `set-id`, and
//! `servobus registers`, the register names they take.
//!
//! Each opens the serial port (or the simulator's pty), builds a driver
//! [`Bus`](servobus_robot::bus::Bus) with reply deadlines derived from the baud rate and the adapter
//! latency, and reports in one line per fact. Errors are one line and a
//! non-zero exit code.

use std::process::ExitCode;
use std::time::Duration;

use anyhow::bail;

use crate::shared::out::{errln, outln};

mod args;
mod open;
mod regs;
pub use args::{PingArgs, ReadArgs, RegistersArgs, ScanArgs, ServoArgs, SetIdArgs, WriteArgs};
pub use regs::{list as registers, read, set_id, write};

use open::{check_id, open};
use servobus_protocol::registers::Series;
use servobus_robot::scan::{self, adapt_latency, table_bauds, Found, Scan, ScanError};

/// Runs `servobus scan`.
pub fn scan(args: ScanArgs) -> anyhow::Result<ExitCode> {
    let bauds: Vec<u32> = if args.all_bauds {
        table_bauds()
    } else {
        vec![args.baud]
    };
    let mut bus = open(&args.port, bauds[0], Series::Sts, 0)?;
    let started = std::time::Instant::now();
    let learn = args.port.latency_us.is_none();
    let scanned = scan::scan(&mut bus, &bauds, learn).map_err(|e| match e {
        ScanError::Baud { baud, source } => anyhow::Error::new(source)
            .context(format!("cannot set {} to {baud} baud", args.port.port)),
        e => e.into(),
    })?;
    if let Some(slow) = scanned.slow {
        errln!(
            "warning: the adapter's latency is about {} us, more than the {} us assumed: \
             asking silent IDs again (pass --latency-us to skip this)",
            slow.measured.as_micros(),
            slow.assumed.as_micros()
        );
    }
    let Scan {
        found, collisions, ..
    } = scanned;
    let elapsed = started.elapsed();
    if args.json {
        print_scan_json(&args.port.port, &found, &collisions, elapsed)?;
    } else {
        print_scan_table(&args.port.port, &found, elapsed)?;
    }
    for (id, baud) in &collisions {
        errln!(
            "error: ID {id} at {baud} baud: corrupted replies (checksum errors): \
             probably two servos share this ID; connect them one at a time and use set-id"
        );
    }
    if found.is_empty() && collisions.is_empty() {
        let hint = if args.all_bauds {
            "check the power and the wiring (data, ground)"
        } else {
            "check the power and the wiring, or try every baud rate with --all-bauds"
        };
        bail!(
            "no servo answered on {} at {}; {hint}",
            args.port.port,
            baud_list(&bauds)
        );
    }
    if !collisions.is_empty() {
        // A shared ID is a problem found: the servos on it cannot be used.
        return Ok(ExitCode::from(crate::shared::exit::PROBLEM));
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints what a scan of `port` found, and the IDs whose replies
/// collided, as one JSON line.
fn print_scan_json(
    port: &str,
    found: &[Found],
    collisions: &[(u8, u32)],
    elapsed: Duration,
) -> anyhow::Result<()> {
    let servos: Vec<_> = found
        .iter()
        .map(|f| {
            serde_json::json!({
                "id": f.id,
                "baud": f.baud,
                "model": f.model.map(|m| m.name),
                "model_number": f.model_number,
                "firmware": format!("{}.{}", f.firmware.0, f.firmware.1),
                "position": f.position,
                "voltage_v": f.voltage_v,
                "temperature_c": f.temperature_c,
            })
        })
        .collect();
    let coll: Vec<_> = collisions
        .iter()
        .map(|(id, baud)| serde_json::json!({"id": id, "baud": baud}))
        .collect();
    let out = serde_json::json!({
        "port": port,
        "servos": servos,
        "collisions": coll,
        "elapsed_s": elapsed.as_secs_f64(),
    });
    outln!("{}", crate::shared::json::line(&out)?)?;
    Ok(())
}

/// Prints what a scan of `port` found as a table, a servo a line, and
/// their count.
fn print_scan_table(port: &str, found: &[Found], elapsed: Duration) -> anyhow::Result<()> {
    if !found.is_empty() {
        outln!(
            "{:>3}  {:<9} {:>8}  {:>8}  {:>7}  {:>5}  BAUD",
            "ID",
            "MODEL",
            "FIRMWARE",
            "POSITION",
            "VOLTAGE",
            "TEMP"
        )?;
    }
    for f in found {
        let model = f
            .model
            .map_or_else(|| format!("#{}", f.model_number), |m| m.name.to_string());
        let opt = |v: Option<String>| v.unwrap_or_else(|| "?".into());
        outln!(
            "{:>3}  {:<9} {:>8}  {:>8}  {:>7}  {:>5}  {}",
            f.id,
            model,
            format!("{}.{}", f.firmware.0, f.firmware.1),
            opt(f.position.map(|p| p.to_string())),
            opt(f.voltage_v.map(|v| format!("{v:.1} V"))),
            opt(f.temperature_c.map(|t| format!("{t} C"))),
            f.baud
        )?;
    }
    outln!(
        "found {} servo(s) on {} in {:.2} s",
        found.len(),
        port,
        elapsed.as_secs_f64()
    )?;
    Ok(())
}

/// Runs `servobus ping`.
pub fn ping(args: PingArgs) -> anyhow::Result<ExitCode> {
    let ServoArgs { port, baud, id } = &args.servo;
    check_id(*id)?;
    let mut bus = open(port, *baud, Series::Sts, 2)?;
    if port.latency_us.is_none() {
        adapt_latency(&mut bus, *id)?;
    }
    let flags = bus.ping(*id)?;
    outln!(
        "servo {id} answered in {} us, status {flags}",
        bus.last_rtt().as_micros()
    )?;
    Ok(ExitCode::SUCCESS)
}

/// Baud rates for a message: `1000000 baud` or `8 baud rates`.
fn baud_list(bauds: &[u32]) -> String {
    match bauds {
        [one] => format!("{one} baud"),
        many => format!("{} baud rates", many.len()),
    }
}
