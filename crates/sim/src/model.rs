//! The memory tables of the simulated servo models: layout, access and
//! factory value of every byte.
//!
//! The layouts follow `control-tables.md` (Feetech's published STS/SMS and
//! SCS tables, as the Feetech SDKs and LeRobot use them). Factory values are
//! Feetech's where a public source states them; the rest (reserved bytes,
//! gains, factory-area tuning bytes) are plausible values, chosen so that
//! host software sees what it expects.

/// Byte order of the multi-byte registers of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Endian {
    /// STS/SMS series: low byte first.
    Little,
    /// SCS series: high byte first.
    Big,
}

/// How one byte of the memory table may be written, and whether it persists.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Area {
    /// Read-only (version, model, present values, reserved bytes): writes are
    /// ignored.
    ReadOnly,
    /// EEPROM: writes apply at once and survive a power cycle only when the
    /// lock register is open (0).
    Eeprom,
    /// RAM: writes apply at once and are lost at a power cycle.
    Ram,
}

/// One register of a model: a run of `size` bytes at `address`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reg {
    /// First byte.
    pub address: u8,
    /// Length in bytes (1 or 2).
    pub size: u8,
    /// Access of every byte of the register.
    pub area: Area,
    /// Factory value, as an unsigned raw value (sign-magnitude registers are
    /// stored raw).
    pub factory: u16,
    /// The register's name, as Feetech's tables spell it.
    pub name: &'static str,
}

const fn r(address: u8, size: u8, area: Area, factory: u16, name: &'static str) -> Reg {
    Reg {
        address,
        size,
        area,
        factory,
        name,
    }
}

use Area::{Eeprom as E, Ram as M, ReadOnly as R};

/// A servo model as the simulator needs it: identity, memory table and the
/// physical figures of its dynamics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimModel {
    /// Model name, lower case (e.g. `sts3215`).
    pub name: &'static str,
    /// Model number, stored at address 3.
    pub number: u16,
    /// Firmware version bytes (addresses 0 and 1).
    pub firmware: (u8, u8),
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
    /// Stall current in present-current counts.
    pub stall_current: f64,
    /// Bytes of the memory table; reads past it answer zeros (see the crate docs).
    pub table_len: usize,
    /// Every register with its access and factory value; unlisted bytes are
    /// reserved: read-only, reading 0.
    pub registers: &'static [Reg],
}

