//! The request/reply engine under [`Bus`](crate::Bus): send a frame, then
//! feed what comes back through the streaming decoder until a sink is
//! satisfied or the deadline passes.
//!
//! Invariants kept here, for every transaction kind:
//! - input is drained (transport and decoder) before each request, so a late
//!   reply to an earlier request cannot be taken for the current one;
//! - on a port that may echo, one frame identical to the current request
//!   (a half-duplex echo) and any frame identical to the previous one (a
//!   late echo, while one can still come) are never handed to the sink as
//!   a reply, nor is any frame with the broadcast ID (only the host sends
//!   those); once the port is known not to echo, a frame identical to the
//!   request is its reply (a PING answered with status 0x01 is);
//! - whether the port echoes is learned from what comes back (see
//!   [`PortEcho`]): an echo is recognised only where it cannot be a reply,
//!   so a missing servo behind an echoing adapter is never answered by its
//!   own request;
//! - every byte received is accounted for: in a reply, an echo, or the
//!   discarded count.

use std::time::Duration;

use servobus_protocol::{
    parse_frame, Decoder, Event, Instruction, Packet, BROADCAST_ID, MAX_FRAME_LEN,
};

use servobus_timing::Link;

use crate::{Bus, Clock, Transport, TransportError};

/// Receives what the engine finds while waiting.
pub(crate) trait Sink {
    /// A valid frame that is neither an echo nor a host frame. Returns `true`
    /// when the wait is over.
    fn packet(&mut self, packet: &Packet<'_>, now: Duration) -> bool;
    /// A complete frame with a bad checksum; `id` is its (untrusted) ID byte.
    fn checksum_error(&mut self, id: u8);
}

/// What one wait saw, besides what the sink took.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Tally {
    /// Whether the sink declared the wait over before the deadline.
    pub done: bool,
    pub echoes: u64,
    /// Every byte discarded, stale input included.
    pub discarded_bytes: u64,
    /// Bytes discarded that arrived during this wait and were not merely
    /// cut off by the deadline (garbled replies).
    pub garbage_bytes: u64,
    /// Bytes of a frame still incomplete at the deadline (a late reply).
    pub truncated_bytes: u64,
    pub checksum_errors: u64,
    /// Whether a copy of the request was skipped as its echo on a port not
    /// yet known to echo, where the copy could have been the reply itself
    /// (a PING answered with status 0x01): whether it was cannot be told
    /// from this wait.
    pub ambiguous_copy: bool,
    /// When the last copy of the request taken for its echo arrived.
    pub copy_at: Option<Duration>,
}

/// How many replies in a row must come with no echo before them for the
/// port to be taken as one that does not echo. An echoing adapter echoes
/// every request before any reply can come, so one echo lost to noise does
/// not make it look silent; three in a row without one does.
pub(crate) const SILENT_AFTER: u8 = 3;

/// What the bus knows about whether its port echoes requests back.
///
/// Learned from the traffic: a copy of a request that cannot be its own
/// reply (a WRITE, a READ of other than 2 bytes, anything to the broadcast
/// ID), or a copy followed by the reply, shows an echo; [`SILENT_AFTER`]
/// replies in a row with no copy of the request before them show none. A
/// copy of a request that could be its reply (a PING; a servo with status
/// 0x01 answers it with its own bytes) shows nothing either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PortEcho {
    /// `Some(true)`: the port echoes; `Some(false)`: it does not; `None`:
    /// not known yet.
    pub known: Option<bool>,
    /// Replies in a row that came with no echo before them, while unknown.
    silent_replies: u8,
}

impl PortEcho {
    /// Nothing known.
    pub const UNKNOWN: PortEcho = PortEcho {
        known: None,
        silent_replies: 0,
    };

    /// Known not to echo.
    pub const SILENT: PortEcho = PortEcho {
        known: Some(false),
        silent_replies: 0,
    };

    /// Takes in what one wait showed: `Some(true)` an echo, `Some(false)` a
    /// reply with no echo before it.
    fn learn(&mut self, shown: Option<bool>) {
        match shown {
            Some(true) => {
                *self = PortEcho {
                    known: Some(true),
                    silent_replies: 0,
                }
            }
            Some(false) if self.known.is_none() => {
                self.silent_replies = self.silent_replies.saturating_add(1);
                if self.silent_replies >= SILENT_AFTER {
                    self.known = Some(false);
                }
            }
            _ => {}
        }
    }
}

