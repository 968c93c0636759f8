//! Register blocks: a start address and a length, the unit of every SYNC
//! WRITE, SYNC READ and READ a cycle does.

use servobus_protocol::registers::{sts, Register};

/// A contiguous block of `len` bytes of the memory table starting at
/// `address`: what a cycle writes to, or reads from, every servo.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Block {
    /// The first register address.
    pub address: u8,
    /// The number of bytes (at least 1).
    pub len: u8,
}

impl Block {
    /// The block of `len` bytes at `address`.
    pub const fn new(address: u8, len: u8) -> Block {
        Block { address, len }
    }

    /// The registers `first..=last` (in address order) as one block.
    pub const fn span(first: &Register, last: &Register) -> Block {
        Block::new(first.address, (last.end() - first.address as u16) as u8)
    }

    /// Goal position only (2 bytes at 42): the smallest goal block.
    pub const GOAL_POSITION: Block =
        Block::span(sts::GOAL_POSITION.register(), sts::GOAL_POSITION.register());
    /// Goal position, goal time and goal speed (6 bytes at 42), as in the
    /// manual's SYNC WRITE examples.
    pub const POSITION_TIME_SPEED: Block =
        Block::span(sts::GOAL_POSITION.register(), sts::GOAL_SPEED.register());
    /// Acceleration, goal position, goal time and goal speed (7 bytes at 41).
    pub const ACCEL_POSITION_TIME_SPEED: Block =
        Block::span(sts::ACCELERATION.register(), sts::GOAL_SPEED.register());

    /// Present position only (2 bytes at 56): the smallest feedback block.
    pub const PRESENT_POSITION: Block = Block::span(
        sts::PRESENT_POSITION.register(),
        sts::PRESENT_POSITION.register(),
    );
    /// Position, speed, load, voltage, temperature, async flag, status,
    /// moving and current (15 bytes, 56..=70): the whole feedback block.
    pub const FEEDBACK: Block = Block::span(
        sts::PRESENT_POSITION.register(),
        sts::PRESENT_CURRENT.register(),
    );

    /// Bytes per servo in a SYNC WRITE frame: the ID, then the block.
    pub const fn sync_write_stride(&self) -> usize {
        1 + self.len as usize
    }

    /// Whether the block stays inside the 256-byte memory table and is not
    /// empty.
    pub const fn is_valid(&self) -> bool {
        self.len > 0 && self.address as usize + self.len as usize <= 256
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_blocks_match_the_control_table() {
        // Goal position 42 (2), goal time 44 (2), goal speed 46 (2) end at 48.
        assert_eq!(
            Block::POSITION_TIME_SPEED.address + Block::POSITION_TIME_SPEED.len,
            48
        );
        // Acceleration 41 (1) precedes them.
        assert_eq!(
            Block::ACCEL_POSITION_TIME_SPEED.address + Block::ACCEL_POSITION_TIME_SPEED.len,
            48
        );
        // Present current 69 (2) ends the feedback block at 70 inclusive.
        assert_eq!(Block::FEEDBACK.address + Block::FEEDBACK.len, 71);
        assert!(Block::FEEDBACK.is_valid());
        assert!(!Block::new(1, 0).is_valid());
        assert!(Block::new(255, 1).is_valid());
        assert!(!Block::new(255, 2).is_valid());
    }
}
