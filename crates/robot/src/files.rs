//! Output files written whole or not at all: a log, a plot, a calibration
//! or a robot file goes to a temporary beside its path and replaces it
//! only once complete ([`write_atomic`], [`AtomicFile`]), so that a run
//! that fails or is stopped leaves an earlier file untouched; a path that
//! cannot be written is refused before anything moves ([`check_output`]).

pub use servobus_io::{check_output, write_atomic, AtomicFile, OutputError};
