//! The STS/SMS and SCS control tables.
//!
//! Sources: Feetech's SDKs (Python `ftservo-python-sdk`, C++ `SMS_STS.h`,
//! `SCSCL.h`) and LeRobot's feetech `tables.py`, as collected in the
//! project's control-tables reference. Names are servobus's own snake_case;
//! [`ALIASES`] maps the names other tools use.

use super::{Access, ByteOrder, Register, RegisterMap, Series};

/// Addresses of the registers servobus uses, in the STS/SMS layout. The SCS
/// layout shares all of them except the lock ([`SCS_LOCK`](addr::SCS_LOCK))
/// and has no offset, mode, current or firmware-minor semantics to rely on.
pub mod addr {
    /// Firmware major version (read-only).
    pub const FIRMWARE_MAJOR: u8 = 0;
    /// Firmware minor version (read-only).
    pub const FIRMWARE_MINOR: u8 = 1;
    /// Model number, 2 bytes (read-only).
    pub const MODEL_NUMBER: u8 = 3;
    /// Servo ID.
    pub const ID: u8 = 5;
    /// Baud-rate index (see [`baud_rate`](crate::registers::baud_rate)).
    pub const BAUD_RATE: u8 = 6;
    /// Return delay, in 2 us units.
    pub const RETURN_DELAY: u8 = 7;
    /// Response status level: 0 answers PING and READ only, 1 answers all.
    pub const STATUS_LEVEL: u8 = 8;
    /// Minimum angle limit, 2 bytes.
    pub const MIN_ANGLE_LIMIT: u8 = 9;
    /// Maximum angle limit, 2 bytes.
    pub const MAX_ANGLE_LIMIT: u8 = 11;
    /// Position offset (homing), 2 bytes, sign bit 11.
    pub const OFFSET: u8 = 31;
    /// Operating mode: 0 position, 1 constant speed, 2 PWM, 3 step.
    pub const MODE: u8 = 33;
    /// Torque enable.
    pub const TORQUE_ENABLE: u8 = 40;
    /// Acceleration, in 100 steps/s^2.
    pub const ACCELERATION: u8 = 41;
    /// Goal position, 2 bytes, sign bit 15.
    pub const GOAL_POSITION: u8 = 42;
    /// Goal time, 2 bytes, ms.
    pub const GOAL_TIME: u8 = 44;
    /// Goal speed, 2 bytes, steps/s, sign bit 15.
    pub const GOAL_SPEED: u8 = 46;
    /// Torque limit, 2 bytes.
    pub const TORQUE_LIMIT: u8 = 48;
    /// EEPROM lock of the STS/SMS series.
    pub const LOCK: u8 = 55;
    /// EEPROM lock of the SCS series.
    pub const SCS_LOCK: u8 = 48;
    /// Present position, 2 bytes, sign bit 15.
    pub const PRESENT_POSITION: u8 = 56;
    /// Present speed, 2 bytes, sign bit 15.
    pub const PRESENT_SPEED: u8 = 58;
    /// Present load, 2 bytes, sign bit 10.
    pub const PRESENT_LOAD: u8 = 60;
    /// Present voltage, 0.1 V.
    pub const PRESENT_VOLTAGE: u8 = 62;
    /// Present temperature, degrees C.
    pub const PRESENT_TEMPERATURE: u8 = 63;
    /// Set while a REG WRITE waits for ACTION.
    pub const ASYNC_FLAG: u8 = 64;
    /// Servo status: the status byte's bits.
    pub const STATUS: u8 = 65;
    /// 1 while moving.
    pub const MOVING: u8 = 66;
    /// Present current, 2 bytes, sign bit 15.
    pub const PRESENT_CURRENT: u8 = 69;
    /// Maximum temperature limit, degrees C (EEPROM).
    pub const MAX_TEMPERATURE: u8 = 13;
    /// Maximum input voltage, 0.1 V (EEPROM).
    pub const MAX_VOLTAGE: u8 = 14;
    /// Minimum input voltage, 0.1 V (EEPROM).
    pub const MIN_VOLTAGE: u8 = 15;
    /// Maximum torque, 0.1 % (EEPROM).
    pub const MAX_TORQUE: u8 = 16;
    /// Unloading condition: which status bits release the torque (EEPROM).
    pub const UNLOADING_CONDITION: u8 = 19;
    /// Position loop P gain (EEPROM).
    pub const P_GAIN: u8 = 21;
    /// Clockwise dead zone, ticks (EEPROM).
    pub const CW_DEAD_ZONE: u8 = 26;
    /// Counter-clockwise dead zone, ticks (EEPROM).
    pub const CCW_DEAD_ZONE: u8 = 27;
    /// Protection time, 10 ms units (STS, EEPROM).
    pub const PROTECTION_TIME: u8 = 35;
}

