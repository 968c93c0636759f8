//! The simulated servo models: the protocol crate's [`Model`] (register
//! map, factory values, resolution, speed, turnaround) plus the one figure
//! only a simulation needs (stall current).
//!
//! Nothing about a model or its memory layout is written here: every
//! accessor reads the protocol crate's model or register map, and
//! [`SimModel::factory_table`] lays out that map with its factory values, so
//! the simulator and the driver cannot disagree about an address, a size, a
//! byte order, a sign bit or a status level.

use servobus_protocol::registers::{
    self, scs, sts, Access, ByteOrder, Model, Register, RegisterMap, Series, StatusLevel,
};

/// A servo model as the simulator needs it: the protocol crate's model and
/// the simulator's own stall current.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimModel {
    /// The protocol crate's model: name, number, series, resolution, speed
    /// and reply turnaround.
    pub model: Model,
    /// Stall current in present-current counts: the simulator's own figure
    /// (0 for models whose current register is not simulated).
    pub stall_current: f64,
}

impl SimModel {
    /// The simulation of `model`, with `stall_current` in present-current
    /// counts.
    pub const fn simulate(model: Model, stall_current: f64) -> SimModel {
        SimModel {
            model,
            stall_current,
        }
    }

    /// Feetech STS3215 (SO-100/SO-101 arms).
    pub const STS3215: SimModel = SimModel::simulate(registers::STS3215, 415.0);
    /// Feetech STS3250.
    pub const STS3250: SimModel = SimModel::simulate(registers::STS3250, 700.0);
    /// Feetech SM8512BL (SMS series, RS-485).
    pub const SM8512BL: SimModel = SimModel::simulate(registers::SM8512BL, 1500.0);
    /// Feetech SCS0009 (SCS series).
    pub const SCS0009: SimModel = SimModel::simulate(registers::SCS0009, 0.0);
    /// Feetech SCS15 (SCS series).
    pub const SCS15: SimModel = SimModel::simulate(registers::SCS15, 0.0);

    /// Every model the simulator knows: one per protocol model.
    pub const ALL: [SimModel; 5] = [
        SimModel::STS3215,
        SimModel::STS3250,
        SimModel::SM8512BL,
        SimModel::SCS0009,
        SimModel::SCS15,
    ];

    /// The model with this name (as [`registers::model_by_name`] matches it),
    /// if known.
    pub fn by_name(name: &str) -> Option<&'static SimModel> {
        let model = registers::model_by_name(name)?;
        SimModel::by_number(model.number)
    }

    /// The model with this model number, if known.
    pub fn by_number(number: u16) -> Option<&'static SimModel> {
        const ALL: &[SimModel] = &SimModel::ALL;
        ALL.iter().find(|m| m.model.number == number)
    }

    /// The model's name, as the protocol crate spells it (e.g. `STS3215`).
    pub const fn name(&self) -> &'static str {
        self.model.name
    }

    /// The series' register map: layout, access and factory values.
    pub const fn map(&self) -> &'static RegisterMap {
        self.model.series.map()
    }

    /// Byte order of two-byte registers.
    pub const fn byte_order(&self) -> ByteOrder {
        self.model.series.byte_order()
    }

    /// Which instructions the servo answers when register 8 holds `value`.
    pub const fn status_level(&self, value: u8) -> StatusLevel {
        StatusLevel::from_register(self.model.series, value)
    }

    /// Sign bit of goal and present position (none on SCS: unsigned).
    pub const fn position_sign_bit(&self) -> Option<u8> {
        match self.model.series {
            Series::Sts => sts::PRESENT_POSITION.register().sign_bit,
            Series::Scs => scs::PRESENT_POSITION.register().sign_bit,
        }
    }

    /// Sign bit of the homing offset register (31), when the series has one
    /// (STS/SMS; it also has the operating mode and the protection time).
    pub const fn offset_sign_bit(&self) -> Option<u8> {
        match self.model.series {
            Series::Sts => sts::OFFSET.register().sign_bit,
            Series::Scs => None,
        }
    }

    /// Nominal supply voltage in 0.1 V: what present voltage reads at rest
    /// (the map's factory value).
    pub const fn nominal_voltage(&self) -> u8 {
        match self.model.series {
            Series::Sts => sts::PRESENT_VOLTAGE.register().factory as u8,
            Series::Scs => scs::PRESENT_VOLTAGE.register().factory as u8,
        }
    }

    /// Top speed in ticks per second at nominal voltage.
    pub fn max_speed(&self) -> f64 {
        f64::from(self.model.max_speed)
    }

    /// The register that contains byte `address`, if any.
    pub fn register_at(&self, address: usize) -> Option<&'static Register> {
        u8::try_from(address)
            .ok()
            .and_then(|a| self.map().containing(a))
    }

    /// The register with this name (as [`RegisterMap::get`] matches it).
    pub fn register(&self, name: &str) -> Option<&'static Register> {
        self.map().get(name)
    }

    /// Access of byte `address` (reserved and past-the-end bytes are read-only).
    pub fn area(&self, address: usize) -> Access {
        self.register_at(address)
            .map_or(Access::ReadOnly, |reg| reg.access)
    }

    /// The factory memory table: every register of the map at its factory
    /// value, the model number filled in, reserved bytes 0. Reads past its
    /// end answer zeros (see the crate docs).
    pub fn factory_table(&self) -> Vec<u8> {
        let map = self.map();
        let mut t = vec![0u8; map.table_len()];
        for reg in map.registers {
            let raw = if reg.address == registers::addr::MODEL_NUMBER {
                self.model.number
            } else {
                reg.factory
            };
            let bytes = &mut t[usize::from(reg.address)..usize::from(reg.end())];
            registers::write_uint(u32::from(raw), map.byte_order, bytes);
        }
        t
    }

    /// Degrees per tick.
    pub fn deg_per_tick(&self) -> f64 {
        self.model.deg_per_tick()
    }
}

/// The sign bit of a sign-magnitude STS register (SCS servos share the
/// bits of present speed and load; their goal speed never reaches bit 15).
const fn sign_bit_of(reg: &Register) -> u8 {
    match reg.sign_bit {
        Some(bit) => bit,
        None => panic!("an unsigned register has no sign bit"),
    }
}

/// Sign bit of present speed and goal speed.
pub(crate) const SPEED_BIT: u8 = sign_bit_of(sts::PRESENT_SPEED.register());
/// Sign bit of present load.
pub(crate) const LOAD_BIT: u8 = sign_bit_of(sts::PRESENT_LOAD.register());
/// Sign bit of present current.
pub(crate) const CURRENT_BIT: u8 = sign_bit_of(sts::PRESENT_CURRENT.register());
