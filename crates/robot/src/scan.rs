//! Finding servos on a port: every ID at one or more baud rates of the
//! servo table, each servo found identified (model, firmware, position,
//! voltage, temperature), two servos sharing an ID told apart from
//! silence, and a slow adapter caught before it hides anyone.
//!
//! Nothing here prints: a slower adapter than assumed is data
//! ([`Scan::slow`]), for the program to show as it likes.

use std::time::Duration;

use servobus_driver::{Bus, BusError, Transport};
use servobus_protocol::registers::{self, addr, Model, Series};
use servobus_protocol::{BROADCAST_ID, MAX_ID};

/// The longest latency any adapter is waited for while measuring it (an
/// FTDI latency timer goes up to 255 ms).
pub const LATENCY_CEILING: Duration = Duration::from_millis(300);
/// PINGs an adapter's latency is measured with: few enough to stay quick,
/// enough that one lucky reply does not set the figure.
pub const LATENCY_PINGS: u32 = 3;
/// How long a broadcast PING waits for the first byte of an answer, and
/// then for the line to fall quiet: longer than the gaps between servos
/// answering one after another at the lowest rate, and than the usual
/// 16 ms latency timer of a USB adapter, which hands bytes over in bursts.
pub const BROADCAST_LISTEN: Duration = Duration::from_millis(40);
/// The measured latency's worst case is allowed this many times over in
/// the deadlines: room for the spikes a USB adapter shows now and then.
pub const LATENCY_HEADROOM: u32 = 2;

/// What a scan found about one servo.
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// Its ID.
    pub id: u8,
    /// The baud rate it answered at.
    pub baud: u32,
    /// Its model, when the model number is one servobus knows.
    pub model: Option<&'static Model>,
    /// The model number read (little-endian when no model has it).
    pub model_number: u16,
    /// Firmware version, major and minor.
    pub firmware: (u8, u8),
    /// Present position, ticks (`None` when it could not be read).
    pub position: Option<i32>,
    /// Supply voltage, V.
    pub voltage_v: Option<f64>,
    /// Temperature, degrees Celsius.
    pub temperature_c: Option<u8>,
}

impl Found {
    /// A servo that answered PING but not the reads that identify it.
    fn unknown(id: u8, baud: u32) -> Found {
        Found {
            id,
            baud,
            model: None,
            model_number: 0,
            firmware: (0, 0),
            position: None,
            voltage_v: None,
            temperature_c: None,
        }
    }
}

/// An adapter slower than the scan assumed: the silent IDs were asked
/// again with deadlines that fit it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlowLink {
    /// The adapter's typical latency, measured.
    pub measured: Duration,
    /// The latency the scan had assumed.
    pub assumed: Duration,
}

/// What a scan found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scan {
    /// The servos that answered, by baud rate then ID.
    pub found: Vec<Found>,
    /// IDs (and baud rates) whose replies collided: two servos or more
    /// probably share the ID.
    pub collisions: Vec<(u8, u32)>,
    /// Set when the adapter turned out slower than assumed.
    pub slow: Option<SlowLink>,
}

/// Why a scan stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScanError {
    /// The port could not be moved to a baud rate.
    #[error("cannot set the port to {baud} baud")]
    Baud {
        /// The rate.
        baud: u32,
        /// The bus's error.
        #[source]
        source: BusError,
    },
    /// The bus failed otherwise than by a silent or garbled reply.
    #[error("scan stopped at ID {id}")]
    Stopped {
        /// The ID asked.
        id: u8,
        /// The bus's error.
        #[source]
        source: BusError,
    },
}

/// Every baud rate of the servos' baud table, fastest first.
pub fn table_bauds() -> Vec<u32> {
    (0..8).filter_map(registers::baud_rate).collect()
}

