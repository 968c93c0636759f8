//! `servobus bench`: the achieved bus update rate of a robot's buses.
//!
//! Each bus runs free (no pacing) for a fixed time, cycle after cycle: a
//! SYNC WRITE of every servo's goal position, then a SYNC READ of every
//! present position (one READ per servo on SCS buses). The goals are the
//! positions read before the run, so nothing moves. The figures are compared
//! with what servobus-timing predicts for the same cycle: the wire-limited
//! rate (bytes on the wire only) and the planned rate (with the adapter
//! latency, return delays and turnarounds of the robot file).
//!
//! Without `--port` every bus is served by the simulator on its own
//! pseudo-terminal, paced at the wire rate, and reached through the same
//! serial-port code as real servos. There, once the bench is done, the
//! pseudo-terminal's own request/reply floor for the same bytes is measured
//! too (`floor_rate_hz`, [`servobus_robot::sim::pty_floor`]), and `floor_ratio` is
//! achieved / floor: both are mean rates, cycles per second.
//!
//! `overruns` counts the cycles whose period exceeded the planned full cycle
//! time (`budget`'s `cycle_time_us`).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{bail, Context};
use serde::Serialize;
use servobus_config::{load_robot, BusConfig, Robot, RobotOptions};
use servobus_robot::bench::Quantiles;
use servobus_robot::sim::PtyServer;

use crate::shared::out::{outln, StdoutError};
use crate::shared::ports::{bus_ports, open_bus, Allowance};
use servobus_robot::bench::{measure_link, measure_on, BenchError, BusBench};

mod floor;

/// Arguments of `servobus bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot: a file, or a built-in name (default: the built-in so101).
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub robot: Option<PathBuf>,
    /// Its port (without one, the simulator on a pty) and calibration:
    /// with a port it must match the servos.
    #[command(flatten)]
    pub hardware: crate::shared::flags::HardwareArgs,
    /// How long to measure, in seconds.
    #[arg(long, default_value = "5", value_parser = crate::shared::args::measure_seconds_arg)]
    pub seconds: Duration,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Wait for replies by polling the port without blocking, on every bus
    /// (as `busy_poll: true` in the robot file).
    #[arg(long)]
    pub busy_poll: bool,
    /// Accept a robot whose rate is above its buses' maximum (servos read
    /// round-robin when it plays), as `round_robin: true` on every bus.
    #[arg(long)]
    pub round_robin: bool,
}

/// The whole report: the slowest bus's figures at the top level (the ones
/// the architecture page lists), every bus in `buses`.
#[derive(Debug, Clone, Serialize)]
struct BenchReport {
    robot: String,
    seconds: f64,
    cycles: u64,
    achieved_rate_hz: f64,
    planned_rate_hz: f64,
    wire_limited_rate_hz: f64,
    /// Achieved over wire-limited rate.
    efficiency: f64,
    /// The slowest bus's pty floor, mean rate, Hz (0 on serial ports).
    floor_rate_hz: f64,
    /// The slowest bus's achieved over floor rate (0 without a floor).
    floor_ratio: f64,
    period_error_us: Quantiles,
    /// Cycles, over every bus, whose period exceeded the planned cycle time.
    overruns: u64,
    timeouts: u64,
    /// Replies that came after their deadline (the servo answered, the
    /// host delivered them late), over every bus: not timeouts.
    late_replies: u64,
    retries: u64,
    missed_replies: u64,
    buses: Vec<BusBench>,
}