use Access::{Eeprom as E, Ram as W, ReadOnly as R};

const fn reg(
    name: &'static str,
    address: u8,
    size: u8,
    access: Access,
    sign_bit: Option<u8>,
    unit: &'static str,
    description: &'static str,
) -> Register {
    Register {
        name,
        address,
        size,
        access,
        sign_bit,
        unit,
        description,
    }
}

/// Names used by other tools (LeRobot, Feetech's SDKs) for servobus's
/// registers: `(alias, canonical name)`.
pub(crate) const ALIASES: &[(&str, &str)] = &[
    ("model", "model_number"),
    ("return_delay_time", "return_delay"),
    ("response_status_level", "status_level"),
    ("min_position_limit", "min_angle_limit"),
    ("max_position_limit", "max_angle_limit"),
    ("max_temperature_limit", "max_temperature"),
    ("max_voltage_limit", "max_voltage"),
    ("min_voltage_limit", "min_voltage"),
    ("max_torque_limit", "max_torque"),
    ("minimum_startup_force", "min_startup_force"),
    ("homing_offset", "offset"),
    ("position_offset", "offset"),
    ("operating_mode", "mode"),
    ("running_time", "goal_time"),
    ("goal_velocity", "goal_speed"),
    ("present_velocity", "present_speed"),
    ("async_write_flag", "async_flag"),
    ("sync_write_flag", "async_flag"),
    ("maximum_acceleration", "max_acceleration"),
];

