//! servobus-sim.
