//! The checks of the decoder fuzz target, shared with the regression test
//! that replays `testdata/fuzz/` (included by both by path).
//!
//! Input format: byte 0 chooses the chunk sizes, bit 0 of byte 1 announces an
//! echo (the first valid frame of the stream), the rest is the byte stream.
//! Besides "never panics" it checks: every byte ends up in exactly one packet,
//! echo or discarded range, in stream order; every packet is a valid frame
//! made of the stream's own bytes; the totals agree; and feeding the same
//! stream in one piece finds the same packets, echoes and checksum errors at
//! the same offsets.

use servobus_protocol::{parse_frame, Decoder, Event};

#[derive(Debug, PartialEq, Eq)]
enum Ev {
    Packet(u64, usize),
    Echo(u64, usize),
    Discarded(u64, usize),
    Checksum(u64),
}

fn record(ev: Event<'_>, stream: &[u8], at: &mut u64) -> Ev {
    match ev {
        Event::Packet { packet, start } => {
            assert_eq!(start, *at, "packets start where the last event ended");
            let s = start as usize;
            let bytes = packet.bytes();
            assert_eq!(
                &stream[s..s + bytes.len()],
                bytes,
                "a packet is the stream's bytes"
            );
            assert!(parse_frame(bytes).is_ok(), "a packet is a valid frame");
            *at += bytes.len() as u64;
            Ev::Packet(start, bytes.len())
        }
        Event::Echo { start, len } => {
            assert_eq!(start, *at);
            *at += len as u64;
            Ev::Echo(start, len)
        }
        Event::Discarded { start, len, .. } => {
            assert_eq!(start, *at);
            assert!(len > 0, "no empty discards");
            *at += len as u64;
            Ev::Discarded(start, len)
        }
        Event::ChecksumError { start, .. } => {
            assert_eq!(start, *at);
            Ev::Checksum(start)
        }
    }
}

fn run(stream: &[u8], chunk_seed: u8, echo: Option<&[u8]>) -> Vec<Ev> {
    let mut dec = Decoder::new();
    if let Some(e) = echo {
        dec.expect_echo(e);
    }
    let mut events = Vec::new();
    let mut at = 0u64;
    let mut rest = stream;
    let mut k = 0usize;
    while !rest.is_empty() {
        // Chunk sizes cycle through a pattern derived from the seed: 1..=64.
        let size = if chunk_seed == 0 {
            rest.len()
        } else {
            1 + (usize::from(chunk_seed).wrapping_mul(k + 7) % 64)
        };
        k += 1;
        let n = size.min(rest.len());
        let mut chunk = &rest[..n];
        rest = &rest[n..];
        while let Some(ev) = dec.decode(&mut chunk) {
            events.push(record(ev, stream, &mut at));
        }
        assert!(chunk.is_empty());
    }
    while let Some(ev) = dec.finish() {
        events.push(record(ev, stream, &mut at));
    }
    assert_eq!(at, stream.len() as u64, "every byte accounted for");
    assert_eq!(dec.pending(), 0);
    let s = dec.stats();
    assert_eq!(s.bytes_in, stream.len() as u64);
    assert_eq!(
        s.packet_bytes + s.echo_bytes + s.discarded_bytes,
        s.bytes_in
    );
    events
}

/// Runs one fuzz input (see the module docs for its format) and panics on
/// any broken invariant.
pub fn check_input(data: &[u8]) {
    let [chunk_seed, echo_sel, stream @ ..] = data else {
        return;
    };
    // An echo candidate: the first valid frame in the stream, if any.
    let echo = (echo_sel & 1 == 1)
        .then(|| (0..stream.len()).find_map(|i| parse_frame(&stream[i..]).ok()))
        .flatten()
        .map(|(p, _)| p.bytes());
    // Chunking may split a discarded range in two, but never changes which
    // packets, echoes and checksum errors are found, or where.
    let found = |evs: Vec<Ev>| -> Vec<Ev> {
        evs.into_iter()
            .filter(|e| !matches!(e, Ev::Discarded(..)))
            .collect()
    };
    let chunked = found(run(stream, *chunk_seed, echo));
    let whole = found(run(stream, 0, echo));
    assert_eq!(chunked, whole, "chunking does not change what is found");
}
