//! A streaming decoder: finds packets in a byte stream that arrives in
//! arbitrary chunks, with garbage, corrupted frames and echoes.
//!
//! The decoder keeps at most one frame's worth of unconsumed bytes (plus room
//! to read more) in a fixed internal buffer, so it never allocates. Every byte
//! pushed into it ends up in exactly one of: a [`Event::Packet`], an
//! [`Event::Echo`], a [`Event::Discarded`] range, or the bytes still pending.
//!
//! Resynchronisation never skips more than it must: when a frame turns out to
//! be bad (impossible length, wrong checksum, truncated at the end of the
//! stream) only its first byte and the bytes up to the next possible header
//! (`FF FF`) are discarded, and scanning resumes there, so a valid packet that
//! starts inside the bad one is still found.
//!
//! A corrupted length byte can make the decoder wait for up to 259 bytes
//! before it sees that the frame is bad: packets behind it are then delayed,
//! not lost. Call [`Decoder::finish`] at the end of a reply window to flush
//! them.

use crate::packet::{check_frame, ParseError};
use crate::{Packet, MAX_FRAME_LEN};

const BUF: usize = 2 * MAX_FRAME_LEN;

/// Why bytes were discarded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DiscardReason {
    /// Bytes before a packet header.
    Garbage,
    /// The first byte of an `FF FF FF` run, or a header whose ID byte is 0xFF
    /// (up to the next possible header).
    InvalidId,
    /// A header whose length byte is below 2 (up to the next possible header).
    BadLength,
    /// A frame whose checksum did not match, up to the next possible header
    /// inside or after it (reported just after the matching
    /// [`Event::ChecksumError`]).
    Checksum,
    /// A frame that never completed, up to the next possible header (reported
    /// by [`Decoder::finish`]).
    Truncated,
}

/// One thing the decoder found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event<'a> {
    /// A complete packet with a valid checksum.
    Packet {
        /// The packet, borrowing the decoder's buffer.
        packet: Packet<'a>,
        /// Stream offset of its first byte.
        start: u64,
    },
    /// The echo of the frame announced with [`Decoder::expect_echo`], skipped.
    Echo {
        /// Stream offset of its first byte.
        start: u64,
        /// Its length.
        len: usize,
    },
    /// Bytes that belong to no packet.
    Discarded {
        /// Stream offset of the first discarded byte.
        start: u64,
        /// Number of bytes.
        len: usize,
        /// Why.
        reason: DiscardReason,
    },
    /// A complete frame whose checksum failed. Consumes nothing itself: its
    /// bytes up to the next possible header are reported as
    /// [`DiscardReason::Checksum`] next, and scanning resumes there.
    ChecksumError {
        /// The ID byte of the bad frame.
        id: u8,
        /// Stream offset of the frame.
        start: u64,
        /// The checksum its contents give.
        expected: u8,
        /// The checksum byte it carries.
        found: u8,
    },
}

/// Running totals of what a [`Decoder`] has seen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DecoderStats {
    /// Bytes pushed into the decoder.
    pub bytes_in: u64,
    /// Valid packets yielded (echoes excluded).
    pub packets: u64,
    /// Bytes of yielded packets.
    pub packet_bytes: u64,
    /// Echo frames skipped.
    pub echoes: u64,
    /// Bytes of skipped echoes.
    pub echo_bytes: u64,
    /// Bytes discarded, for any reason.
    pub discarded_bytes: u64,
    /// Frames whose checksum failed.
    pub checksum_errors: u64,
}

/// The streaming packet decoder. See the [module docs](self).
///
/// ```
/// use servobus_protocol::{Decoder, Event};
///
/// let mut dec = Decoder::new();
/// // Garbage, then a status reply split over two reads.
/// let mut chunks: [&[u8]; 2] = [&[0x00, 0x13, 0xFF, 0xFF, 0x01], &[0x02, 0x00, 0xFC]];
/// let mut packets = 0;
/// let mut garbage = 0;
/// for chunk in &mut chunks {
///     while let Some(ev) = dec.decode(chunk) {
///         match ev {
///             Event::Packet { packet, .. } => { assert_eq!(packet.id(), 1); packets += 1 }
///             Event::Discarded { len, .. } => garbage += len,
///             _ => {}
///         }
///     }
/// }
/// assert_eq!((packets, garbage), (1, 2));
/// ```
#[derive(Clone)]
pub struct Decoder {
    buf: [u8; BUF],
    /// Unconsumed bytes are `buf[start..end]`.
    start: usize,
    end: usize,
    /// Stream offset of `buf[start]`.
    offset: u64,
    /// The first byte of the window is to be discarded for a checksum failure.
    checksum_skip: bool,
    echo: [u8; MAX_FRAME_LEN],
    echo_len: usize,
    stats: DecoderStats,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl core::fmt::Debug for Decoder {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Decoder")
            .field("pending", &self.pending())
            .field("offset", &self.offset)
            .field("expecting_echo", &(self.echo_len > 0))
            .field("stats", &self.stats)
            .finish()
    }
}

