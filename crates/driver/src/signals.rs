//! Holding SIGINT, SIGTERM and SIGHUP while a servo's EEPROM is open.
//!
//! An EEPROM transaction (unlock, write, verify, lock) cut in the middle
//! leaves a servo with its lock open, or with a new `min_angle_limit` and
//! the old `max_angle_limit`. Only SIGKILL and power loss may do that: the
//! signals a user or a service manager sends to stop a program are held
//! for the length of the transaction, then acted on as the program would
//! have acted on them (a process with default dispositions ends; a Ctrl-C
//! handler, Python's included, runs).
//!
//! | while a [`SignalHold`] lives                         | when the last one ends                       |
//! |------------------------------------------------------|----------------------------------------------|
//! | SIGINT, SIGTERM, SIGHUP are blocked in its thread     | the thread's signal mask is restored         |
//! | a handler that only records them is installed         | the program's own dispositions are restored  |
//! | a second (third, ...) signal is recorded, not acted on| each signal recorded is raised once, in order|
//!
//! Blocking them in the holding thread keeps a serial read of the
//! transaction from being cut short with `EINTR`; the recording handler
//! catches those delivered to other threads. The handler only stores into
//! an atomic, so it is async-signal-safe. Holds nest and may be taken by
//! several threads at once: the program's dispositions come back when the
//! last one ends.
//!
//! [`SignalHold::new`] is what [`Bus::write_eeprom`](crate::Bus::write_eeprom)
//! and [`Bus::write_eeprom_all`](crate::Bus::write_eeprom_all) take around
//! each servo's transaction; a program that writes several servos as one
//! step can hold its own around them.
//!
//! A program that must say what it did when it is stopped (a command
//! writing six servos) also calls [`catch_stop_signals`]: the signals then
//! only set a flag, [`stop_signal`], which the library's multi-servo writes
//! (a calibration stored in the servos, the doctor's fixes) read between
//! two servos, ending there with what was done. The program reports it and
//! exits.
//!
//! On platforms without POSIX signals a hold does nothing and no signal is
//! caught.

/// The signals held: interrupt (Ctrl-C), terminate (`kill`, systemd),
/// hang-up (a closed terminal).
#[cfg(unix)]
const HELD: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

/// While it lives, SIGINT, SIGTERM and SIGHUP are held (see the [module
/// documentation](self)); dropping it acts on those that came.
///
/// It is not `Send`: the signal mask it restores is its thread's.
#[derive(Debug)]
#[must_use = "the signals are held only while the hold lives"]
pub struct SignalHold {
    #[cfg(unix)]
    mask: imp::Mask,
    _not_send: std::marker::PhantomData<*const ()>,
}

impl SignalHold {
    /// Holds SIGINT, SIGTERM and SIGHUP until the hold is dropped.
    pub fn new() -> SignalHold {
        SignalHold {
            #[cfg(unix)]
            mask: imp::enter(),
            _not_send: std::marker::PhantomData,
        }
    }
}

impl Default for SignalHold {
    fn default() -> Self {
        SignalHold::new()
    }
}

impl Drop for SignalHold {
    fn drop(&mut self) {
        #[cfg(unix)]
        imp::leave(&self.mask);
    }
}

/// Whether one of the held signals arrived since the current holds began
/// (and so will be acted on when the last of them ends): a program that
/// writes several servos asks this between two of them. Outside a hold,
/// whether one waits blocked by the program itself.
pub fn held_signal_pending() -> bool {
    #[cfg(unix)]
    {
        imp::pending()
    }
    #[cfg(not(unix))]
    {
        false
    }
}

/// A stop signal [`catch_stop_signals`] caught.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum StopSignal {
    /// SIGINT (Ctrl-C).
    Interrupt,
    /// SIGTERM (`kill`, a service manager).
    Terminate,
    /// SIGHUP (the terminal closed).
    HangUp,
}

impl StopSignal {
    /// Its name: `SIGINT`, `SIGTERM` or `SIGHUP`.
    pub fn name(self) -> &'static str {
        match self {
            StopSignal::Interrupt => "SIGINT",
            StopSignal::Terminate => "SIGTERM",
            StopSignal::HangUp => "SIGHUP",
        }
    }
}

impl std::fmt::Display for StopSignal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// From now on, SIGINT, SIGTERM and SIGHUP only set the flag
/// [`stop_signal`] reads: the program stops where it chooses, after
/// saying what it did. Call it once, before the work a signal must not cut
/// short without a report; a later call changes nothing.
///
/// # Errors
/// The OS error when a handler cannot be installed.
pub fn catch_stop_signals() -> std::io::Result<()> {
    #[cfg(unix)]
    {
        imp::catch()
    }
    #[cfg(not(unix))]
    {
        Ok(())
    }
}