/// Whether a copy of `request` could be its own reply, byte for byte: a
/// status frame carries the servo's ID, the flags where the request has its
/// instruction, and as many parameters as the instruction returns. A PING
/// (no parameters) is answered by a status frame of the same size; so is a
/// READ of 2 bytes, or an ACTION or RESET. A WRITE (parameters, none in the
/// reply), any other READ and anything to the broadcast ID (no servo sends
/// that ID) cannot be. A frame that cannot be parsed, or an instruction
/// whose reply is not known, could.
fn may_be_own_reply(request: &[u8]) -> bool {
    let Ok((packet, _)) = parse_frame(request) else {
        return true;
    };
    if packet.is_broadcast() {
        return false;
    }
    let params = packet.params();
    let reply_params = match packet.instruction() {
        Some(Instruction::Read) => params.get(1).map(|&n| usize::from(n)),
        Some(
            Instruction::Ping
            | Instruction::Write
            | Instruction::RegWrite
            | Instruction::Action
            | Instruction::Reset,
        ) => Some(0),
        _ => None,
    };
    match reply_params {
        Some(n) => n == params.len(),
        None => true,
    }
}

/// Transport, clock, decoder and the reused frame buffers.
pub(crate) struct Io<T> {
    pub transport: T,
    decoder: Decoder,
    /// The request being sent: `tx[..tx_len]`.
    pub tx: [u8; MAX_FRAME_LEN],
    pub tx_len: usize,
    /// The request sent before it, kept to recognise a late echo.
    prev: [u8; MAX_FRAME_LEN],
    prev_len: usize,
    rx: [u8; 256],
    /// Whether the adapter may echo requests (see `BusSettings::echo`):
    /// off, nothing is taken for an echo and nothing is learned.
    pub echo: bool,
    /// Whether this port echoes, as far as it has shown.
    pub port_echo: PortEcho,
    /// How many times the current request was sent, and how many copies of
    /// it were taken for its echo: while fewer were seen than sent, a late
    /// echo of it may still come once it is the previous request.
    sends: u32,
    echoes_seen: u32,
    /// Whether a late echo of the previous request may still come.
    prev_echo_owed: bool,
    /// Decoder totals at the start of the current request.
    base_discarded: u64,
    base_echoes: u64,
    base_checksum: u64,
    /// Stale bytes dropped by the last `send`.
    stale: u64,
    /// When the last request sent has left the host's transmitter.
    line_free: Duration,
    /// Servos whose last reply was counted as a timeout and has not come
    /// since: a reply from one of them that arrives later is a late
    /// reply, not a lost one.
    overdue: [bool; 256],
    overdue_count: usize,
    /// Overdue servos whose one frame in a later read was taken as that
    /// read's answer, though it may have been the late reply: they stay
    /// overdue for one read more.
    doubtful: [bool; 256],
    /// Overdue servos whose reply arrived, for the bus to count.
    late: [u8; 256],
    pub late_len: usize,
}

impl<T: Transport> Io<T> {
    pub fn new(transport: T) -> Self {
        Io {
            transport,
            decoder: Decoder::new(),
            tx: [0; MAX_FRAME_LEN],
            tx_len: 0,
            prev: [0; MAX_FRAME_LEN],
            prev_len: 0,
            rx: [0; 256],
            echo: true,
            port_echo: PortEcho::UNKNOWN,
            sends: 0,
            echoes_seen: 0,
            prev_echo_owed: false,
            base_discarded: 0,
            base_echoes: 0,
            base_checksum: 0,
            stale: 0,
            line_free: Duration::ZERO,
            overdue: [false; 256],
            overdue_count: 0,
            doubtful: [false; 256],
            late: [0; 256],
            late_len: 0,
        }
    }

    /// Makes room for a new request: the current one becomes the previous.
    /// Encode into `self.tx` right after and set `tx_len`.
    pub fn begin(&mut self) {
        self.prev[..self.tx_len].copy_from_slice(&self.tx[..self.tx_len]);
        self.prev_len = self.tx_len;
        self.tx_len = 0;
        self.prev_echo_owed = self.echoes_seen < self.sends;
        self.sends = 0;
        self.echoes_seen = 0;
    }

    /// Whether a copy of the request may be the port's echo: the bus lets
    /// the adapter echo and this port is not known not to.
    pub fn may_echo(&self) -> bool {
        self.echo && self.port_echo.known != Some(false)
    }

