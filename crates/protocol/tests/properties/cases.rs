//! The decoder on hand-written streams: the cases the properties cover
//! only by chance.

use servobus_protocol::{Decoder, DiscardReason};

use crate::ops::{encoded, Op};
use crate::stream::{check_tiling, packets, run, status, Seen, What};

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
            Seen::at(0, What::BadChecksum),
            Seen::at(0, What::Discarded(bad.len(), DiscardReason::Checksum)),
            Seen::at(bad.len() as u64, What::Packet(good)),
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