const STS_REGISTERS: &[Register] = &[
    reg(
        "firmware_major",
        0,
        1,
        R,
        None,
        "",
        "firmware major version",
    ),
    reg(
        "firmware_minor",
        1,
        1,
        R,
        None,
        "",
        "firmware minor version",
    ),
    reg(
        "model_number",
        3,
        2,
        R,
        None,
        "",
        "model number (STS3215 = 777)",
    ),
    reg("id", 5, 1, E, None, "", "servo ID, 0..=253"),
    reg(
        "baud_rate",
        6,
        1,
        E,
        None,
        "index",
        "baud-rate index, 0 = 1 Mbps",
    ),
    reg(
        "return_delay",
        7,
        1,
        E,
        None,
        "2 us",
        "delay before a reply",
    ),
    reg(
        "status_level",
        8,
        1,
        E,
        None,
        "",
        "0: reply to PING/READ only; 1: all",
    ),
    reg(
        "min_angle_limit",
        9,
        2,
        E,
        None,
        "steps",
        "lowest goal accepted",
    ),
    reg(
        "max_angle_limit",
        11,
        2,
        E,
        None,
        "steps",
        "highest goal accepted",
    ),
    reg(
        "max_temperature",
        13,
        1,
        E,
        None,
        "degC",
        "overheat threshold",
    ),
    reg(
        "max_voltage",
        14,
        1,
        E,
        None,
        "0.1 V",
        "over-voltage threshold",
    ),
    reg(
        "min_voltage",
        15,
        1,
        E,
        None,
        "0.1 V",
        "under-voltage threshold",
    ),
    reg(
        "max_torque",
        16,
        2,
        E,
        None,
        "0.1 %",
        "torque ceiling, 0..=1000",
    ),
    reg(
        "phase",
        18,
        1,
        E,
        None,
        "",
        "phase bits; bit 4 angle feedback mode",
    ),
    reg("unloading_condition", 19, 1, E, None, "", "protection mask"),
    reg("led_alarm_condition", 20, 1, E, None, "", "LED alarm mask"),
    reg("p_coefficient", 21, 1, E, None, "", "position loop P"),
    reg("d_coefficient", 22, 1, E, None, "", "position loop D"),
    reg("i_coefficient", 23, 1, E, None, "", "position loop I"),
    reg(
        "min_startup_force",
        24,
        2,
        E,
        None,
        "0.1 %",
        "minimum output",
    ),
    reg(
        "cw_dead_zone",
        26,
        1,
        E,
        None,
        "steps",
        "clockwise dead zone",
    ),
    reg(
        "ccw_dead_zone",
        27,
        1,
        E,
        None,
        "steps",
        "counter-clockwise dead zone",
    ),
    reg(
        "protection_current",
        28,
        2,
        E,
        None,
        "6.5 mA",
        "current limit",
    ),
    reg(
        "angular_resolution",
        30,
        1,
        E,
        None,
        "",
        "angular resolution factor",
    ),
    reg(
        "offset",
        31,
        2,
        E,
        Some(11),
        "steps",
        "homing offset: present = actual - offset",
    ),
    reg(
        "mode",
        33,
        1,
        E,
        None,
        "",
        "0 position, 1 speed, 2 PWM, 3 step",
    ),
    reg(
        "protective_torque",
        34,
        1,
        E,
        None,
        "%",
        "torque after overload",
    ),
    reg(
        "protection_time",
        35,
        1,
        E,
        None,
        "10 ms",
        "overload time before protection",
    ),
    reg("overload_torque", 36, 1, E, None, "%", "overload threshold"),
    reg("speed_p_coefficient", 37, 1, E, None, "", "speed loop P"),
    reg(
        "overcurrent_time",
        38,
        1,
        E,
        None,
        "10 ms",
        "over-current time before protection",
    ),
    reg("speed_i_coefficient", 39, 1, E, None, "", "speed loop I"),
    reg(
        "torque_enable",
        40,
        1,
        W,
        None,
        "",
        "0 off, 1 on, 128 sets midpoint",
    ),
    reg(
        "acceleration",
        41,
        1,
        W,
        None,
        "100 steps/s^2",
        "0 = no limit",
    ),
    reg(
        "goal_position",
        42,
        2,
        W,
        Some(15),
        "steps",
        "target position",
    ),
    reg(
        "goal_time",
        44,
        2,
        W,
        None,
        "ms",
        "move time (PWM in mode 2)",
    ),
    reg(
        "goal_speed",
        46,
        2,
        W,
        Some(15),
        "steps/s",
        "speed limit; 0 = maximum",
    ),
    reg(
        "torque_limit",
        48,
        2,
        W,
        None,
        "0.1 %",
        "torque ceiling now",
    ),
    reg(
        "lock",
        55,
        1,
        W,
        None,
        "",
        "0: EEPROM writes persist; 1: locked",
    ),
    reg(
        "present_position",
        56,
        2,
        R,
        Some(15),
        "steps",
        "measured position",
    ),
    reg(
        "present_speed",
        58,
        2,
        R,
        Some(15),
        "steps/s",
        "measured speed",
    ),
    reg(
        "present_load",
        60,
        2,
        R,
        Some(10),
        "0.1 %",
        "output PWM duty",
    ),
    reg("present_voltage", 62, 1, R, None, "0.1 V", "input voltage"),
    reg(
        "present_temperature",
        63,
        1,
        R,
        None,
        "degC",
        "internal temperature",
    ),
    reg(
        "async_flag",
        64,
        1,
        R,
        None,
        "",
        "1 while a REG WRITE waits",
    ),
    reg(
        "status",
        65,
        1,
        R,
        None,
        "",
        "error bits, as the status byte",
    ),
    reg("moving", 66, 1, R, None, "", "1 while moving"),
    reg(
        "present_current",
        69,
        2,
        R,
        Some(15),
        "6.5 mA",
        "motor current",
    ),
    reg(
        "max_acceleration",
        85,
        1,
        E,
        None,
        "100 steps/s^2",
        "factory acceleration ceiling",
    ),
];

