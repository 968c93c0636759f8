//! The STS/SMS and SCS control tables: every register written once, with
//! its Rust type, access, sign bit and factory value.
//!
//! Sources: Feetech's SDKs (Python `ftservo-python-sdk`, C++ `SMS_STS.h`,
//! `SCSCL.h`) and LeRobot's feetech `tables.py`, as collected in the
//! project's control-tables reference. Names are servobus's own snake_case;
//! [`ALIASES`] maps the names other tools use.
//!
//! Factory values are Feetech's where a public source states them (ID 1,
//! return delay 250, angle limits, maximum temperature 70, torque 1000, the
//! lock closed). The rest (gains, tuning bytes, firmware version) are what
//! servos of the series are commonly reported to hold, and read-only
//! registers give what a servo at rest on its nominal supply reports
//! (12.0 V for STS, 6.0 V for SCS, 25 C): plausible starting values for the
//! simulator, not guarantees about a servo on the bench.

use super::{ByteOrder, RegisterMap, Series};

/// Declares one series' registers as typed constants and lists them, in
/// address order, as `REGISTERS`. A row reads either
/// `CONST: type = (address access sign factory "name" "unit" "description");`
/// where `sign` is the sign bit of a sign-magnitude register or `-`, or
/// `CONST: type = (sts factory);` for a register laid out exactly as the
/// STS/SMS one of the same name, with its own factory value, or
/// `CONST: type = (sts @ address factory);` for the STS/SMS register moved
/// to another address.
macro_rules! table {
    ($($konst:ident: $ty:ty = ($($row:tt)*);)*) => {
        $(
            #[doc = table!(@doc $konst $($row)*)]
            pub const $konst: Reg<$ty> = Reg::new(table!(@register $konst $ty; $($row)*));
        )*
        /// Every register of the series, in address order.
        pub(crate) const REGISTERS: &[Register] = &[$($konst.register),*];
    };
    (@register $konst:ident $ty:ty; sts $factory:literal) => {
        Register { factory: $factory, ..super::sts::$konst.register }
    };
    (@register $konst:ident $ty:ty; sts @ $addr:literal $factory:literal) => {
        Register { address: $addr, factory: $factory, ..super::sts::$konst.register }
    };
    (@register $konst:ident $ty:ty;
        $addr:literal $access:ident $sign:tt $factory:literal $name:literal $unit:literal $desc:literal) => {
        Register {
            name: $name,
            address: $addr,
            size: <$ty as RegisterValue>::SIZE,
            access: $access,
            sign_bit: table!(@sign $sign),
            factory: $factory,
            unit: $unit,
            description: $desc,
        }
    };
    (@doc $konst:ident sts $factory:literal) => {
        concat!("As [`sts::", stringify!($konst), "`](super::sts::", stringify!($konst),
            "), factory value ", stringify!($factory), ".")
    };
    (@doc $konst:ident sts @ $addr:literal $factory:literal) => {
        concat!("As [`sts::", stringify!($konst), "`](super::sts::", stringify!($konst),
            ") at address ", stringify!($addr), ", factory value ", stringify!($factory), ".")
    };
    (@doc $konst:ident $addr:literal $access:ident $sign:tt $factory:literal
        $name:literal $unit:literal $desc:literal) => {
        concat!("`", $name, "` (", stringify!($addr), "): ", $desc, ".")
    };
    (@sign -) => { None };
    (@sign $bit:literal) => { Some($bit) };
}

/// The STS/SMS registers (little-endian), as typed constants.
pub mod sts {
    use crate::registers::typed::{Reg, RegisterValue};
    use crate::registers::{
        Access::Eeprom as E, Access::Ram as W, Access::ReadOnly as R, Register,
    };

