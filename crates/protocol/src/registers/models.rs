//! Servo models: the number a servo reports in register 3 and what it means.

use core::time::Duration;

use super::{RegisterMap, Series};

/// Time a servo's firmware takes from the end of a request to the start of
/// its reply, on top of its return delay (register 7).
///
/// **A guess, not a measurement:** no public source states it. 50 us is
/// within what LeRobot users see on SO-101 arms at 1 Mbps (a six-servo SYNC
/// READ in about 1.0 ms, which leaves tens of microseconds per reply beyond
/// wire time). Reply deadlines add a margin on top, so an error here costs
/// a little waiting, not lost replies. Every model uses this one figure.
pub const REPLY_TURNAROUND: Duration = Duration::from_micros(50);

/// How long a servo's shaft trails a moving goal: the time constant of the
/// first-order lag between its motion profile and its shaft, which a goal
/// following a smooth path sees as a delay of this much.
///
/// **A prior, not a measurement:** 10 ms is the lag of the STS3215 as the
/// simulator models it (at 1000 ticks/s the shaft trails the profile by
/// about 10 ticks), in line with the 10-20 ms lead LeRobot users find on
/// SO-101 arms. A run starts its lead from it (plus its own loop delay) and
/// then identifies the real figure from the tracking errors. Every model
/// uses this one figure until one is measured.
pub const RESPONSE_LAG: Duration = Duration::from_millis(10);

/// The `acceleration` register's value of the fastest limited motion
/// profile: what LeRobot's `configure_motors` writes to an SO-101's servos,
/// and the highest Feetech's tools offer (0 means no limit at all).
pub const FASTEST_PROFILE: f64 = 254.0;

/// A servo model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Model {
    /// Product name in upper case, e.g. `STS3215`.
    pub name: &'static str,
    /// The value of its model-number register (address 3, 2 bytes, in the
    /// series' byte order).
    pub number: u16,
    /// The series, which decides the register map and byte order.
    pub series: Series,
    /// Position ticks over [`Model::range_deg`].
    pub resolution: u32,
    /// Mechanical range covered by `resolution` ticks, in degrees.
    pub range_deg: f64,
    /// Highest useful goal speed, in steps/s.
    pub max_speed: u32,
    /// Time from the end of a request to the start of the reply, beyond
    /// the return delay ([`REPLY_TURNAROUND`] for every model).
    pub turnaround: Duration,
    /// How long the shaft trails a moving goal ([`RESPONSE_LAG`] for every
    /// model): the simulator's lag, and the prior of a run's lead.
    pub response_lag: Duration,
}

impl Model {
    /// The model's register map.
    pub const fn map(&self) -> &'static RegisterMap {
        self.series.map()
    }

    /// Degrees per position tick.
    pub fn deg_per_tick(&self) -> f64 {
        self.range_deg / f64::from(self.resolution)
    }

    /// What the model can do in its fastest limited motion profile: top
    /// speed (deg/s) and the acceleration of its `acceleration` register
    /// at [`FASTEST_PROFILE`] (deg/s^2), where that register's unit is
    /// stated in steps/s^2 (the STS and SMS series); `None` otherwise.
    pub fn fastest_profile(&self) -> Option<(f64, f64)> {
        let reg = self.map().get("acceleration")?;
        let (scale, unit) = reg.unit.trim().split_once(' ')?;
        let scale: f64 = scale
            .parse()
            .ok()
            .filter(|s: &f64| s.is_finite() && *s > 0.0)?;
        (unit.trim() == "steps/s^2").then(|| {
            let deg = self.deg_per_tick();
            (
                f64::from(self.max_speed) * deg,
                scale * FASTEST_PROFILE * deg,
            )
        })
    }

    /// The highest position value (`resolution - 1`).
    pub const fn max_position(&self) -> u32 {
        self.resolution - 1
    }
}

/// Every known model.
///
/// Where the numbers come from:
/// - STS3215 = 777, STS3250 = 2825, SM8512BL = 11272, SCS0009 = 1284:
///   LeRobot's feetech `tables.py` (`MODEL_NUMBER_TABLE`), which reads them
///   from real servos; the first three are also in the control-tables
///   reference.
/// - SCS15 = 1792 (0x0700): a community driver's model table; not confirmed
///   by Feetech's SDKs or LeRobot, and another community table lists 14.
///   Treat it as provisional: a servo reporting an unknown number is still
///   usable with `--model` given explicitly.
/// - Resolutions: 4096 ticks per turn for STS/SMS, 1024 over about 300
///   degrees for SCS (control-tables reference, LeRobot `MODEL_RESOLUTION`).
/// - `max_speed`: 3400 steps/s for STS3215 at 12 V (control-tables
///   reference). The other STS/SMS models are given the same figure, and the
///   SCS figures are estimates from nominal no-load speeds; none of them is
///   measured, so robot files should set their own velocity limits.
pub static MODELS: [Model; 5] = [STS3215, STS3250, SM8512BL, SCS0009, SCS15];

/// A model with the turnaround and response lag every model shares
/// ([`REPLY_TURNAROUND`], [`RESPONSE_LAG`]).
const fn model(
    name: &'static str,
    number: u16,
    series: Series,
    resolution: u32,
    range_deg: f64,
    max_speed: u32,
) -> Model {
    Model {
        name,
        number,
        series,
        resolution,
        range_deg,
        max_speed,
        turnaround: REPLY_TURNAROUND,
        response_lag: RESPONSE_LAG,
    }
}

/// Feetech STS3215.
pub const STS3215: Model = model("STS3215", 777, Series::Sts, 4096, 360.0, 3400);

/// Feetech STS3250.
pub const STS3250: Model = model("STS3250", 2825, Series::Sts, 4096, 360.0, 3400);

/// Feetech SM8512BL.
pub const SM8512BL: Model = model("SM8512BL", 11272, Series::Sts, 4096, 360.0, 3400);

/// Feetech SCS0009.
pub const SCS0009: Model = model("SCS0009", 1284, Series::Scs, 1024, 300.0, 1500);

/// Feetech SCS15.
pub const SCS15: Model = model("SCS15", 1792, Series::Scs, 1024, 300.0, 1000);

/// The model whose model-number register reads `number`.
pub fn model_by_number(number: u16) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.number == number)
}

/// The model whose model-number register (address 3) holds `bytes`, read
/// before the series is known: the two bytes are tried in the byte order of
/// STS/SMS servos (little-endian) and of SCS servos (big-endian), since the
/// order is part of what is being found out. No known model's number reads
/// as another's in the other order.
pub fn model_by_register(bytes: [u8; 2]) -> Option<&'static Model> {
    model_by_number(u16::from_le_bytes(bytes))
        .or_else(|| model_by_number(u16::from_be_bytes(bytes)))
}

/// The model called `name`, ignoring ASCII case and `-`, `_`, space
/// (`sts3215`, `STS-3215`).
pub fn model_by_name(name: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| super::same_name(m.name, name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fastest_profile_is_top_speed_and_the_ramp_at_254() {
        let (v, a) = STS3215.fastest_profile().expect("an STS ramp in steps/s^2");
        let deg = 360.0 / 4096.0;
        assert!((v - 3400.0 * deg).abs() < 1e-9, "{v}");
        assert!((a - 25_400.0 * deg).abs() < 1e-9, "{a}");
        // The SCS series' ramp has no stated unit: no figure is made up.
        assert_eq!(SCS0009.fastest_profile(), None);
    }
}
