//! The status level (register 8): which instructions a servo answers.

use super::Series;

/// Which instructions a servo answers: its status level (register 8).
///
/// STS/SMS servos: 0 answers PING and READ only, 1 answers everything.
/// SCS servos (SCS0009): 0 answers PING only, 1 PING and READ, 2 everything.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum StatusLevel {
    /// Only PING is answered.
    PingOnly,
    /// PING, READ and SYNC READ are answered; writes are not.
    PingAndRead,
    /// Every instruction addressed to one servo is answered (the factory
    /// setting).
    #[default]
    All,
}

impl StatusLevel {
    /// The level of a servo of `series` whose register 8 holds `value`.
    pub const fn from_register(series: Series, value: u8) -> StatusLevel {
        match series {
            Series::Sts => StatusLevel::from_sts(value),
            Series::Scs => StatusLevel::from_scs(value),
        }
    }

    /// The level of an STS/SMS servo whose register 8 holds `value`.
    pub const fn from_sts(value: u8) -> StatusLevel {
        if value == 0 {
            StatusLevel::PingAndRead
        } else {
            StatusLevel::All
        }
    }

    /// The level of an SCS servo whose register 8 holds `value`.
    pub const fn from_scs(value: u8) -> StatusLevel {
        match value {
            0 => StatusLevel::PingOnly,
            1 => StatusLevel::PingAndRead,
            _ => StatusLevel::All,
        }
    }

    /// Whether READ and SYNC READ are answered.
    pub const fn answers_reads(self) -> bool {
        !matches!(self, StatusLevel::PingOnly)
    }

    /// Whether WRITE, REG WRITE, ACTION and RESET are answered.
    pub const fn answers_writes(self) -> bool {
        matches!(self, StatusLevel::All)
    }
}
