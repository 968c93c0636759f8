//! The terminal of the live views (`monitor`, `play --monitor`): whether
//! there is one, taking it over and giving it back, and the keys read on
//! it; and the view of a running motion from its telemetry.

use std::io::IsTerminal;
use std::time::Duration;

use crossbeam_channel::TryRecvError;
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use servobus::monitor::{view, Frame, TelemetryRows};
use servobus_config::{Robot, Units};
use servobus_robot::{Command, Telemetry};

/// How often `play --monitor` redraws.
const PLAY_REFRESH_HZ: f64 = 20.0;

/// Whether the live view can run: standard output is a terminal, and keys
/// can be read from one (standard input, or the controlling terminal
/// `/dev/tty`, as the terminal library reads them). Not under cron, CI,
/// `ssh` without `-t`, or with the output redirected.
pub(crate) fn terminal_available() -> bool {
    std::io::stdout().is_terminal()
        && (std::io::stdin().is_terminal()
            || std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open("/dev/tty")
                .is_ok())
}

/// `play --monitor` without a terminal: refused before anything moves.
///
/// # Errors
/// An input error (exit 2) when [`terminal_available`] is false.
pub(crate) fn check_play_terminal() -> anyhow::Result<()> {
    if terminal_available() {
        return Ok(());
    }
    Err(crate::shared::exit::input(
        "--monitor needs a terminal (stdin and stdout must be one) and there is none; \
         nothing was moved. Play without --monitor (progress lines), or run `servobus \
         monitor --json` beside it",
    ))
}

/// Restores the terminal when dropped (the view ends, an error returns);
/// ratatui's panic hook restores it on a panic too.
pub(crate) struct Screen(pub(crate) ratatui::DefaultTerminal);

impl Screen {
    /// Takes the terminal (raw mode, alternate screen).
    ///
    /// # Errors
    /// When the terminal refuses; it is left as it was.
    pub(crate) fn open() -> anyhow::Result<Screen> {
        match ratatui::try_init() {
            Ok(terminal) => Ok(Screen(terminal)),
            Err(e) => {
                ratatui::restore();
                Err(anyhow::Error::new(e).context("cannot take over the terminal"))
            }
        }
    }
}

impl Drop for Screen {
    fn drop(&mut self) {
        // While unwinding, ratatui's panic hook has restored the terminal
        // already; leaving the alternate screen twice would move the cursor
        // back over the panic message.
        if !std::thread::panicking() {
            ratatui::restore();
        }
    }
}

/// Makes the monitor panic after this many refreshes: how
/// `scripts/monitor_tmux.sh` shows that a panic restores the terminal.
pub(crate) const TEST_PANIC: &str = "SERVOBUS_MONITOR_TEST_PANIC";

pub(crate) fn test_panic_after() -> Option<u64> {
    std::env::var(TEST_PANIC).ok()?.parse().ok()
}

/// What a key asks for.
pub(crate) enum Key {
    Quit,
    TorqueOff,
    Other,
}

/// Waits up to `timeout` for a key.
pub(crate) fn key(timeout: Duration) -> anyhow::Result<Option<Key>> {
    if !event::poll(timeout)? {
        return Ok(None);
    }
    let Event::Key(k) = event::read()? else {
        return Ok(Some(Key::Other));
    };
    if k.kind != KeyEventKind::Press {
        return Ok(Some(Key::Other));
    }
    Ok(Some(match k.code {
        KeyCode::Char('q') | KeyCode::Esc => Key::Quit,
        KeyCode::Char('c') if k.modifiers.contains(KeyModifiers::CONTROL) => Key::Quit,
        KeyCode::Char(' ') => Key::TorqueOff,
        _ => Key::Other,
    }))
}

/// `servobus play --monitor`: the monitor's view of a running motion, from
/// its telemetry only. `q` stops the motion (jerk-limited) and Space turns
/// the torque off; the view ends with the run.
pub fn watch_run(
    runner: &servobus_robot::Run,
    robot: &Robot,
    units: Units,
    rate_hz: f64,
) -> anyhow::Result<()> {
    let shown =
        Screen::open().and_then(|mut screen| show_run(&mut screen, runner, robot, units, rate_hz));
    if shown.is_err() {
        // The terminal failed (refused, or gone mid-run): stop the motion
        // (jerk-limited) rather than let it run on unwatched; the caller
        // joins the run and reports.
        let _ = runner.send(Command::Stop);
    }
    shown
}

/// The view of [`watch_run`] on `screen`, until the run ends.
fn show_run(
    screen: &mut Screen,
    runner: &servobus_robot::Run,
    robot: &Robot,
    units: Units,
    rate_hz: f64,
) -> anyhow::Result<()> {
    let mut rows = TelemetryRows::new(robot, units, 1.0 / rate_hz);
    let telemetry = runner.telemetry();
    let period = Duration::from_secs_f64(1.0 / PLAY_REFRESH_HZ);
    let mut note: Option<String> = None;
    let title = format!("{} (play)", robot.name);
    loop {
        let mut ended = false;
        loop {
            match telemetry.try_recv() {
                Ok(Telemetry::Cycle(sample)) => rows.record(&sample),
                Ok(Telemetry::Fault(fault)) => note = Some(format!("fault: {fault}")),
                Ok(Telemetry::Finished(_)) => ended = true,
                Ok(_) => {}
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    ended = true;
                    break;
                }
            }
        }
        let frame: Frame = rows.frame(note.clone());
        screen.0.draw(|f| view::draw(f, &frame, &title))?;
        if ended || (runner.is_finished() && telemetry.is_empty()) {
            return Ok(());
        }
        match key(period)? {
            Some(Key::Quit) => {
                let _ = runner.send(Command::Stop);
                note = Some("stopping".into());
            }
            Some(Key::TorqueOff) => {
                let _ = runner.send(Command::TorqueOff);
                note = Some("torque OFF".into());
            }
            _ => {}
        }
    }
}
