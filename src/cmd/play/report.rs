//! The plan printed before a run of `servobus play` and the report after it.

use super::load::RecordingInfo;
use std::io::Write;
use std::path::Path;

use servobus_config::{Motion, Robot};
use servobus_robot::Trajectory;

use super::args::Args;
use super::setup::Backend;
use crate::record::{CsvLog, PlotData};
use crate::shared::flags::Recording;
use crate::shared::out::{err, out, outln, StdoutError};
use crate::shared::write_report;

pub(super) fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    )
}

pub(super) fn print_plan(
    motion: &Motion,
    robot: &Robot,
    trajectory: &Trajectory,
    rate_hz: f64,
    backend: &Backend,
) -> anyhow::Result<()> {
    let on = match backend {
        Backend::Fast => "the simulator, virtual time".to_string(),
        Backend::Simulated => "the simulator, real time".to_string(),
        Backend::Hardware(ports) => format!("servos on {}", ports.join(", ")),
    };
    outln!(
        "{} on {} ({} joints, {} bus{}) via {on}",
        file_name(&motion.path),
        robot.name,
        robot.joint_count(),
        robot.buses.len(),
        if robot.buses.len() == 1 { "" } else { "es" },
    )?;
    if motion.keyframes.is_empty() {
        // A recording has samples, not keyframes (its figures follow the
        // plan).
        outln!(
            "  path {:.2} s through a recording, at {rate_hz} Hz",
            trajectory.duration()
        )?;
    } else {
        outln!(
            "  path {:.2} s, {} keyframes x {}, at {rate_hz} Hz",
            trajectory.duration(),
            motion.keyframes.len(),
            motion.repeat
        )?;
    }
    for bus in &robot.buses {
        let plan = bus.plan(rate_hz)?;
        let every = if plan.read_every() > 1 {
            format!(", each servo read every {} cycles", plan.read_every())
        } else {
            String::new()
        };
        outln!(
            "  bus {}: {} servos at {} baud, {} B and {:.0} us per cycle, {:.1} % of the period \
             (max {:.0} Hz){every}",
            bus.name,
            plan.servos(),
            bus.baud,
            plan.bytes_per_cycle(),
            plan.cycle_time_us(),
            100.0 * plan.utilisation(),
            plan.fastest_rate_hz(),
        )?;
    }
    Ok(())
}

/// What became of the outputs written once the run has ended.
#[derive(Default)]
pub(super) struct Outputs {
    /// The outputs that could not be written, in order.
    failed: Vec<anyhow::Error>,
    log_written: bool,
    plot_written: bool,
    /// Where the recording for the Rerun viewer went, once finished.
    rerun: Option<String>,
}

impl Outputs {
    /// Finishes the log, if any: kept also when the run ended in an error.
    pub(super) fn finish_log(&mut self, log: Option<CsvLog>) {
        if let Some(log) = log {
            match log.finish() {
                Ok(()) => self.log_written = true,
                Err(e) => self.failed.push(e),
            }
        }
    }

    /// Finishes the recording for the Rerun viewer, if any: kept also
    /// when the run ended in an error (which it shows).
    pub(super) fn finish_rerun(&mut self, rerun: Recording) {
        match rerun.finish() {
            Ok(what) => self.rerun = what,
            Err(e) => self.failed.push(e),
        }
    }

    /// Draws the plot's series to `path`.
    pub(super) fn draw_plot(
        &mut self,
        plot: &PlotData,
        path: &Path,
        motion: &Motion,
        robot: &Robot,
    ) {
        let title = format!(
            "{} on {}: planned vs measured",
            file_name(&motion.path),
            robot.name
        );
        match plot.draw(path, &title, &motion.units.to_string()) {
            Ok(()) => self.plot_written = true,
            Err(e) => self.failed.push(e),
        }
    }

    /// Says every output that failed (before the run's own error).
    pub(super) fn say_failed(&self) {
        for failed in &self.failed {
            crate::shared::exit::report(failed);
        }
    }

    /// Prints the report `text` to stdout, or to stderr once stdout has
    /// failed (`stdout`: while the run went on). An output that failed
    /// fails the command (exit 1) after the report: each error is said,
    /// the last by `main` as it returns.
    pub(super) fn print(mut self, text: &[u8], stdout: Option<StdoutError>) -> anyhow::Result<()> {
        let text = String::from_utf8_lossy(text);
        // The report goes to stdout; once stdout has failed (closed by its
        // reader, or full), to stderr, and the command exits 1 after it.
        let stdout = match stdout {
            Some(e) => Some(e),
            None => out!("{text}").err(),
        };
        if let Some(e) = stdout {
            err!("{text}");
            self.failed.push(e.into());
        }
        let last = self.failed.pop();
        self.say_failed();
        match last {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// The report after the run: one JSON object with `--json`, else the text
/// report with the recording and the outputs written.
pub(super) fn report_text(
    args: &Args,
    report: &servobus_robot::Report,
    motion: &Motion,
    robot: &Robot,
    recording: Option<&RecordingInfo>,
    outputs: &Outputs,
) -> anyhow::Result<Vec<u8>> {
    let mut text = Vec::new();
    if args.json {
        let mut value = serde_json::to_value(report)?;
        if let (Some(r), Some(obj)) = (recording, value.as_object_mut()) {
            obj.insert("recording".into(), r.json(motion.units));
        }
        writeln!(text, "{}", crate::shared::json::pretty(&value)?)?;
    } else {
        write_report(&mut text, report, robot.lead.is_none())?;
        if let Some(r) = recording {
            writeln!(text, "  {}", r.describe(motion.units))?;
        }
        if let (true, Some(path)) = (outputs.log_written, &args.log) {
            writeln!(text, "log: {}", path.display())?;
        }
        if let (true, Some(path)) = (outputs.plot_written, &args.plot) {
            writeln!(text, "plot: {}", path.display())?;
        }
        match (&outputs.rerun, &args.rerun.rerun) {
            (Some(_), Some(path)) => {
                writeln!(
                    text,
                    "rerun: {} (`rerun {}` opens it)",
                    path.display(),
                    path.display()
                )?;
            }
            (Some(what), None) => writeln!(text, "rerun: sent to {what}")?,
            (None, _) => {}
        }
    }
    Ok(text)
}
