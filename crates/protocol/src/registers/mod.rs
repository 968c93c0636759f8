//! Register maps (control tables) as data, and per-register value conversion.
//!
//! Feetech servos come in two families that share the packet format but not
//! the memory layout:
//!
//! | series | byte order | SYNC READ | lock register | models |
//! |---|---|---|---|---|
//! | [`Series::Sts`] (STS/SMS) | little-endian | yes | 55 | STS3215, STS3250, SM8512BL |
//! | [`Series::Scs`] | big-endian | no | 48 | SCS0009, SCS15 |
//!
//! Multi-byte registers hold signed quantities in *sign-magnitude* form: one
//! bit (the register's [`Register::sign_bit`]) is the direction and the bits
//! below it the magnitude. [`Register::decode`] and [`Register::encode`] do
//! the conversion for one register and one byte order, refusing values that
//! do not fit.
//!
//! Every register is a typed constant of [`sts`] or [`scs`] (a [`Reg<T>`]:
//! `sts::PRESENT_POSITION` reads as an `i16`, `scs::PRESENT_POSITION` as a
//! `u16`); [`RegisterMap`] lists them for lookup by name or address, and
//! [`addr`] gives the raw addresses. Each fact (address, size, sign bit,
//! factory value) is written once, in the tables.
//!
//! ```
//! use servobus_protocol::registers::{self, ByteOrder, Series};
//!
//! let map = Series::Sts.map();
//! let reg = map.get("Present_Position").unwrap();
//! assert_eq!((reg.address, reg.size), (56, 2));
//! // 0x8064 little-endian: sign bit 15 set, magnitude 100.
//! assert_eq!(reg.decode(&[0x64, 0x80], ByteOrder::Little), Ok(-100));
//!
//! let mut out = [0u8; 2];
//! reg.encode(-100, ByteOrder::Big, &mut out).unwrap();
//! assert_eq!(out, [0x80, 0x64]);
//!
//! let model = registers::model_by_number(777).unwrap();
//! assert_eq!((model.name, model.series), ("STS3215", Series::Sts));
//! ```
//!
//! # Readings taken where sources disagree
//!
//! - **Lock address.** STS/SMS lock at 55, SCS at 48 (Feetech's C++ SDK,
//!   `SMS_STS.h` and `SCSCL.h`). Some third-party tables put the STS lock at
//!   48; on STS servos 48 is the torque limit, so writing a lock value there
//!   would silently limit torque.
//! - **Baud-rate indices** follow Feetech's SDKs (see [`baud_rate`]); LeRobot's
//!   table differs from index 5 on and is not used.
//! - **Sign-magnitude decoding** masks the bits above the sign bit (as
//!   LeRobot does) rather than keeping them (as Feetech's C++ SDK does for the
//!   load): a value then always fits back into its register, so
//!   `encode(decode(bytes))` round-trips for every value a servo reports in
//!   range.
//! - **Goal time (44)** is read as unsigned milliseconds. In PWM mode (mode 2)
//!   the same register carries a PWM value with sign bit 10; decode it with
//!   [`sign_magnitude`] when the mode is known.
//! - **SCS positions are unsigned** (0..1023): the SCS series has no
//!   multi-turn or offset, and Feetech's `SCSCL` driver reads them unsigned;
//!   present speed (sign bit 15) and load (sign bit 10) are signed as on STS.
//! - **Register 85 (maximum acceleration)** is a factory parameter; it is
//!   listed as EEPROM because it persists.

mod baud;
mod models;
mod reply;
mod status_level;
mod tables;
mod typed;