/// The first stop signal caught since [`catch_stop_signals`], if any.
pub fn stop_signal() -> Option<StopSignal> {
    #[cfg(unix)]
    {
        imp::caught()
    }
    #[cfg(not(unix))]
    {
        None
    }
}

#[cfg(unix)]
mod imp {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Mutex, PoisonError};

    use super::HELD;

    /// A thread's signal mask, as it was before a hold.
    pub(super) struct Mask(libc::sigset_t);

    impl std::fmt::Debug for Mask {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("Mask")
        }
    }

    /// The holds alive in the process and the dispositions they replaced.
    struct State {
        depth: usize,
        saved: [Option<libc::sigaction>; 3],
    }

    // SAFETY: `sigaction` is plain data (a handler address, flags, a mask);
    // it is only read and written under the mutex.
    unsafe impl Send for State {}

    static STATE: Mutex<State> = Mutex::new(State {
        depth: 0,
        saved: [None, None, None],
    });

    /// Which held signal came (by its index in [`HELD`]) since the holds began.
    static RECEIVED: [AtomicBool; 3] = [
        AtomicBool::new(false),
        AtomicBool::new(false),
        AtomicBool::new(false),
    ];

    /// The recording handler: one atomic store, async-signal-safe.
    extern "C" fn record(signal: libc::c_int) {
        if let Some(i) = HELD.iter().position(|&s| s == signal) {
            RECEIVED[i].store(true, Ordering::SeqCst);
        }
    }

    fn held_set() -> libc::sigset_t {
        // SAFETY: a zeroed sigset_t is valid storage for sigemptyset, which
        // initialises it; sigaddset takes signal numbers that exist.
        unsafe {
            let mut set: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut set);
            for s in HELD {
                libc::sigaddset(&mut set, s);
            }
            set
        }
    }

    /// The first stop signal caught (its number), 0 for none.
    static CAUGHT: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(0);

    /// The catching handler: one atomic compare-and-swap, async-signal-safe.
    extern "C" fn stop(signal: libc::c_int) {
        let _ = CAUGHT.compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst);
    }

    /// Installs `handler` for `signal`, returning the disposition it replaced.
    fn install(
        signal: libc::c_int,
        handler: extern "C" fn(libc::c_int),
    ) -> Option<libc::sigaction> {
        // SAFETY: `action` is fully initialised (zeroed, then its handler,
        // flags and empty mask set); `old` is valid storage the call fills.
        // Both handlers only do atomic operations.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = handler as usize;
            action.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            let mut old: libc::sigaction = std::mem::zeroed();
            (libc::sigaction(signal, &action, &mut old) == 0).then_some(old)
        }
    }

    pub(super) fn catch() -> std::io::Result<()> {
        let mut state = STATE.lock().unwrap_or_else(PoisonError::into_inner);
        for (i, &signal) in HELD.iter().enumerate() {
            if state.depth > 0 {
                // Inside a hold: the disposition to come back to changes.
                if let Some(saved) = state.saved[i].as_mut() {
                    saved.sa_sigaction = stop as extern "C" fn(libc::c_int) as usize;
                    saved.sa_flags = libc::SA_RESTART;
                    continue;
                }
            }
            if install(signal, stop).is_none() {
                return Err(std::io::Error::last_os_error());
            }
        }
        Ok(())
    }

    pub(super) fn caught() -> Option<super::StopSignal> {
        match CAUGHT.load(Ordering::SeqCst) {
            libc::SIGINT => Some(super::StopSignal::Interrupt),
            libc::SIGTERM => Some(super::StopSignal::Terminate),
            libc::SIGHUP => Some(super::StopSignal::HangUp),
            _ => None,
        }
    }

    pub(super) fn pending() -> bool {
        if RECEIVED.iter().any(|r| r.load(Ordering::SeqCst)) {
            return true;
        }
        // Those blocked in a holding thread wait in the kernel instead.
        // SAFETY: `set` is valid storage that sigpending fills before
        // sigismember reads it.
        unsafe {
            let mut set: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut set);
            libc::sigpending(&mut set) == 0 && HELD.iter().any(|&s| libc::sigismember(&set, s) == 1)
        }
    }

    pub(super) fn enter() -> Mask {
        {
            let mut state = STATE.lock().unwrap_or_else(PoisonError::into_inner);
            if state.depth == 0 {
                for r in &RECEIVED {
                    r.store(false, Ordering::SeqCst);
                }
                for (i, &signal) in HELD.iter().enumerate() {
                    state.saved[i] = install(signal, record);
                }
            }
            state.depth += 1;
        }
        let set = held_set();
        // SAFETY: both pointers are valid sigset_t storage; `old` is
        // filled by the call before it is read.
        unsafe {
            let mut old: libc::sigset_t = std::mem::zeroed();
            libc::pthread_sigmask(libc::SIG_BLOCK, &set, &mut old);
            Mask(old)
        }
    }

    pub(super) fn leave(mask: &Mask) {
        let mut raise = [false; 3];
        {
            let mut state = STATE.lock().unwrap_or_else(PoisonError::into_inner);
            state.depth = state.depth.saturating_sub(1);
            if state.depth == 0 {
                for (i, &signal) in HELD.iter().enumerate() {
                    if let Some(old) = state.saved[i].take() {
                        // SAFETY: `old` is what sigaction returned for this
                        // signal: putting it back is always valid.
                        unsafe {
                            libc::sigaction(signal, &old, std::ptr::null_mut());
                        }
                    }
                    raise[i] = RECEIVED[i].swap(false, Ordering::SeqCst);
                }
            }
        }
        // Signals still pending in this thread reach the program's own
        // dispositions (or the recording handler, if another hold lives).
        // SAFETY: `mask.0` is the mask pthread_sigmask returned earlier.
        unsafe {
            libc::pthread_sigmask(libc::SIG_SETMASK, &mask.0, std::ptr::null_mut());
        }
        for (i, &signal) in HELD.iter().enumerate() {
            if raise[i] {
                // SAFETY: raising a signal has no memory-safety
                // preconditions; the program's disposition decides.
                unsafe {
                    libc::raise(signal);
                }
            }
        }
    }
}

