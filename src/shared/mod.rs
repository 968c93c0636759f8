//! What several commands share: the end-of-run report, Ctrl-C during a
//! run, a calibration refusal said with its remedy, and the live views'
//! terminal. No command imports
//! another command; what two of them need lives here.

pub(crate) mod ctrl_c;
pub(crate) mod refusal;
pub(crate) mod report;
pub(crate) mod screen;

pub(crate) use ctrl_c::install_ctrl_c;
pub(crate) use refusal::{check_bus, check_buses, refused};
pub(crate) use report::write_report;
