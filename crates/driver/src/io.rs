//! The request/reply engine under [`Bus`](crate::Bus): send a frame, then
//! feed what comes back through the streaming decoder until a sink is
//! satisfied or the deadline passes.
//!
//! Invariants kept here, for every transaction kind:
//! - input is drained (transport and decoder) before each request, so a late
//!   reply to an earlier request cannot be taken for the current one;
//! - a frame identical to the current or the previous request (a half-duplex
//!   echo, possibly a late one) and any frame with the broadcast ID (only the
//!   host sends those) is never handed to the sink as a reply;
//! - every byte received is accounted for: in a reply, an echo, or the
//!   discarded count.

use std::time::Duration;

use servobus_protocol::{Decoder, Event, Packet, BROADCAST_ID, MAX_FRAME_LEN};

use servobus_timing::Link;

use crate::{Clock, Transport, TransportError};

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
}

/// Transport, clock, decoder and the reused frame buffers.
pub(crate) struct Io<T, C> {
    pub transport: T,
    pub clock: C,
    decoder: Decoder,
    /// The request being sent: `tx[..tx_len]`.
    pub tx: [u8; MAX_FRAME_LEN],
    pub tx_len: usize,
    /// The request sent before it, kept to recognise a late echo.
    prev: [u8; MAX_FRAME_LEN],
    prev_len: usize,
    rx: [u8; 256],
    /// Whether the adapter may echo requests (see `BusSettings::echo`).
    pub echo: bool,
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

impl<T: Transport, C: Clock> Io<T, C> {
    pub fn new(transport: T, clock: C) -> Self {
        Io {
            transport,
            clock,
            decoder: Decoder::new(),
            tx: [0; MAX_FRAME_LEN],
            tx_len: 0,
            prev: [0; MAX_FRAME_LEN],
            prev_len: 0,
            rx: [0; 256],
            echo: true,
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
        let now = self.clock.now();
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
        let start = before.max(self.clock.now().saturating_sub(wire_time));
        self.line_free = start + wire_time;
        if self.echo {
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
        self.clock.now().max(self.line_free)
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
        let mut own = Own {
            tx: &self.tx[..self.tx_len],
            prev: &self.prev[..self.prev_len],
            // Without echo, no frame of ours is expected back: behave as if
            // the echo had already been skipped, and trust identical frames.
            echo_seen: !self.echo,
            prev_is_echo: self.echo,
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
                        if own.handle(ev, &self.clock, sink, &mut tally) {
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
                if own.handle(ev, &self.clock, sink, &mut tally) {
                    // Bytes after the awaited reply are not for us.
                    tally.discarded_bytes += input.len() as u64;
                    break 'wait;
                }
            }
        }
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

/// The frames this host sent last. One copy of the current request is its
/// echo; a second identical copy can only be a reply that happens to have
/// the same bytes (e.g. a PING answered with status 0x01).
struct Own<'a> {
    tx: &'a [u8],
    prev: &'a [u8],
    echo_seen: bool,
    prev_is_echo: bool,
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
                let echo = bytes == self.tx && !self.echo_seen;
                self.echo_seen |= echo;
                if echo || (self.prev_is_echo && bytes == self.prev) || packet.id() == BROADCAST_ID
                {
                    tally.echoes += 1;
                    return false;
                }
                let done = sink.packet(&packet, clock.now());
                tally.done |= done;
                done
            }
            Event::ChecksumError { id, .. } => {
                sink.checksum_error(id);
                false
            }
            Event::Echo { .. } => {
                self.echo_seen = true;
                false
            }
            Event::Discarded { .. } => false,
        }
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