    /// Drains input, then sends `tx[..tx_len]` on `wire`. Returns the time
    /// sending started, from which reply deadlines are measured: now, or when the
    /// request before it (one nobody answers, e.g. a SYNC WRITE) has left
    /// the transmitter. A write returns once the bytes are queued, so a
    /// SYNC READ sent right after a long SYNC WRITE starts on the wire only
    /// when the SYNC WRITE is through; measured from the write call, its
    /// deadline would be short by the rest of the SYNC WRITE.
    pub fn send(&mut self, wire: &Link) -> Result<Duration, TransportError> {
        // What arrived since the last wait is looked at before it is
        // dropped: a servo's late reply shows that it answered.
        let now = self.transport.clock().now();
        self.take_late(now)?;
        self.transport.discard_input()?;
        // Bytes pending in the decoder belong to an earlier exchange; they
        // count as discarded in this one, but not as garbage of its reply.
        self.stale = self.decoder.clear() as u64;
        let stats = self.decoder.stats();
        self.base_discarded = stats.discarded_bytes;
        self.base_echoes = stats.echoes;
        self.base_checksum = stats.checksum_errors;
        let before = self.next_start();
        self.transport.write_all(&self.tx[..self.tx_len])?;
        // A host descheduled before or during the write sends the request
        // late: the servo cannot answer before it has heard it, so the
        // deadline runs from when the bytes can have left, not from when the
        // thread meant to send them. A write returns once its bytes are
        // queued (or, on a transport that models the wire, once they are
        // through it): the request started no earlier than its return less its
        // wire time, and a prompt write keeps the earlier stamp.
        let wire_time = wire.wire_time(self.tx_len);
        let start = before.max(self.transport.clock().now().saturating_sub(wire_time));
        self.line_free = start + wire_time;
        self.sends = self.sends.saturating_add(1);
        if self.may_echo() {
            self.decoder.expect_echo(&self.tx[..self.tx_len]);
        }
        Ok(start)
    }

    /// Marks servo `id`'s reply as lost (counted as a timeout) until it
    /// comes.
    pub fn overdue(&mut self, id: u8) {
        self.doubtful[usize::from(id)] = false;
        let slot = &mut self.overdue[usize::from(id)];
        if !*slot {
            *slot = true;
            self.overdue_count += 1;
        }
    }

    /// Servo `id` answered in time: nothing of it is overdue.
    pub fn answered(&mut self, id: u8) {
        self.doubtful[usize::from(id)] = false;
        let slot = &mut self.overdue[usize::from(id)];
        if *slot {
            *slot = false;
            self.overdue_count -= 1;
        }
    }

    /// Overdue servo `id` sent one frame in a read, taken as its answer
    /// though it may have been its late reply to an earlier one: should
    /// the answer come after, it shows that. It stays overdue for one
    /// read more (a servo whose reply was really lost is then answered).
    pub fn answered_in_doubt(&mut self, id: u8) {
        let doubtful = &mut self.doubtful[usize::from(id)];
        if *doubtful {
            self.answered(id);
        } else {
            *doubtful = true;
        }
    }

    /// Which servos are overdue, by ID.
    pub fn overdue_flags(&self) -> [bool; 256] {
        self.overdue
    }

    /// Servo `id`'s late reply arrived: noted for the bus to count, if it
    /// was overdue.
    pub fn late_reply(&mut self, id: u8) {
        self.doubtful[usize::from(id)] = false;
        let slot = &mut self.overdue[usize::from(id)];
        if *slot {
            *slot = false;
            self.overdue_count -= 1;
            self.late[self.late_len] = id;
            self.late_len += 1;
        }
    }

    /// The overdue servos whose replies arrived, once each (see
    /// [`Io::take_late`]); the caller counts them, then clears `late_len`.
    pub fn late(&self) -> &[u8] {
        &self.late[..self.late_len]
    }

    /// Reads what arrives until `deadline` (what has arrived, for a
    /// deadline of now), or until no servo is overdue, and notes each
    /// overdue servo whose reply is in it ([`Io::late`]). The bytes are
    /// consumed: they belong to no request still waited for.
    ///
    /// # Errors
    /// Transport failures other than a timeout.
    pub fn take_late(&mut self, deadline: Duration) -> Result<(), TransportError> {
        while self.overdue_count > 0 {
            let n = match read_through_signals(&mut self.transport, &mut self.rx, deadline) {
                Ok(0) | Err(TransportError::TimedOut) => return Ok(()),
                Ok(n) => n,
                Err(e) => return Err(e),
            };
            // The IDs of the frames in it (at most one frame per 6 bytes).
            let mut ids = [0u8; 256];
            let mut found = 0;
            let mut input = &self.rx[..n.min(self.rx.len())];
            while let Some(ev) = self.decoder.decode(&mut input) {
                if let (Event::Packet { packet, .. }, Some(slot)) = (ev, ids.get_mut(found)) {
                    *slot = packet.id();
                    found += 1;
                }
            }
            for &id in &ids[..found] {
                self.late_reply(id);
            }
        }
        Ok(())
    }

