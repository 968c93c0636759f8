//! Instruction packets read back as typed commands: what a servo (or the
//! simulator, or `servobus decode`) makes of a packet a host sent.

use crate::{Instruction, Packet};

/// The meaning of an instruction packet, borrowing its parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command<'a> {
    /// PING: report the working state.
    Ping,
    /// READ `len` bytes from `address`.
    Read {
        /// First address.
        address: u8,
        /// Bytes to read.
        len: u8,
    },
    /// WRITE `data` at `address`, effective at once.
    Write {
        /// First address.
        address: u8,
        /// Bytes to write.
        data: &'a [u8],
    },
    /// REG WRITE `data` at `address`, held until ACTION.
    RegWrite {
        /// First address.
        address: u8,
        /// Bytes to write.
        data: &'a [u8],
    },
    /// ACTION: apply held REG WRITE data.
    Action,
    /// RESET the memory table to factory values.
    Reset,
    /// SYNC READ `len` bytes at `address` from each of `ids`, in order.
    SyncRead {
        /// First address.
        address: u8,
        /// Bytes each servo answers with.
        len: u8,
        /// The servos asked, in answer order.
        ids: &'a [u8],
    },
    /// SYNC WRITE one block per servo.
    SyncWrite(SyncWrite<'a>),
}

/// The body of a SYNC WRITE: `len` bytes at `address` for each servo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncWrite<'a> {
    /// First address of every block.
    pub address: u8,
    /// Bytes per servo (L), at least 1.
    pub len: u8,
    /// `(id, block)` records back to back, each `len + 1` bytes; a whole
    /// number of them, at least one.
    records: &'a [u8],
}

impl<'a> SyncWrite<'a> {
    /// Number of servos addressed.
    pub fn servos(&self) -> usize {
        self.records.len() / (usize::from(self.len) + 1)
    }

    /// Each servo's ID and data block, in frame order.
    pub fn blocks(&self) -> impl ExactSizeIterator<Item = (u8, &'a [u8])> + Clone + 'a {
        self.records
            .chunks_exact(usize::from(self.len) + 1)
            .map(|r| (r[0], &r[1..]))
    }

    /// The data block for servo `id`, if the frame has one.
    pub fn block_for(&self, id: u8) -> Option<&'a [u8]> {
        self.blocks().find(|(i, _)| *i == id).map(|(_, d)| d)
    }
}

/// Why an instruction packet has no valid meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CommandError {
    /// The fifth byte is not a known instruction code.
    #[error("unknown instruction code 0x{0:02X}")]
    UnknownInstruction(u8),
    /// The parameters do not have a shape the instruction allows.
    #[error("{instruction} cannot have {len} parameter byte(s): {why}")]
    BadParams {
        /// The instruction.
        instruction: Instruction,
        /// The number of parameter bytes the packet has.
        len: usize,
        /// What the instruction needs.
        why: &'static str,
    },
}

impl<'a> Command<'a> {
    /// The instruction of this command.
    pub const fn instruction(&self) -> Instruction {
        match self {
            Command::Ping => Instruction::Ping,
            Command::Read { .. } => Instruction::Read,
            Command::Write { .. } => Instruction::Write,
            Command::RegWrite { .. } => Instruction::RegWrite,
            Command::Action => Instruction::Action,
            Command::Reset => Instruction::Reset,
            Command::SyncRead { .. } => Instruction::SyncRead,
            Command::SyncWrite(_) => Instruction::SyncWrite,
        }
    }

    /// The memory range `(address, len)` the command reads or writes, if any.
    pub fn span(&self) -> Option<(u8, usize)> {
        match self {
            Command::Read { address, len } | Command::SyncRead { address, len, .. } => {
                Some((*address, usize::from(*len)))
            }
            Command::Write { address, data } | Command::RegWrite { address, data } => {
                Some((*address, data.len()))
            }
            Command::SyncWrite(s) => Some((s.address, usize::from(s.len))),
            Command::Ping | Command::Action | Command::Reset => None,
        }
    }

    /// Interprets the parameters of `packet` as its instruction's.
    ///
    /// # Errors
    /// [`CommandError::UnknownInstruction`] for an unknown code, or
    /// [`CommandError::BadParams`] when the parameters do not fit it (for
    /// example a READ without exactly 2 parameters, or a SYNC WRITE whose
    /// records do not divide evenly).
    pub fn parse(packet: &Packet<'a>) -> Result<Command<'a>, CommandError> {
        let code = packet.code();
        let instruction =
            Instruction::from_code(code).ok_or(CommandError::UnknownInstruction(code))?;
        let p = packet.params();
        let bad = |why| {
            Err(CommandError::BadParams {
                instruction,
                len: p.len(),
                why,
            })
        };
        match instruction {
            Instruction::Ping | Instruction::Action | Instruction::Reset if !p.is_empty() => {
                bad("no parameters")
            }
            Instruction::Ping => Ok(Command::Ping),
            Instruction::Action => Ok(Command::Action),
            Instruction::Reset => Ok(Command::Reset),
            Instruction::Read => match *p {
                [address, len] => Ok(Command::Read { address, len }),
                _ => bad("an address and a length"),
            },
            Instruction::Write | Instruction::RegWrite => match *p {
                [address, ref data @ ..] if !data.is_empty() => {
                    Ok(if instruction == Instruction::Write {
                        Command::Write { address, data }
                    } else {
                        Command::RegWrite { address, data }
                    })
                }
                _ => bad("an address and at least one data byte"),
            },
            Instruction::SyncRead => match *p {
                [address, len, ref ids @ ..] if !ids.is_empty() => {
                    Ok(Command::SyncRead { address, len, ids })
                }
                _ => bad("an address, a length and at least one ID"),
            },
            Instruction::SyncWrite => match *p {
                [address, len, ref records @ ..]
                    if len > 0
                        && !records.is_empty()
                        && records.len() % (usize::from(len) + 1) == 0 =>
                {
                    Ok(Command::SyncWrite(SyncWrite {
                        address,
                        len,
                        records,
                    }))
                }
                _ => bad("an address, a length L >= 1 and whole records of L + 1 bytes"),
            },
        }
    }
}

impl<'a> Packet<'a> {
    /// The packet read as an instruction: see [`Command::parse`].
    ///
    /// # Errors
    /// As [`Command::parse`].
    pub fn command(&self) -> Result<Command<'a>, CommandError> {
        Command::parse(self)
    }
}
