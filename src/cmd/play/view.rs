//! What `servobus play` shows while it runs: the progress, the log and plot
//! series, and Ctrl-C. A closed stdout (`play ... | head`) is taken as
//! Ctrl-C once: a jerk-limited stop, then hold and report (on stderr).

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use crossbeam_channel::RecvTimeoutError;
use servobus_config::Units;
use servobus_robot::{Command, CommandSender, Run, Telemetry};

use super::args::Args;
use crate::record::{CsvLog, PlotData};
use crate::shared::flags::Recording;
use crate::shared::out::{errln, outln, StdoutError};

/// How long the final position is held (and tracked) after the path.
pub(super) const SETTLE: Duration = servobus_robot::SETTLE;

/// The fraction of the limits the runtime's approach moves at (its
/// `RunOptions::approach`).
pub(super) const APPROACH: f64 = servobus_robot::APPROACH;

/// What the live view and the plot show besides the telemetry.
pub(super) struct Shown<'a> {
    pub(super) names: Vec<String>,
    /// The name of each joint's bus.
    pub(super) bus_of: Vec<String>,
    /// Path times of the keyframes.
    pub(super) keyframes: Vec<f64>,
    /// The approach to the path's start as the run planned it
    /// ([`Run::approach`]), s: the path's times shift by it.
    pub(super) approach: f64,
    pub(super) settle: f64,
    /// The robot's geometry, for the plot's views in space.
    pub(super) geometry: Option<servobus_kinematics::Geometry>,
    /// The recording replayed, per joint on the path's clock (see
    /// `RecordingInfo::series`): drawn beside the run on the plot.
    pub(super) recording: Option<&'a [Vec<(f64, f64)>]>,
}

/// What a run leaves to write once it has ended.
pub(super) struct Followed {
    /// The log, to finish.
    pub(super) log: Option<CsvLog>,
    /// The plot's series, to draw.
    pub(super) plot: Option<PlotData>,
    /// Why stdout could not be written while the run went on: the report
    /// goes to stderr then, and the command exits 1.
    pub(super) stdout: Option<StdoutError>,
}

/// Reads the telemetry until the run ends: progress, log, plot series.
#[allow(clippy::too_many_arguments)] // the run, its outputs and what they show
pub(super) fn follow(
    runner: &Run,
    args: &Args,
    (mut log, rerun): (Option<CsvLog>, &mut Recording),
    shown: &Shown,
    units: Units,
    duration: f64,
) -> anyhow::Result<Followed> {
    let mut plot = args.plot.as_ref().map(|_| {
        PlotData::new(shown.names.clone(), shown.bus_of.clone())
            .with_frames(shown.geometry.clone(), units)
    });
    let mut announced = false;
    let mut progress = Progress::new(args.json, duration, &units.to_string(), runner.commands());
    let telemetry = runner.telemetry();
    loop {
        let message = telemetry.recv_timeout(Duration::from_millis(100));
        if let Ok(m) = &message {
            rerun.telemetry(m);
        }
        match message {
            Ok(Telemetry::Cycle(sample)) => {
                if !announced {
                    announced = true;
                    let approach = shown.approach;
                    if approach > 0.0 {
                        progress.message(&format!("moving to the first keyframe, {approach:.1} s"));
                    }
                    progress.set_total(approach + duration + shown.settle);
                    if let Some(plot) = &mut plot {
                        plot.mark_approach(approach);
                        plot.mark_keyframes(shown.keyframes.iter().map(|t| t + approach));
                        if let Some(recording) = shown.recording {
                            plot.mark_recording(recording, approach);
                        }
                    }
                }
                if let Some(log) = &mut log {
                    // A failed write stops the log, not the run; it is
                    // reported after the run.
                    let failed = log.has_failed();
                    log.record(&sample);
                    if !failed && log.has_failed() {
                        progress.message(&format!(
                            "the log {} cannot be written; the run goes on without it",
                            log.path().display()
                        ));
                    }
                }
                if let Some(plot) = &mut plot {
                    plot.record(&sample);
                }
                progress.cycle(&sample);
            }
            Ok(Telemetry::Fault(fault)) => progress.message(&format!("fault: {fault}")),
            Ok(Telemetry::Finished(_)) => {}
            Ok(_) => {}
            Err(RecvTimeoutError::Timeout) => {
                if runner.is_finished() && telemetry.is_empty() {
                    break;
                }
            }
            Err(RecvTimeoutError::Disconnected) => break,
        }
    }
    progress.finish();
    Ok(Followed {
        log,
        plot,
        stdout: progress.stdout,
    })
}

