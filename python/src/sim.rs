//! `servobus.Sim`: a robot's simulated servos served on a pseudo-terminal
//! from a thread of this process, as `servobus sim` serves them.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use pyo3::prelude::*;
use servobus_config::builtin::{path_or_name, Kind};
use servobus_robot::sim::{Faults, PtyServer};
use servobus_robot::sim::{Hand, Mounting, SimRobot, SimRobotBuilder};

use crate::errors::{chain, poisoned, Class, Failure, Outcome};
use crate::load::load_robot;

/// The serving thread and the flag that stops it.
struct Serving {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<(), String>>>,
}

/// A robot's simulated servos on a pseudo-terminal, served from a thread:
/// any program that opens a serial port can talk to them at `.port`.
///
/// `Sim(robot="so101", faults=None, mounting=None, hand=None, pacing=True)`:
/// `faults` as `servobus sim --faults` (`"drop=0.01,vanish=3,seed=7"`),
/// `mounting` and `hand` files or built-in names as `servobus sim`'s.
/// A context manager: the server stops at the end of the `with` block (or
/// at `.close()`).
#[pyclass(module = "servobus._native", name = "Sim")]
pub struct Sim {
    port: String,
    servos: usize,
    serving: Mutex<Serving>,
}

/// `builder` with the servos mounted as `mounting` says and the hand `hand`
/// on the joints (each a file or a built-in name, as `servobus sim` takes
/// them).
pub(crate) fn with_bodies<'a>(
    mut builder: SimRobotBuilder<'a>,
    mounting: Option<&str>,
    hand: Option<&str>,
) -> Outcome<SimRobotBuilder<'a>> {
    let config = builder.robot();
    if let Some(m) = mounting {
        let path = path_or_name(Kind::Mounting, Path::new(m));
        builder = builder.mounting(Mounting::load(&path, config)?);
    }
    if let Some(h) = hand {
        let path = path_or_name(Kind::Hand, Path::new(h));
        builder = builder.hand(Hand::load(&path, config)?);
    }
    Ok(builder)
}

/// Starts serving; the pty's path and the number of servos.
fn start(
    robot: &str,
    faults: Option<&str>,
    mounting: Option<&str>,
    hand: Option<&str>,
    pacing: bool,
) -> Outcome<(String, usize, Serving)> {
    let robot = load_robot(robot, None)?;
    let config = robot.config();
    let faults = match faults {
        Some(spec) => spec
            .parse::<Faults>()
            .map_err(|e| Failure::usage(format!("faults `{spec}`: {}", chain(&e))))?,
        None => Faults::none(),
    };
    let builder = with_bodies(SimRobot::builder(config), mounting, hand)?;
    let moved_by_hand = hand.is_some() || mounting.is_some();
    let (baud, servos) = builder.served(None)?;
    let count = servos.len();
    let mut server = PtyServer::open(baud, servos)?;
    server.set_pacing(pacing);
    server.set_faults(faults);
    if moved_by_hand {
        // Bodies move while no client talks.
        server.set_tick(Some(servobus_robot::sim::TRUTH_PERIOD));
    }
    let port = server.client_path().display().to_string();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let (ready, started) = crossbeam_channel::bounded(1);
    let thread = std::thread::Builder::new()
        .name("servobus-sim".into())
        .spawn(move || {
            let _ = ready.send(());
            let served = server.serve(&flag).map_err(|e| chain(&e));
            server.settle();
            served
        })
        .map_err(|e| {
            Failure::new(
                Class::Error,
                format!("cannot start the simulator's thread: {e}"),
            )
        })?;
    // A client's first request is answered in time only once the thread
    // serves: wait for it to start (a thread that died says so at close).
    let _ = started.recv_timeout(std::time::Duration::from_secs(5));
    Ok((
        port,
        count,
        Serving {
            stop,
            thread: Some(thread),
        },
    ))
}

impl Sim {
    /// Stops the server and waits for its thread.
    fn stop(&self) -> Outcome<()> {
        let mut serving = self.serving.lock().map_err(poisoned)?;
        serving.stop.store(true, Ordering::SeqCst);
        match serving.thread.take().map(JoinHandle::join) {
            None | Some(Ok(Ok(()))) => Ok(()),
            Some(Ok(Err(why))) => Err(Failure::new(Class::PortError, why)),
            Some(Err(_)) => Err(Failure::new(
                Class::Error,
                "the simulator's thread panicked",
            )),
        }
    }
}

#[pymethods]
impl Sim {
    /// Starts serving `robot`'s servos on a new pseudo-terminal.
    #[new]
    #[pyo3(signature = (robot="so101", faults=None, mounting=None, hand=None, pacing=true))]
    fn new(
        py: Python<'_>,
        robot: &str,
        faults: Option<&str>,
        mounting: Option<&str>,
        hand: Option<&str>,
        pacing: bool,
    ) -> PyResult<Self> {
        let (port, servos, serving) =
            py.allow_threads(|| start(robot, faults, mounting, hand, pacing))?;
        Ok(Sim {
            port,
            servos,
            serving: Mutex::new(serving),
        })
    }

    /// The path to open as a serial port (e.g. `/dev/pts/3`).
    #[getter]
    fn port(&self) -> &str {
        &self.port
    }

    /// How many servos are served.
    #[getter]
    fn servo_count(&self) -> usize {
        self.servos
    }

    /// Whether the server is still serving.
    #[getter]
    fn running(&self) -> PyResult<bool> {
        let serving = self.serving.lock().map_err(poisoned)?;
        Ok(serving.thread.as_ref().is_some_and(|t| !t.is_finished()))
    }

    /// Stops serving (the pty goes away); a second call does nothing.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        Ok(py.allow_threads(|| self.stop())?)
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }

    fn __repr__(&self) -> String {
        format!("<servobus.Sim: {} servos on {}>", self.servos, self.port)
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        if let Ok(serving) = self.serving.get_mut() {
            serving.stop.store(true, Ordering::SeqCst);
            if let Some(t) = serving.thread.take() {
                let _ = t.join();
            }
        }
    }
}
