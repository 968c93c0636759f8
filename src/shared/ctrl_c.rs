//! Ctrl-C during a run, as every command that runs one takes it.

use std::sync::atomic::{AtomicU32, Ordering};

use servobus_robot::{Command, CommandSender};

use crate::shared::out::errln;

/// Ctrl-C once: a jerk-limited stop, then hold and report. Twice: torque off.
/// `commands` is the run's
/// ([`Run::commands`](servobus_robot::Run::commands)).
pub(crate) fn install_ctrl_c(commands: CommandSender) {
    let seen = AtomicU32::new(0);
    let installed = ctrlc::set_handler(move || {
        let n = seen.fetch_add(1, Ordering::SeqCst);
        let command = if n == 0 {
            errln!("\nstopping (jerk-limited), then holding; Ctrl-C again turns the torque off");
            Command::Stop
        } else {
            errln!("\ntorque off");
            Command::TorqueOff
        };
        // The run may have ended already; nothing else to do then.
        let _ = commands.try_send(command);
    });
    if let Err(e) = installed {
        // Tests and embedders may have a handler already; playing still works.
        errln!("warning: Ctrl-C handling unavailable ({e})");
    }
}
