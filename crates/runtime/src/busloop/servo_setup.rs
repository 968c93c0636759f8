//! What start-up checks and sets on each servo before torque goes on:
//!
//! - its operating mode (register `mode`, 33) must be its joint's: 1
//!   (constant speed) for a wheel, 0 for a position joint. A mode is an
//!   EEPROM setting: the loop never writes it (the facade stores it at
//!   connect when asked, `--write-servos`), and refuses to start instead
//!   ([`RunError::Mode`]), naming the doctor command that sets it. A
//!   series without the register (SCS) has position joints only and is
//!   not asked.
//! - the joint's RAM `servo:` settings (`torque_limit`, `acceleration`,
//!   ...) are written after the motion profiles are released, so that a
//!   joint's own `acceleration` wins over the release, and read back.
//! - the joint's EEPROM `servo:` settings are read and compared: those the
//!   servo holds otherwise go in the report
//!   ([`BusReport::eeprom_differences`](crate::BusReport)). EEPROM settings are
//!   the doctor's to check and fix (`servobus doctor --fix
//!   --write-servos`), never written here.

use servobus_driver::{Bus, Transport};
use servobus_protocol::registers::{addr, Register};

use crate::config::{BusConfig, ServoWrite};
use crate::error::RunError;
use crate::report::SettingDifference;

/// One joint's servo as start-up sees it.
#[derive(Debug)]
struct Servo {
    joint: String,
    id: u8,
    /// The operating mode its joint needs.
    mode: u8,
    /// Its RAM `servo:` settings.
    writes: Vec<ServoWrite>,
    /// Its EEPROM `servo:` settings (compared, never written).
    eeprom: Vec<ServoWrite>,
}

/// The start-up checks and settings of one bus's servos.
#[derive(Debug)]
pub(crate) struct ServoSetup {
    mode: Option<&'static Register>,
    servos: Vec<Servo>,
}

impl ServoSetup {
    /// The checks of `config`'s joints.
    pub fn new(config: &BusConfig, mode: Option<&'static Register>) -> Self {
        let servos = config
            .joints
            .iter()
            .map(|j| {
                let (eeprom, writes) = j.servo_writes().iter().partition(|w| w.eeprom);
                Servo {
                    joint: j.name.clone(),
                    id: j.id,
                    mode: j.mode.operating_mode(),
                    writes,
                    eeprom,
                }
            })
            .collect();
        ServoSetup { mode, servos }
    }

    /// Reads every servo's operating mode and compares it with its joint's.
    ///
    /// # Errors
    ///
    /// [`RunError::Mode`] naming the first servo in the wrong mode,
    /// [`RunError::NoServo`] for one whose mode cannot be read,
    /// [`RunError::Startup`] when the bus fails.
    pub fn check_modes<T: Transport>(&self, bus: &mut Bus<T>, name: &str) -> Result<(), RunError> {
        let Some(reg) = self.mode else {
            return Ok(());
        };
        let order = bus.settings().series.byte_order();
        let ids: Vec<u8> = self.servos.iter().map(|s| s.id).collect();
        let read = bus
            .sync_read_patiently(addr::MODE, reg.size, &ids)
            .map_err(|source| RunError::Startup {
                bus: name.to_owned(),
                what: "reading the servos' operating modes",
                source,
            })?;
        for (s, r) in self.servos.iter().zip(read.iter()) {
            let found = match r {
                Ok(reply) => reg.decode(reply.data, order).map_err(|e| e.to_string()),
                Err(m) => Err(m.reason.to_string()),
            };
            let found = found.map_err(|reason| RunError::NoServo {
                bus: name.to_owned(),
                id: s.id,
                joint: s.joint.clone(),
                reason: format!("its operating mode cannot be read: {reason}"),
            })?;
            let wanted = s.mode;
            if found != i32::from(wanted) {
                return Err(RunError::Mode {
                    bus: name.to_owned(),
                    joint: s.joint.clone(),
                    id: s.id,
                    found: u8::try_from(found).unwrap_or(u8::MAX),
                    wanted,
                });
            }
        }
        Ok(())
    }

    /// Reads every joint's EEPROM `servo:` settings and returns those its
    /// servo holds otherwise (one that cannot be read is left out: the
    /// doctor examines it).
    pub fn compare_eeprom<T: Transport>(&self, bus: &mut Bus<T>) -> Vec<SettingDifference> {
        let mut out = Vec::new();
        for s in &self.servos {
            for w in &s.eeprom {
                let wanted = i32::try_from(w.raw).unwrap_or(i32::MAX);
                if let Ok((held, _)) = bus.read_register(s.id, w.register) {
                    if held != wanted {
                        out.push(SettingDifference {
                            joint: s.joint.clone(),
                            id: s.id,
                            setting: w.setting,
                            register: w.register.name,
                            held,
                            wanted,
                        });
                    }
                }
            }
        }
        out
    }

    /// Writes every joint's RAM `servo:` settings and reads each back.
    ///
    /// # Errors
    ///
    /// [`RunError::Startup`] when a write or a read fails,
    /// [`RunError::Setting`] when a servo holds another value than written
    /// (one that clamps it, or not of the model the robot file says).
    pub fn write_settings<T: Transport>(
        &self,
        bus: &mut Bus<T>,
        name: &str,
    ) -> Result<(), RunError> {
        for s in &self.servos {
            for w in &s.writes {
                let raw = i32::try_from(w.raw).unwrap_or(i32::MAX);
                let startup = |source| RunError::Startup {
                    bus: name.to_owned(),
                    what: "writing the joints' `servo:` settings",
                    source,
                };
                bus.write_register(s.id, w.register, raw).map_err(startup)?;
                let (held, _) = bus.read_register(s.id, w.register).map_err(startup)?;
                if held != raw {
                    return Err(RunError::Setting {
                        bus: name.to_owned(),
                        joint: s.joint.clone(),
                        id: s.id,
                        setting: w.setting,
                        wrote: raw,
                        held,
                    });
                }
            }
        }
        Ok(())
    }
}
