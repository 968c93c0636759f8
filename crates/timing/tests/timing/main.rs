//! The timing integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

mod no_alloc;
mod pack_props;
mod worked_examples;