    table! {
        FIRMWARE_MAJOR: u8 = (0 R - 3 "firmware_major" "" "firmware major version");
        FIRMWARE_MINOR: u8 = (1 R - 10 "firmware_minor" "" "firmware minor version");
        MODEL_NUMBER: u16 = (3 R - 777 "model_number" "" "model number (STS3215 = 777)");
        ID: u8 = (5 E - 1 "id" "" "servo ID, 0..=253");
        BAUD_RATE: u8 = (6 E - 0 "baud_rate" "index" "baud-rate index, 0 = 1 Mbps");
        RETURN_DELAY: u8 = (7 E - 250 "return_delay" "2 us" "delay before a reply");
        STATUS_LEVEL: u8 = (8 E - 1 "status_level" "" "0: reply to PING/READ only; 1: all");
        MIN_ANGLE_LIMIT: u16 = (9 E - 0 "min_angle_limit" "steps" "lowest goal accepted");
        MAX_ANGLE_LIMIT: u16 = (11 E - 4095 "max_angle_limit" "steps" "highest goal accepted");
        MAX_TEMPERATURE: u8 = (13 E - 70 "max_temperature" "degC" "overheat threshold");
        MAX_VOLTAGE: u8 = (14 E - 140 "max_voltage" "0.1 V" "over-voltage threshold");
        MIN_VOLTAGE: u8 = (15 E - 40 "min_voltage" "0.1 V" "under-voltage threshold");
        MAX_TORQUE: u16 = (16 E - 1000 "max_torque" "0.1 %" "torque ceiling, 0..=1000");
        PHASE: u8 = (18 E - 12 "phase" "" "phase bits; bit 4 angle feedback mode");
        UNLOADING_CONDITION: u8 = (19 E - 44 "unloading_condition" "" "protection mask");
        LED_ALARM_CONDITION: u8 = (20 E - 47 "led_alarm_condition" "" "LED alarm mask");
        P_COEFFICIENT: u8 = (21 E - 32 "p_coefficient" "" "position loop P");
        D_COEFFICIENT: u8 = (22 E - 32 "d_coefficient" "" "position loop D");
        I_COEFFICIENT: u8 = (23 E - 0 "i_coefficient" "" "position loop I");
        MIN_STARTUP_FORCE: u16 = (24 E - 16 "min_startup_force" "0.1 %" "minimum output");
        CW_DEAD_ZONE: u8 = (26 E - 1 "cw_dead_zone" "steps" "clockwise dead zone");
        CCW_DEAD_ZONE: u8 = (27 E - 1 "ccw_dead_zone" "steps" "counter-clockwise dead zone");
        PROTECTION_CURRENT: u16 = (28 E - 500 "protection_current" "6.5 mA" "current limit");
        ANGULAR_RESOLUTION: u8 = (30 E - 1 "angular_resolution" "" "angular resolution factor");
        OFFSET: i16 = (31 E 11 0 "offset" "steps" "homing offset: present = actual - offset");
        MODE: u8 = (33 E - 0 "mode" "" "0 position, 1 speed, 2 PWM, 3 step");
        PROTECTIVE_TORQUE: u8 = (34 E - 20 "protective_torque" "%" "torque after overload");
        PROTECTION_TIME: u8 = (35 E - 200 "protection_time" "10 ms" "overload time before protection");
        OVERLOAD_TORQUE: u8 = (36 E - 80 "overload_torque" "%" "overload threshold");
        SPEED_P_COEFFICIENT: u8 = (37 E - 10 "speed_p_coefficient" "" "speed loop P");
        OVERCURRENT_TIME: u8 = (38 E - 200 "overcurrent_time" "10 ms" "over-current time before protection");
        SPEED_I_COEFFICIENT: u8 = (39 E - 200 "speed_i_coefficient" "" "speed loop I");
        TORQUE_ENABLE: u8 = (40 W - 0 "torque_enable" "" "0 off, 1 on, 128 sets midpoint");
        ACCELERATION: u8 = (41 W - 0 "acceleration" "100 steps/s^2" "0 = no limit");
        GOAL_POSITION: i16 = (42 W 15 0 "goal_position" "steps" "target position");
        GOAL_TIME: u16 = (44 W - 0 "goal_time" "ms" "move time (PWM in mode 2)");
        GOAL_SPEED: i16 = (46 W 15 0 "goal_speed" "steps/s" "speed limit; 0 = maximum");
        TORQUE_LIMIT: u16 = (48 W - 1000 "torque_limit" "0.1 %" "torque ceiling now");
        LOCK: u8 = (55 W - 1 "lock" "" "0: EEPROM writes persist; 1: locked");
        PRESENT_POSITION: i16 = (56 R 15 0 "present_position" "steps" "measured position");
        PRESENT_SPEED: i16 = (58 R 15 0 "present_speed" "steps/s" "measured speed");
        PRESENT_LOAD: i16 = (60 R 10 0 "present_load" "0.1 %" "output PWM duty");
        PRESENT_VOLTAGE: u8 = (62 R - 120 "present_voltage" "0.1 V" "input voltage");
        PRESENT_TEMPERATURE: u8 = (63 R - 25 "present_temperature" "degC" "internal temperature");
        ASYNC_FLAG: u8 = (64 R - 0 "async_flag" "" "1 while a REG WRITE waits");
        STATUS: u8 = (65 R - 0 "status" "" "error bits, as the status byte");
        MOVING: u8 = (66 R - 0 "moving" "" "1 while moving");
        PRESENT_CURRENT: i16 = (69 R 15 0 "present_current" "6.5 mA" "motor current");
        GOAL_POSITION_2: u16 = (71 R - 0 "goal_position_2" "steps" "firmware's copy of the goal (undocumented)");
        MOVING_THRESHOLD: u8 = (80 E - 1 "moving_threshold" "" "speed below which moving reads 0");
        DTS: u8 = (81 E - 32 "dts" "ms" "factory tuning byte (undocumented)");
        SPEED_UNIT_FACTOR: u8 = (82 E - 1 "speed_unit_factor" "" "factory tuning byte (undocumented)");
        HTS: u8 = (83 E - 20 "hts" "" "factory tuning byte (undocumented)");
        MAX_SPEED_LIMIT: u8 = (84 E - 254 "max_speed_limit" "" "factory speed ceiling");
        MAX_ACCELERATION: u8 = (85 E - 150 "max_acceleration" "100 steps/s^2" "factory acceleration ceiling");
        ACCELERATION_MULTIPLIER: u8 = (86 E - 50 "acceleration_multiplier" "" "factory tuning byte (undocumented)");
    }
}

