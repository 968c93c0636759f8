//! The trajectory integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

#[path = "../common/mod.rs"]
mod common;

mod alloc;
mod choreography;
mod golden;
mod properties;
mod ruckig;
mod timed;
mod track;
mod track_walk;
