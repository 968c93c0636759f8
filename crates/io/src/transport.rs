//! The [`Transport`] trait: the bytes of a serial bus, with deadlines.

use std::time::Duration;

/// Why a transport operation failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TransportError {
    /// No byte arrived before the deadline. The port is fine; try again.
    #[error("timed out waiting for bytes")]
    TimedOut,
    /// The port is gone (unplugged adapter, closed pty): give up.
    #[error("port disconnected: {0}")]
    Disconnected(String),
    /// Any other I/O failure.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
}

impl TransportError {
    /// Whether this is a timeout (the port itself still works).
    pub fn is_timeout(&self) -> bool {
        matches!(self, TransportError::TimedOut)
    }
}

/// A half-duplex byte pipe to a bus of servos.
///
/// Deadlines are times on the time base of the [`Clock`](crate::Clock) the
/// transport was built with (a `Duration` since that clock's epoch).
pub trait Transport {
    /// Sends every byte of `bytes`.
    ///
    /// # Errors
    /// [`TransportError::Disconnected`] or [`TransportError::Io`].
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError>;

    /// Reads at least one byte into `buf`, waiting until `deadline` at most,
    /// and returns how many were read (never 0 for a non-empty `buf`).
    ///
    /// # Errors
    /// [`TransportError::TimedOut`] when nothing arrived by the deadline;
    /// [`TransportError::Disconnected`] or [`TransportError::Io`] otherwise.
    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError>;

    /// Drops every byte received but not yet read.
    ///
    /// # Errors
    /// [`TransportError::Disconnected`] or [`TransportError::Io`].
    fn discard_input(&mut self) -> Result<(), TransportError>;
}

impl<T: Transport + ?Sized> Transport for &mut T {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        (**self).write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        (**self).read(buf, deadline)
    }
    fn discard_input(&mut self) -> Result<(), TransportError> {
        (**self).discard_input()
    }
}

impl<T: Transport + ?Sized> Transport for Box<T> {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        (**self).write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        (**self).read(buf, deadline)
    }
    fn discard_input(&mut self) -> Result<(), TransportError> {
        (**self).discard_input()
    }
}
