//! What several commands share: the range-checked argument parsers
//! ([`args`]), the exit codes and error messages ([`exit`]), stdout that
//! reports a closed pipe instead of panicking ([`out`]), JSON output
//! ([`json`]), opening a robot's ports ([`ports`]), the end-of-run report,
//! Ctrl-C during a run, a calibration refusal said with its remedy, and
//! the live views' terminal. `src/cmd/` holds one module per command and
//! no command imports another; what two of them need lives here.

pub(crate) mod args;
pub(crate) mod ctrl_c;
pub(crate) mod exit;
pub(crate) mod flags;
pub(crate) mod json;
pub(crate) mod os_error;
pub(crate) mod out;
pub(crate) mod ports;
pub(crate) mod refusal;
pub(crate) mod report;
pub(crate) mod screen;

pub(crate) use ctrl_c::install_ctrl_c;
pub(crate) use refusal::{check_bus, check_buses, refused};
pub(crate) use report::write_report;