pub use baud::{
    baud_index, baud_rate, next_baud_above, return_delay_from_register, BAUD_RATES,
    FACTORY_RETURN_DELAY, MAX_SERVO_BAUD, RETURN_DELAY_UNIT,
};
pub use models::{
    model_by_name, model_by_number, model_by_register, Model, FASTEST_PROFILE, MODELS,
    REPLY_TURNAROUND, RESPONSE_LAG, SCS0009, SCS15, SM8512BL, STS3215, STS3250,
};
pub use reply::return_delay_register;
pub use status_level::StatusLevel;
pub use tables::{addr, scs, sts, SCS, STS};
pub use typed::{Reg, RegisterValue};

/// A family of servos sharing one memory layout and byte order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Series {
    /// STS and SMS series (STS3215, STS3250, SM8512BL, ...): little-endian,
    /// SYNC READ supported.
    Sts,
    /// SCS series (SCS0009, SCS15, ...): big-endian, no SYNC READ.
    Scs,
}

impl Series {
    /// The register map of the series.
    pub const fn map(self) -> &'static RegisterMap {
        match self {
            Series::Sts => &STS,
            Series::Scs => &SCS,
        }
    }

    /// How multi-byte registers are laid out on the wire.
    pub const fn byte_order(self) -> ByteOrder {
        match self {
            Series::Sts => ByteOrder::Little,
            Series::Scs => ByteOrder::Big,
        }
    }

    /// Whether the firmware answers SYNC READ (0x82). SCS servos do not: read
    /// them one at a time.
    pub const fn has_sync_read(self) -> bool {
        matches!(self, Series::Sts)
    }
}

named! {
    /// A short lowercase name: `sts` or `scs`.
    Series {
        Sts => "sts",
        Scs => "scs",
    }
}

/// Byte order of multi-byte registers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ByteOrder {
    /// Low byte first (STS/SMS).
    Little,
    /// High byte first (SCS).
    Big,
}

/// Who may write a register, and whether a write persists.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Access {
    /// Reported by the servo; writes are refused or ignored.
    ReadOnly,
    /// Writable, kept over a power cycle when the lock register is open.
    Eeprom,
    /// Writable, lost at power-off.
    Ram,
}

impl Access {
    /// Whether a host may write the register.
    pub const fn is_writable(self) -> bool {
        !matches!(self, Access::ReadOnly)
    }
}

named! {
    /// A short lowercase name: `read-only`, `eeprom` or `ram`.
    Access {
        ReadOnly => "read-only",
        Eeprom => "eeprom",
        Ram => "ram",
    }
}

/// Why a register value could not be converted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ValueError {
    /// The byte slice does not have the register's size.
    #[error("register {register} is {expected} byte(s) wide, got {actual}")]
    Length {
        /// The register's name.
        register: &'static str,
        /// The register's size.
        expected: usize,
        /// The slice length given.
        actual: usize,
    },
    /// The value does not fit the register.
    #[error("value {value} does not fit register {register} (range {min}..={max})")]
    OutOfRange {
        /// The register's name.
        register: &'static str,
        /// The value given.
        value: i32,
        /// The smallest value the register holds.
        min: i32,
        /// The largest value the register holds.
        max: i32,
    },
}

/// One register of a control table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Register {
    /// Canonical snake_case name, e.g. `present_position`.
    pub name: &'static str,
    /// Address of its first byte.
    pub address: u8,
    /// Size in bytes (1 or 2).
    pub size: u8,
    /// Who may write it.
    pub access: Access,
    /// The direction bit of a sign-magnitude value, `None` for unsigned.
    pub sign_bit: Option<u8>,
    /// Raw content after a factory reset (for read-only registers: what a
    /// servo at rest reports; see the tables' notes on sources).
    pub factory: u16,
    /// Unit of the raw value, e.g. `steps/s`, `0.1 V`; empty when unitless.
    pub unit: &'static str,
    /// One line on what it does.
    pub description: &'static str,
}

impl Register {
    /// The address just past the register.
    pub const fn end(&self) -> u16 {
        self.address as u16 + self.size as u16
    }

    /// Whether `address` is one of the register's bytes.
    pub const fn contains(&self, address: u8) -> bool {
        address >= self.address && (address as u16) < self.end()
    }

