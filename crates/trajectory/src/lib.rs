//! servobus-trajectory.