/// Measures the adapter's latency with servo `id` and widens the bus's
/// deadlines to [`LATENCY_HEADROOM`] times it when the assumed latency is
/// too short (for tools that work on one servo and can afford the PINGs).
///
/// # Errors
/// The bus's, when the servo does not answer.
pub fn adapt_latency<T: Transport>(bus: &mut Bus<T>, id: u8) -> Result<(), BusError> {
    let m = bus.measure_latency(id, LATENCY_PINGS, LATENCY_CEILING)?;
    if m.max * LATENCY_HEADROOM > bus.settings().link.latency {
        bus.set_latency(m.max * LATENCY_HEADROOM);
    }
    Ok(())
}

/// Identifies servo `id` (firmware, model, position, voltage, temperature)
/// and switches the bus to its series.
///
/// # Errors
/// The bus's, when the servo does not answer the first read.
pub fn identify<T: Transport>(bus: &mut Bus<T>, id: u8) -> Result<Found, BusError> {
    let mut head = [0u8; 5];
    bus.read(id, addr::FIRMWARE_MAJOR, &mut head)?;
    let number = [head[3], head[4]];
    let model = registers::model_by_register(number);
    let model_number = model.map_or(u16::from_le_bytes(number), |m| m.number);
    let series = model.map_or(Series::Sts, |m| m.series);
    let mut settings = *bus.settings();
    settings.series = series;
    bus.set_settings(settings);
    let mut state = [0u8; 8];
    let (position, voltage_v, temperature_c) =
        match bus.read(id, addr::PRESENT_POSITION, &mut state) {
            Ok(_) => {
                let pos = series
                    .map()
                    .at(addr::PRESENT_POSITION)
                    .and_then(|r| r.decode(&state[..2], series.byte_order()).ok());
                (pos, Some(f64::from(state[6]) / 10.0), Some(state[7]))
            }
            Err(e) if e.is_retryable() && !matches!(e, BusError::Corrupt { .. }) => {
                (None, None, None)
            }
            Err(e) => return Err(e),
        };
    Ok(Found {
        id,
        baud: bus.baud(),
        model,
        model_number,
        firmware: (head[0], head[1]),
        position,
        voltage_v,
        temperature_c,
    })
}

/// Asks every ID at each of `bauds` in turn (through [`Bus::set_baud`]),
/// absent IDs once: that is what makes a scan fast. With more than one
/// rate, each is first asked with one broadcast PING
/// ([`Bus::anyone_answers`]), and the IDs are asked only at the rates where
/// someone answered it; when nobody answered at any rate, every ID is asked
/// at every rate all the same (a servo deaf to the broadcast, or an adapter
/// slower than [`BROADCAST_LISTEN`], is still found). When `learn_latency`,
/// the adapter's latency is then measured on the first servo found and,
/// when it is above what the bus assumed, the silent IDs at that servo's
/// rate are asked again with deadlines that fit ([`Scan::slow`]).
///
/// # Errors
/// [`ScanError::Baud`] when the port cannot take a rate;
/// [`ScanError::Stopped`] when the bus fails otherwise than by a silent or
/// garbled reply.
pub fn scan<T: Transport>(
    bus: &mut Bus<T>,
    bauds: &[u32],
    learn_latency: bool,
) -> Result<Scan, ScanError> {
    let mut out = Scan::default();
    let mut asked = Vec::with_capacity(bauds.len());
    if bauds.len() > 1 {
        for &baud in bauds {
            switch_baud(bus, baud)?;
            let heard =
                bus.anyone_answers(BROADCAST_LISTEN)
                    .map_err(|source| ScanError::Stopped {
                        id: BROADCAST_ID,
                        source,
                    })?;
            if heard {
                asked.push(baud);
            }
        }
    }
    if asked.is_empty() {
        asked.extend_from_slice(bauds);
    }
    for &baud in &asked {
        switch_baud(bus, baud)?;
        let first = out.found.len();
        let mut late = LateReplies::new(bus);
        for id in 0..=MAX_ID {
            let result = ask_past_garbles(bus, id, baud);
            if let Err(BusError::WrongId { actual, .. }) = &result {
                late.note(*actual);
            }
            out.sort(result, (id, baud))?;
        }
        // A servo whose reply came late (a loaded machine) answered: it is
        // asked again, with retries, a few rounds at most.
        for _ in 0..LATE_ROUNDS {
            let again = late.take(bus, &out, baud)?;
            if again.is_empty() {
                break;
            }
            for id in again {
                let result = ask(bus, id, baud, LATE_RETRIES);
                out.sort(result, (id, baud))?;
            }
        }
        if let Some(at_baud) = out.found.get_mut(first..) {
            at_baud.sort_by_key(|f| f.id);
        }
    }
    if learn_latency {
        if let Some(first) = out.found.first().map(|f| (f.id, f.baud)) {
            rescan_if_slow(bus, first, &mut out)?;
        }
    }
    Ok(out)
}