    /// When the last request sent was through the host's transmitter: when
    /// the servos had heard the whole of it, and so when a servo answering
    /// it took what it reports (its present position, say). The wire model
    /// is all this rests on: a thread descheduled after the reply came
    /// does not move it.
    pub fn heard(&self) -> Duration {
        self.line_free
    }

    /// When a request sent now starts on the wire: now, or once the
    /// requests before it are through the transmitter.
    pub fn next_start(&self) -> Duration {
        self.transport.clock().now().max(self.line_free)
    }

    /// Feeds received bytes to `sink` until it is satisfied or `deadline`
    /// passes.
    ///
    /// # Errors
    /// Transport failures other than a timeout.
    pub fn exchange<S: Sink>(
        &mut self,
        deadline: Duration,
        sink: &mut S,
    ) -> Result<Tally, TransportError> {
        let mut tally = Tally::default();
        let may_echo = self.may_echo();
        let tx = &self.tx[..self.tx_len];
        let mut own = Own {
            tx,
            prev: &self.prev[..self.prev_len],
            // Without echo, no frame of ours is expected back: behave as if
            // the echo had already been skipped, and trust identical frames.
            echo_seen: !may_echo,
            prev_is_echo: may_echo && self.prev_echo_owed,
            learn: self.echo,
            tx_may_be_reply: None,
            copies: 0,
            shown: None,
        };
        'wait: loop {
            let n = match read_through_signals(&mut self.transport, &mut self.rx, deadline) {
                Ok(n) => n,
                Err(TransportError::TimedOut) => {
                    // Whatever is pending will not complete in time: give up
                    // on it, but still look for frames inside it. What is
                    // dropped here was cut off by the deadline (a late reply),
                    // not garbled.
                    let before = self.decoder.stats().discarded_bytes;
                    while let Some(ev) = self.decoder.finish() {
                        if own.handle(ev, self.transport.clock(), sink, &mut tally) {
                            break;
                        }
                    }
                    tally.truncated_bytes += self.decoder.stats().discarded_bytes - before;
                    break 'wait;
                }
                Err(e) => return Err(e),
            };
            let mut input = &self.rx[..n.min(self.rx.len())];
            while let Some(ev) = self.decoder.decode(&mut input) {
                if own.handle(ev, self.transport.clock(), sink, &mut tally) {
                    // Bytes after the awaited reply are not for us.
                    tally.discarded_bytes += input.len() as u64;
                    break 'wait;
                }
            }
        }
        self.echoes_seen = self.echoes_seen.saturating_add(own.copies);
        tally.ambiguous_copy = own.learn
            && own.copies > 0
            && own.tx_may_be_reply == Some(true)
            && own.shown.is_none()
            && self.port_echo.known.is_none();
        self.port_echo.learn(own.shown);
        let stats = self.decoder.stats();
        let window = stats.discarded_bytes - self.base_discarded;
        tally.garbage_bytes = window.saturating_sub(tally.truncated_bytes);
        tally.discarded_bytes += window + self.stale;
        self.stale = 0;
        tally.echoes += stats.echoes - self.base_echoes;
        tally.checksum_errors += stats.checksum_errors - self.base_checksum;
        self.base_discarded = stats.discarded_bytes;
        self.base_echoes = stats.echoes;
        self.base_checksum = stats.checksum_errors;
        Ok(tally)
    }
}

/// The frames this host sent last. On a port that may echo, one copy of
/// the current request is its echo; a second identical copy can only be a
/// reply that happens to have the same bytes (e.g. a PING answered with
/// status 0x01). It also notes what the wait shows about the port's echo.
struct Own<'a> {
    tx: &'a [u8],
    prev: &'a [u8],
    /// Whether the copy of `tx` taken for its echo has come (or none is
    /// expected).
    echo_seen: bool,
    /// Whether a copy of `prev` is a late echo.
    prev_is_echo: bool,
    /// Whether echo is looked for and learned at all (`BusSettings::echo`).
    learn: bool,
    /// Whether a copy of `tx` could be the reply to it ([`may_be_own_reply`]),
    /// once a copy came (see `Own::may_be_reply`).
    tx_may_be_reply: Option<bool>,
    /// Copies of `tx` taken for its echo in this wait.
    copies: u32,
    /// What this wait showed: `Some(true)` an echo, `Some(false)` the
    /// awaited reply with no copy of the request before it.
    shown: Option<bool>,
}