enum Step {
    NeedMore,
    Discard(usize, DiscardReason),
    Frame(usize),
    BadChecksum { id: u8, expected: u8, found: u8 },
}

impl Decoder {
    /// A decoder at stream offset 0 with nothing pending.
    pub const fn new() -> Self {
        Decoder {
            buf: [0; BUF],
            start: 0,
            end: 0,
            offset: 0,
            checksum_skip: false,
            echo: [0; MAX_FRAME_LEN],
            echo_len: 0,
            stats: DecoderStats {
                bytes_in: 0,
                packets: 0,
                packet_bytes: 0,
                echoes: 0,
                echo_bytes: 0,
                discarded_bytes: 0,
                checksum_errors: 0,
            },
        }
    }

    /// Announces the frame just sent: if the next valid frame is a
    /// byte-for-byte copy of it (a half-duplex adapter's echo), it is
    /// reported as [`Event::Echo`] instead of a packet. The expectation ends
    /// at the first valid frame, echo or not. Frames longer than the longest
    /// possible frame are ignored.
    pub fn expect_echo(&mut self, frame: &[u8]) {
        if frame.len() <= MAX_FRAME_LEN {
            self.echo[..frame.len()].copy_from_slice(frame);
            self.echo_len = frame.len();
        } else {
            self.echo_len = 0;
        }
    }

    /// Forgets any expected echo.
    pub fn clear_echo(&mut self) {
        self.echo_len = 0;
    }

    /// Bytes pushed but not yet consumed (an incomplete frame, usually).
    pub fn pending(&self) -> usize {
        self.end - self.start
    }

    /// Stream offset of the next unconsumed byte.
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// Totals so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Drops the pending bytes without reporting them (counted as discarded)
    /// and forgets any expected echo, e.g. after the host drained its input.
    /// Returns how many bytes were dropped.
    pub fn clear(&mut self) -> usize {
        let n = self.pending();
        self.offset += n as u64;
        self.stats.discarded_bytes += n as u64;
        self.start = 0;
        self.end = 0;
        self.checksum_skip = false;
        self.echo_len = 0;
        n
    }