const STS_REGS: &[Reg] = &[
    r(0, 1, R, 3, "Firmware_Major_Version"),
    r(1, 1, R, 10, "Firmware_Minor_Version"),
    r(3, 2, R, 777, "Model_Number"),
    r(5, 1, E, 1, "ID"),
    r(6, 1, E, 0, "Baud_Rate"),
    r(7, 1, E, 250, "Return_Delay_Time"),
    r(8, 1, E, 1, "Response_Status_Level"),
    r(9, 2, E, 0, "Min_Position_Limit"),
    r(11, 2, E, 4095, "Max_Position_Limit"),
    r(13, 1, E, 70, "Max_Temperature_Limit"),
    r(14, 1, E, 140, "Max_Voltage_Limit"),
    r(15, 1, E, 40, "Min_Voltage_Limit"),
    r(16, 2, E, 1000, "Max_Torque_Limit"),
    r(18, 1, E, 12, "Phase"),
    r(19, 1, E, 44, "Unloading_Condition"),
    r(20, 1, E, 47, "LED_Alarm_Condition"),
    r(21, 1, E, 32, "P_Coefficient"),
    r(22, 1, E, 32, "D_Coefficient"),
    r(23, 1, E, 0, "I_Coefficient"),
    r(24, 2, E, 16, "Minimum_Startup_Force"),
    r(26, 1, E, 1, "CW_Dead_Zone"),
    r(27, 1, E, 1, "CCW_Dead_Zone"),
    r(28, 2, E, 500, "Protection_Current"),
    r(30, 1, E, 1, "Angular_Resolution"),
    r(31, 2, E, 0, "Homing_Offset"),
    r(33, 1, E, 0, "Operating_Mode"),
    r(34, 1, E, 20, "Protective_Torque"),
    r(35, 1, E, 200, "Protection_Time"),
    r(36, 1, E, 80, "Overload_Torque"),
    r(37, 1, E, 10, "Velocity_Closed_Loop_P"),
    r(38, 1, E, 200, "Over_Current_Protection_Time"),
    r(39, 1, E, 200, "Velocity_Closed_Loop_I"),
    r(40, 1, M, 0, "Torque_Enable"),
    r(41, 1, M, 0, "Acceleration"),
    r(42, 2, M, 0, "Goal_Position"),
    r(44, 2, M, 0, "Goal_Time"),
    r(46, 2, M, 0, "Goal_Velocity"),
    r(48, 2, M, 1000, "Torque_Limit"),
    r(55, 1, M, 1, "Lock"),
    r(56, 2, R, 0, "Present_Position"),
    r(58, 2, R, 0, "Present_Velocity"),
    r(60, 2, R, 0, "Present_Load"),
    r(62, 1, R, 120, "Present_Voltage"),
    r(63, 1, R, 25, "Present_Temperature"),
    r(64, 1, R, 0, "Async_Write_Flag"),
    r(65, 1, R, 0, "Status"),
    r(66, 1, R, 0, "Moving"),
    r(69, 2, R, 0, "Present_Current"),
    r(71, 2, R, 0, "Goal_Position_2"),
    r(80, 1, E, 1, "Moving_Velocity_Threshold"),
    r(81, 1, E, 32, "DTs"),
    r(82, 1, E, 1, "Velocity_Unit_Factor"),
    r(83, 1, E, 20, "Hts"),
    r(84, 1, E, 254, "Maximum_Velocity_Limit"),
    r(85, 1, E, 150, "Maximum_Acceleration"),
    r(86, 1, E, 50, "Acceleration_Multiplier"),
];

const SCS_REGS: &[Reg] = &[
    r(0, 1, R, 2, "Firmware_Major_Version"),
    r(1, 1, R, 9, "Firmware_Minor_Version"),
    r(3, 2, R, 1284, "Model_Number"),
    r(5, 1, E, 1, "ID"),
    r(6, 1, E, 0, "Baud_Rate"),
    r(7, 1, E, 0, "Return_Delay_Time"),
    r(8, 1, E, 2, "Response_Status_Level"),
    r(9, 2, E, 0, "Min_Position_Limit"),
    r(11, 2, E, 1023, "Max_Position_Limit"),
    r(13, 1, E, 70, "Max_Temperature_Limit"),
    r(14, 1, E, 80, "Max_Voltage_Limit"),
    r(15, 1, E, 40, "Min_Voltage_Limit"),
    r(16, 2, E, 1000, "Max_Torque_Limit"),
    r(18, 1, E, 0, "Phase"),
    r(19, 1, E, 37, "Unloading_Condition"),
    r(20, 1, E, 37, "LED_Alarm_Condition"),
    r(21, 1, E, 15, "P_Coefficient"),
    r(22, 1, E, 0, "D_Coefficient"),
    r(23, 1, E, 0, "I_Coefficient"),
    r(24, 2, E, 0, "Minimum_Startup_Force"),
    r(26, 1, E, 1, "CW_Dead_Zone"),
    r(27, 1, E, 1, "CCW_Dead_Zone"),
    r(37, 1, E, 20, "Protective_Torque"),
    r(38, 1, E, 200, "Protection_Time"),
    r(40, 1, M, 0, "Torque_Enable"),
    r(41, 1, M, 0, "Acceleration"),
    r(42, 2, M, 0, "Goal_Position"),
    r(44, 2, M, 0, "Running_Time"),
    r(46, 2, M, 0, "Goal_Velocity"),
    r(48, 1, M, 1, "Lock"),
    r(56, 2, R, 0, "Present_Position"),
    r(58, 2, R, 0, "Present_Velocity"),
    r(60, 2, R, 0, "Present_Load"),
    r(62, 1, R, 60, "Present_Voltage"),
    r(63, 1, R, 25, "Present_Temperature"),
    r(64, 1, R, 0, "Sync_Write_Flag"),
    r(65, 1, R, 0, "Status"),
    r(66, 1, R, 0, "Moving"),
    r(78, 1, E, 50, "PWM_Maximum_Step"),
    r(79, 1, E, 1, "Moving_Velocity_Threshold"),
    r(80, 1, E, 32, "DTs"),
    r(81, 1, E, 1, "Minimum_Velocity_Limit"),
    r(82, 1, E, 30, "Maximum_Velocity_Limit"),
    r(83, 1, E, 0, "Acceleration_2"),
];