/// Runs `servobus bench`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let path = args
        .robot
        .clone()
        .unwrap_or_else(|| servobus::builtin::robot_path_or_name("so101".as_ref()));
    let mut robot = load_robot(
        &path,
        &RobotOptions::default()
            .calibration(args.hardware.calibration.as_deref())
            .any_rate(),
    )?;
    // The robot's rate must fit as it would for `play`: bench measures the
    // cycle that rate would run.
    for bus in &mut robot.buses {
        bus.round_robin |= args.round_robin;
        if let Err(why) = bus.check_rate(robot.rate_hz) {
            let why = crate::shared::flags::rate_advice(&why);
            return Err(crate::shared::exit::input(format!(
                "robot `{}`, bus `{}`: its rate {}",
                robot.name, bus.name, why
            )));
        }
    }
    let duration = args.seconds;

    let mut runs = Vec::new();
    let ports = bus_ports(&robot, args.hardware.port.as_slice());
    for ((index, bus), port) in robot.buses.iter().enumerate().zip(ports) {
        let robot = robot.clone();
        let mut bus = bus.clone();
        bus.busy_poll |= args.busy_poll;
        runs.push(std::thread::spawn(move || {
            bench_bus(&robot, index, &bus, port, duration)
        }));
    }
    let mut buses = Vec::new();
    for run in runs {
        match run.join() {
            Ok(result) => buses.push(result?),
            Err(_) => bail!("a bus thread panicked"),
        }
    }
    let report = summarise(&robot, args.seconds.as_secs_f64(), buses);
    if args.json {
        outln!("{}", crate::shared::json::pretty(&report)?)?;
    } else {
        print_text(&report)?;
    }
    Ok(ExitCode::SUCCESS)
}

fn bench_bus(
    robot: &Robot,
    index: usize,
    bus: &BusConfig,
    port: Option<String>,
    duration: Duration,
) -> anyhow::Result<BusBench> {
    // The simulator (when no port is given) serves until `stop`.
    let stop = Arc::new(AtomicBool::new(false));
    let (path, server, backend) = match &port {
        Some(port) => (port.clone(), None, format!("serial port {port}")),
        None => {
            let servos = servobus_robot::sim::bus_servos(robot, bus)?;
            let mut server = PtyServer::open(bus.baud, servos)
                .with_context(|| format!("bus `{}`: cannot start the simulator", bus.name))?;
            let path = server.path().to_string_lossy().into_owned();
            let flag = Arc::clone(&stop);
            let handle = std::thread::spawn(move || server.serve(&flag));
            (path, Some(handle), "simulator on a pty".to_string())
        }
    };
    let server_ran = server.is_some();
    let mut measured_latency_us = None;
    // One bus for the calibration check and the measurement: the port is
    // opened once.
    let result = open_bus(bus, &path, Allowance::Assumed).and_then(|mut servo_bus| {
        if let Some(port) = &port {
            crate::shared::check_bus(robot, index, &mut servo_bus, port)?;
        }
        // On a port, the cycle is planned on the adapter as measured (the
        // probe `budget --port` runs); on the simulator, as `budget` plans.
        let link = match &port {
            Some(_) => {
                let pty = servo_bus.transport().is_pty();
                let measured = measure_link(&mut servo_bus, bus, pty)?;
                measured_latency_us = Some(measured.ping_latency.as_secs_f64() * 1e6);
                measured.link
            }
            None => bus.budget_link(),
        };
        measure_on(&mut servo_bus, bus, &link, duration).map_err(|e| match e {
            e @ BenchError::Missing { .. } => {
                anyhow::anyhow!("{e}; check the port and `servobus scan`")
            }
            e => e.into(),
        })
    });
    stop.store(true, Ordering::SeqCst);
    if let Some(handle) = server {
        match handle.join() {
            Ok(served) => served.with_context(|| format!("bus `{}`: simulator", bus.name))?,
            Err(_) => bail!("bus `{}`: the simulator thread panicked", bus.name),
        }
    }
    let mut bench = result?;
    bench.backend = backend;
    bench.measured_latency_us = measured_latency_us;
    if server_ran {
        // Measured after the bench, not beside it: the two would share the
        // machine's cores and slow each other down.
        bench.floor_rate_hz = floor::floor_rate_hz(bus, duration)?;
        bench.floor_ratio = bench.achieved_rate_hz / bench.floor_rate_hz.max(f64::MIN_POSITIVE);
    }
    Ok(bench)
}

