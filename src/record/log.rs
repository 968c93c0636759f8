//! The CSV log of a run (`play --log`): one row per cycle and joint.
//!
//! The rows go, while the run goes on, to a temporary file beside the log
//! ([`AtomicFile`]), which replaces the log once the run is over
//! ([`CsvLog::finish`]). A run refused before it moved drops the log: the
//! temporary is removed and a log of an earlier run is untouched. A write
//! that fails during the run (a full disk) stops the logging, not the run:
//! the temporary is removed at once, and [`CsvLog::finish`] returns the
//! error, naming the file, after the run.

use std::path::{Path, PathBuf};

use anyhow::Context;
use servobus_config::limits::Fixed;
use servobus_config::Units;
use servobus_kinematics::Geometry;
use servobus_robot::files::AtomicFile;
use servobus_robot::odometry::{pose_figures, Odometer};
use servobus_robot::CycleSample;

use super::frames::FrameTracker;

/// The CSV log of a run.
pub struct CsvLog {
    /// `None` once a write has failed.
    writer: Option<csv::Writer<AtomicFile>>,
    path: PathBuf,
    /// Written in place (not a regular file): a failure leaves part of it.
    direct: bool,
    names: Vec<String>,
    /// The named frames' positions, when the robot has a geometry.
    frames: Option<FrameTracker>,
    /// The current sample's frame cells: x, y, z (mm) of each frame, empty
    /// until every joint has been read.
    frame_cells: Vec<String>,
    /// A mobile base's odometry, when the robot has one.
    odometer: Option<Odometer>,
    /// The first write error.
    failed: Option<csv::Error>,
}

impl CsvLog {
    /// Starts the log `path` (its temporary) and writes the header; angles
    /// are in `units`. With the robot's `geometry`, each row also gives the
    /// position of every named frame (`tool`, `foot_<leg>`) by forward
    /// kinematics of the measured angles: `<frame>_x_mm`, `_y_mm`, `_z_mm`.
    /// With an `odometer` (a robot with a mobile base), each row ends with
    /// the base's odometry so far: `base_x_m`, `base_y_m`,
    /// `base_theta_deg`.
    ///
    /// # Errors
    /// The path cannot be an output, or the temporary cannot be created.
    pub fn create(
        path: &Path,
        names: Vec<String>,
        units: Units,
        geometry: Option<Geometry>,
        odometer: Option<Odometer>,
    ) -> anyhow::Result<Self> {
        let file = AtomicFile::create(path)?;
        let mut log = CsvLog {
            direct: file.is_direct(),
            writer: Some(csv::Writer::from_writer(file)),
            path: path.to_path_buf(),
            names,
            frames: geometry.and_then(|g| FrameTracker::new(g, units)),
            frame_cells: Vec::new(),
            odometer,
            failed: None,
        };
        let mut spatial: Vec<String> = log
            .frames
            .iter()
            .flat_map(FrameTracker::names)
            .flat_map(|n| ["x", "y", "z"].map(|axis| format!("{n}_{axis}_mm")))
            .collect();
        log.frame_cells = vec![String::new(); spatial.len()];
        if let Some(o) = &log.odometer {
            for (name, _) in pose_figures(&o.pose()) {
                spatial.push(name.to_owned());
                log.frame_cells.push(String::new());
            }
        }
        write(
            &mut log.writer,
            &mut log.failed,
            &[
                "time_s".to_string(),
                "bus".into(),
                "cycle".into(),
                "joint".into(),
                format!("commanded_{units}"),
                format!("planned_{units}"),
                format!("measured_{units}"),
                format!("error_{units}"),
                format!("velocity_{units}_s"),
                "feedback_age_ms".into(),
                "stale".into(),
                "clamped".into(),
                "lateness_us".into(),
                "busy_us".into(),
                "skipped".into(),
            ],
            &spatial,
        );
        Ok(log)
    }

    /// Writes one row per joint of `sample` (nothing once a write failed).
    pub fn record(&mut self, sample: &CycleSample) {
        if let Some(frames) = &mut self.frames {
            frames.update(sample);
            let positions = frames.positions().unwrap_or_default();
            for (cell, v) in self.frame_cells.iter_mut().zip(positions.iter().flatten()) {
                *cell = Fixed(*v, 3).to_string();
            }
        }
        if let Some(o) = &mut self.odometer {
            let pose = o.take(sample);
            let cells = self.frame_cells.iter_mut().rev().take(3).rev();
            for (cell, (_, v)) in cells.zip(pose_figures(&pose)) {
                *cell = Fixed(v, 5).to_string();
            }
        }
        for j in sample.joints() {
            let name = self.names.get(j.joint).map_or("?", String::as_str);
            let row = [
                format!("{:.6}", sample.time_s),
                sample.bus.to_string(),
                sample.cycle.to_string(),
                name.to_string(),
                Fixed(j.commanded, 4).to_string(),
                Fixed(j.planned, 4).to_string(),
                j.measured
                    .map_or_else(String::new, |m| Fixed(m, 4).to_string()),
                Fixed(j.error, 4).to_string(),
                Fixed(j.velocity, 4).to_string(),
                format!("{:.3}", j.feedback_age.as_secs_f64() * 1e3),
                u8::from(j.stale).to_string(),
                u8::from(j.clamped).to_string(),
                format!("{:.1}", sample.lateness.as_secs_f64() * 1e6),
                format!("{:.1}", sample.busy.as_secs_f64() * 1e6),
                sample.skipped.to_string(),
            ];
            write(&mut self.writer, &mut self.failed, &row, &self.frame_cells);
        }
    }

    /// The log's path, as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether a write has failed (the log will not be kept).
    pub fn has_failed(&self) -> bool {
        self.failed.is_some()
    }

    /// Makes the rows the log: flushes them and replaces the file at the
    /// log's path with them.
    ///
    /// # Errors
    /// The first write error of the run, or the flush's or the rename's,
    /// naming the file; a regular file at the path is then as it was before
    /// the run.
    pub fn finish(self) -> anyhow::Result<()> {
        let path = self.path.display();
        let what = if self.direct {
            format!("the log {path} is incomplete")
        } else {
            format!("the log {path} was not kept")
        };
        let result = match (self.failed, self.writer) {
            (Some(e), _) => Err(anyhow::Error::new(e)),
            (None, Some(writer)) => match writer.into_inner() {
                Ok(file) => file.commit().map_err(anyhow::Error::new),
                Err(e) => Err(anyhow::Error::new(e.into_error())),
            },
            (None, None) => Ok(()),
        };
        result.context(what)
    }
}

/// Writes one row, `row` then `more`; the first error ends the logging
/// (drops the writer, and with it the temporary) and is kept in `failed`.
fn write(
    writer: &mut Option<csv::Writer<AtomicFile>>,
    failed: &mut Option<csv::Error>,
    row: &[String],
    more: &[String],
) {
    if let Some(w) = writer {
        if let Err(e) = w.write_record(row.iter().chain(more)) {
            *writer = None;
            *failed = Some(e);
        }
    }
}