/// Rounds of asking again the IDs whose replies came late.
const LATE_ROUNDS: usize = 3;
/// Retries of the PING to an ID whose reply came late.
const LATE_RETRIES: u8 = 2;
/// How long the end of a pass waits for replies still on their way.
const LATE_WAIT: Duration = Duration::from_millis(5);

/// The IDs whose replies came after their deadlines during a pass: in the
/// next ID's turn ([`BusError::WrongId`]), or counted by the bus as it
/// drained the line before the next request.
struct LateReplies {
    /// Each ID's late-reply count when the pass began.
    seen: Vec<u64>,
    /// IDs whose replies came in another ID's turn.
    wrong_turn: Vec<u8>,
}

impl LateReplies {
    fn new<T: Transport>(bus: &Bus<T>) -> LateReplies {
        LateReplies {
            seen: (0..=MAX_ID)
                .map(|id| bus.servo_counters(id).late_replies)
                .collect(),
            wrong_turn: Vec::new(),
        }
    }

    fn note(&mut self, id: u8) {
        if !self.wrong_turn.contains(&id) {
            self.wrong_turn.push(id);
        }
    }

    /// The late IDs not yet found at `baud`, after waiting for replies still
    /// on their way; each is returned once per late reply.
    fn take<T: Transport>(
        &mut self,
        bus: &mut Bus<T>,
        out: &Scan,
        baud: u32,
    ) -> Result<Vec<u8>, ScanError> {
        bus.await_late_replies(LATE_WAIT)
            .map_err(|source| ScanError::Stopped {
                id: BROADCAST_ID,
                source,
            })?;
        let mut ids = std::mem::take(&mut self.wrong_turn);
        for id in 0..=MAX_ID {
            let now = bus.servo_counters(id).late_replies;
            if let Some(seen) = self.seen.get_mut(usize::from(id)) {
                if now > *seen {
                    *seen = now;
                    if !ids.contains(&id) {
                        ids.push(id);
                    }
                }
            }
        }
        ids.retain(|&id| !out.knows(id, baud));
        ids.sort_unstable();
        Ok(ids)
    }
}

/// How many times an ID whose reply came garbled is asked in all before
/// the scan calls it a collision.
pub const COLLISION_ASKS: usize = 3;

/// Whether an answer came garbled: a corrupt frame, or one of the wrong
/// length (two servos answering at once garble each other's replies).
fn garbled(result: &Result<Found, BusError>) -> bool {
    matches!(
        result,
        Err(BusError::Corrupt { .. } | BusError::WrongLength { .. })
    )
}

