//! Instruction codes and the status (error) byte.

use core::fmt;

/// An instruction a host sends to one servo or to all of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Instruction {
    /// Query the servo's working state; answered even when broadcast.
    Ping = 0x01,
    /// Read `L` bytes of the memory table from an address.
    Read = 0x02,
    /// Write bytes into the memory table; they take effect at once.
    Write = 0x03,
    /// Write bytes that take effect only when ACTION arrives.
    RegWrite = 0x04,
    /// Execute the data held by an earlier REG WRITE.
    Action = 0x05,
    /// Reset the memory table to factory values.
    Reset = 0x06,
    /// Read the same block from several servos; each answers in list order
    /// (STS/SMS series only).
    SyncRead = 0x82,
    /// Write a block of the same address and length to several servos at once.
    SyncWrite = 0x83,
}

impl Instruction {
    /// Every instruction, in code order.
    pub const ALL: [Instruction; 8] = [
        Instruction::Ping,
        Instruction::Read,
        Instruction::Write,
        Instruction::RegWrite,
        Instruction::Action,
        Instruction::Reset,
        Instruction::SyncRead,
        Instruction::SyncWrite,
    ];

    /// The instruction with wire code `code`, if there is one.
    pub const fn from_code(code: u8) -> Option<Instruction> {
        Some(match code {
            0x01 => Instruction::Ping,
            0x02 => Instruction::Read,
            0x03 => Instruction::Write,
            0x04 => Instruction::RegWrite,
            0x05 => Instruction::Action,
            0x06 => Instruction::Reset,
            0x82 => Instruction::SyncRead,
            0x83 => Instruction::SyncWrite,
            _ => return None,
        })
    }

    /// The wire code of the instruction.
    #[inline]
    pub const fn code(self) -> u8 {
        self as u8
    }
}

named! {
    /// The name used by the manual, e.g. `SYNC WRITE`.
    Instruction {
        Ping => "PING",
        Read => "READ",
        Write => "WRITE",
        RegWrite => "REG WRITE",
        Action => "ACTION",
        Reset => "RESET",
        SyncRead => "SYNC READ",
        SyncWrite => "SYNC WRITE",
    }
}

/// The error byte of a status packet (and register 65 of STS servos), with
/// Feetech's meanings. Bits without a known meaning are kept, never dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct StatusFlags(pub u8);

impl StatusFlags {
    /// Bit 0: input voltage out of range.
    pub const VOLTAGE: u8 = 0x01;
    /// Bit 1: angle (magnetic) sensor error.
    pub const ANGLE_SENSOR: u8 = 0x02;
    /// Bit 2: overheat.
    pub const OVERHEAT: u8 = 0x04;
    /// Bit 3: over-current.
    pub const OVERCURRENT: u8 = 0x08;
    /// Bit 5: overload.
    pub const OVERLOAD: u8 = 0x20;
    /// Every bit with a documented meaning.
    pub const KNOWN: u8 =
        Self::VOLTAGE | Self::ANGLE_SENSOR | Self::OVERHEAT | Self::OVERCURRENT | Self::OVERLOAD;

    /// Each known flag's bit and its one name, in bit order: what
    /// [`StatusFlags::names`] and `Display` print, and what every other
    /// place that names a flag should take.
    pub const NAMES: [(u8, &'static str); 5] = [
        (Self::VOLTAGE, "voltage"),
        (Self::ANGLE_SENSOR, "angle sensor"),
        (Self::OVERHEAT, "overheat"),
        (Self::OVERCURRENT, "over-current"),
        (Self::OVERLOAD, "overload"),
    ];

    /// The raw byte.
    #[inline]
    pub const fn bits(self) -> u8 {
        self.0
    }
    /// No flag set: the servo reports no error.
    #[inline]
    pub const fn is_ok(self) -> bool {
        self.0 == 0
    }
    /// Whether every bit of `mask` is set.
    #[inline]
    pub const fn contains(self, mask: u8) -> bool {
        self.0 & mask == mask && mask != 0
    }
    /// Input voltage out of range.
    pub const fn voltage(self) -> bool {
        self.contains(Self::VOLTAGE)
    }
    /// Angle sensor error.
    pub const fn angle_sensor(self) -> bool {
        self.contains(Self::ANGLE_SENSOR)
    }
    /// Overheat.
    pub const fn overheat(self) -> bool {
        self.contains(Self::OVERHEAT)
    }
    /// Over-current.
    pub const fn overcurrent(self) -> bool {
        self.contains(Self::OVERCURRENT)
    }
    /// Overload.
    pub const fn overload(self) -> bool {
        self.contains(Self::OVERLOAD)
    }
    /// Bits set that have no documented meaning (bits 4, 6 and 7).
    pub const fn unknown_bits(self) -> u8 {
        self.0 & !Self::KNOWN
    }
    /// The names of the known flags that are set, in bit order.
    pub fn names(self) -> impl Iterator<Item = &'static str> {
        Self::NAMES
            .into_iter()
            .filter(move |(mask, _)| self.0 & mask != 0)
            .map(|(_, name)| name)
    }
}

impl fmt::Display for StatusFlags {
    /// `ok`, or the flag names joined by `+`, with unknown bits in hex.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_ok() {
            return f.write_str("ok");
        }
        let mut first = true;
        for name in self.names() {
            if !first {
                f.write_str("+")?;
            }
            f.write_str(name)?;
            first = false;
        }
        if self.unknown_bits() != 0 {
            if !first {
                f.write_str("+")?;
            }
            write!(f, "unknown(0x{:02X})", self.unknown_bits())?;
        }
        Ok(())
    }
}
