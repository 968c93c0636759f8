//! `servobus budget`: what one control cycle costs on each bus of a robot,
//! the fastest rate it allows, and what to change when a rate does not fit.

use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use serde::Serialize;
use servobus_config::{load_robot, BusConfig, RobotOptions};
use servobus_robot::bench::{measure_link, MeasuredLink};
use servobus_robot::timing::{floor_rate_hz, Change, Link, Plan};

use crate::shared::out::{errln, out, outln};
use crate::shared::ports::{open_bus, Allowance};

/// Arguments of `servobus budget`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot: a file, or a built-in name (`servobus list`).
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub robot: std::path::PathBuf,
    /// Control rate in Hz (default: the robot's).
    #[arg(long, value_parser = crate::shared::args::rate_arg)]
    pub rate: Option<f64>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Serial port of the robot's first bus: measure its adapter first
    /// (the start-up probe of `latency_us: auto`) and budget on what was
    /// measured. Without it, the robot file's latency, and on the built-in
    /// simulator the pseudo-terminal's cost of each exchange.
    #[arg(long)]
    pub port: Option<String>,
}

/// One bus in `--json` output (the names are the architecture page's).
#[derive(Debug, Serialize)]
struct BusBudget {
    name: String,
    servos: usize,
    bytes_per_cycle: usize,
    wire_time_us: f64,
    /// The servos' turnarounds of the full cycle (one per reply), us.
    turnaround_time_us: f64,
    /// The servos' return delays of the full cycle (one per reply), us.
    return_delay_time_us: f64,
    /// The adapter's latency of the full cycle (one per round trip), us.
    latency_time_us: f64,
    /// The link's overheads of the full cycle (one per round trip, one
    /// per reply: the pseudo-terminal's hand-offs on the simulator), us.
    overhead_time_us: f64,
    /// Where the link's costs come from: `simulator` (the built-in
    /// simulator's pseudo-terminal), `robot file` or `measured` (`--port`).
    link: String,
    /// The port measured (`--port`), if any.
    port: Option<String>,
    /// The median of what each PING of the measurement took beyond the
    /// wire and the servo, us (with `--port`; else null).
    measured_latency_us: Option<f64>,
    /// The rate the wire alone allows (no turnaround, return delay,
    /// latency or overhead), Hz.
    wire_limited_rate_hz: f64,
    cycle_time_us: f64,
    max_rate_hz: f64,
    rate_hz: f64,
    utilisation: f64,
    /// Every servo read back every cycle at `rate_hz`.
    feasible: bool,
    /// Each servo is read once every this many cycles (0: the rate cannot
    /// run at all).
    read_every: usize,
    /// The changes that would make the full cycle fit, cheapest first.
    fixes: Vec<String>,
    /// The bus allows reading servos round-robin (`round_robin: true`).
    round_robin: bool,
}

#[derive(Debug, Serialize)]
struct Budget {
    buses: Vec<BusBudget>,
}

/// Runs `servobus budget`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let robot = load_robot(&args.robot, &RobotOptions::default().any_rate())?;
    // Both checked: `--rate` by its parser, the robot's rate by the loader.
    let rate = args.rate.unwrap_or(robot.rate_hz);
    let mut out = Budget { buses: Vec::new() };
    let mut text = String::new();
    // The rate fits when every bus reads every servo each cycle, or runs a
    // round-robin cycle its robot file explicitly allows.
    let mut all_fit = true;
    text.push_str(&format!(
        "robot `{}` ({}) at {} Hz: each cycle writes goal positions and reads present positions\n",
        robot.name,
        robot.path.display(),
        fmt_hz(rate)
    ));
    for (index, bus) in robot.buses.iter().enumerate() {
        // Only the bus whose port the command line gives is measured.
        let measured = match (&args.port, index) {
            (Some(port), 0) => Some(measure(bus, port)?),
            _ => None,
        };
        let (budget, lines) = bus_budget(bus, rate, measured.as_ref())?;
        all_fit &= budget.feasible || (bus.round_robin && budget.read_every > 0);
        text.push_str(&lines);
        out.buses.push(budget);
    }
    if args.json {
        outln!("{}", crate::shared::json::pretty(&out)?)?;
    } else {
        out!("{text}")?;
    }
    Ok(if all_fit {
        ExitCode::SUCCESS
    } else {
        if !args.json {
            errln!(
                "error: {} Hz does not fit every bus of `{}` (see the fixes above)",
                fmt_hz(rate),
                robot.name
            );
        }
        ExitCode::FAILURE
    })
}

/// A port's adapter, measured as a run with `latency_us: auto` does.
struct Measured {
    port: String,
    link: MeasuredLink,
}

