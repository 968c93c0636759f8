//! One servo bus, below the robot: for tools that talk to servos by ID
//! (scan, read, write, set an ID, monitor, calibrate) rather than play a
//! robot. A [`Bus`] runs single-servo and SYNC transactions over a
//! [`Transport`] (a serial port, or the simulator) with reply deadlines
//! from the link, bounded retries and counters; the register map of each
//! servo [`Series`] is in [`registers`]. Stop signals (Ctrl-C, SIGTERM,
//! SIGHUP) are caught with [`catch_stop_signals`] so that a transaction
//! under way (an EEPROM write above all) finishes before the program
//! stops, and read back with [`stop_signal`].

pub use servobus_driver::registers;
pub use servobus_driver::{
    catch_stop_signals, stop_signal, Bus, BusError, Clock, OpenError, SerialTransport, Series,
    StatusLevel, StopSignal, SystemClock, Transport, TransportError, PROBE_CEILING, PROBE_PINGS,
};