#[cfg(all(test, unix))]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;

    use super::{held_signal_pending, SignalHold};

    /// The tests of this module change the process's signal dispositions:
    /// one at a time. No other test of this binary takes a hold.
    static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

    static HUPS: AtomicUsize = AtomicUsize::new(0);

    extern "C" fn count(_: libc::c_int) {
        HUPS.fetch_add(1, Ordering::SeqCst);
    }

    /// Installs [`count`] for SIGHUP: the program's own handler.
    fn program_handler() {
        // SAFETY: `action` is fully initialised; the handler does one
        // atomic add.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = count as extern "C" fn(libc::c_int) as usize;
            libc::sigemptyset(&mut action.sa_mask);
            assert_eq!(
                libc::sigaction(libc::SIGHUP, &action, std::ptr::null_mut()),
                0
            );
        }
    }

    fn hang_up() {
        // SAFETY: no memory is involved; the disposition is ours.
        assert_eq!(unsafe { libc::raise(libc::SIGHUP) }, 0);
    }

    #[test]
    fn a_signal_in_a_hold_is_acted_on_once_the_hold_ends() {
        let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
        program_handler();
        HUPS.store(0, Ordering::SeqCst);
        let hold = SignalHold::new();
        assert!(!held_signal_pending());
        hang_up();
        hang_up(); // a second one does not cut it either
        assert_eq!(HUPS.load(Ordering::SeqCst), 0);
        assert!(held_signal_pending());
        drop(hold);
        // Standard signals do not queue: the program hears one hang-up.
        assert_eq!(HUPS.load(Ordering::SeqCst), 1);
        assert!(!held_signal_pending());
        // After the hold the program's handler is its own again.
        hang_up();
        assert_eq!(HUPS.load(Ordering::SeqCst), 2);
    }

    #[test]
    fn nested_holds_act_when_the_outer_one_ends() {
        let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
        program_handler();
        HUPS.store(0, Ordering::SeqCst);
        let outer = SignalHold::new();
        let inner = SignalHold::new();
        hang_up();
        drop(inner);
        assert_eq!(HUPS.load(Ordering::SeqCst), 0);
        assert!(held_signal_pending());
        drop(outer);
        assert_eq!(HUPS.load(Ordering::SeqCst), 1);
    }

    #[test]
    fn a_signal_another_thread_receives_is_recorded_and_raised() {
        let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
        program_handler();
        HUPS.store(0, Ordering::SeqCst);
        // A thread started before the hold does not block the signal: the
        // recording handler runs there.
        let (go, wait) = std::sync::mpsc::channel::<()>();
        let other = std::thread::spawn(move || {
            if wait.recv().is_ok() {
                hang_up();
            }
        });
        let hold = SignalHold::new();
        go.send(()).expect("the thread waits");
        other.join().expect("the thread");
        assert_eq!(HUPS.load(Ordering::SeqCst), 0);
        assert!(held_signal_pending());
        drop(hold);
        assert_eq!(HUPS.load(Ordering::SeqCst), 1);
    }

    #[test]
    fn a_caught_signal_in_a_hold_is_seen_once_the_hold_ends() {
        let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
        let hold = SignalHold::new();
        // Caught from inside a hold: the disposition it comes back to.
        super::catch_stop_signals().expect("handlers installed");
        hang_up();
        assert_eq!(super::stop_signal(), None);
        drop(hold);
        assert_eq!(super::stop_signal(), Some(super::StopSignal::HangUp));
        assert_eq!(super::StopSignal::HangUp.to_string(), "SIGHUP");
    }
}
