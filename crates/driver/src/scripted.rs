//! A port for the driver's own tests and benches: a virtual clock at
//! 1 Mbaud, and a [`Script`] that plays the servos (what they answer, and
//! when). The transport's part is written once here; each test keeps only
//! what its servos do.

use std::time::Duration;

use crate::{ManualClock, Transport, TransportError};

/// What a read returns: bytes read, or why none.
pub type Received = Result<usize, TransportError>;

/// What the servos behind a [`ScriptedPort`] do with the host's bytes.
pub trait Script {
    /// The host wrote `bytes`, at `clock`'s time (which the script may move
    /// on, as a write that takes time does).
    ///
    /// # Errors
    /// What the script's port reports.
    fn write(&mut self, clock: &ManualClock, bytes: &[u8]) -> Result<(), TransportError>;

    /// The host reads into `buf`, waiting until `deadline` at most: what
    /// the servos have sent by then ([`TransportError::TimedOut`] for
    /// nothing, with the clock at the deadline).
    ///
    /// # Errors
    /// [`TransportError::TimedOut`], or what the script's port reports.
    fn read(&mut self, clock: &ManualClock, buf: &mut [u8], deadline: Duration) -> Received;

    /// The host drops whatever it received and has not read.
    fn discard(&mut self, clock: &ManualClock);
}

/// A port at 1 Mbaud on a [`ManualClock`] whose far end is a [`Script`].
#[derive(Debug)]
pub struct ScriptedPort<S> {
    clock: ManualClock,
    /// The servos' part.
    pub script: S,
}

impl<S> ScriptedPort<S> {
    /// `script` behind a port on `clock` (a clone: the caller keeps its
    /// handle on the same time).
    pub fn new(clock: &ManualClock, script: S) -> Self {
        ScriptedPort {
            clock: clock.clone(),
            script,
        }
    }
}

impl<S: Script> Transport for ScriptedPort<S> {
    type Clock = ManualClock;

    fn clock(&self) -> &ManualClock {
        &self.clock
    }

    fn baud(&self) -> u32 {
        1_000_000
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.script.write(&self.clock, bytes)
    }

    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        self.script.read(&self.clock, buf, deadline)
    }

    fn discard_input(&mut self) -> Result<(), TransportError> {
        self.script.discard(&self.clock);
        Ok(())
    }
}
