//! servobus's Python extension, `servobus._native`: a typed bus of Feetech
//! servos, the simulator on a pseudo-terminal, and robots' plans, runs and
//! live streams. The Python package `servobus` wraps it (typed reports,
//! numpy arrays, the exception classes under `servobus.Error`); every call
//! that waits on a bus, a port or a run releases the GIL.

mod bus;
mod calibration;
mod checks;
mod doctor;
mod errors;
mod load;
mod models;
mod robot;
mod sim;
mod stream;
mod units;

use pyo3::prelude::*;

/// The module `servobus._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<bus::Bus>()?;
    m.add_class::<sim::Sim>()?;
    m.add_class::<robot::Robot>()?;
    m.add_class::<stream::Stream>()?;
    calibration::register(m)?;
    models::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
