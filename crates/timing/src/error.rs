//! Why a cycle could not be planned.

use core::time::Duration;

use crate::{Block, Change};

/// Why [`plan`](crate::plan) found no plan.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CycleError {
    /// The bus has no servos.
    #[error("the bus has no servos")]
    NoServos,
    /// More servos than there are IDs.
    #[error("{count} servos on one bus: at most 254 (IDs 0..=253)")]
    TooManyServos {
        /// Servos given.
        count: usize,
    },
    /// A servo's ID is outside 0..=253.
    #[error("servo ID {id} is not valid (0..=253)")]
    InvalidId {
        /// The ID.
        id: u8,
    },
    /// Two servos share an ID.
    #[error("servo ID {id} appears twice on the bus")]
    DuplicateId {
        /// The ID.
        id: u8,
    },
    /// The rate is not a positive finite number of hertz.
    #[error("invalid rate {rate_hz} Hz: it must be positive and finite")]
    InvalidRate {
        /// The rate given.
        rate_hz: f64,
    },
    /// A block is empty, runs past address 255, or is longer than a frame
    /// can carry (250 bytes written, 253 read).
    #[error("invalid block of {} bytes at address {}", .block.len, .block.address)]
    InvalidBlock {
        /// The block.
        block: Block,
    },
    /// Not even a cycle reading one servo fits the rate.
    #[error(
        "{rate_hz} Hz cannot be met: even the shortest cycle (all goals, one servo read) takes {} us; to fit the full cycle, {fix}",
        .min_cycle_time.as_micros()
    )]
    Infeasible {
        /// The rate asked for.
        rate_hz: f64,
        /// The shortest cycle possible (all servos written, one read).
        min_cycle_time: Duration,
        /// The cheapest change that makes the full cycle fit.
        fix: Change,
    },
}
