//! SYNC WRITE and SYNC READ: one request for many servos, results per servo.
//!
//! A SYNC READ never fails as a whole because one servo did not answer: each
//! servo gets its own outcome, the answers that came are kept, and the
//! missing ones say why. Replies are matched to servos by ID only (a reply
//! from an ID not asked, or a second reply from one that already answered,
//! is counted and dropped), so no data is ever attributed to the wrong servo.
//!
//! Results live in storage owned by the bus and reused from call to call;
//! [`SyncRead`] borrows it.

mod read;
mod results;
mod write;

pub use read::{PATIENCE, PATIENT_TRIES};
pub(crate) use results::SyncStore;
pub use results::{Missing, MissingReason, SyncRead, SyncReply};
