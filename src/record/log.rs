//! The CSV log of a run (`play --log`): one row per cycle and joint.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Context;
use servobus_runtime::CycleSample;

/// The CSV log of a run.
pub struct CsvLog {
    writer: csv::Writer<BufWriter<File>>,
    names: Vec<String>,
}

impl CsvLog {
    /// Creates `path` and writes the header; angles are in `units`.
    pub fn create(path: &Path, names: Vec<String>, units: &str) -> anyhow::Result<Self> {
        let file = File::create(path)
            .with_context(|| format!("cannot create the log {}", path.display()))?;
        let mut writer = csv::Writer::from_writer(BufWriter::new(file));
        writer.write_record([
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
        ])?;
        Ok(CsvLog { writer, names })
    }

    /// Writes one row per joint of `sample`.
    pub fn record(&mut self, sample: &CycleSample) -> anyhow::Result<()> {
        for j in sample.joints() {
            let name = self.names.get(j.joint).map_or("?", String::as_str);
            self.writer.write_record([
                format!("{:.6}", sample.time_s),
                sample.bus.to_string(),
                sample.cycle.to_string(),
                name.to_string(),
                format!("{:.4}", j.commanded),
                format!("{:.4}", j.planned),
                j.measured.map_or_else(String::new, |m| format!("{m:.4}")),
                format!("{:.4}", j.error),
                format!("{:.4}", j.velocity),
                format!("{:.3}", j.feedback_age.as_secs_f64() * 1e3),
                u8::from(j.stale).to_string(),
                u8::from(j.clamped).to_string(),
                format!("{:.1}", sample.lateness.as_secs_f64() * 1e6),
                format!("{:.1}", sample.busy.as_secs_f64() * 1e6),
                sample.skipped.to_string(),
            ])?;
        }
        Ok(())
    }

    /// Flushes the file.
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.writer.flush()?;
        Ok(())
    }
}
