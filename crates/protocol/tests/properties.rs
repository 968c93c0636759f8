//! Property tests: encoding round-trips through parsing for every instruction,
//! and the streaming decoder survives any interleaving of packets, garbage,
//! corrupted frames and arbitrary chunking, accounting for every byte.

use proptest::prelude::*;
use servobus_protocol::{
    encode, parse_frame, Command, Decoder, DiscardReason, Event, StatusFlags, BROADCAST_ID,
    MAX_FRAME_LEN,
};

/// What the host (or a servo) says, as plain data.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Op {
    Ping(u8),
    Read(u8, u8, u8),
    Write(u8, u8, Vec<u8>),
    RegWrite(u8, u8, Vec<u8>),
    Action(u8),
    Reset(u8),
    SyncRead(u8, u8, Vec<u8>),
    SyncWrite(u8, u8, Vec<(u8, Vec<u8>)>),
    Status(u8, u8, Vec<u8>),
}

fn servo_id() -> impl Strategy<Value = u8> {
    0u8..=253
}

fn any_id() -> impl Strategy<Value = u8> {
    prop_oneof![servo_id(), Just(BROADCAST_ID)]
}

fn op() -> impl Strategy<Value = Op> {
    let data = proptest::collection::vec(any::<u8>(), 1..=40);
    prop_oneof![
        any_id().prop_map(Op::Ping),
        (servo_id(), any::<u8>(), 1u8..=255).prop_map(|(i, a, l)| Op::Read(i, a, l)),
        (any_id(), any::<u8>(), data.clone()).prop_map(|(i, a, d)| Op::Write(i, a, d)),
        (any_id(), any::<u8>(), data).prop_map(|(i, a, d)| Op::RegWrite(i, a, d)),
        any_id().prop_map(Op::Action),
        any_id().prop_map(Op::Reset),
        (
            any::<u8>(),
            1u8..=255,
            proptest::collection::vec(servo_id(), 1..=30)
        )
            .prop_map(|(a, l, ids)| Op::SyncRead(a, l, ids)),
        (any::<u8>(), 1u8..=12)
            .prop_flat_map(|(a, l)| {
                let block = proptest::collection::vec(any::<u8>(), usize::from(l));
                let max = 251 / (usize::from(l) + 1);
                (
                    Just(a),
                    Just(l),
                    proptest::collection::vec((servo_id(), block), 1..=max.min(20)),
                )
            })
            .prop_map(|(a, l, blocks)| Op::SyncWrite(a, l, blocks)),
        (
            servo_id(),
            any::<u8>(),
            proptest::collection::vec(any::<u8>(), 0..=40)
        )
            .prop_map(|(i, f, p)| Op::Status(i, f, p)),
    ]
}

fn encode_op(op: &Op, buf: &mut [u8]) -> usize {
    let r = match op {
        Op::Ping(id) => encode::ping(buf, *id),
        Op::Read(id, a, l) => encode::read(buf, *id, *a, *l),
        Op::Write(id, a, d) => encode::write(buf, *id, *a, d),
        Op::RegWrite(id, a, d) => encode::reg_write(buf, *id, *a, d),
        Op::Action(id) => encode::action(buf, *id),
        Op::Reset(id) => encode::reset(buf, *id),
        Op::SyncRead(a, l, ids) => encode::sync_read(buf, *a, *l, ids),
        Op::SyncWrite(a, l, blocks) => {
            encode::sync_write(buf, *a, *l, blocks.iter().map(|(i, d)| (*i, d.as_slice())))
        }
        Op::Status(id, f, p) => encode::status(buf, *id, StatusFlags(*f), p),
    };
    r.expect("valid op encodes")
}

fn encoded(op: &Op) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_op(op, &mut buf);
    buf[..n].to_vec()
}

