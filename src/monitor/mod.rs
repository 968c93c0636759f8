//! `servobus monitor`: what every servo of a bus is doing, refreshed live.
//! The sampler (the [`Poller`] and its [`Frame`]s) is the library's
//! ([`servobus_robot::monitor`]); the table they render as is [`view`].

pub mod view;

pub use servobus_robot::monitor::*;