/// The SCS registers (big-endian, no offset or mode; unsigned positions), as
/// typed constants.
pub mod scs {
    use crate::registers::typed::{Reg, RegisterValue};
    use crate::registers::{
        Access::Eeprom as E, Access::Ram as W, Access::ReadOnly as R, Register,
    };

    table! {
        FIRMWARE_MAJOR: u8 = (sts 2);
        FIRMWARE_MINOR: u8 = (sts 9);
        MODEL_NUMBER: u16 = (3 R - 1284 "model_number" "" "model number (SCS0009 = 1284)");
        ID: u8 = (sts 1);
        BAUD_RATE: u8 = (sts 0);
        RETURN_DELAY: u8 = (sts 0);
        STATUS_LEVEL: u8 = (8 E - 2 "status_level" "" "0 PING only, 1 READ, 2 all");
        MIN_ANGLE_LIMIT: u16 = (sts 0);
        MAX_ANGLE_LIMIT: u16 = (sts 1023);
        MAX_TEMPERATURE: u8 = (sts 70);
        MAX_VOLTAGE: u8 = (sts 80);
        MIN_VOLTAGE: u8 = (sts 40);
        MAX_TORQUE: u16 = (sts 1000);
        PHASE: u8 = (18 E - 0 "phase" "" "phase bits");
        UNLOADING_CONDITION: u8 = (sts 37);
        LED_ALARM_CONDITION: u8 = (sts 37);
        P_COEFFICIENT: u8 = (sts 15);
        D_COEFFICIENT: u8 = (sts 0);
        I_COEFFICIENT: u8 = (sts 0);
        MIN_STARTUP_FORCE: u16 = (sts 0);
        CW_DEAD_ZONE: u8 = (sts 1);
        CCW_DEAD_ZONE: u8 = (sts 1);
        PROTECTIVE_TORQUE: u8 = (sts @ 37 20);
        PROTECTION_TIME: u8 = (sts @ 38 200);
        TORQUE_ENABLE: u8 = (40 W - 0 "torque_enable" "" "0 off, 1 on");
        ACCELERATION: u8 = (41 W - 0 "acceleration" "" "acceleration");
        GOAL_POSITION: u16 = (42 W - 0 "goal_position" "steps" "target position, 0..=1023");
        GOAL_TIME: u16 = (44 W - 0 "goal_time" "ms" "move time (PWM in PWM mode)");
        GOAL_SPEED: u16 = (46 W - 0 "goal_speed" "steps/s" "speed limit; 0 = maximum");
        LOCK: u8 = (sts @ 48 1);
        PRESENT_POSITION: u16 = (56 R - 0 "present_position" "steps" "measured position");
        PRESENT_SPEED: i16 = (sts 0);
        PRESENT_LOAD: i16 = (sts 0);
        PRESENT_VOLTAGE: u8 = (sts 60);
        PRESENT_TEMPERATURE: u8 = (sts 25);
        ASYNC_FLAG: u8 = (sts 0);
        STATUS: u8 = (sts 0);
        MOVING: u8 = (sts 0);
        PRESENT_CURRENT: u16 = (69 R - 0 "present_current" "" "motor current");
        PWM_MAX_STEP: u8 = (78 E - 50 "pwm_max_step" "" "factory tuning byte (undocumented)");
        MOVING_THRESHOLD: u8 = (79 E - 1 "moving_threshold" "" "speed below which moving reads 0");
        DTS: u8 = (80 E - 32 "dts" "ms" "factory tuning byte (undocumented)");
        MIN_SPEED_LIMIT: u8 = (81 E - 1 "min_speed_limit" "" "factory speed floor");
        MAX_SPEED_LIMIT: u8 = (82 E - 30 "max_speed_limit" "" "factory speed ceiling");
        ACCELERATION_2: u8 = (83 E - 0 "acceleration_2" "" "factory tuning byte (undocumented)");
    }
}