/// [`ask`], and when the answer came garbled, asks again: two servos sharing
/// an ID garble each other every time, noise on the line (a reply cut by
/// a simulator just starting, a loose cable) now and then. Of at most
/// [`COLLISION_ASKS`] asks, a majority garbled is a collision (the garbled
/// answer is returned); otherwise the answer of the last clean ask is.
fn ask_past_garbles<T: Transport>(bus: &mut Bus<T>, id: u8, baud: u32) -> Result<Found, BusError> {
    let first = ask(bus, id, baud, 0);
    if !garbled(&first) {
        return first;
    }
    let need = COLLISION_ASKS / 2 + 1;
    let (mut garbles, mut cleans) = (1, 0);
    let mut last_clean = None;
    while garbles < need && cleans < need {
        let again = ask(bus, id, baud, 0);
        if garbled(&again) {
            garbles += 1;
        } else {
            cleans += 1;
            last_clean = Some(again);
        }
    }
    match last_clean {
        Some(clean) if cleans >= need => clean,
        _ => first,
    }
}

/// Asks servo `id` at `baud` (an absent ID once, with `retries` 0: that is
/// what makes a scan fast) and, when it answers, what it is.
fn ask<T: Transport>(bus: &mut Bus<T>, id: u8, baud: u32, retries: u8) -> Result<Found, BusError> {
    let mut s = *bus.settings();
    s.series = Series::Sts;
    s.retries = retries;
    bus.set_settings(s);
    let answered = bus.ping(id);
    bus.set_settings(s.with_retries(1));
    match answered {
        Ok(_) => match identify(bus, id) {
            Err(e) if e.is_timeout() => Ok(Found::unknown(id, baud)),
            other => other,
        },
        Err(e) => Err(e),
    }
}

impl Scan {
    /// Files what asking servo `id` at `baud` gave: a servo found, a
    /// collision, or silence; any other error ends the scan.
    fn sort(
        &mut self,
        result: Result<Found, BusError>,
        (id, baud): (u8, u32),
    ) -> Result<(), ScanError> {
        match result {
            Ok(f) => self.found.push(f),
            // Two servos answering at once garble each other's replies.
            Err(BusError::Corrupt { .. } | BusError::WrongLength { .. }) => {
                self.collisions.push((id, baud));
            }
            Err(BusError::Timeout { .. } | BusError::WrongId { .. }) => {}
            Err(source) => return Err(ScanError::Stopped { id, source }),
        }
        Ok(())
    }

    fn knows(&self, id: u8, baud: u32) -> bool {
        self.found.iter().any(|f| f.id == id && f.baud == baud)
            || self.collisions.contains(&(id, baud))
    }
}

/// Moves the port and the bus's deadlines to `baud`.
fn switch_baud<T: Transport>(bus: &mut Bus<T>, baud: u32) -> Result<(), ScanError> {
    bus.set_baud(baud)
        .map_err(|source| ScanError::Baud { baud, source })
}

/// Measures the latency on servo `first` and, when it exceeds the one the
/// scan assumed, asks every silent ID again at that baud rate.
fn rescan_if_slow<T: Transport>(
    bus: &mut Bus<T>,
    (first, baud): (u8, u32),
    out: &mut Scan,
) -> Result<(), ScanError> {
    let assumed = bus.settings().link.latency;
    switch_baud(bus, baud)?;
    let Ok(m) = bus.measure_latency(first, LATENCY_PINGS, LATENCY_CEILING) else {
        return Ok(());
    };
    // Occasional spikes are what retries are for; a typical latency above
    // the assumed one means the first pass could not hear anyone.
    if m.mean <= assumed {
        return Ok(());
    }
    out.slow = Some(SlowLink {
        measured: m.mean,
        assumed,
    });
    bus.set_latency(m.max * LATENCY_HEADROOM);
    for id in 0..=MAX_ID {
        if out.knows(id, baud) {
            continue;
        }
        let mut s = *bus.settings();
        s.series = Series::Sts;
        s.retries = 1;
        bus.set_settings(s);
        let result = bus.ping(id).and_then(|_| identify(bus, id));
        out.sort(result, (id, baud))?;
    }
    out.found.sort_by_key(|f| (f.baud, f.id));
    Ok(())
}
