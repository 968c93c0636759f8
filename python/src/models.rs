//! What a servo model can do, for Python: its top speed and the fastest
//! acceleration its motion profile is set to, in degrees
//! ([`Model::fastest_profile`], the protocol crate's per-model facts), and
//! the jerk ramp of live following ([`MODEL_JERK_RAMP_S`]). The LeRobot
//! plugin's live limits default to these, so that the live loop keeps up
//! the way LeRobot's raw goal writes do, with the same limits as
//! `servobus follow`.

use pyo3::prelude::*;
use servobus_config::MODEL_JERK_RAMP_S;
use servobus_protocol::registers::{model_by_name, Model};

use crate::errors::{Class, Failure, Outcome};

/// `(max_velocity, max_acceleration)` of `model`, in degrees per second
/// and per second squared.
fn limits_of(model: &Model) -> Outcome<(f64, f64)> {
    model.fastest_profile().ok_or_else(|| {
        Failure::new(
            Class::Error,
            format!(
                "{} states no acceleration in steps/s^2: give the live limits",
                model.name
            ),
        )
    })
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

/// Registers the module's functions and `MODEL_JERK_RAMP_S`: how long live
/// following's jerk limit takes to reach a model's acceleration, s.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(model_limits, m)?)?;
    m.add("MODEL_JERK_RAMP_S", MODEL_JERK_RAMP_S)?;
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