/// Addresses of the registers servobus uses, in the STS/SMS layout, for code
/// that works with raw addresses (frames, blocks, the simulator's memory).
/// Each is taken from the typed constant in [`sts`], never written again.
/// The SCS layout shares all of them except the lock
/// ([`SCS_LOCK`](addr::SCS_LOCK)) and has no offset, mode or signed position.
pub mod addr {
    use super::{scs, sts};

    /// `pub const NAME: u8` for each STS register `NAME`, its address.
    macro_rules! addresses {
        ($($konst:ident)*) => {$(
            #[doc = concat!("Address of [`sts::", stringify!($konst), "`].")]
            pub const $konst: u8 = sts::$konst.register.address;
        )*};
    }

    addresses! {
        FIRMWARE_MAJOR FIRMWARE_MINOR MODEL_NUMBER ID BAUD_RATE RETURN_DELAY STATUS_LEVEL
        MIN_ANGLE_LIMIT MAX_ANGLE_LIMIT MAX_TEMPERATURE MAX_VOLTAGE MIN_VOLTAGE MAX_TORQUE
        UNLOADING_CONDITION CW_DEAD_ZONE CCW_DEAD_ZONE OFFSET MODE PROTECTION_TIME
        TORQUE_ENABLE ACCELERATION GOAL_POSITION GOAL_TIME GOAL_SPEED TORQUE_LIMIT LOCK
        PRESENT_POSITION PRESENT_SPEED PRESENT_LOAD PRESENT_VOLTAGE PRESENT_TEMPERATURE
        ASYNC_FLAG STATUS MOVING PRESENT_CURRENT
    }

    /// Address of [`sts::P_COEFFICIENT`], the position loop's P gain.
    pub const P_GAIN: u8 = sts::P_COEFFICIENT.register.address;
    /// Address of [`scs::LOCK`], the EEPROM lock of the SCS series.
    pub const SCS_LOCK: u8 = scs::LOCK.register.address;
}

/// Names used by other tools (LeRobot, Feetech's SDKs) for servobus's
/// registers: `(alias, canonical name)`.
pub(crate) const ALIASES: &[(&str, &str)] = &[
    ("model", "model_number"),
    ("firmware_major_version", "firmware_major"),
    ("firmware_minor_version", "firmware_minor"),
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
    ("velocity_closed_loop_p", "speed_p_coefficient"),
    ("velocity_closed_loop_i", "speed_i_coefficient"),
    ("over_current_protection_time", "overcurrent_time"),
    ("running_time", "goal_time"),
    ("goal_velocity", "goal_speed"),
    ("present_velocity", "present_speed"),
    ("async_write_flag", "async_flag"),
    ("sync_write_flag", "async_flag"),
    ("moving_velocity_threshold", "moving_threshold"),
    ("velocity_unit_factor", "speed_unit_factor"),
    ("maximum_velocity_limit", "max_speed_limit"),
    ("minimum_velocity_limit", "min_speed_limit"),
    ("pwm_maximum_step", "pwm_max_step"),
    ("maximum_acceleration", "max_acceleration"),
];

/// The STS/SMS control table (little-endian, lock at 55).
pub static STS: RegisterMap = RegisterMap {
    series: Series::Sts,
    byte_order: ByteOrder::Little,
    lock_address: sts::LOCK.register.address,
    registers: sts::REGISTERS,
};

/// The SCS control table (big-endian, lock at 48, no offset or mode).
pub static SCS: RegisterMap = RegisterMap {
    series: Series::Scs,
    byte_order: ByteOrder::Big,
    lock_address: scs::LOCK.register.address,
    registers: scs::REGISTERS,
};
