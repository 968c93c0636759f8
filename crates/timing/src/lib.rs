//! servobus-timing.
