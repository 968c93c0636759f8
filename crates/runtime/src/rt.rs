//! Real-time set-up of the calling thread: core pinning and SCHED_FIFO, and
//! on Linux always the smallest timer slack (1 ns), so that the pacer's
//! sleeps wake when asked instead of up to 50 us later.
//!
//! All are best effort: where the operating system refuses (no permission,
//! no such core) the thread runs on with normal scheduling and the reason is
//! returned as a warning, never as a failure.

/// What to ask of the operating system for the control thread.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RtOptions {
    /// Pin the thread to this core.
    pub core: Option<usize>,
    /// Run the thread under SCHED_FIFO with this priority (1..=99).
    pub fifo_priority: Option<i32>,
}

/// What [`apply`] achieved; `warnings` says what it could not do and why.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RtReport {
    /// The core the thread is pinned to.
    pub pinned: Option<usize>,
    /// The SCHED_FIFO priority in effect.
    pub fifo_priority: Option<i32>,
    /// The thread's timer slack was lowered to 1 ns.
    pub low_timer_slack: bool,
    /// One line per option that could not be applied.
    pub warnings: Vec<String>,
}

/// Applies `options` to the calling thread. Call it once, when the control
/// thread starts, before its loop.
pub fn apply(options: RtOptions) -> RtReport {
    let mut report = RtReport {
        low_timer_slack: set_low_timer_slack(),
        ..RtReport::default()
    };
    if let Some(core) = options.core {
        let ids = core_affinity::get_core_ids().unwrap_or_default();
        match ids.into_iter().find(|c| c.id == core) {
            Some(id) if core_affinity::set_for_current(id) => report.pinned = Some(core),
            Some(_) => report
                .warnings
                .push(format!("could not pin the control thread to core {core}")),
            None => report.warnings.push(format!(
                "core {core} does not exist; the control thread is not pinned"
            )),
        }
    }
    if let Some(priority) = options.fifo_priority {
        match set_fifo(priority) {
            Ok(()) => report.fifo_priority = Some(priority),
            Err(why) => report.warnings.push(format!(
                "SCHED_FIFO priority {priority} not applied ({why}); running with normal scheduling"
            )),
        }
    }
    report
}

#[cfg(target_os = "linux")]
fn set_fifo(priority: i32) -> std::io::Result<()> {
    let param = libc::sched_param {
        sched_priority: priority.clamp(1, 99),
    };
    // SAFETY: `param` is a valid, initialised sched_param that outlives the
    // call; pid 0 means the calling thread.
    let rc = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
    if rc == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// Lowers the calling thread's timer slack to 1 ns (Linux; the default is
/// 50 us, which the kernel may add to every sleep of a normal thread).
#[cfg(target_os = "linux")]
fn set_low_timer_slack() -> bool {
    // SAFETY: PR_SET_TIMERSLACK takes one integer argument and only affects
    // the calling thread.
    unsafe { libc::prctl(libc::PR_SET_TIMERSLACK, 1 as libc::c_ulong) == 0 }
}

#[cfg(not(target_os = "linux"))]
fn set_low_timer_slack() -> bool {
    false
}

#[cfg(not(target_os = "linux"))]
fn set_fifo(_priority: i32) -> std::io::Result<()> {
    Err(std::io::Error::new(
        std::io::ErrorKind::Unsupported,
        "SCHED_FIFO is only supported on Linux",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn impossible_requests_warn_instead_of_failing() {
        let report = apply(RtOptions {
            core: Some(100_000),
            fifo_priority: None,
        });
        assert_eq!(report.pinned, None);
        assert_eq!(report.warnings.len(), 1);
        assert!(report.warnings[0].contains("core 100000"));
        let plain = apply(RtOptions::default());
        assert!(plain.warnings.is_empty());
        assert_eq!((plain.pinned, plain.fifo_priority), (None, None));
        assert_eq!(plain.low_timer_slack, cfg!(target_os = "linux"));
    }
}
