//! What `servobus play` keeps of the telemetry, and reads back: a CSV log
//! (one row per cycle and joint), the series of the plot (planned and
//! measured position and tracking error per joint), and a recorded path to
//! play again.

mod frames;
mod log;
mod plot;
mod recording;
pub(crate) mod space;
pub(crate) mod svg;

pub use log::CsvLog;
pub use plot::PlotData;
pub use recording::read_recording;
