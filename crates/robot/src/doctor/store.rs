//! `--write-servos` on a run: before a run on real servos, what the robot
//! file asks of each servo's EEPROM (its joint's operating mode, the
//! EEPROM registers of its `servo:` settings) is read and, where the servo
//! holds something else, stored with the doctor's own writes: the torque
//! off before a mode changes, the EEPROM locked again after, each write
//! one transaction that a stop signal cannot cut. Nothing else is written,
//! and a servo that already holds what the file asks is left alone.

use serde::Serialize;
use servobus_config::Robot;
use servobus_driver::{Bus, BusError, Transport};

use super::probe::{read_state, Ctx};
use super::{apply, Applied, BusPort, FixError, Fixing, SettingMismatch};

/// One register stored in a servo's EEPROM at connect.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StoredSetting {
    /// The robot file's bus.
    pub bus: String,
    /// The servo.
    pub id: u8,
    /// The register, what the servo held before and what it holds now.
    pub setting: SettingMismatch,
}

impl std::fmt::Display for StoredSetting {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.setting;
        let shown = |raw: i32, units: &Option<String>| match units {
            Some(u) => format!("{u} ({raw})"),
            None => raw.to_string(),
        };
        write!(
            f,
            "bus `{}`: joint `{}` (servo {}): stored {} (register {}) {} -> {}",
            self.bus,
            s.joint,
            self.id,
            s.register,
            s.address,
            shown(s.found, &s.found_as),
            shown(s.wanted, &s.wanted_as)
        )
    }
}

/// Why storing what the robot file asks failed.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// The port failed.
    #[error(transparent)]
    Bus(#[from] BusError),
    /// A write, or its check, failed (the writes before it were made).
    #[error("servo {id}: storing {register} failed: {source}")]
    Write {
        /// The servo.
        id: u8,
        /// The register.
        register: &'static str,
        /// What failed.
        #[source]
        source: Box<FixError>,
    },
}

/// Reads what bus `index` of `robot` (through `bus`, on `port`) asks of
/// each of its servos' EEPROM and stores what differs. Servos that do not
/// answer are skipped: the checks before the run name them.
///
/// # Errors
/// [`StoreError::Bus`] when the port fails, [`StoreError::Write`] when a
/// servo does not take a write.
pub fn store_wanted_settings<T: Transport>(
    bus: &mut Bus<T>,
    robot: &Robot,
    index: usize,
    port: &str,
) -> Result<Vec<StoredSetting>, StoreError> {
    let Some(cfg) = robot.buses.get(index) else {
        return Ok(Vec::new());
    };
    let target = BusPort {
        port: Some(port.to_owned()),
        baud: cfg.baud,
    };
    let ctx = Ctx {
        robot,
        bus: cfg,
        target: &target,
        real: true,
    };
    let saved = *bus.settings();
    bus.set_settings(saved.with_retries(2));
    let mut findings = Vec::new();
    for joint in &cfg.joints {
        match read_state(bus, joint.id) {
            Ok(state) => ctx.wanted_settings(&state, joint, &mut findings),
            Err(e) if e.is_retryable() => {}
            Err(e) => {
                bus.set_settings(saved);
                return Err(e.into());
            }
        }
    }
    bus.set_settings(saved);
    let how = Fixing {
        robot,
        bus: index,
        write_servos: true,
    };
    let outcomes = apply(bus, &findings, &how)?;
    let mut stored = Vec::new();
    for outcome in outcomes {
        let register = match &outcome.applied {
            Applied::Stored { register, .. } => *register,
            _ => "?",
        };
        outcome.result.map_err(|source| StoreError::Write {
            id: outcome.id,
            register,
            source: Box::new(source),
        })?;
        let found = findings
            .iter()
            .find(|f| f.id == Some(outcome.id) && f.register == Some(register));
        if let Some(setting) = found.and_then(|f| f.setting.clone()) {
            stored.push(StoredSetting {
                bus: cfg.name.clone(),
                id: outcome.id,
                setting,
            });
        }
    }
    Ok(stored)
}
