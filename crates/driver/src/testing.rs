//! Unit tests of the bus against a small scripted transport in virtual time.
//! (The full behaviour is tested against the simulator in
//! `crates/sim/tests/driver*.rs`.)

use std::collections::VecDeque;
use std::time::Duration;

use servobus_protocol::registers::Series;
use servobus_protocol::{encode, parse_frame, Instruction, Packet, StatusFlags};

use crate::scripted::{Received, Script, ScriptedPort};
use crate::{Bus, BusError, BusSettings, Clock, ManualClock, MissingReason, TransportError};

type Responder = Box<dyn FnMut(&Packet<'_>) -> Vec<Vec<u8>>>;

/// Delivers the responder's frames, one after another, 100 us apart after
/// each request; optionally echoes the request first.
struct Scripted {
    inbox: VecDeque<(Duration, Vec<u8>)>,
    responder: Responder,
    echo: bool,
    sent: Vec<Vec<u8>>,
    /// How long each write call holds the thread before the bytes leave (a
    /// host descheduled while sending).
    stall: Duration,
}

impl Scripted {
    fn new(responder: Responder) -> Self {
        Scripted {
            inbox: VecDeque::new(),
            responder,
            echo: false,
            sent: Vec::new(),
            stall: Duration::ZERO,
        }
    }
}

impl Script for Scripted {
    fn write(&mut self, clock: &ManualClock, bytes: &[u8]) -> Result<(), TransportError> {
        clock.advance(self.stall);
        let now = clock.now();
        self.sent.push(bytes.to_vec());
        if self.echo {
            self.inbox.push_back((now, bytes.to_vec()));
        }
        if let Ok((p, _)) = parse_frame(bytes) {
            for (k, frame) in (self.responder)(&p).into_iter().enumerate() {
                let at = now + Duration::from_micros(100) * (k as u32 + 1);
                self.inbox.push_back((at, frame));
            }
        }
        Ok(())
    }

    fn read(&mut self, clock: &ManualClock, buf: &mut [u8], deadline: Duration) -> Received {
        match self.inbox.front_mut() {
            Some((at, bytes)) if *at <= deadline => {
                clock.advance_to(*at);
                let n = buf.len().min(bytes.len());
                buf[..n].copy_from_slice(&bytes[..n]);
                bytes.drain(..n);
                if bytes.is_empty() {
                    self.inbox.pop_front();
                }
                Ok(n)
            }
            _ => {
                clock.advance_to(deadline);
                Err(TransportError::TimedOut)
            }
        }
    }

    fn discard(&mut self, clock: &ManualClock) {
        let now = clock.now();
        self.inbox.retain(|(at, _)| *at > now);
    }
}

fn status(id: u8, flags: u8, params: &[u8]) -> Vec<u8> {
    let mut buf = [0u8; 64];
    let n = encode::status(&mut buf, id, StatusFlags(flags), params).unwrap_or(0);
    buf[..n].to_vec()
}

fn bus(responder: Responder) -> (Bus<ScriptedPort<Scripted>>, ManualClock) {
    let clock = ManualClock::new();
    let settings = BusSettings::new(Series::Sts).with_latency(Duration::from_millis(1));
    let port = ScriptedPort::new(&clock, Scripted::new(responder));
    (Bus::new(port, settings), clock)
}

#[test]
fn ping_read_write_and_their_counters() {
    let (mut bus, _) = bus(Box::new(|p| match p.instruction() {
        Some(Instruction::Read) if p.id() == 3 => vec![status(3, 0, &[0x34, 0x12])],
        Some(_) if p.id() == 3 => vec![status(3, 0x20, &[])],
        _ => vec![],
    }));
    assert_eq!(bus.ping(3).map(|f| f.overload()).ok(), Some(true));
    let mut out = [0u8; 2];
    assert!(bus.read(3, 56, &mut out).is_ok());
    assert_eq!(out, [0x34, 0x12]);
    assert!(bus.write(3, 42, &[0, 8]).is_ok());
    let c = bus.servo_counters(3);
    assert_eq!((c.transactions, c.status_errors, c.timeouts), (3, 2, 0));
    assert_eq!(c.rtt.count, 3);
    // Broadcast writes are not answered and not waited for.
    assert!(matches!(bus.write(0xFE, 40, &[1]), Ok(None)));
}

#[test]
fn timeout_is_derived_from_the_link_and_retries_are_bounded() {
    let (mut bus, clock) = bus(Box::new(|_| vec![]));
    let t0 = clock.now();
    let err = bus.ping(9).unwrap_err();
    let waited = clock.now() - t0;
    // PING at 1 Mbps, 1 ms latency: 6 + 6 bytes (120 us) + 50 us turnaround
    // + 1 ms + 200 us margin = 1.37 ms, asked twice (one retry).
    assert!(
        matches!(err, BusError::Timeout { id: 9, waited } if waited == Duration::from_micros(1370))
    );
    assert_eq!(waited, Duration::from_micros(2 * 1370));
    let c = bus.counters();
    assert_eq!(
        (c.transactions, c.retries, c.timeouts, c.failures),
        (1, 1, 2, 1)
    );
}

#[test]
fn a_request_held_up_by_the_host_is_waited_for_from_when_it_left() {
    let (mut bus, clock) = bus(Box::new(|p| vec![status(p.id(), 0, &[])]));
    // The thread is descheduled for 5 ms in every write: the servo hears
    // each request 5 ms after the call began and answers 100 us later,
    // far past the 1.37 ms deadline counted from the call. Counted from
    // the write's return less the request's 60 us of wire, it is in time.
    bus.transport_mut().script.stall = Duration::from_millis(5);
    let t0 = clock.now();
    assert!(bus.ping(4).is_ok());
    assert_eq!(clock.now() - t0, Duration::from_micros(5_100));
    assert_eq!(bus.counters().timeouts, 0);
    // A silent servo still times out on the first try, its deadline
    // counted from when the request can have left: 5 ms - 60 us + 1.37 ms,
    // twice.
    let (mut bus, clock) = bus_silent();
    bus.transport_mut().script.stall = Duration::from_millis(5);
    let t0 = clock.now();
    assert!(matches!(bus.ping(9), Err(BusError::Timeout { id: 9, .. })));
    assert_eq!(
        clock.now() - t0,
        Duration::from_micros(2 * (5_000 - 60 + 1_370))
    );
    assert_eq!(bus.counters().timeouts, 2);
}

fn bus_silent() -> (Bus<ScriptedPort<Scripted>>, ManualClock) {
    bus(Box::new(|_| vec![]))
}

#[test]
fn echo_is_skipped_and_wrong_ids_are_not_taken() {
    let (mut bus, _) = bus(Box::new(|p| {
        if p.instruction() == Some(Instruction::Read) {
            // Another servo answers first, then the right one.
            vec![status(7, 0, &[1, 2]), status(p.id(), 0, &[5, 6])]
        } else {
            vec![]
        }
    }));
    bus.transport_mut().script.echo = true;
    let mut out = [0u8; 2];
    assert!(bus.read(4, 56, &mut out).is_ok());
    assert_eq!(out, [5, 6]);
    let c = bus.counters();
    assert_eq!((c.echoes, c.wrong_replies), (1, 1));
}

#[test]
fn a_reply_from_the_wrong_id_only_is_an_error() {
    let (mut bus, _) = bus(Box::new(|p| vec![status(p.id() + 1, 0, &[])]));
    let err = bus.ping(4).unwrap_err();
    assert!(
        matches!(
            err,
            BusError::WrongId {
                expected: 4,
                actual: 5
            }
        ),
        "{err}"
    );
}

#[test]
fn corrupt_replies_are_reported_as_such() {
    let (mut bus, _) = bus(Box::new(|p| {
        let mut f = status(p.id(), 0, &[]);
        let last = f.len() - 1;
        f[last] ^= 0x55;
        vec![f]
    }));
    let err = bus.ping(2).unwrap_err();
    assert!(matches!(err, BusError::Corrupt { id: 2 }), "{err}");
    assert_eq!(bus.counters().checksum_errors, 2);
}

#[test]
fn sync_read_keeps_answers_and_names_the_missing() {
    let (mut bus, _) = bus(Box::new(|p| {
        if p.instruction() != Some(Instruction::SyncRead) {
            return vec![];
        }
        let ids = &p.params()[2..];
        ids.iter()
            .filter(|&&id| id != 2)
            .map(|&id| status(id, 0, &[id, 0]))
            .collect()
    }));
    let r = bus.sync_read(56, 2, &[1, 2, 3]).map(|r| {
        let v: Vec<_> = r.iter().collect();
        (r.answered(), v)
    });
    let Ok((answered, v)) = r else {
        panic!("sync read failed");
    };
    assert_eq!(answered, 2);
    assert_eq!(v[0].map(|r| r.data).ok(), Some(&[1u8, 0][..]));
    assert_eq!(
        v[1].map_err(|m| (m.id, m.reason)),
        Err((2, MissingReason::NoReply))
    );
    assert_eq!(v[2].map(|r| (r.id, r.data[0])).ok(), Some((3, 3)));
    assert_eq!(bus.servo_counters(2).timeouts, 1);
    assert!(bus.sync_read(56, 2, &[1, 1]).is_err());
    assert!(bus.sync_read(56, 2, &[3, 254]).is_err());
    // A refused request leaves the storage clean for the next one.
    let again = bus
        .sync_read(56, 2, &[3, 1])
        .map(|r| (r.len(), r.answered()));
    assert_eq!(again.ok(), Some((2, 2)));
}

#[test]
fn sync_write_splits_long_frames() {
    let (mut bus, _) = bus(Box::new(|_| vec![]));
    let ids: Vec<u8> = (0..100).collect();
    // Each servo's two bytes are its ID and 7: recognisable in the frames.
    let data: Vec<u8> = ids.iter().flat_map(|&id| [id, 7]).collect();
    bus.sync_write(42, &ids, &data).expect("a valid SYNC WRITE");
    // 251 / 3 = 83 servos per frame: two frames, of 83 and 17 servos.
    let sent = &bus.transport().script.sent;
    assert_eq!(sent.len(), 2);
    let mut next = 0u8;
    for (frame, servos) in sent.iter().zip([83usize, 17]) {
        // FF FF FE len 83 42 2 (id d0 d1)... checksum, where len counts
        // the instruction, the parameters and the checksum.
        let len = 3 * servos + 4;
        assert_eq!(frame.len(), len + 4);
        assert_eq!(frame[..7], [0xFF, 0xFF, 0xFE, len as u8, 0x83, 42, 2]);
        for servo in frame[7..frame.len() - 1].chunks(3) {
            assert_eq!(servo, [next, next, 7]);
            next += 1;
        }
        // The manual's checksum: the complement of the byte sum from the
        // ID on.
        let sum = frame[2..frame.len() - 1]
            .iter()
            .fold(0u8, |s, &b| s.wrapping_add(b));
        assert_eq!(frame[frame.len() - 1], !sum);
    }
    assert_eq!(next, 100, "every servo once, in order");
    assert!(bus.sync_write(42, &ids, &data[..199]).is_err());
    assert_eq!(
        bus.transport().script.sent.len(),
        2,
        "nothing sent when refused"
    );
    // An invalid ID in the second frame refuses the first one too.
    let mut bad = ids.clone();
    bad[90] = 254;
    assert!(matches!(
        bus.sync_write(42, &bad, &data),
        Err(BusError::Encode(_))
    ));
    assert_eq!(
        bus.transport().script.sent.len(),
        2,
        "a half-valid request sends nothing"
    );
}