/// Opens `port` for `bus` and measures its adapter.
fn measure(bus: &BusConfig, port: &str) -> anyhow::Result<Measured> {
    let mut servo_bus = open_bus(bus, port, Allowance::Assumed)?;
    let pty = servo_bus.transport().is_pty();
    let link = measure_link(&mut servo_bus, bus, pty)
        .with_context(|| format!("measuring the adapter on {port}"))?;
    Ok(Measured {
        port: port.to_owned(),
        link,
    })
}

/// The figures of one bus at `rate`, and their human-readable lines.
fn bus_budget(
    bus: &BusConfig,
    rate: f64,
    measured: Option<&Measured>,
) -> anyhow::Result<(BusBudget, String)> {
    let cost = BusCost::new(bus, rate, measured)?;
    let budget = cost.figures();
    let mut s = cost.header_lines();
    cost.push_time_lines(&mut s, &budget);
    cost.push_verdict(&mut s, &budget);
    Ok((budget, s))
}

/// One bus's cycle at a rate: what its `--json` figures and its lines are
/// both made of.
struct BusCost<'a> {
    /// The bus, as its robot file gives it.
    bus: &'a BusConfig,
    /// Its adapter as measured (`--port`), if it was.
    measured: Option<&'a Measured>,
    /// The control rate asked for, Hz.
    rate: f64,
    /// The link the cycle is costed on.
    link: Link,
    /// A plan whose full cycle (every servo read) is the bus's, whatever
    /// the rate.
    reference: Plan,
    /// The plan at `rate`, or why it cannot run.
    at_rate: Result<Plan, String>,
}

/// A duration in microseconds.
fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

impl<'a> BusCost<'a> {
    /// Plans `bus` at `rate` on its link (as measured, if it was).
    fn new(bus: &'a BusConfig, rate: f64, measured: Option<&'a Measured>) -> anyhow::Result<Self> {
        let link = measured.map_or_else(|| bus.budget_link(), |m| m.link.link);
        // The full cycle's cost does not depend on the rate: plan at a rate any
        // bus can run to get it even when `rate` itself cannot run.
        let reference = bus
            .plan_on(&link, f64::MIN_POSITIVE)
            .with_context(|| format!("bus `{}`", bus.name))?;
        Ok(BusCost {
            bus,
            measured,
            rate,
            link,
            reference,
            at_rate: bus.plan_on(&link, rate).map_err(|e| e.to_string()),
        })
    }

    /// Each servo is read once every this many cycles (0: cannot run).
    fn read_every(&self) -> usize {
        self.at_rate.as_ref().map_or(0, Plan::read_every)
    }

