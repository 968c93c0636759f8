//! The servos' baud-rate table (register 6) and the return-delay register
//! (7): the one place servobus knows which index means which rate.

use core::time::Duration;

use super::sts;

/// Baud rate for each value of the baud-rate register (address 6), index =
/// register value: 0 = 1 Mbps, 1 = 500 kbps, 2 = 250 kbps, 3 = 128 kbps,
/// 4 = 115200, 5 = 76800, 6 = 57600, 7 = 38400.
///
/// This is the table of Feetech's Python and C++ SDKs, which agree with each
/// other; LeRobot's table differs from index 5 on and is not used.
pub const BAUD_RATES: [u32; 8] = [
    1_000_000, 500_000, 250_000, 128_000, 115_200, 76_800, 57_600, 38_400,
];

/// The highest baud rate the servos support (index 0 of [`BAUD_RATES`]).
pub const MAX_SERVO_BAUD: u32 = BAUD_RATES[0];

/// The baud rate selected by register value `index`, or `None` for a value
/// outside the table.
pub const fn baud_rate(index: u8) -> Option<u32> {
    if (index as usize) < BAUD_RATES.len() {
        Some(BAUD_RATES[index as usize])
    } else {
        None
    }
}

/// The register value that selects `baud`, or `None` when the servos have no
/// such setting.
pub const fn baud_index(baud: u32) -> Option<u8> {
    let mut i = 0;
    while i < BAUD_RATES.len() {
        if BAUD_RATES[i] == baud {
            return Some(i as u8);
        }
        i += 1;
    }
    None
}

/// The lowest table baud rate strictly above `baud`, or `None` when `baud` is
/// already at or above 1 Mbps.
pub const fn next_baud_above(baud: u32) -> Option<u32> {
    // The table is in descending order: the last entry above `baud` is the
    // lowest one above it.
    let mut best = None;
    let mut i = 0;
    while i < BAUD_RATES.len() {
        if BAUD_RATES[i] > baud {
            best = Some(BAUD_RATES[i]);
        }
        i += 1;
    }
    best
}

/// Unit of the return-delay register (address 7): 2 us.
pub const RETURN_DELAY_UNIT: Duration = Duration::from_micros(2);

/// The factory return delay of STS/SMS servos (register value 250: 500 us).
/// Robots set it to 0.
pub const FACTORY_RETURN_DELAY: Duration =
    return_delay_from_register(sts::RETURN_DELAY.register.factory as u8);

/// The return delay set by register value `value` (2 us units).
pub const fn return_delay_from_register(value: u8) -> Duration {
    Duration::from_micros(2 * value as u64)
}