impl SimModel {
    /// Feetech STS3215 (SO-100/SO-101 arms): 4096 ticks a turn, 12 V.
    pub const STS3215: SimModel = SimModel {
        name: "sts3215",
        number: 777,
        firmware: (3, 10),
        endian: Endian::Little,
        sync_read: true,
        lock_address: 55,
        three_status_levels: false,
        position_sign_bit: Some(15),
        offset_sign_bit: Some(11),
        resolution: 4096,
        range_deg: 360.0,
        max_speed: 3400.0,
        nominal_voltage: 120,
        stall_current: 415.0,
        table_len: 87,
        registers: STS_REGS,
    };

    /// Feetech STS3250: the STS3215's table with model number 2825.
    pub const STS3250: SimModel = SimModel {
        name: "sts3250",
        number: 2825,
        stall_current: 700.0,
        ..SimModel::STS3215
    };

    /// Feetech SM8512BL (SMS series, RS-485): the STS table with model
    /// number 11272.
    pub const SM8512BL: SimModel = SimModel {
        name: "sm8512bl",
        number: 11272,
        stall_current: 1500.0,
        ..SimModel::STS3215
    };

    /// Feetech SCS0009: big-endian SCS series, 1024 ticks over 300 degrees,
    /// no SYNC READ, lock at 48.
    pub const SCS0009: SimModel = SimModel {
        name: "scs0009",
        number: 1284,
        firmware: (2, 9),
        endian: Endian::Big,
        sync_read: false,
        lock_address: 48,
        three_status_levels: true,
        position_sign_bit: None,
        offset_sign_bit: None,
        resolution: 1024,
        range_deg: 300.0,
        max_speed: 1500.0,
        nominal_voltage: 60,
        stall_current: 0.0,
        table_len: 84,
        registers: SCS_REGS,
    };

    /// Feetech SCS15: the SCS0009's table with model number 1792.
    pub const SCS15: SimModel = SimModel {
        name: "scs15",
        number: 1792,
        max_speed: 1000.0,
        ..SimModel::SCS0009
    };

    /// Every model the simulator knows.
    pub const ALL: [SimModel; 5] = [
        SimModel::STS3215,
        SimModel::STS3250,
        SimModel::SM8512BL,
        SimModel::SCS0009,
        SimModel::SCS15,
    ];

