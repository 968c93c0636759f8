//! The sim integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

#[path = "../common/mod.rs"]
mod common;

mod body;
mod bus;
mod dynamics;
mod instructions;
mod link_served;
mod model;
mod object;
mod pty;