    /// Whether the register shares a byte with `[address, address + len)`.
    pub const fn overlaps(&self, address: u8, len: usize) -> bool {
        (self.address as usize) < address as usize + len && (address as usize) < self.end() as usize
    }

    /// Whether values are sign-magnitude.
    pub const fn is_signed(&self) -> bool {
        self.sign_bit.is_some()
    }

    /// The smallest and largest values the register holds.
    pub const fn range(&self) -> (i32, i32) {
        match self.sign_bit {
            Some(bit) => {
                let max = (1i32 << bit) - 1;
                (-max, max)
            }
            None => (0, ((1u32 << (8 * self.size as u32)) - 1) as i32),
        }
    }

    /// The value of the register's raw (unsigned, already byte-ordered)
    /// content.
    pub const fn from_raw(&self, raw: u32) -> i32 {
        match self.sign_bit {
            Some(bit) => sign_magnitude(raw, bit),
            None => raw as i32,
        }
    }

    /// The raw content that holds `value`.
    ///
    /// # Errors
    /// [`ValueError::OutOfRange`] when `value` does not fit.
    pub const fn to_raw(&self, value: i32) -> Result<u32, ValueError> {
        let (min, max) = self.range();
        if value < min || value > max {
            return Err(ValueError::OutOfRange {
                register: self.name,
                value,
                min,
                max,
            });
        }
        Ok(match self.sign_bit {
            Some(bit) => to_sign_magnitude(value, bit),
            None => value as u32,
        })
    }

    /// Decodes the register's bytes (exactly [`Register::size`] of them) as a
    /// value.
    ///
    /// # Errors
    /// [`ValueError::Length`] when `bytes` is not the register's size.
    pub fn decode(&self, bytes: &[u8], order: ByteOrder) -> Result<i32, ValueError> {
        if bytes.len() != usize::from(self.size) {
            return Err(self.length_error(bytes.len()));
        }
        Ok(self.from_raw(read_uint(bytes, order)))
    }

    /// Encodes `value` into `out` (exactly [`Register::size`] bytes).
    ///
    /// # Errors
    /// [`ValueError::OutOfRange`] when `value` does not fit, or
    /// [`ValueError::Length`] when `out` is not the register's size.
    pub fn encode(&self, value: i32, order: ByteOrder, out: &mut [u8]) -> Result<(), ValueError> {
        if out.len() != usize::from(self.size) {
            return Err(self.length_error(out.len()));
        }
        let raw = self.to_raw(value)?;
        write_uint(raw, order, out);
        Ok(())
    }

    const fn length_error(&self, actual: usize) -> ValueError {
        ValueError::Length {
            register: self.name,
            expected: self.size as usize,
            actual,
        }
    }
}

/// Decodes a sign-magnitude value whose direction bit is `sign_bit`. Bits
/// above the sign bit are ignored (see the [module docs](self)).
///
/// ```
/// use servobus_protocol::registers::sign_magnitude;
/// assert_eq!(sign_magnitude(0x0400 | 25, 10), -25);
/// assert_eq!(sign_magnitude(25, 10), 25);
/// ```
pub const fn sign_magnitude(raw: u32, sign_bit: u8) -> i32 {
    let bit = if sign_bit > 30 { 30 } else { sign_bit };
    let magnitude = (raw & ((1u32 << bit) - 1)) as i32;
    if raw & (1u32 << bit) != 0 {
        -magnitude
    } else {
        magnitude
    }
}

