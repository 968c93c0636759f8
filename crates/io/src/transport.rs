//! The [`Transport`] trait: the bytes of a serial bus, with deadlines, on
//! the clock and at the baud rate the transport owns.

use std::time::Duration;

use crate::Clock;

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
    /// The transport cannot run at the baud rate asked for (its rate is
    /// fixed, or the port refused it). The rate in use is unchanged.
    #[error("cannot switch to {requested} baud (staying at {current})")]
    BaudRefused {
        /// The rate asked for.
        requested: u32,
        /// The rate still in use.
        current: u32,
    },
}

impl TransportError {
    /// Whether this is a timeout (the port itself still works).
    pub fn is_timeout(&self) -> bool {
        matches!(self, TransportError::TimedOut)
    }
}

/// A half-duplex byte pipe to a bus of servos.
///
/// The transport owns the two facts every reply deadline is built on: the
/// [`Clock`] its deadlines are measured on (a `Duration` since that clock's
/// epoch) and the baud rate its bytes travel at. A bus built on it takes
/// both from here, so they are given once, when the transport is made.
pub trait Transport {
    /// The clock deadlines are measured on.
    type Clock: Clock;

    /// The clock deadlines are measured on (a bus clones it).
    fn clock(&self) -> &Self::Clock;

    /// The baud rate the bytes travel at now.
    fn baud(&self) -> u32;

    /// Moves the transport to `baud`.
    ///
    /// The default refuses: a transport whose rate is fixed (a test double)
    /// need not implement it.
    ///
    /// # Errors
    /// [`TransportError::BaudRefused`] when the rate cannot be used (the
    /// rate in use is unchanged); [`TransportError::Disconnected`] or
    /// [`TransportError::Io`] for a port that fails.
    fn set_baud(&mut self, baud: u32) -> Result<(), TransportError> {
        Err(TransportError::BaudRefused {
            requested: baud,
            current: self.baud(),
        })
    }

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

/// A borrowed or boxed transport is a transport: the same calls,
/// forwarded (so `&mut port` and `Box<dyn Transport<Clock = C>>` can drive
/// a bus).
macro_rules! forward_transport {
    ($($wrapper:ty),*) => {$(
        impl<T: Transport + ?Sized> Transport for $wrapper {
            type Clock = T::Clock;
            fn clock(&self) -> &Self::Clock {
                (**self).clock()
            }
            fn baud(&self) -> u32 {
                (**self).baud()
            }
            fn set_baud(&mut self, baud: u32) -> Result<(), TransportError> {
                (**self).set_baud(baud)
            }
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
    )*};
}

forward_transport!(&mut T, Box<T>);
