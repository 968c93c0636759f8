//! The simulated servo models: the protocol crate's facts about each model
//! (register map, factory values, resolution, speed), plus the few figures
//! only a simulation needs (stall current).
//!
//! Nothing about the memory layout is written here: [`SimModel::factory_table`]
//! lays out the protocol crate's register map with its factory values, so
//! the simulator and the driver cannot disagree about an address, a size, a
//! byte order or a sign bit.

use servobus_protocol::registers::{self, scs, sts, Model, RegisterMap, Series};

pub use servobus_protocol::registers::{Access as Area, ByteOrder as Endian, Register};

/// A servo model as the simulator needs it. Every field but
/// [`SimModel::stall_current`] is derived from the protocol crate's
/// [`Model`] and register map; they are kept as fields so that the servo's
/// hot paths read them without a lookup.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimModel {
    /// The protocol crate's model: name, number, series, resolution.
    pub model: Model,
    /// Model name, as the protocol crate spells it (e.g. `STS3215`).
    pub name: &'static str,
    /// Model number, stored at address 3.
    pub number: u16,
    /// The series' register map: layout, access and factory values.
    pub map: &'static RegisterMap,
    /// Byte order of two-byte registers.
    pub endian: Endian,
    /// Whether the firmware answers SYNC READ (STS/SMS yes, SCS no).
    pub sync_read: bool,
    /// Address of the EEPROM lock register (55 on STS/SMS, 48 on SCS).
    pub lock_address: u8,
    /// Whether the status level register (8) has three levels (SCS: 0 PING
    /// only, 1 PING and READ, 2 all) instead of two (STS: 0 PING and READ, 1 all).
    pub three_status_levels: bool,
    /// Sign bit of goal and present position (15 on STS, none on SCS).
    pub position_sign_bit: Option<u8>,
    /// Sign bit of the homing offset register (31), when the model has one.
    pub offset_sign_bit: Option<u8>,
    /// Ticks per `range_deg`.
    pub resolution: u32,
    /// Mechanical range in degrees covered by `resolution` ticks.
    pub range_deg: f64,
    /// Top speed in ticks per second at nominal voltage.
    pub max_speed: f64,
    /// Nominal supply voltage in 0.1 V (what present voltage reads at rest).
    pub nominal_voltage: u8,
    /// Stall current in present-current counts: the simulator's own figure
    /// (0 for models whose current register is not simulated).
    pub stall_current: f64,
    /// Bytes of the memory table; reads past it answer zeros (see the crate docs).
    pub table_len: usize,
}

impl SimModel {
    /// The simulation of `model`, with `stall_current` in present-current
    /// counts.
    pub const fn simulate(model: Model, stall_current: f64) -> SimModel {
        let map = model.series.map();
        let (position, offset, voltage) = match model.series {
            Series::Sts => (
                sts::PRESENT_POSITION.register().sign_bit,
                sts::OFFSET.register().sign_bit,
                sts::PRESENT_VOLTAGE.register().factory,
            ),
            Series::Scs => (
                scs::PRESENT_POSITION.register().sign_bit,
                None,
                scs::PRESENT_VOLTAGE.register().factory,
            ),
        };
        let last = map.registers[map.registers.len() - 1];
        SimModel {
            model,
            name: model.name,
            number: model.number,
            map,
            endian: map.byte_order,
            sync_read: model.series.has_sync_read(),
            lock_address: map.lock_address,
            three_status_levels: matches!(model.series, Series::Scs),
            position_sign_bit: position,
            offset_sign_bit: offset,
            resolution: model.resolution,
            range_deg: model.range_deg,
            max_speed: model.max_speed as f64,
            nominal_voltage: voltage as u8,
            stall_current,
            table_len: last.end() as usize,
        }
    }

    /// Feetech STS3215 (SO-100/SO-101 arms): 4096 ticks a turn, 12 V.
    pub const STS3215: SimModel = SimModel::simulate(registers::STS3215, 415.0);
    /// Feetech STS3250: the STS table with model number 2825.
    pub const STS3250: SimModel = SimModel::simulate(registers::STS3250, 700.0);
    /// Feetech SM8512BL (SMS series, RS-485): the STS table with model
    /// number 11272.
    pub const SM8512BL: SimModel = SimModel::simulate(registers::SM8512BL, 1500.0);
    /// Feetech SCS0009: big-endian SCS series, 1024 ticks over 300 degrees,
    /// no SYNC READ, lock at 48.
    pub const SCS0009: SimModel = SimModel::simulate(registers::SCS0009, 0.0);
    /// Feetech SCS15: the SCS table with model number 1792.
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
        ALL.iter().find(|m| m.number == number)
    }

    /// The register that contains byte `address`, if any.
    pub fn register_at(&self, address: usize) -> Option<&'static Register> {
        u8::try_from(address)
            .ok()
            .and_then(|a| self.map.containing(a))
    }

    /// The register with this name (as [`RegisterMap::get`] matches it).
    pub fn register(&self, name: &str) -> Option<&'static Register> {
        self.map.get(name)
    }

    /// Access of byte `address` (reserved and past-the-end bytes are read-only).
    pub fn area(&self, address: usize) -> Area {
        self.register_at(address)
            .map_or(Area::ReadOnly, |reg| reg.access)
    }

    /// The factory memory table: every register of the map at its factory
    /// value, the model number filled in, reserved bytes 0.
    pub fn factory_table(&self) -> Vec<u8> {
        let mut t = vec![0u8; self.table_len];
        for reg in self.map.registers {
            let raw = if reg.address == registers::addr::MODEL_NUMBER {
                self.number
            } else {
                reg.factory
            };
            let bytes = &mut t[usize::from(reg.address)..usize::from(reg.end())];
            registers::write_uint(u32::from(raw), self.endian, bytes);
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

/// The raw 16-bit content holding `value` in sign-magnitude form with the
/// sign at `sign_bit`; magnitudes beyond the field saturate
/// ([`registers::to_sign_magnitude`] for the simulator's 16-bit registers).
pub fn sign_magnitude(value: i32, sign_bit: u8) -> u16 {
    registers::to_sign_magnitude(value, sign_bit) as u16
}

/// The value of a 16-bit sign-magnitude register with the sign at
/// `sign_bit` ([`registers::sign_magnitude`] for 16-bit registers).
pub fn from_sign_magnitude(raw: u16, sign_bit: u8) -> i32 {
    registers::sign_magnitude(u32::from(raw), sign_bit)
}
