//! The bus engine shared by the virtual-time [`SimBus`](crate::SimBus) and the
//! wall-clock pty server: it takes the host's bytes at given times, lets the
//! servos execute complete packets, and schedules their replies on the wire
//! with explicit times. It reads no clock itself.

use std::collections::VecDeque;
use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use servobus_protocol::registers::baud_rate;
use servobus_protocol::{parse_frame, Instruction, ParseError, BROADCAST_ID};
use servobus_timing::Link;

use crate::{Faults, SimServo};

/// Running totals of what happened on a simulated bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct SimStats {
    /// Bytes the host sent.
    pub bytes_from_host: u64,
    /// Valid instruction packets the servos received.
    pub requests: u64,
    /// Bytes the servos skipped: garbage, bad checksums, truncated frames.
    pub bytes_ignored: u64,
    /// Status replies put on the wire (before collisions).
    pub replies: u64,
    /// Replies the fault injector dropped.
    pub dropped: u64,
    /// Replies the fault injector corrupted.
    pub corrupted: u64,
    /// Replies the fault injector delayed.
    pub delayed: u64,
    /// Replies the fault injector held on the host's side.
    pub held: u64,
    /// Bytes that collided with another servo's bytes.
    pub collided_bytes: u64,
    /// Request bytes echoed back to the host.
    pub echoed_bytes: u64,
}

/// One byte on its way to the host and the time it becomes readable.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RxByte {
    pub ready: Duration,
    pub byte: u8,
}

/// The state of one simulated bus.
#[derive(Debug)]
pub(crate) struct Engine {
    pub link: Link,
    pub servos: Vec<SimServo>,
    pub faults: Faults,
    rng: SmallRng,
    /// Bytes travelling to the host, in order of readiness.
    pub rx: VecDeque<RxByte>,
    /// When the host's transmitter is free again.
    host_free: Duration,
    /// The servos' receive buffer (they all hear the same bytes).
    inbuf: Vec<u8>,
    /// When the last byte of `inbuf` arrived.
    in_last: Duration,
    /// Time a servo takes before its return delay starts: `None` (the
    /// default) is each servo's model figure, the one `servobus budget`
    /// charges ([`servobus_protocol::registers::REPLY_TURNAROUND`], a
    /// guess); `Some` overrides it for every servo.
    pub turnaround: Option<Duration>,
    /// The host adapter's latency: added to every byte's readiness.
    pub latency: Duration,
    /// Until when the host's side holds what arrives (a held reply, see
    /// [`Faults::hold`]): nothing is readable before the bytes held.
    held_until: Duration,
    pub stats: SimStats,
    pub disconnected: bool,
    /// When the bus heard its first byte (the origin of
    /// [`Faults::vanish_after`]).
    first_heard: Option<Duration>,
    /// How many of [`Faults::vanish_after`] have vanished (sorted by time).
    vanished: usize,
}

impl Engine {
    pub(crate) fn new(baud: u32) -> Engine {
        Engine {
            link: Link::new(baud),
            servos: Vec::new(),
            faults: Faults::none(),
            rng: SmallRng::seed_from_u64(0),
            rx: VecDeque::new(),
            host_free: Duration::ZERO,
            inbuf: Vec::new(),
            in_last: Duration::ZERO,
            turnaround: None,
            latency: Duration::ZERO,
            held_until: Duration::ZERO,
            stats: SimStats::default(),
            disconnected: false,
            first_heard: None,
            vanished: 0,
        }
    }

    pub(crate) fn byte_time(&self) -> Duration {
        self.link.wire_time(1)
    }

    pub(crate) fn set_faults(&mut self, faults: Faults) {
        self.rng = SmallRng::seed_from_u64(faults.seed);
        self.faults = faults;
        self.faults.vanish_after.sort_by_key(|&(_, after)| after);
        self.vanished = 0;
        for i in 0..self.servos.len() {
            self.apply_static_faults(i);
        }
    }

    pub(crate) fn add_servo(&mut self, servo: SimServo) -> usize {
        self.servos.push(servo);
        let i = self.servos.len() - 1;
        self.apply_static_faults(i);
        i
    }

    fn apply_static_faults(&mut self, i: usize) {
        self.faults.apply_to(&mut self.servos[i]);
    }

    /// Whether servo `s` hears the bus: connected and at the bus's baud rate
    /// (within the 3 % a UART tolerates).
    fn listens(&self, s: &SimServo) -> bool {
        if s.is_offline() {
            return false;
        }
        let Some(baud) = baud_rate(s.baud_index()) else {
            return false;
        };
        let bus = f64::from(self.link.baud);
        ((f64::from(baud) - bus) / bus).abs() < 0.03
    }

