//! What `servobus follow` keeps of the follower's telemetry while it
//! follows: the log and plot being written, the take for `--record`, the
//! recording for the Rerun viewer, the errors against the leader, the
//! faults and the stalls.

use servobus_config::Robot;
use servobus_robot::{CycleSample, Telemetry};

use super::against::FollowErrors;
use super::args::Args;
use crate::record::{CsvLog, PlotData};
use crate::shared::flags::Recording;
use crate::shared::out::errln;

/// What the follower's telemetry gives while following.
pub(super) struct Seen {
    /// The `--log` being written.
    pub(super) log: Option<CsvLog>,
    /// The `--plot` series being gathered.
    pub(super) plot: Option<PlotData>,
    /// `time_s` and commanded angles (robot units) per cycle, for --record.
    pub(super) take: Vec<(f64, Vec<f64>)>,
    /// The follower's readings against the leader's.
    pub(super) errors: FollowErrors,
    /// The newest commanded angle of each joint (robot units).
    commanded: Vec<f64>,
    /// The follower cycles seen.
    pub(super) cycles: u64,
    /// The faults reported, as text.
    pub(super) faults: Vec<String>,
    /// The follower's joint names, for the stall lines.
    pub(super) names: Vec<String>,
    /// Stall events: joint index, held (or let go), time s, position.
    pub(super) stalls: Vec<(usize, bool, f64, f64)>,
    /// A live line rewritten in place is on stderr (a terminal): a warning
    /// starts a line of its own.
    pub(super) live_line: bool,
    /// The recording for the Rerun viewer (`--rerun`, `--rerun-connect`),
    /// every message of the follower's telemetry handed to it.
    pub(super) rerun: Recording,
}

impl Seen {
    /// Nothing seen yet: the log created (`--log`), the plot's series
    /// ready (`--plot`), the recording started (`--rerun`: the follower's
    /// tree and meshes logged); `terminal`: stderr is one.
    pub(super) fn new(
        args: &Args,
        robot: &Robot,
        names: &[String],
        terminal: bool,
    ) -> anyhow::Result<Self> {
        let units = robot.units;
        let log = match &args.log {
            Some(path) => Some(CsvLog::create(
                path,
                names.to_vec(),
                units,
                robot.geometry(),
                servobus_robot::odometry::Odometer::of(robot, units),
            )?),
            None => None,
        };
        let bus_of = robot
            .buses
            .iter()
            .flat_map(|b| b.joints.iter().map(|_| b.name.clone()))
            .collect();
        Ok(Seen {
            log,
            plot: args.plot.as_ref().map(|_| {
                PlotData::new(names.to_vec(), bus_of)
                    .following()
                    .with_frames(robot.geometry(), units)
            }),
            take: Vec::new(),
            errors: FollowErrors::new(names.len()),
            commanded: vec![0.0; names.len()],
            cycles: 0,
            faults: Vec::new(),
            names: names.to_vec(),
            stalls: Vec::new(),
            live_line: !args.json && terminal,
            rerun: args.rerun.start(robot, units)?,
        })
    }

    /// Takes a message of the follower's telemetry in: a cycle
    /// ([`Seen::sample`]), a fault or a stall said on stderr and kept.
    pub(super) fn take(&mut self, m: Telemetry, record: bool) {
        self.rerun.telemetry(&m);
        match m {
            Telemetry::Cycle(s) => self.sample(&s, record),
            Telemetry::Fault(f) => {
                errln!("fault: {f}");
                self.faults.push(f.to_string());
            }
            Telemetry::Stall(e) => {
                let name = self.names.get(e.joint).map_or("?", String::as_str);
                let start = if self.live_line { "\n" } else { "" };
                if e.held {
                    errln!(
                        "{start}warning: {name} (ID {}) stalled at {:.1} at {:.2} s: held there \
                         with its goal within {:.1} of it (bounded effort); the session goes on",
                        e.servo_id,
                        e.position,
                        e.time_s,
                        e.push.abs()
                    );
                } else {
                    errln!("{start}{name} follows again at {:.2} s", e.time_s);
                }
                self.stalls.push((e.joint, e.held, e.time_s, e.position));
            }
            _ => {}
        }
    }

    /// Takes one follower cycle: logged, plotted, its errors counted, and
    /// its commanded angles kept for `--record`.
    pub(super) fn sample(&mut self, s: &CycleSample, record: bool) {
        if let Some(log) = &mut self.log {
            log.record(s);
        }
        if let Some(plot) = &mut self.plot {
            plot.record(s);
        }
        self.errors.sample(s);
        for j in s.joints() {
            if let Some(c) = self.commanded.get_mut(j.joint) {
                *c = j.commanded;
            }
        }
        self.cycles += 1;
        if record {
            self.take.push((s.time_s, self.commanded.clone()));
        }
    }
}