/// The live progress: a bar on a terminal, a line a second otherwise.
pub(super) struct Progress {
    bar: Option<indicatif::ProgressBar>,
    plain: bool,
    units: String,
    duration: f64,
    worst: f64,
    first: Option<(u64, f64)>,
    last: (u64, f64),
    last_line: Instant,
    /// Where a closed stdout sends its stop.
    commands: CommandSender,
    /// Why stdout failed, once it has: no more lines go there.
    stdout: Option<StdoutError>,
}

impl Progress {
    pub(super) fn new(json: bool, duration: f64, units: &str, commands: CommandSender) -> Self {
        // The bar draws on stderr and hides itself when that is no
        // terminal: then plain lines on stdout instead.
        let terminal = std::io::stdout().is_terminal() && std::io::stderr().is_terminal();
        let bar = (!json && terminal).then(|| {
            let bar = indicatif::ProgressBar::new((duration * 1000.0).max(1.0) as u64);
            let style = indicatif::ProgressStyle::with_template("{spinner} [{bar:40}] {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> ");
            bar.set_style(style);
            bar
        });
        Progress {
            bar,
            plain: !json && !terminal,
            units: units.to_string(),
            duration,
            worst: 0.0,
            first: None,
            last: (0, 0.0),
            last_line: Instant::now(),
            commands,
            stdout: None,
        }
    }

    pub(super) fn cycle(&mut self, sample: &servobus_robot::CycleSample) {
        for j in sample.joints() {
            if j.measured.is_some() && !j.stale {
                self.worst = self.worst.max(j.error.abs());
            }
        }
        if sample.bus != 0 {
            return;
        }
        let first = *self.first.get_or_insert((sample.cycle, sample.time_s));
        self.last = (sample.cycle, sample.time_s);
        let span = self.last.1 - first.1;
        let rate = if span > 0.0 {
            (self.last.0 - first.0) as f64 / span
        } else {
            0.0
        };
        let msg = format!(
            "{:.1} / {:.1} s  {:.1} Hz  worst error {:.2} {}",
            sample.time_s, self.duration, rate, self.worst, self.units
        );
        if let Some(bar) = &self.bar {
            bar.set_length((self.duration.max(sample.time_s) * 1000.0) as u64);
            bar.set_position((sample.time_s * 1000.0) as u64);
            bar.set_message(msg);
        } else if self.plain && self.last_line.elapsed() >= Duration::from_secs(1) {
            self.last_line = Instant::now();
            if let Err(e) = outln!("{msg}") {
                self.stdout_failed(e);
            }
        }
    }

    /// Stdout failed: no more lines go there. Closed by its reader, it is
    /// a stop as Ctrl-C's; any other failure leaves the motion to end.
    fn stdout_failed(&mut self, e: StdoutError) {
        self.plain = false;
        if e.is_closed() {
            errln!("\nstdout was closed: stopping (jerk-limited), then holding");
            // The run may have ended already; nothing else to do then.
            let _ = self.commands.try_send(Command::Stop);
        } else {
            errln!("\n{e}: the run goes on, its report will be on stderr");
        }
        self.stdout = Some(e);
    }

    /// The run's whole length: approach, path and settling.
    pub(super) fn set_total(&mut self, total_s: f64) {
        self.duration = total_s;
    }

    pub(super) fn message(&self, text: &str) {
        match &self.bar {
            Some(bar) => bar.println(text),
            None => errln!("{text}"),
        }
    }

    pub(super) fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