/// Reads a frame back into an [`Op`]: the inverse of [`encode_op`].
fn interpret(frame: &[u8], from_servo: bool) -> Op {
    let (p, used) = parse_frame(frame).expect("parses");
    assert_eq!(used, frame.len());
    if from_servo {
        return Op::Status(p.id(), p.status().bits(), p.params().to_vec());
    }
    let id = p.id();
    match p.command().expect("a valid command") {
        Command::Ping => Op::Ping(id),
        Command::Read { address, len } => Op::Read(id, address, len),
        Command::Write { address, data } => Op::Write(id, address, data.to_vec()),
        Command::RegWrite { address, data } => Op::RegWrite(id, address, data.to_vec()),
        Command::Action => Op::Action(id),
        Command::Reset => Op::Reset(id),
        Command::SyncRead { address, len, ids } => {
            assert_eq!(id, BROADCAST_ID);
            Op::SyncRead(address, len, ids.to_vec())
        }
        Command::SyncWrite(s) => {
            assert_eq!(id, BROADCAST_ID);
            Op::SyncWrite(
                s.address,
                s.len,
                s.blocks().map(|(i, d)| (i, d.to_vec())).collect(),
            )
        }
    }
}

/// An event with owned contents.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Ev {
    Packet {
        start: u64,
        bytes: Vec<u8>,
    },
    Echo {
        start: u64,
        len: usize,
    },
    Discarded {
        start: u64,
        len: usize,
        reason: DiscardReason,
    },
    Checksum {
        start: u64,
    },
}

fn own(ev: Event<'_>) -> Ev {
    match ev {
        Event::Packet { packet, start } => Ev::Packet {
            start,
            bytes: packet.bytes().to_vec(),
        },
        Event::Echo { start, len } => Ev::Echo { start, len },
        Event::Discarded { start, len, reason } => Ev::Discarded { start, len, reason },
        Event::ChecksumError { start, .. } => Ev::Checksum { start },
    }
}

/// Feeds `stream` in chunks of the given sizes (cycled), then finishes.
fn run(dec: &mut Decoder, stream: &[u8], chunks: &[usize]) -> Vec<Ev> {
    let mut out = Vec::new();
    let mut rest = stream;
    let mut k = 0;
    while !rest.is_empty() {
        let n = chunks[k % chunks.len()].clamp(1, rest.len());
        k += 1;
        let mut chunk = &rest[..n];
        rest = &rest[n..];
        while let Some(ev) = dec.decode(&mut chunk) {
            out.push(own(ev));
        }
        assert!(
            chunk.is_empty(),
            "decode returns None only when input is used up"
        );
    }
    while let Some(ev) = dec.finish() {
        out.push(own(ev));
    }
    assert_eq!(dec.pending(), 0);
    out
}

/// Every byte of the stream is in exactly one packet, echo or discarded
/// range, in order; packets are valid and are the stream's own bytes.
fn check_tiling(stream: &[u8], events: &[Ev]) {
    let mut at = 0u64;
    for ev in events {
        match ev {
            Ev::Packet { start, bytes } => {
                assert_eq!(*start, at, "{events:?}");
                let s = *start as usize;
                assert_eq!(&stream[s..s + bytes.len()], &bytes[..]);
                assert!(parse_frame(bytes).is_ok());
                at += bytes.len() as u64;
            }
            Ev::Echo { start, len } | Ev::Discarded { start, len, .. } => {
                assert_eq!(*start, at, "{events:?}");
                assert!(*len > 0);
                at += *len as u64;
            }
            Ev::Checksum { start } => assert_eq!(*start, at),
        }
    }
    assert_eq!(at, stream.len() as u64, "every byte accounted for");
}

#[derive(Debug, Clone)]
enum Piece {
    Frame(Op),
    Garbage(Vec<u8>),
}