    /// Takes bytes from the front of `input` as needed and returns the next
    /// event, or `None` when `input` is exhausted and no event is ready. Call
    /// it in a loop until it returns `None`; `input` is advanced past the
    /// bytes taken.
    pub fn decode<'s>(&'s mut self, input: &mut &[u8]) -> Option<Event<'s>> {
        loop {
            // The common case first: a whole valid frame at the front.
            if let Some(len) = self.whole_frame() {
                return Some(self.frame(len));
            }
            match self.step(false) {
                Step::NeedMore => {
                    if input.is_empty() {
                        return None;
                    }
                    self.fill(input);
                }
                step => return Some(self.apply(step)),
            }
        }
    }

    /// [`Decoder::decode`] for a stream that ends with `input`: once `input`
    /// is used up, the end is declared as by [`Decoder::finish`]. Call it in
    /// a loop until it returns `None` to see every event of a complete
    /// capture, a trailing incomplete frame included.
    pub fn decode_to_end<'s>(&'s mut self, input: &mut &[u8]) -> Option<Event<'s>> {
        loop {
            match self.step(false) {
                Step::NeedMore if input.is_empty() => {
                    return match self.step(true) {
                        Step::NeedMore => None,
                        step => Some(self.apply(step)),
                    };
                }
                Step::NeedMore => self.fill(input),
                step => return Some(self.apply(step)),
            }
        }
    }

    /// Declares the end of the stream (or of a reply window): an incomplete
    /// frame at the front is given up on (discarded up to the next possible
    /// header, as [`DiscardReason::Truncated`]) and the remaining bytes are
    /// scanned again. Call it in a loop until it returns
    /// `None`; afterwards nothing is pending.
    pub fn finish(&mut self) -> Option<Event<'_>> {
        match self.step(true) {
            Step::NeedMore => None,
            step => Some(self.apply(step)),
        }
    }

    /// The length of the complete, valid frame at the front of the window,
    /// if there is one: the fast path of [`Decoder::decode`], which
    /// [`Decoder::step`] would reach too, through the header scan and the
    /// typed parse errors.
    #[inline(always)]
    fn whole_frame(&self) -> Option<usize> {
        if self.checksum_skip {
            return None;
        }
        let w = &self.buf[self.start..self.end];
        let [0xFF, 0xFF, id, length, ..] = *w else {
            return None;
        };
        if id == 0xFF || length < 2 {
            return None;
        }
        let total = crate::FRAME_OVERHEAD + usize::from(length) - 2;
        let frame = w.get(..total)?;
        let (&sum, body) = frame[2..].split_last()?;
        (crate::checksum(body) == sum).then_some(total)
    }

    fn fill(&mut self, input: &mut &[u8]) {
        if self.end == BUF {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        let n = input.len().min(BUF - self.end);
        self.buf[self.end..self.end + n].copy_from_slice(&input[..n]);
        self.end += n;
        self.stats.bytes_in += n as u64;
        *input = &input[n..];
    }

    fn step(&self, at_end: bool) -> Step {
        let w = &self.buf[self.start..self.end];
        if self.checksum_skip {
            return Step::Discard(self.checksum_skip_len(), DiscardReason::Checksum);
        }
        if w.is_empty() {
            return Step::NeedMore;
        }
        let i = next_header(w, 0);
        if i > 0 {
            return Step::Discard(i, DiscardReason::Garbage);
        }
        // A bad frame gives up only its first byte as such; the bytes up to the
        // next place a header could start cannot begin a packet either, so
        // they are discarded with it under the same reason (one event per bad
        // frame, same accounting as rescanning them one by one).
        let bad = |reason| Step::Discard(next_header(w, 1), reason);
        match check_frame(w) {
            Ok(len) => Step::Frame(len),
            Err(ParseError::Incomplete { .. }) if at_end => bad(DiscardReason::Truncated),
            Err(ParseError::Incomplete { .. }) => Step::NeedMore,
            Err(ParseError::InvalidId) => bad(DiscardReason::InvalidId),
            Err(ParseError::BadLength(_)) => bad(DiscardReason::BadLength),
            Err(ParseError::Checksum { expected, found }) => Step::BadChecksum {
                id: w[2],
                expected,
                found,
            },
            // Unreachable after the header scan above; treat as garbage.
            Err(ParseError::NoHeader) => bad(DiscardReason::Garbage),
        }
    }

    /// Bytes to discard after a checksum failure at the window's start.
    fn checksum_skip_len(&self) -> usize {
        next_header(&self.buf[self.start..self.end], 1)
    }

    fn consume(&mut self, n: usize) -> (usize, u64) {
        let at = self.start;
        let offset = self.offset;
        self.start += n;
        self.offset += n as u64;
        if self.start == self.end {
            self.start = 0;
            self.end = 0;
        }
        (at, offset)
    }

    fn apply(&mut self, step: Step) -> Event<'_> {
        match step {
            Step::NeedMore => unreachable!("NeedMore is handled by the callers"),
            Step::Discard(len, reason) => {
                self.checksum_skip = false;
                let (_, start) = self.consume(len);
                self.stats.discarded_bytes += len as u64;
                Event::Discarded { start, len, reason }
            }
            Step::BadChecksum {
                id,
                expected,
                found,
            } => {
                self.checksum_skip = true;
                self.stats.checksum_errors += 1;
                Event::ChecksumError {
                    id,
                    start: self.offset,
                    expected,
                    found,
                }
            }
            Step::Frame(len) => self.frame(len),
        }
    }

    /// Takes the valid frame of `len` bytes at the front of the window.
    #[inline(always)]
    fn frame(&mut self, len: usize) -> Event<'_> {
        let is_echo =
            self.echo_len == len && self.buf[self.start..self.start + len] == self.echo[..len];
        self.echo_len = 0;
        let (at, start) = self.consume(len);
        if is_echo {
            self.stats.echoes += 1;
            self.stats.echo_bytes += len as u64;
            Event::Echo { start, len }
        } else {
            self.stats.packets += 1;
            self.stats.packet_bytes += len as u64;
            // `consume` may reset the indices, but never moves bytes.
            Event::Packet {
                packet: Packet::from_valid(&self.buf[at..at + len]),
                start,
            }
        }
    }
}

/// The first index at or after `from` where a header could start: `FF FF`,
/// or a lone `FF` as the last byte (its partner may still arrive). Returns
/// `w.len()` when there is none.
fn next_header(w: &[u8], from: usize) -> usize {
    let mut i = from;
    while i < w.len() {
        match memchr_ff(&w[i..]) {
            None => return w.len(),
            Some(k) => {
                let at = i + k;
                if at + 1 == w.len() || w[at + 1] == 0xFF {
                    return at;
                }
                i = at + 1;
            }
        }
    }
    w.len()
}

/// Position of the first `FF` byte.
#[inline]
fn memchr_ff(w: &[u8]) -> Option<usize> {
    w.iter().position(|&b| b == 0xFF)
}