fn summarise(robot: &Robot, seconds: f64, buses: Vec<BusBench>) -> BenchReport {
    let slowest = buses
        .iter()
        .min_by(|a, b| a.achieved_rate_hz.total_cmp(&b.achieved_rate_hz));
    let pick = |f: fn(&BusBench) -> f64| slowest.map_or(0.0, f);
    let achieved = pick(|b| b.achieved_rate_hz);
    let wire = pick(|b| b.wire_limited_rate_hz);
    BenchReport {
        robot: robot.name.clone(),
        seconds,
        cycles: slowest.map_or(0, |b| b.cycles),
        achieved_rate_hz: achieved,
        planned_rate_hz: pick(|b| b.planned_rate_hz),
        wire_limited_rate_hz: wire,
        efficiency: if wire > 0.0 { achieved / wire } else { 0.0 },
        floor_rate_hz: pick(|b| b.floor_rate_hz),
        floor_ratio: pick(|b| b.floor_ratio),
        period_error_us: slowest.map_or_else(Quantiles::default, |b| b.period_error_us),
        overruns: buses.iter().map(|b| b.overruns).sum(),
        timeouts: buses.iter().map(|b| b.timeouts).sum(),
        late_replies: buses.iter().map(|b| b.late_replies).sum(),
        retries: buses.iter().map(|b| b.retries).sum(),
        missed_replies: buses.iter().map(|b| b.missed_replies).sum(),
        buses,
    }
}

fn print_text(r: &BenchReport) -> Result<(), StdoutError> {
    outln!("bench of {} for {:.1} s", r.robot, r.seconds)?;
    for b in &r.buses {
        outln!(
            "bus {} ({} servos, {}{}): {} cycles, {:.1} Hz achieved; wire-limited {:.1} Hz \
             ({:.1} %), planned with latencies {:.1} Hz",
            b.name,
            b.servos,
            b.backend,
            if b.busy_poll { ", busy polling" } else { "" },
            b.cycles,
            b.achieved_rate_hz,
            b.wire_limited_rate_hz,
            100.0 * b.achieved_rate_hz / b.wire_limited_rate_hz.max(f64::MIN_POSITIVE),
            b.planned_rate_hz,
        )?;
        outln!(
            "  period us: p50 {:.0}  p99 {:.0}  max {:.0};  error from the mean: p50 {:.0}  p99 {:.0}  max {:.0}",
            b.period_us.p50,
            b.period_us.p99,
            b.period_us.max,
            b.period_error_us.p50,
            b.period_error_us.p99,
            b.period_error_us.max
        )?;
        if b.floor_rate_hz > 0.0 {
            outln!(
                "  the pty's own floor for this cycle: {:.1} Hz (mean); achieved / floor {:.3}",
                b.floor_rate_hz,
                b.floor_ratio
            )?;
        }
        outln!(
            "  overruns {} (cycles longer than the planned {:.0} us)  timeouts {}  late replies {}  \
             retries {}  missed replies {}  checksum errors {}",
            b.overruns,
            1e6 / b.planned_rate_hz.max(f64::MIN_POSITIVE),
            b.timeouts,
            b.late_replies,
            b.retries,
            b.missed_replies,
            b.checksum_errors
        )?;
        let w = b
            .servo_rtt
            .iter()
            .map(|s| s.joint.len())
            .fold(16, usize::max);
        for s in &b.servo_rtt {
            outln!(
                "  servo {:>3} {:<w$} round trip mean {:>6.0} us  max {:>6.0} us  ({} replies, {} timeouts)",
                s.id, s.joint, s.rtt_mean_us, s.rtt_max_us, s.replies, s.timeouts
            )?;
        }
    }
    Ok(())
}