/// Garbage that looks like the start of frames as often as it looks random.
fn garbage(with_ff: bool) -> BoxedStrategy<Vec<u8>> {
    if !with_ff {
        return proptest::collection::vec(0u8..0xFF, 1..20).boxed();
    }
    prop_oneof![
        proptest::collection::vec(any::<u8>(), 1..20),
        (1usize..5).prop_map(|n| vec![0xFF; n]),
        // A frame cut short.
        (op(), any::<prop::sample::Index>()).prop_map(|(o, i)| {
            let f = encoded(&o);
            f[..1 + i.index(f.len() - 1)].to_vec()
        }),
        // A frame with one byte (not the header) corrupted.
        (op(), any::<prop::sample::Index>(), 1u8..=255).prop_map(|(o, i, x)| {
            let mut f = encoded(&o);
            let at = 2 + i.index(f.len() - 2);
            f[at] ^= x;
            f
        }),
        // Headers with impossible ID or length bytes.
        Just(vec![0xFF, 0xFF, 0xFF]),
        (0u8..2).prop_map(|l| vec![0xFF, 0xFF, 0x01, l]),
    ]
    .boxed()
}

fn pieces(with_ff: bool) -> impl Strategy<Value = Vec<Piece>> {
    proptest::collection::vec(
        prop_oneof![
            3 => op().prop_map(Piece::Frame),
            1 => garbage(with_ff).prop_map(Piece::Garbage),
        ],
        0..30,
    )
}

/// Concatenates the pieces; returns the stream and the originals' spans.
fn assemble(pieces: &[Piece]) -> (Vec<u8>, Vec<(u64, Vec<u8>)>) {
    let mut stream = Vec::new();
    let mut frames = Vec::new();
    for p in pieces {
        match p {
            Piece::Frame(o) => {
                let f = encoded(o);
                frames.push((stream.len() as u64, f.clone()));
                stream.extend(f);
            }
            Piece::Garbage(g) => stream.extend(g),
        }
    }
    (stream, frames)
}

/// PROPTEST_CASES when set; 1000 under `CI=true`, so that the gate
/// explores enough to mean something; 300 otherwise, to keep a local debug
/// run short on a loaded machine.
fn cases() -> u32 {
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|c| c.parse().ok())
        .unwrap_or(if ci { 1000 } else { 300 })
}

fn chunks() -> impl Strategy<Value = Vec<usize>> {
    proptest::collection::vec(1usize..80, 1..10)
}

