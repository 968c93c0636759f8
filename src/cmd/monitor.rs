//! `servobus monitor`: a live view of every servo of a bus (or one JSON line
//! per refresh), and the same view of a running motion for
//! `servobus play --monitor`. The reading and the drawing live in
//! [`servobus::monitor`]; this file owns the terminal and the keys.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{bail, Context};
use servobus::monitor::{self, view, Poller, Watched};
use servobus_config::{load_robot, Robot, RobotOptions};
use servobus_protocol::registers::Series;
use servobus_robot::bus::{Bus, Transport};

use crate::shared::out::{errln, outln};
use crate::shared::ports::{open_bus, open_plain_bus, Allowance};
use crate::shared::screen::{key, terminal_available, test_panic_after, Key, Screen, TEST_PANIC};

/// Baud rate a scan without a robot file uses (the servos' factory rate).
const SCAN_BAUD: u32 = 1_000_000;

/// Arguments of `servobus monitor`.
#[derive(Debug, clap::Args)]
#[command(
    mut_arg("port", |a| a.help(
        "Serial port (without --robot, every servo found on it is watched)"
    )),
    mut_arg("calibration", |a| a.requires("robot").help(
        "Calibration file for the joint angles (default: the one the robot file names with \
         `calibration:`)"
    ))
)]
pub struct Args {
    /// Robot file (or a built-in robot's name): joint names, models and the
    /// bus (without --port, its built-in simulator).
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub robot: Option<PathBuf>,
    /// The port and the calibration.
    #[command(flatten)]
    pub hardware: crate::shared::flags::HardwareArgs,
    /// Print one JSON line per refresh instead of the live view (what
    /// happens anyway without a terminal). Exits 1 when a refresh saw a
    /// servo missing or reporting a status flag.
    #[arg(long)]
    pub json: bool,
    /// Refreshes per second.
    #[arg(long, default_value = "20", value_parser = crate::shared::args::refresh_rate_arg)]
    pub rate: f64,
    /// Stop after this many refreshes (default: until `q`, or Ctrl-C).
    #[arg(long, value_parser = crate::shared::args::count_arg)]
    pub count: Option<u64>,
    /// The robot file's bus to watch (default: the first).
    #[arg(long)]
    pub bus: Option<String>,
}

/// Runs `servobus monitor`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let robot = match &args.robot {
        Some(path) => Some(load_robot(
            path,
            &RobotOptions::default()
                .calibration(args.hardware.calibration.as_deref())
                .any_rate(),
        )?),
        None => None,
    };
    let cfg = match &robot {
        Some(r) => {
            let found = match &args.bus {
                Some(name) => r.buses.iter().find(|b| &b.name == name),
                None => r.buses.first(),
            };
            Some(found.ok_or_else(|| no_such_bus(r, args.bus.as_deref()))?)
        }
        None => None,
    };
    // Before the bus is touched: without a terminal, JSON lines instead.
    let live = !args.json && terminal_available();
    if !args.json && !live {
        errln!(
            "note: no terminal (stdin and stdout must be one): printing one JSON line per \
             refresh instead of the live view, as --json does"
        );
    }
    let port = args
        .hardware
        .port
        .clone()
        .or_else(|| cfg.and_then(|c| c.port.clone()));
    match (port, robot.as_ref(), cfg) {
        (Some(port), _, _) => {
            let mut bus = match cfg {
                Some(c) => open_bus(c, &port, Allowance::Assumed)?,
                None => open_plain_bus(&port, SCAN_BAUD, Series::Sts, None)?,
            };
            if let (Some(r), Some(c)) = (robot.as_ref(), cfg) {
                // Angles are shown through the calibration: the servos must
                // match it (and hold its session offsets) first.
                let index = r.buses.iter().position(|b| b.name == c.name).unwrap_or(0);
                crate::shared::check_bus(r, index, &mut bus, &port)?;
            }
            let servos = match (robot.as_ref(), cfg) {
                (Some(r), Some(c)) => Watched::of_bus(c, r.units),
                _ => Poller::scan(&mut bus).context("scanning the port")?,
            };
            if servos.is_empty() {
                bail!("no servo answered on {port}");
            }
            watch(&mut bus, Poller::new(servos), &args, live, &port, |_| {})
        }
        (None, Some(r), Some(c)) => {
            let index = r.buses.iter().position(|b| b.name == c.name).unwrap_or(0);
            let mut buses = servobus_robot::sim::virtual_buses(r)?;
            let mut bus = buses.swap_remove(index);
            let poller = Poller::new(Watched::of_bus(c, r.units));
            let title = format!("{} (built-in simulator)", r.name);
            // The simulator runs in virtual time: keep it level with the
            // wall clock.
            let started = Instant::now();
            watch(&mut bus, poller, &args, live, &title, |b| {
                b.clock().advance_to(started.elapsed());
            })
        }
        _ => Err(crate::shared::exit::input(
            "give --robot FILE, --port PATH, or both",
        )),
    }
}

