//! Property tests: encoding round-trips through parsing for every instruction,
//! and the streaming decoder survives any interleaving of packets, garbage,
//! corrupted frames and arbitrary chunking, accounting for every byte.

//!
//! The generators and helpers are in `ops` and `stream`; the decoder's
//! hand-written cases in `cases`.

mod cases;
mod ops;
mod stream;

use proptest::prelude::*;
use servobus_protocol::{encode, Decoder, MAX_FRAME_LEN};

use ops::{encoded, interpret, op, servo_id, Op};
use stream::{assemble, check_tiling, decode_to_end, pieces, run, Seen, What};

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
            .filter_map(|e| match e.what {
                What::Packet(bytes) => Some((e.start, bytes)),
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
            .filter_map(|e| e.packet().map(|bytes| (e.start, bytes.len())))
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
        prop_assert_eq!(decode_to_end(&stream), one_chunk);
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
                Seen::at(0, What::Echo(req.len())),
                Seen::at(req.len() as u64, What::Packet(rep)),
            ]
        );
        prop_assert_eq!(dec.stats().echoes, 1);
    }
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