const SCS_REGISTERS: &[Register] = &[
    reg(
        "firmware_major",
        0,
        1,
        R,
        None,
        "",
        "firmware major version",
    ),
    reg(
        "firmware_minor",
        1,
        1,
        R,
        None,
        "",
        "firmware minor version",
    ),
    reg(
        "model_number",
        3,
        2,
        R,
        None,
        "",
        "model number (SCS0009 = 1284)",
    ),
    reg("id", 5, 1, E, None, "", "servo ID, 0..=253"),
    reg(
        "baud_rate",
        6,
        1,
        E,
        None,
        "index",
        "baud-rate index, 0 = 1 Mbps",
    ),
    reg(
        "return_delay",
        7,
        1,
        E,
        None,
        "2 us",
        "delay before a reply",
    ),
    reg(
        "status_level",
        8,
        1,
        E,
        None,
        "",
        "0 PING only, 1 READ, 2 all",
    ),
    reg(
        "min_angle_limit",
        9,
        2,
        E,
        None,
        "steps",
        "lowest goal accepted",
    ),
    reg(
        "max_angle_limit",
        11,
        2,
        E,
        None,
        "steps",
        "highest goal accepted",
    ),
    reg(
        "max_temperature",
        13,
        1,
        E,
        None,
        "degC",
        "overheat threshold",
    ),
    reg(
        "max_voltage",
        14,
        1,
        E,
        None,
        "0.1 V",
        "over-voltage threshold",
    ),
    reg(
        "min_voltage",
        15,
        1,
        E,
        None,
        "0.1 V",
        "under-voltage threshold",
    ),
    reg(
        "max_torque",
        16,
        2,
        E,
        None,
        "0.1 %",
        "torque ceiling, 0..=1000",
    ),
    reg("phase", 18, 1, E, None, "", "phase bits"),
    reg("unloading_condition", 19, 1, E, None, "", "protection mask"),
    reg("led_alarm_condition", 20, 1, E, None, "", "LED alarm mask"),
    reg("p_coefficient", 21, 1, E, None, "", "position loop P"),
    reg("d_coefficient", 22, 1, E, None, "", "position loop D"),
    reg("i_coefficient", 23, 1, E, None, "", "position loop I"),
    reg(
        "min_startup_force",
        24,
        2,
        E,
        None,
        "0.1 %",
        "minimum output",
    ),
    reg(
        "cw_dead_zone",
        26,
        1,
        E,
        None,
        "steps",
        "clockwise dead zone",
    ),
    reg(
        "ccw_dead_zone",
        27,
        1,
        E,
        None,
        "steps",
        "counter-clockwise dead zone",
    ),
    reg(
        "protective_torque",
        37,
        1,
        E,
        None,
        "%",
        "torque after overload",
    ),
    reg(
        "protection_time",
        38,
        1,
        E,
        None,
        "10 ms",
        "overload time before protection",
    ),
    reg("torque_enable", 40, 1, W, None, "", "0 off, 1 on"),
    reg("acceleration", 41, 1, W, None, "", "acceleration"),
    reg(
        "goal_position",
        42,
        2,
        W,
        None,
        "steps",
        "target position, 0..=1023",
    ),
    reg(
        "goal_time",
        44,
        2,
        W,
        None,
        "ms",
        "move time (PWM in PWM mode)",
    ),
    reg(
        "goal_speed",
        46,
        2,
        W,
        None,
        "steps/s",
        "speed limit; 0 = maximum",
    ),
    reg(
        "lock",
        48,
        1,
        W,
        None,
        "",
        "0: EEPROM writes persist; 1: locked",
    ),
    reg(
        "present_position",
        56,
        2,
        R,
        None,
        "steps",
        "measured position",
    ),
    reg(
        "present_speed",
        58,
        2,
        R,
        Some(15),
        "steps/s",
        "measured speed",
    ),
    reg(
        "present_load",
        60,
        2,
        R,
        Some(10),
        "0.1 %",
        "output PWM duty",
    ),
    reg("present_voltage", 62, 1, R, None, "0.1 V", "input voltage"),
    reg(
        "present_temperature",
        63,
        1,
        R,
        None,
        "degC",
        "internal temperature",
    ),
    reg(
        "async_flag",
        64,
        1,
        R,
        None,
        "",
        "1 while a REG WRITE waits",
    ),
    reg(
        "status",
        65,
        1,
        R,
        None,
        "",
        "error bits, as the status byte",
    ),
    reg("moving", 66, 1, R, None, "", "1 while moving"),
    reg("present_current", 69, 2, R, None, "", "motor current"),
];

/// The STS/SMS control table (little-endian, lock at 55).
pub static STS: RegisterMap = RegisterMap {
    series: Series::Sts,
    byte_order: ByteOrder::Little,
    lock_address: addr::LOCK,
    registers: STS_REGISTERS,
};

/// The SCS control table (big-endian, lock at 48, no offset or mode).
pub static SCS: RegisterMap = RegisterMap {
    series: Series::Scs,
    byte_order: ByteOrder::Big,
    lock_address: addr::SCS_LOCK,
    registers: SCS_REGISTERS,
};