/// `--bus NAME` that the robot file does not have (or a robot file with no
/// bus at all): an input error naming the buses there are.
fn no_such_bus(robot: &Robot, name: Option<&str>) -> anyhow::Error {
    let names: Vec<&str> = robot.buses.iter().map(|b| b.name.as_str()).collect();
    let file = robot.path.display();
    match name {
        Some(name) => crate::shared::exit::input(format!(
            "--bus {name}: {file} has no such bus (buses: {})",
            names.join(", ")
        )),
        None => crate::shared::exit::input(format!("{file}: the robot has no bus")),
    }
}

/// Watches the servos until `q` or `--count` refreshes: on the screen when
/// `live`, else one JSON line per refresh. Exits 1 when any refresh saw a
/// servo missing or reporting a status flag.
fn watch<T: Transport>(
    bus: &mut Bus<T>,
    mut poller: Poller,
    args: &Args,
    live: bool,
    title: &str,
    mut before_poll: impl FnMut(&Bus<T>),
) -> anyhow::Result<ExitCode> {
    let period = Duration::from_secs_f64(1.0 / args.rate);
    let mut screen = if live { Some(Screen::open()?) } else { None };
    if screen.is_none() {
        // Without a screen (a pipe, a log) Ctrl-C, SIGTERM and SIGHUP end
        // the watch after the line being written: a reader never gets half
        // a line, and the exit status is the watch's own.
        if let Err(e) = servobus_robot::bus::catch_stop_signals() {
            errln!("warning: signals cannot be caught ({e}): Ctrl-C may cut the last line");
        }
    }
    let mut problem = false;
    let mut note: Option<String> = None;
    let mut refreshes = 0u64;
    let mut next = Instant::now();
    let panic_after = test_panic_after();
    loop {
        before_poll(bus);
        poller.poll(bus).context("reading the servos")?;
        refreshes += 1;
        if panic_after == Some(refreshes) {
            panic!("{TEST_PANIC} asked for a panic after {refreshes} refreshes");
        }
        let frame = poller.frame(bus.clock(), note.clone());
        problem |= frame.has_problem();
        match &mut screen {
            None => outln!("{}", crate::shared::json::line(&frame)?)?,
            Some(s) => {
                s.0.draw(|f| view::draw(f, &frame, title))?;
            }
        }
        if args.count.is_some_and(|n| refreshes >= n) || stopped(screen.is_none()) {
            break;
        }
        next += period;
        // Keys are read until the next refresh is due.
        loop {
            let left = next.saturating_duration_since(Instant::now());
            if screen.is_none() {
                // In short naps, so that a stop signal ends the watch soon.
                let until = Instant::now() + left;
                while !stopped(true) && Instant::now() < until {
                    std::thread::sleep(until.saturating_duration_since(Instant::now()).min(NAP));
                }
                break;
            }
            match key(left)? {
                Some(Key::Quit) => return Ok(exit_code(problem)),
                Some(Key::TorqueOff) => {
                    monitor::torque_off(bus, poller.ids()).context("torque off")?;
                    note = Some("torque OFF sent to every servo (one SYNC WRITE)".into());
                }
                Some(Key::Other) => {}
                None => break,
            }
        }
        if Instant::now() > next + period {
            // Fell behind (a slow bus): start counting afresh.
            next = Instant::now();
        }
    }
    Ok(exit_code(problem))
}

/// The longest sleep between checks for a stop signal without a screen.
const NAP: Duration = Duration::from_millis(20);

/// Whether a stop signal came, where they are caught (without a screen).
fn stopped(caught: bool) -> bool {
    caught && servobus_robot::bus::stop_signal().is_some()
}

/// 1 when a problem was seen, else 0.
fn exit_code(problem: bool) -> ExitCode {
    if problem {
        ExitCode::from(crate::shared::exit::PROBLEM)
    } else {
        ExitCode::SUCCESS
    }
}
