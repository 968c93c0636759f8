//! The driver integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

mod no_alloc;
mod queued_write;
mod soak;
mod typed;
