//! The bus tools: `servobus scan`, `ping`, `read`, `write` and `set-id`, and
//! `servobus registers`, the register names they take.
//!
//! Each opens the serial port (or the simulator's pty), builds a driver
//! [`Bus`](servobus_robot::bus::Bus) with reply deadlines derived from the baud rate and the adapter
//! latency, and reports in one line per fact. Errors are one line and a
//! non-zero exit code.

use std::process::ExitCode;
use std::time::Duration;

use anyhow::{bail, Context};

use crate::shared::exit::input;
use crate::shared::out::{errln, outln};

mod regs;
pub use regs::{list as registers, read, set_id, write};

use crate::shared::ports::{open_plain_bus, SerialBus};
use servobus_protocol::registers::{addr, Series};
use servobus_protocol::MAX_ID;
use servobus_robot::scan::{self, adapt_latency, identify, table_bauds, Found, Scan, ScanError};

/// Options every bus tool shares.
#[derive(Debug, clap::Args)]
pub struct PortArgs {
    /// Serial port (or the pty of `servobus sim`).
    #[arg(long)]
    pub port: String,
    /// The adapter's latency per transaction, in microseconds (default: the
    /// FTDI latency timer when the adapter is an FTDI one, else 1000).
    #[arg(long, value_name = "US", value_parser = super::latency_us_arg)]
    pub latency_us: Option<u64>,
}

/// Arguments of `servobus scan`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Two servos sharing an ID (their replies collide) is a problem found: exit 1."
)]
pub struct ScanArgs {
    /// Port and latency.
    #[command(flatten)]
    pub port: PortArgs,
    /// Baud rate (one of the servos' table: 1000000, 500000, ... 38400).
    #[arg(long, default_value_t = 1_000_000, value_parser = super::baud_arg)]
    pub baud: u32,
    /// Try every baud rate of the servo baud table.
    #[arg(long, conflicts_with = "baud")]
    pub all_bauds: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Port, baud rate and servo: what every single-servo tool needs.
#[derive(Debug, clap::Args)]
pub struct ServoArgs {
    /// Port and latency.
    #[command(flatten)]
    pub port: PortArgs,
    /// Baud rate (one of the servos' table: 1000000, 500000, ... 38400).
    #[arg(long, default_value_t = 1_000_000, value_parser = super::baud_arg)]
    pub baud: u32,
    /// Servo ID (for set-id: the servo's current ID).
    #[arg(long)]
    pub id: u8,
}

/// Arguments of `servobus ping`.
#[derive(Debug, clap::Args)]
pub struct PingArgs {
    /// Port, baud rate and servo.
    #[command(flatten)]
    pub servo: ServoArgs,
}

/// Arguments of `servobus read`.
#[derive(Debug, clap::Args)]
pub struct ReadArgs {
    /// Port, baud rate and servo.
    #[command(flatten)]
    pub servo: ServoArgs,
    /// Register name, e.g. present_position (or its address).
    pub register: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `servobus write`.
#[derive(Debug, clap::Args)]
pub struct WriteArgs {
    /// Port, baud rate and servo.
    #[command(flatten)]
    pub servo: ServoArgs,
    /// Register name, e.g. goal_position (or its address).
    pub register: String,
    /// Value to write.
    #[arg(allow_negative_numbers = true)]
    pub value: i64,
}

/// Arguments of `servobus registers`.
#[derive(Debug, clap::Args)]
pub struct RegistersArgs {
    /// Only this series' table: sts (STS/SMS servos) or scs.
    #[arg(long, value_parser = ["sts", "scs"])]
    pub series: Option<String>,
}

/// Arguments of `servobus set-id`.
#[derive(Debug, clap::Args)]
pub struct SetIdArgs {
    /// Port, baud rate and servo.
    #[command(flatten)]
    pub servo: ServoArgs,
    /// The new ID.
    pub new_id: u8,
}

/// Opens the port and builds a bus; warns about a slow FTDI latency timer.
fn open(port: &PortArgs, baud: u32, series: Series, retries: u8) -> anyhow::Result<SerialBus> {
    let latency = port.latency_us.map(Duration::from_micros);
    let mut bus = open_plain_bus(&port.port, baud, series, latency)?;
    bus.set_settings(bus.settings().with_retries(retries));
    Ok(bus)
}

fn check_id(id: u8) -> anyhow::Result<()> {
    if id > MAX_ID {
        return Err(input(format!("ID {id} is not a servo ID (0..={MAX_ID})")));
    }
    Ok(())
}

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

/// Opens the bus and learns the servo's series from its model number.
fn open_servo(servo: &ServoArgs) -> anyhow::Result<(SerialBus, Found)> {
    let ServoArgs { port, baud, id } = servo;
    let (baud, id) = (*baud, *id);
    check_id(id)?;
    let mut bus = open(port, baud, Series::Sts, 2)?;
    if port.latency_us.is_none() {
        adapt_latency(&mut bus, id).with_context(|| format!("servo {id}"))?;
    }
    let found = identify(&mut bus, id).with_context(|| {
        format!(
            "servo {id} at {baud} baud (to find the servos and their rates: \
             servobus scan --port {} --all-bauds)",
            port.port
        )
    })?;
    // A servo at a status level that leaves WRITE unanswered (0 on STS,
    // below 2 on SCS) is written without waiting for replies, so that
    // `servobus write ... status_level 1` (doctor's fix) can reach it.
    let mut level = [0u8; 1];
    if bus.read(id, addr::STATUS_LEVEL, &mut level).is_ok() {
        let series = bus.settings().series;
        let s = bus
            .settings()
            .with_replies(servobus_robot::bus::StatusLevel::from_register(
                series, level[0],
            ));
        bus.set_settings(s);
    }
    Ok((bus, found))
}

/// Baud rates for a message: `1000000 baud` or `8 baud rates`.
fn baud_list(bauds: &[u32]) -> String {
    match bauds {
        [one] => format!("{one} baud"),
        many => format!("{} baud rates", many.len()),
    }
}