impl Own<'_> {
    /// Handles one decoder event; returns `true` when the sink is done.
    fn handle<C: Clock, S: Sink>(
        &mut self,
        ev: Event<'_>,
        clock: &C,
        sink: &mut S,
        tally: &mut Tally,
    ) -> bool {
        match ev {
            Event::Packet { packet, .. } => {
                let bytes = packet.bytes();
                let copy = bytes == self.tx;
                // The expected echo; or, on any port servobus looks for echo
                // on, a copy that cannot be a reply: an echo even on a port
                // taken for one that does not echo (it does, then).
                if copy && (!self.echo_seen || (self.learn && !self.may_be_reply())) {
                    self.echoed();
                    tally.copy_at = Some(clock.now());
                    tally.echoes += 1;
                    return false;
                }
                if (self.prev_is_echo && bytes == self.prev) || packet.id() == BROADCAST_ID {
                    tally.echoes += 1;
                    return false;
                }
                let done = sink.packet(&packet, clock.now());
                tally.done |= done;
                if done && self.learn && !copy {
                    // The reply, unlike the request: the copy before it was
                    // no reply but the echo; with none before it, the port
                    // did not echo this request.
                    if self.copies > 0 {
                        self.shown = Some(true);
                    } else {
                        self.shown.get_or_insert(false);
                    }
                }
                done
            }
            Event::ChecksumError { id, .. } => {
                sink.checksum_error(id);
                false
            }
            Event::Echo { .. } => {
                self.echoed();
                tally.copy_at = Some(clock.now());
                false
            }
            Event::Discarded { .. } => false,
        }
    }
}

impl Own<'_> {
    /// Whether a copy of `tx` could be its reply ([`may_be_own_reply`]),
    /// worked out at the first copy: most waits see none.
    fn may_be_reply(&mut self) -> bool {
        let tx = self.tx;
        *self
            .tx_may_be_reply
            .get_or_insert_with(|| may_be_own_reply(tx))
    }

    /// A copy of the request was taken for its echo: it shows the port
    /// echoes when it cannot have been the reply.
    fn echoed(&mut self) {
        self.echo_seen = true;
        self.copies = self.copies.saturating_add(1);
        if self.learn && !self.may_be_reply() {
            self.shown = Some(true);
        }
    }
}

impl<T: Transport> Bus<T> {
    /// Whether this bus's port echoes requests, as it has shown so far:
    /// `Some(true)` it does, `Some(false)` it does not, `None` not known yet
    /// (see [`BusSettings::echo`](crate::BusSettings::echo)). While it is
    /// not known, a frame identical to the request is skipped as its echo.
    pub fn port_echoes(&self) -> Option<bool> {
        self.io.port_echo.known
    }

    /// Tells the bus whether its port echoes (`Some`), or has it learn that
    /// again from the traffic (`None`). With echo on in its settings: told
    /// `Some(true)`, it skips one copy of each request for good; told `Some(false)`, it takes a frame
    /// identical to the request for the reply, until a copy of a request
    /// that cannot be a reply comes back (the port echoes after all). To
    /// take nothing for an echo whatever comes back, turn
    /// [`BusSettings::echo`](crate::BusSettings::echo) off.
    pub fn set_port_echoes(&mut self, echoes: Option<bool>) {
        self.io.port_echo = PortEcho {
            known: echoes,
            silent_replies: 0,
        };
    }
}

/// How many signals in a row one read sits through before it gives up: far
/// more than a person or a service manager sends, few enough that a signal
/// storm cannot keep a transaction waiting beyond its deadlines for long.
const INTERRUPTIONS: usize = 64;

/// [`Transport::read`], sitting through signals: a read cut short by one
/// (`EINTR`: a serial port's poll is never restarted, whatever the
/// handler's flags) waits again until the same deadline. Without this a
/// Ctrl-C caught by the program, or held through an EEPROM transaction
/// ([`crate::SignalHold`]), would fail the transaction it came during.
pub(crate) fn read_through_signals<T: Transport>(
    transport: &mut T,
    buf: &mut [u8],
    deadline: Duration,
) -> Result<usize, TransportError> {
    let mut left = INTERRUPTIONS;
    loop {
        match transport.read(buf, deadline) {
            Err(TransportError::Io(e))
                if e.kind() == std::io::ErrorKind::Interrupted && left > 0 =>
            {
                left -= 1;
            }
            other => return other,
        }
    }
}