    /// The host sends `bytes` starting at `start` (or when its transmitter
    /// frees up); servos execute every packet completed by them. Returns
    /// when the last byte has left.
    pub(crate) fn transmit(&mut self, bytes: &[u8], start: Duration) -> Duration {
        let t0 = start.max(self.host_free);
        self.vanish_due(t0);
        // A servo drops a partial frame after the line has been idle for a
        // while, as the firmware's receive timeout does.
        let idle = self.link.wire_time(20).max(Duration::from_micros(100));
        if t0 > self.in_last + idle && !self.inbuf.is_empty() {
            self.stats.bytes_ignored += self.inbuf.len() as u64;
            self.inbuf.clear();
        }
        self.stats.bytes_from_host += bytes.len() as u64;
        let mut end = t0;
        for (i, &b) in bytes.iter().enumerate() {
            end = t0 + self.link.wire_time(i + 1);
            if self.faults.echo {
                self.push_rx(end, b, Duration::ZERO);
                self.stats.echoed_bytes += 1;
            }
            self.inbuf.push(b);
            self.in_last = end;
            self.scan(end);
        }
        self.host_free = end;
        end
    }

    /// Disconnects the servos of [`Faults::vanish_after`] whose time has
    /// come by `t`; each is done once (`vanished` counts those done, in the
    /// list's order of due times).
    fn vanish_due(&mut self, t: Duration) {
        let first = *self.first_heard.get_or_insert(t);
        while let Some(&(id, after)) = self.faults.vanish_after.get(self.vanished) {
            if t < first + after {
                return;
            }
            for s in self.servos.iter_mut().filter(|s| s.id() == id) {
                s.set_offline(true);
            }
            self.vanished += 1;
        }
    }

    /// Finds complete packets in the receive buffer; `t` is the arrival
    /// time of its last byte.
    fn scan(&mut self, t: Duration) {
        loop {
            match parse_frame(&self.inbuf) {
                Ok((_, n)) => {
                    let frame: Vec<u8> = self.inbuf.drain(..n).collect();
                    self.dispatch(&frame, t);
                }
                Err(ParseError::Incomplete { .. }) => return,
                Err(_) => {
                    // Not a frame here (garbage, bad length, bad checksum):
                    // skip one byte and look again.
                    self.inbuf.remove(0);
                    self.stats.bytes_ignored += 1;
                }
            }
            if self.inbuf.is_empty() {
                return;
            }
        }
    }

    fn dispatch(&mut self, frame: &[u8], t: Duration) {
        let Ok((packet, _)) = parse_frame(frame) else {
            return;
        };
        self.stats.requests += 1;
        let mut replies: Vec<(u8, Duration, Vec<u8>)> = Vec::new();
        for i in 0..self.servos.len() {
            if !self.listens(&self.servos[i]) {
                continue;
            }
            let s = &mut self.servos[i];
            let id = s.id();
            // The reply waits the firmware's turnaround and the return delay,
            // as the budget's cycle cost charges them.
            let turnaround = self.turnaround.unwrap_or(s.model().model.turnaround);
            let delay = s.return_delay() + turnaround;
            if let Some(reply) = s.handle(&packet, t) {
                replies.push((id, delay, reply));
            }
        }
        if replies.is_empty() {
            return;
        }
        let sequential = match packet.instruction() {
            Some(Instruction::SyncRead) => {
                // Reply in the order of the request's ID list; servos with
                // the same ID answer in the same slot and collide.
                let ids = packet.params().get(2..).unwrap_or(&[]);
                let pos = |id: u8| ids.iter().position(|&x| x == id).unwrap_or(usize::MAX);
                replies.sort_by_key(|r| pos(r.0));
                true
            }
            Some(Instruction::Ping) if packet.id() == BROADCAST_ID => {
                // Servos answer a broadcast PING one after another, in ID order.
                replies.sort_by_key(|r| r.0);
                true
            }
            _ => false,
        };
        let mut burst: Vec<(Duration, Vec<u8>, Duration)> = Vec::new();
        let mut cursor = t;
        let mut k = 0;
        while k < replies.len() {
            // Replies of one slot: one servo, or several sharing an ID.
            let slot_end = if sequential {
                k + replies[k..]
                    .iter()
                    .take_while(|r| r.0 == replies[k].0)
                    .count()
            } else {
                replies.len()
            };
            let mut next = cursor;
            for (_, delay, reply) in replies[k..slot_end].iter_mut() {
                let mut start = cursor + *delay;
                let mut bytes = std::mem::take(reply);
                let mut held = Duration::ZERO;
                if !self.fault(&mut bytes, &mut start, &mut held) {
                    continue;
                }
                let end = start + self.link.wire_time(bytes.len());
                next = next.max(end);
                burst.push((start, bytes, held));
            }
            cursor = next;
            k = slot_end;
        }
        self.stats.replies += burst.len() as u64;
        self.put_on_wire(burst);
    }

