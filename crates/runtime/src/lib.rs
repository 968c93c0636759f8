//! servobus-runtime.