    /// Where the link's costs come from.
    fn source(&self) -> &'static str {
        match self.measured {
            Some(_) => "measured",
            None if self.bus.port.is_none() => "simulator",
            None => "robot file",
        }
    }

    /// The `--json` figures of the bus.
    fn figures(&self) -> BusBudget {
        let (bus, full, link) = (self.bus, self.reference.full_cycle(), &self.link);
        let fixes = self.at_rate.as_ref().map_or_else(|_| Vec::new(), fix_list);
        let overhead = Link {
            latency: Duration::ZERO,
            ..*link
        }
        .exchange_cost(full.round_trips, full.servos_read);
        BusBudget {
            name: bus.name.clone(),
            servos: bus.joints.len(),
            bytes_per_cycle: full.bytes,
            wire_time_us: full.wire_time_us(),
            turnaround_time_us: us(link.turnaround) * full.servos_read as f64,
            return_delay_time_us: us(bus.return_delay) * full.servos_read as f64,
            latency_time_us: us(link.latency) * full.round_trips as f64,
            overhead_time_us: us(overhead),
            link: self.source().to_owned(),
            port: self.measured.map(|m| m.port.clone()),
            measured_latency_us: self.measured.map(|m| us(m.link.ping_latency)),
            wire_limited_rate_hz: full.wire_limited_rate_hz(),
            cycle_time_us: full.cycle_time_us(),
            max_rate_hz: full.max_rate_hz(),
            rate_hz: self.rate,
            utilisation: full.utilisation(self.rate),
            feasible: self.read_every() == 1,
            read_every: self.read_every(),
            fixes: fixes.iter().map(ToString::to_string).collect(),
            round_robin: bus.round_robin,
        }
    }

    /// The bus's first lines: its servos and link, and what a cycle sends.
    fn header_lines(&self) -> String {
        let (bus, full) = (self.bus, self.reference.full_cycle());
        let latency = match self.measured {
            Some(m) => format!(
                "measured on {}: {:.0} us a PING beyond the wire and the servo ({} PINGs)",
                m.port,
                us(m.link.ping_latency),
                m.link.pings
            ),
            None if bus.latency_auto => {
                "auto (measured when the robot runs, or with --port; 0 here)".to_owned()
            }
            None => format!("{} us", bus.latency.as_micros()),
        };
        let mut s = format!(
            "\nbus `{}`: {} servos at {} baud, adapter latency {latency}, return delay {} us\n",
            bus.name,
            bus.joints.len(),
            bus.baud,
            bus.return_delay.as_micros()
        );
        let sync = bus
            .joints
            .iter()
            .filter(|j| j.model.series.has_sync_read())
            .count();
        let feedback = match (sync, bus.joints.len() - sync) {
            (_, 0) => "one SYNC READ".to_owned(),
            (0, n) => format!("{n} READs (no SYNC READ on these servos)"),
            (_, n) => format!("one SYNC READ and {n} READs"),
        };
        s.push_str(&format!(
            "  per cycle: {} bytes in {} SYNC WRITE frame(s) and {feedback}, {} round trip(s)\n",
            full.bytes, full.write_frames, full.round_trips
        ));
        s
    }

    /// Adds the lines of the cycle's time: in all, where it goes, and the
    /// rates it allows.
    fn push_time_lines(&self, s: &mut String, budget: &BusBudget) {
        let (full, link) = (self.reference.full_cycle(), &self.link);
        s.push_str(&format!(
            "  wire time {:.0} us; cycle time {:.0} us with return delays, turnarounds, latency \
             and the link's overhead\n",
            full.wire_time_us(),
            full.cycle_time_us()
        ));
        s.push_str(&format!(
            "  where the {:.0} us go: wire {:.0}; turnaround {} x {:.0} = {:.0} (a guess per reply); \
             return delay {} x {:.0} = {:.0}; adapter latency {} x {:.0} = {:.0}; link overhead \
             {} x {:.0} + {} x {:.0} = {:.0} ({})\n",
            full.cycle_time_us(),
            full.wire_time_us(),
            full.servos_read,
            us(link.turnaround),
            budget.turnaround_time_us,
            full.servos_read,
            us(self.bus.return_delay),
            budget.return_delay_time_us,
            full.round_trips,
            us(link.latency),
            budget.latency_time_us,
            full.round_trips,
            us(link.overhead),
            full.servos_read,
            us(link.reply_overhead),
            budget.overhead_time_us,
            match self.source() {
                "simulator" => "the built-in simulator's pseudo-terminal",
                "measured" => "measured",
                _ => "none given",
            },
        ));
        s.push_str(&format!(
            "  maximum rate {} Hz on this link (the wire alone: {} Hz)\n",
            fmt_hz(full.fastest_rate_hz()),
            fmt_hz(full.wire_limited_rate_hz())
        ));
    }

    /// Adds the line of the rate asked for: its utilisation, whether it
    /// fits, and what would make it fit.
    fn push_verdict(&self, s: &mut String, budget: &BusBudget) {
        s.push_str(&format!(
            "  at {} Hz: utilisation {:.1} %",
            fmt_hz(self.rate),
            100.0 * budget.utilisation
        ));
        match &self.at_rate {
            Ok(_) if budget.feasible => s.push_str(", fits\n"),
            Ok(p) => {
                let (per, every) = (p.schedule().per_cycle, p.read_every());
                s.push_str(&if self.bus.round_robin {
                    format!(
                        "; the full cycle does not fit: round_robin reads {per} servo(s) per cycle, \
                         each every {every} cycles\n"
                    )
                } else {
                    format!(
                        "; does not fit (reading {per} servo(s) per cycle, each every {every} \
                         cycles, would: allow it with `round_robin: true` on the bus or \
                         `play --round-robin`)\n"
                    )
                });
                push_fixes(s, &fix_list(p));
            }
            Err(why) => s.push_str(&format!("; cannot run: {why}\n")),
        }
    }
}

/// The changes that would make the full cycle of `p` fit, cheapest first.
fn fix_list(p: &Plan) -> Vec<Change> {
    p.fixes().iter().collect()
}

/// Adds the list of `fixes`, if there are any.
fn push_fixes(s: &mut String, fixes: &[Change]) {
    if fixes.is_empty() {
        return;
    }
    s.push_str("  to read every servo every cycle, any one of:\n");
    for f in fixes {
        s.push_str(&format!("    - {f}\n"));
    }
}

/// A rate for people: whole hertz above 10 Hz (floored, as every maximum
/// is), one decimal below.
fn fmt_hz(hz: f64) -> String {
    if hz.is_infinite() {
        "unlimited".to_owned()
    } else if hz >= 10.0 {
        format!("{:.0}", floor_rate_hz(hz))
    } else {
        format!("{hz:.1}")
    }
}
