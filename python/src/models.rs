//! What a servo model can do, for Python: its top speed and the fastest
//! acceleration its motion profile is set to, in degrees, from the
//! protocol crate's per-model facts and control table. The LeRobot
//! plugin's live limits default to these, so that the live loop keeps up
//! the way LeRobot's raw goal writes do.
//!
//! | figure                  | from                                                        |
//! |-------------------------|-------------------------------------------------------------|
//! | `max_velocity` (deg/s)  | [`Model::max_speed`] (steps/s) x degrees per step          |
//! | `max_acceleration`      | the `acceleration` register's unit x [`PROFILE_ACCELERATION`] x degrees per step |

use pyo3::prelude::*;
use servobus_protocol::registers::{model_by_name, Model};

use crate::errors::{Failure, Outcome};

/// The value of the `acceleration` register (41) that LeRobot's
/// `configure_motors` writes to every servo of an SO-101 (and Feetech's
/// tools offer as the fastest limited profile; 0 means no limit at all):
/// 254 x 100 steps/s^2 on STS servos.
pub(crate) const PROFILE_ACCELERATION: f64 = 254.0;

/// `(max_velocity, max_acceleration)` of `model`, in degrees per second
/// and per second squared.
fn limits_of(model: &Model) -> Outcome<(f64, f64)> {
    let deg = model.deg_per_tick();
    let register = model.map().get("acceleration").ok_or_else(|| {
        Failure::new(
            "Error",
            format!("{} has no acceleration register", model.name),
        )
    })?;
    let (per_unit, _) = crate::units::physical(register);
    Ok((
        f64::from(model.max_speed) * deg,
        per_unit * PROFILE_ACCELERATION * deg,
    ))
}

/// What servo `model` (a name such as `"sts3215"`) can do: `(max_velocity
/// in deg/s, max_acceleration in deg/s^2)`: its top speed, and the
/// acceleration of its fastest limited motion profile (the `acceleration`
/// register at 254, as LeRobot sets it). Raises `UsageError` for a model
/// servobus does not know.
#[pyfunction]
pub(crate) fn model_limits(model: &str) -> PyResult<(f64, f64)> {
    let found = model_by_name(model)
        .ok_or_else(|| Failure::usage(format!("servo model `{model}`: not one servobus knows")))?;
    Ok(limits_of(found)?)
}

/// Registers the module's functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(model_limits, m)?)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use servobus_protocol::registers::STS3215;

    #[test]
    fn the_sts3215_turns_at_3400_steps_a_second_and_accelerates_at_25400() {
        let (v, a) = limits_of(&STS3215).ok().unwrap_or_default();
        // 3400 steps/s and 25 400 steps/s^2, 4096 steps a turn.
        assert!((v - 3400.0 * 360.0 / 4096.0).abs() < 1e-9, "{v}");
        assert!((a - 25_400.0 * 360.0 / 4096.0).abs() < 1e-9, "{a}");
    }
}