proptest! {
    // See `cases`; PROPTEST_CASES=20000 (as run for the release figures)
    // explores more.
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn decode_of_encode_is_identity(op in op()) {
        let frame = encoded(&op);
        let from_servo = matches!(op, Op::Status(..));
        prop_assert_eq!(interpret(&frame, from_servo), op);
    }

    /// Garbage that holds no `FF` cannot start a frame: every packet comes
    /// out, exactly once, at its offset, and nothing else does.
    #[test]
    fn every_packet_survives_plain_garbage(pieces in pieces(false), chunks in chunks()) {
        let (stream, frames) = assemble(&pieces);
        let mut dec = Decoder::new();
        let events = run(&mut dec, &stream, &chunks);
        check_tiling(&stream, &events);
        let got: Vec<(u64, Vec<u8>)> = events
            .into_iter()
            .filter_map(|e| match e {
                Ev::Packet { start, bytes } => Some((start, bytes)),
                _ => None,
            })
            .collect();
        prop_assert_eq!(got, frames);
        let stats = dec.stats();
        prop_assert_eq!(stats.bytes_in, stream.len() as u64);
        prop_assert_eq!(stats.packet_bytes + stats.discarded_bytes, stream.len() as u64);
    }

    /// With arbitrary garbage (FF runs, cut and corrupted frames), every
    /// packet is still yielded unless garbage that happened to form a valid
    /// frame overlaps it; the decoder never panics and accounts every byte.
    #[test]
    fn every_packet_not_overlapped_by_garbage_survives(
        pieces in pieces(true),
        chunks in chunks(),
    ) {
        let (stream, frames) = assemble(&pieces);
        let mut dec = Decoder::new();
        let events = run(&mut dec, &stream, &chunks);
        check_tiling(&stream, &events);
        let yielded: Vec<(u64, usize)> = events
            .iter()
            .filter_map(|e| match e {
                Ev::Packet { start, bytes } => Some((*start, bytes.len())),
                _ => None,
            })
            .collect();
        for (start, f) in &frames {
            let end = start + f.len() as u64;
            let found = yielded.contains(&(*start, f.len()));
            let spurious_overlap = yielded.iter().any(|&(s, l)| {
                let e = s + l as u64;
                s < end && *start < e && !frames.iter().any(|(fs, ff)| *fs == s && ff.len() == l)
            });
            prop_assert!(found || spurious_overlap, "lost frame at {}: {:?}", start, events);
        }
        let stats = dec.stats();
        prop_assert_eq!(
            stats.packet_bytes + stats.discarded_bytes,
            stream.len() as u64
        );
    }

    /// Arbitrary bytes in arbitrary chunks: no panic, exact tiling.
    #[test]
    fn arbitrary_bytes_are_accounted(
        stream in proptest::collection::vec(
            prop_oneof![any::<u8>(), Just(0xFFu8), Just(0x01u8), Just(0x02u8)],
            0..1500,
        ),
        chunks in chunks(),
    ) {
        let mut dec = Decoder::new();
        let events = run(&mut dec, &stream, &chunks);
        check_tiling(&stream, &events);
        // The whole capture at once, end declared by `decode_to_end`: the
        // same events as decoding it in one chunk and then finishing.
        let one_chunk = run(&mut Decoder::new(), &stream, &[stream.len()]);
        let mut whole = Decoder::new();
        let mut input = &stream[..];
        let mut at_once = Vec::new();
        while let Some(ev) = whole.decode_to_end(&mut input) {
            at_once.push(own(ev));
        }
        prop_assert_eq!(at_once, one_chunk);
    }

    /// A half-duplex adapter echoes the request before the reply arrives.
    #[test]
    fn echo_is_skipped_and_reply_yielded(
        request in op().prop_filter("host op", |o| !matches!(o, Op::Status(..))),
        reply in (servo_id(), proptest::collection::vec(any::<u8>(), 0..10)),
        chunks in chunks(),
    ) {
        let req = encoded(&request);
        let rep = encoded(&Op::Status(reply.0, 0, reply.1));
        let mut stream = req.clone();
        stream.extend(&rep);
        let mut dec = Decoder::new();
        dec.expect_echo(&req);
        let events = run(&mut dec, &stream, &chunks);
        prop_assert_eq!(
            events,
            vec![
                Ev::Echo { start: 0, len: req.len() },
                Ev::Packet { start: req.len() as u64, bytes: rep },
            ]
        );
        prop_assert_eq!(dec.stats().echoes, 1);
    }
}

fn status(id: u8, params: &[u8]) -> Vec<u8> {
    encoded(&Op::Status(id, 0, params.to_vec()))
}

fn packets(events: &[Ev]) -> Vec<Vec<u8>> {
    events
        .iter()
        .filter_map(|e| match e {
            Ev::Packet { bytes, .. } => Some(bytes.clone()),
            _ => None,
        })
        .collect()
}

#[test]
fn ff_inside_params_is_data() {
    let a = status(1, &[0xFF, 0xFF, 0xFF, 0x00]);
    let b = status(2, &[0xFF, 0xFF]);
    let mut stream = a.clone();
    stream.extend(&b);
    for chunk in 1..stream.len() {
        let events = run(&mut Decoder::new(), &stream, &[chunk]);
        check_tiling(&stream, &events);
        assert_eq!(
            packets(&events),
            vec![a.clone(), b.clone()],
            "chunk {chunk}"
        );
    }
}

#[test]
fn ff_runs_before_a_packet_are_discarded() {
    for run_len in 1..8 {
        let p = status(3, &[0x10, 0x20]);
        let mut stream = vec![0xFF; run_len];
        stream.extend(&p);
        let events = run(&mut Decoder::new(), &stream, &[1]);
        check_tiling(&stream, &events);
        assert_eq!(packets(&events), vec![p], "run of {run_len}");
    }
}