    /// Applies the random faults to one reply: corrupts it, delays its
    /// `start` on the wire, or sets how long the host's side holds it
    /// (`held`); false when it is dropped.
    fn fault(&mut self, bytes: &mut [u8], start: &mut Duration, held: &mut Duration) -> bool {
        let f = &self.faults;
        if !f.any_random() {
            return true;
        }
        let (drop, corrupt, delay, by) = (f.drop, f.corrupt, f.delay, f.delay_by);
        if drop > 0.0 && self.rng.gen_bool(drop) {
            self.stats.dropped += 1;
            return false;
        }
        if corrupt > 0.0 && self.rng.gen_bool(corrupt) && !bytes.is_empty() {
            let at = self.rng.gen_range(0..bytes.len());
            bytes[at] ^= self.rng.gen_range(1..=255u8);
            self.stats.corrupted += 1;
        }
        if delay > 0.0 && self.rng.gen_bool(delay) {
            *start += by;
            self.stats.delayed += 1;
        }
        if f.hold > 0.0 && self.rng.gen_bool(f.hold) {
            *held = f.hold_by;
            self.stats.held += 1;
        }
        true
    }

    /// Serialises transmissions onto the wire: bytes that overlap in time
    /// collide into one corrupted byte (the line is wired-AND: a 0 bit wins).
    fn put_on_wire(&mut self, burst: Vec<(Duration, Vec<u8>, Duration)>) {
        let mut bytes: Vec<(Duration, u8, usize)> = Vec::new();
        for (src, (start, frame, _)) in burst.iter().enumerate() {
            for (i, &b) in frame.iter().enumerate() {
                bytes.push((*start + self.link.wire_time(i + 1), b, src));
            }
        }
        bytes.sort_by_key(|b| b.0);
        let bt = self.byte_time();
        // (end, byte, source) of the bytes that reach the host.
        let mut out: Vec<(Duration, u8, usize)> = Vec::with_capacity(bytes.len());
        for (end, b, src) in bytes {
            match out.last_mut() {
                // Consecutive bytes of one transmission never overlap (their
                // spacing may be a nanosecond short of a byte time by rounding).
                Some(last) if last.2 != src && end < last.0 + bt => {
                    last.1 &= b;
                    self.stats.collided_bytes += 1;
                }
                _ => out.push((end, b, src)),
            }
        }
        for (end, b, src) in out {
            // A held reply is handed over whole, once it is all in and the
            // hold is over (a reader woken late finds it buffered).
            let held = burst
                .get(src)
                .map_or(Duration::ZERO, |(start, frame, held)| {
                    if held.is_zero() {
                        Duration::ZERO
                    } else {
                        (*start + self.link.wire_time(frame.len())).saturating_sub(end) + *held
                    }
                });
            self.push_rx(end, b, held);
        }
    }

    fn push_rx(&mut self, arrived: Duration, byte: u8, held: Duration) {
        let mut ready = arrived + self.latency;
        if held > Duration::ZERO {
            ready += held;
            self.held_until = self.held_until.max(ready);
        }
        // The host's side hands bytes over in order: none overtakes one
        // it holds.
        ready = ready.max(self.held_until);
        let rx = RxByte { ready, byte };
        if self.rx.back().is_some_and(|last| last.ready > ready) {
            // Rare (a delayed reply overtaken by a later one): keep the queue
            // ordered by readiness.
            let at = self.rx.partition_point(|b| b.ready <= ready);
            self.rx.insert(at, rx);
        } else {
            self.rx.push_back(rx);
        }
    }

    /// When the next byte for the host becomes readable.
    pub(crate) fn next_ready(&self) -> Option<Duration> {
        self.rx.front().map(|b| b.ready)
    }

    /// The time up to which a read starting with the front byte collects:
    /// the end of the contiguous burst it begins (as an adapter delivers a
    /// reply once the line goes idle), never past `deadline`.
    pub(crate) fn burst_end(&self, now: Duration, deadline: Duration, max: usize) -> Duration {
        let Some(first) = self.rx.front() else {
            return now;
        };
        let gap = self.byte_time() + self.byte_time() / 2;
        let mut until = now.max(first.ready);
        let mut last = first.ready;
        for b in self.rx.iter().take(max).skip(1) {
            if b.ready <= until {
                last = b.ready;
                continue;
            }
            if b.ready <= deadline && b.ready - last <= gap {
                until = b.ready;
                last = b.ready;
            } else {
                break;
            }
        }
        until
    }

    /// Moves the bytes ready at `now` into `buf`.
    pub(crate) fn take_ready(&mut self, now: Duration, buf: &mut [u8]) -> usize {
        let mut n = 0;
        while n < buf.len() {
            match self.rx.front() {
                Some(b) if b.ready <= now => {
                    buf[n] = b.byte;
                    n += 1;
                    self.rx.pop_front();
                }
                _ => break,
            }
        }
        n
    }

    /// Drops every byte ready at `now`.
    pub(crate) fn discard(&mut self, now: Duration) {
        while self.rx.front().is_some_and(|b| b.ready <= now) {
            self.rx.pop_front();
        }
    }

    /// Steps every servo to `t`.
    pub(crate) fn advance_servos(&mut self, t: Duration) {
        for s in &mut self.servos {
            s.advance_to(t);
        }
    }
}