    /// The model with this name (case-insensitive), if known.
    pub fn by_name(name: &str) -> Option<&'static SimModel> {
        const ALL: &[SimModel] = &SimModel::ALL;
        ALL.iter().find(|m| m.name.eq_ignore_ascii_case(name))
    }

    /// The model with this model number, if known.
    pub fn by_number(number: u16) -> Option<&'static SimModel> {
        const ALL: &[SimModel] = &SimModel::ALL;
        ALL.iter().find(|m| m.number == number)
    }

    /// The register that contains byte `address`, if any.
    pub fn register_at(&self, address: usize) -> Option<&'static Reg> {
        self.registers.iter().find(|r| {
            (usize::from(r.address)..usize::from(r.address) + usize::from(r.size))
                .contains(&address)
        })
    }

    /// The register with this name (case-insensitive, `_` optional).
    pub fn register(&self, name: &str) -> Option<&'static Reg> {
        let norm = |s: &str| -> String {
            s.chars()
                .filter(|c| c.is_ascii_alphanumeric())
                .map(|c| c.to_ascii_lowercase())
                .collect()
        };
        let want = norm(name);
        self.registers.iter().find(|r| norm(r.name) == want)
    }

    /// Access of byte `address` (reserved and past-the-end bytes are read-only).
    pub fn area(&self, address: usize) -> Area {
        match self.register_at(address) {
            Some(reg) => reg.area,
            None => Area::ReadOnly,
        }
    }

    /// The factory memory table (with the model number and firmware filled in).
    pub fn factory_table(&self) -> Vec<u8> {
        let mut t = vec![0u8; self.table_len];
        for reg in self.registers {
            let a = usize::from(reg.address);
            match (reg.size, self.endian) {
                (1, _) => t[a] = reg.factory as u8,
                (_, Endian::Little) => t[a..a + 2].copy_from_slice(&reg.factory.to_le_bytes()),
                (_, Endian::Big) => t[a..a + 2].copy_from_slice(&reg.factory.to_be_bytes()),
            }
        }
        t[0] = self.firmware.0;
        t[1] = self.firmware.1;
        match self.endian {
            Endian::Little => t[3..5].copy_from_slice(&self.number.to_le_bytes()),
            Endian::Big => t[3..5].copy_from_slice(&self.number.to_be_bytes()),
        }
        t
    }

    /// Degrees per tick.
    pub fn deg_per_tick(&self) -> f64 {
        self.range_deg / f64::from(self.resolution)
    }
}

/// Encodes `value` in sign-magnitude with the sign at `sign_bit` (as Feetech
/// stores signed registers); magnitudes beyond the field saturate.
pub fn sign_magnitude(value: i32, sign_bit: u8) -> u16 {
    let max = (1i32 << sign_bit) - 1;
    let mag = value.unsigned_abs().min(max as u32) as u16;
    if value < 0 {
        mag | (1u16 << sign_bit)
    } else {
        mag
    }
}

/// Decodes a sign-magnitude raw value with the sign at `sign_bit`; bits above
/// the sign bit are ignored.
pub fn from_sign_magnitude(raw: u16, sign_bit: u8) -> i32 {
    let mask = (1u32 << sign_bit) - 1;
    let mag = (u32::from(raw) & mask) as i32;
    if raw & (1u16 << sign_bit) != 0 {
        -mag
    } else {
        mag
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registers_do_not_overlap_and_fit_the_table() {
        for m in SimModel::ALL {
            let mut seen = vec![false; m.table_len];
            for reg in m.registers {
                for a in reg.address..reg.address + reg.size {
                    assert!(usize::from(a) < m.table_len, "{} {}", m.name, reg.name);
                    assert!(!seen[usize::from(a)], "{} overlaps at {a}", m.name);
                    seen[usize::from(a)] = true;
                }
            }
        }
    }

    #[test]
    fn factory_tables_carry_model_number_in_series_byte_order() {
        assert_eq!(&SimModel::STS3215.factory_table()[3..5], &[0x09, 0x03]);
        assert_eq!(&SimModel::SCS0009.factory_table()[3..5], &[0x05, 0x04]);
        assert_eq!(&SimModel::STS3215.factory_table()[11..13], &[0xFF, 0x0F]);
        assert_eq!(&SimModel::SCS0009.factory_table()[11..13], &[0x03, 0xFF]);
    }

    #[test]
    fn sign_magnitude_round_trips() {
        for v in [-2047, -1, 0, 1, 2047] {
            assert_eq!(from_sign_magnitude(sign_magnitude(v, 11), 11), v);
        }
        assert_eq!(sign_magnitude(-5, 15), 0x8005);
        assert_eq!(sign_magnitude(5000, 11), 2047);
    }
}