#[test]
fn bad_checksum_then_valid_packet() {
    let mut bad = status(1, &[0x01, 0x02]);
    let last = bad.len() - 1;
    bad[last] ^= 0x55;
    let good = status(2, &[0x03]);
    let mut stream = bad.clone();
    stream.extend(&good);
    let events = run(&mut Decoder::new(), &stream, &[3]);
    check_tiling(&stream, &events);
    assert_eq!(
        events,
        vec![
            Ev::Checksum { start: 0 },
            Ev::Discarded {
                start: 0,
                len: bad.len(),
                reason: DiscardReason::Checksum
            },
            Ev::Packet {
                start: bad.len() as u64,
                bytes: good
            },
        ]
    );
}

/// A header whose length byte was corrupted upwards swallows the packets
/// behind it until its checksum fails; they are then found, not lost.
#[test]
fn corrupted_length_delays_but_does_not_lose_packets() {
    let mut stream = vec![0xFF, 0xFF, 0x01, 0xF0, 0x00];
    let replies: Vec<Vec<u8>> = (1..=6).map(|id| status(id, &[id, 0x08])).collect();
    for r in &replies {
        stream.extend(r);
    }
    let events = run(&mut Decoder::new(), &stream, &[7]);
    check_tiling(&stream, &events);
    assert_eq!(packets(&events), replies);
}

#[test]
fn invalid_length_and_id_are_skipped() {
    let p = status(4, &[]);
    for prefix in [
        &[0xFF, 0xFF, 0x04, 0x01][..],
        &[0xFF, 0xFF, 0xFF],
        &[0xFF, 0xFF, 0x04, 0x00],
    ] {
        let mut stream = prefix.to_vec();
        stream.extend(&p);
        let events = run(&mut Decoder::new(), &stream, &[2]);
        check_tiling(&stream, &events);
        assert_eq!(packets(&events), vec![p.clone()], "{prefix:02X?}");
    }
}

#[test]
fn an_echo_that_differs_is_a_packet() {
    let req = encoded(&Op::Ping(1));
    let other = encoded(&Op::Ping(2));
    let mut dec = Decoder::new();
    dec.expect_echo(&req);
    let events = run(&mut dec, &other, &[64]);
    assert_eq!(packets(&events), vec![other]);
    // The expectation ended at that frame: the request itself is now a packet.
    let events = run(&mut dec, &req, &[64]);
    assert_eq!(packets(&events), vec![req]);
}

proptest! {
    /// The flat SYNC WRITE encoder builds exactly the frame of the iterator
    /// form, for any servos and block length that fit one frame.
    #[test]
    fn flat_sync_write_matches_the_iterator_form(
        address in any::<u8>(),
        len in 1u8..=20,
        blocks in proptest::collection::vec((servo_id(), proptest::collection::vec(any::<u8>(), 20)), 1..12),
    ) {
        let l = usize::from(len);
        let ids: Vec<u8> = blocks.iter().map(|(id, _)| *id).collect();
        let data: Vec<u8> = blocks.iter().flat_map(|(_, d)| d[..l].iter().copied()).collect();
        let mut a = [0u8; MAX_FRAME_LEN];
        let mut b = [0u8; MAX_FRAME_LEN];
        let flat = encode::sync_write_flat(&mut a, address, len, &ids, &data);
        let iter = encode::sync_write(
            &mut b,
            address,
            len,
            ids.iter().copied().zip(data.chunks_exact(l)),
        );
        match (flat, iter) {
            (Ok(n), Ok(m)) => prop_assert_eq!(&a[..n], &b[..m]),
            (Err(_), Err(_)) => {}
            (x, y) => prop_assert!(false, "flat {:?} vs iterator {:?}", x, y),
        }
    }
}
