//! Streams of frames and garbage fed to the decoder in chunks, and what it
//! said about them, owned so that runs can be compared.

use proptest::prelude::*;
use servobus_protocol::{parse_frame, Decoder, DiscardReason, Event};

use crate::ops::{encoded, op, Op};

/// One stretch of the stream as the decoder reported it: where it starts
/// and what it was (a checksum error covers no bytes of its own; the
/// discard that follows it does).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Seen {
    pub start: u64,
    pub what: What,
}

/// What a stretch was.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum What {
    Packet(Vec<u8>),
    Echo(usize),
    Discarded(usize, DiscardReason),
    BadChecksum,
}

impl Seen {
    pub fn at(start: u64, what: What) -> Self {
        Seen { start, what }
    }

    /// Bytes of the stream it accounts for.
    fn len(&self) -> usize {
        match &self.what {
            What::Packet(bytes) => bytes.len(),
            What::Echo(len) | What::Discarded(len, _) => *len,
            What::BadChecksum => 0,
        }
    }

    /// The packet's bytes, if it was one.
    pub fn packet(&self) -> Option<&[u8]> {
        match &self.what {
            What::Packet(bytes) => Some(bytes),
            _ => None,
        }
    }
}

fn own(ev: Event<'_>) -> Seen {
    let (start, what) = match ev {
        Event::Packet { packet, start } => (start, What::Packet(packet.bytes().to_vec())),
        Event::Echo { start, len } => (start, What::Echo(len)),
        Event::Discarded { start, len, reason } => (start, What::Discarded(len, reason)),
        Event::ChecksumError { start, .. } => (start, What::BadChecksum),
    };
    Seen::at(start, what)
}

/// Everything `decode_to_end` yields for `stream` given whole.
pub fn decode_to_end(stream: &[u8]) -> Vec<Seen> {
    let mut dec = Decoder::new();
    let mut input = stream;
    let mut out = Vec::new();
    while let Some(ev) = dec.decode_to_end(&mut input) {
        out.push(own(ev));
    }
    out
}

/// Feeds `stream` in chunks of the given sizes (cycled), then finishes.
pub fn run(dec: &mut Decoder, stream: &[u8], chunks: &[usize]) -> Vec<Seen> {
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
pub fn check_tiling(stream: &[u8], events: &[Seen]) {
    let mut at = 0u64;
    for ev in events {
        assert_eq!(ev.start, at, "{events:?}");
        let end = at + ev.len() as u64;
        if let Some(bytes) = ev.packet() {
            assert_eq!(&stream[at as usize..end as usize], bytes);
            assert!(parse_frame(bytes).is_ok());
        } else if ev.what != What::BadChecksum {
            assert!(ev.len() > 0);
        }
        at = end;
    }
    assert_eq!(at, stream.len() as u64, "every byte accounted for");
}

#[derive(Debug, Clone)]
pub enum Piece {
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

pub fn pieces(with_ff: bool) -> impl Strategy<Value = Vec<Piece>> {
    proptest::collection::vec(
        prop_oneof![
            3 => op().prop_map(Piece::Frame),
            1 => garbage(with_ff).prop_map(Piece::Garbage),
        ],
        0..30,
    )
}

/// Concatenates the pieces; returns the stream and the originals' spans.
pub fn assemble(pieces: &[Piece]) -> (Vec<u8>, Vec<(u64, Vec<u8>)>) {
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

/// A status reply from `id` carrying `params`, with no error flags.
pub fn status(id: u8, params: &[u8]) -> Vec<u8> {
    encoded(&Op::Status(id, 0, params.to_vec()))
}

/// The packets among `events`.
pub fn packets(events: &[Seen]) -> Vec<Vec<u8>> {
    events
        .iter()
        .filter_map(|e| e.packet().map(<[u8]>::to_vec))
        .collect()
}
