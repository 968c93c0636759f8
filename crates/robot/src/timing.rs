//! The serial bus's baud budget: what one control cycle costs on the wire
//! ([`Plan`], [`Link`]), the fastest rate a bus can hold
//! ([`floor_rate_hz`]), the changes that make a cycle fit ([`Change`]),
//! and the byte counts of the SYNC instructions ([`sync_write_bytes`],
//! [`Block`]).

pub use servobus_timing::{floor_rate_hz, sync_write_bytes, Block, Change, Link, Plan};