/// Encodes `value` in sign-magnitude form with direction bit `sign_bit`;
/// a magnitude too large for the bits below the sign saturates.
///
/// ```
/// use servobus_protocol::registers::to_sign_magnitude;
/// assert_eq!(to_sign_magnitude(-5, 15), 0x8005);
/// assert_eq!(to_sign_magnitude(5000, 11), 2047);
/// ```
pub const fn to_sign_magnitude(value: i32, sign_bit: u8) -> u32 {
    let bit = if sign_bit > 30 { 30 } else { sign_bit };
    let max = (1u32 << bit) - 1;
    let magnitude = if value.unsigned_abs() > max {
        max
    } else {
        value.unsigned_abs()
    };
    if value < 0 {
        (1u32 << bit) | magnitude
    } else {
        magnitude
    }
}

/// Reads an unsigned integer of up to four bytes in `order`.
pub fn read_uint(bytes: &[u8], order: ByteOrder) -> u32 {
    let fold = |acc: u32, &b: &u8| (acc << 8) | u32::from(b);
    match order {
        ByteOrder::Big => bytes.iter().take(4).fold(0, fold),
        ByteOrder::Little => bytes.iter().take(4).rev().fold(0, fold),
    }
}

/// Writes the low `out.len()` bytes of `value` in `order`.
pub fn write_uint(value: u32, order: ByteOrder, out: &mut [u8]) {
    let n = out.len();
    for (i, b) in out.iter_mut().enumerate() {
        let shift = match order {
            ByteOrder::Little => 8 * i,
            ByteOrder::Big => 8 * (n - 1 - i),
        };
        *b = if shift < 32 {
            (value >> shift) as u8
        } else {
            0
        };
    }
}

/// The control table of one series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RegisterMap {
    /// The series it describes.
    pub series: Series,
    /// Byte order of its multi-byte registers.
    pub byte_order: ByteOrder,
    /// Address of the EEPROM lock register (55 on STS/SMS, 48 on SCS).
    pub lock_address: u8,
    /// Every register, sorted by address.
    pub registers: &'static [Register],
}

impl RegisterMap {
    /// The register called `name`, forgiving of case and of `_`, `-` and
    /// space separators (`present_position`, `Present_Position`,
    /// `PresentPosition` and `present position` are the same), and of a few
    /// aliases other tools use (`homing_offset`, `goal_velocity`,
    /// `present_velocity`, `operating_mode`, `return_delay_time`, ...).
    pub fn get(&self, name: &str) -> Option<&'static Register> {
        let canonical = tables::ALIASES
            .iter()
            .find(|(alias, _)| same_name(alias, name))
            .map_or(name, |(_, canonical)| canonical);
        self.registers.iter().find(|r| same_name(r.name, canonical))
    }

    /// The register that starts at `address`.
    pub fn at(&self, address: u8) -> Option<&'static Register> {
        self.registers.iter().find(|r| r.address == address)
    }

    /// The register that `address` is a byte of.
    pub fn containing(&self, address: u8) -> Option<&'static Register> {
        self.registers.iter().find(|r| r.contains(address))
    }

    /// Bytes of the memory table: up to the end of the last register.
    pub fn table_len(&self) -> usize {
        self.registers.last().map_or(0, |r| usize::from(r.end()))
    }

    /// The registers sharing at least one byte with `[address, address + len)`,
    /// in address order.
    pub fn covering(
        &self,
        address: u8,
        len: usize,
    ) -> impl Iterator<Item = &'static Register> + Clone {
        self.registers
            .iter()
            .filter(move |r| r.overlaps(address, len))
    }
}

/// Compares register names ignoring ASCII case and `_`, `-`, space.
fn same_name(a: &str, b: &str) -> bool {
    let mut x = a
        .bytes()
        .filter(|b| !matches!(b, b'_' | b'-' | b' '))
        .map(|b| b.to_ascii_lowercase());
    let mut y = b
        .bytes()
        .filter(|b| !matches!(b, b'_' | b'-' | b' '))
        .map(|b| b.to_ascii_lowercase());
    loop {
        match (x.next(), y.next()) {
            (None, None) => return true,
            (Some(p), Some(q)) if p == q => {}
            _ => return false,
        }
    }
}
