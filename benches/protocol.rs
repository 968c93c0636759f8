//! Benches of servobus-protocol: the two operations of every control cycle.
//!
//! - `protocol/sync_write_18x7`: encode one SYNC WRITE of a 7-byte block
//!   (acceleration, goal position, goal time, goal speed) to 18 servos into a
//!   reused buffer. Target: at most 100 ns.
//! - `protocol/sync_write_flat_18x7`: the same frame from flat slices of IDs
//!   and data (`encode::sync_write_flat`, what the driver and the packer use).
//! - `protocol/decode_status_stream`: the streaming decoder over a long
//!   stream of status packets, fed in 4 KiB reads. Target: at least 300 MB/s.
//!
//! `crates/protocol/tests/no_alloc.rs` shows that both allocate nothing.

use std::hint::black_box;

use criterion::{Criterion, Throughput};
use servobus_protocol::{encode, Decoder, Event, StatusFlags, MAX_FRAME_LEN};

/// The 18 servos' blocks: acceleration, position, time, speed (little-endian).
fn blocks() -> [[u8; 7]; 18] {
    let mut b = [[0u8; 7]; 18];
    for (i, block) in b.iter_mut().enumerate() {
        let pos = 1000 + 100 * i as u16;
        block[0] = 20;
        block[1..3].copy_from_slice(&pos.to_le_bytes());
        block[3..5].copy_from_slice(&0u16.to_le_bytes());
        block[5..7].copy_from_slice(&1500u16.to_le_bytes());
    }
    b
}

/// `count` status replies to a SYNC READ of position and speed (4 bytes):
/// 10-byte frames, IDs cycling over 1..=18.
fn status_stream(count: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(count * 10);
    let mut buf = [0u8; MAX_FRAME_LEN];
    for i in 0..count {
        let id = (i % 18) as u8 + 1;
        let pos = (i as u16).wrapping_mul(37) & 0x0FFF;
        let [p0, p1] = pos.to_le_bytes();
        let n = encode::status(&mut buf, id, StatusFlags(0), &[p0, p1, 0x10, 0x00])
            .expect("valid status");
        out.extend_from_slice(&buf[..n]);
    }
    out
}

/// Registers the benches of this module.
pub fn benches(c: &mut Criterion) {
    let data = blocks();
    let mut buf = [0u8; MAX_FRAME_LEN];
    let mut g = c.benchmark_group("protocol");
    g.bench_function("sync_write_18x7", |b| {
        b.iter(|| {
            let items = black_box(&data)
                .iter()
                .enumerate()
                .map(|(i, d)| (i as u8 + 1, &d[..]));
            black_box(encode::sync_write(&mut buf, 41, 7, items))
        })
    });
    let ids: [u8; 18] = core::array::from_fn(|i| i as u8 + 1);
    let flat: Vec<u8> = data.iter().flatten().copied().collect();
    g.bench_function("sync_write_flat_18x7", |b| {
        b.iter(|| {
            black_box(encode::sync_write_flat(
                &mut buf,
                41,
                7,
                black_box(&ids),
                black_box(&flat),
            ))
        })
    });

    let stream = status_stream(100_000);
    g.throughput(Throughput::Bytes(stream.len() as u64));
    let mut dec = Decoder::new();
    g.bench_function("decode_status_stream", |b| {
        b.iter(|| {
            let mut packets = 0u32;
            for chunk in black_box(&stream).chunks(4096) {
                let mut input = chunk;
                while let Some(ev) = dec.decode(&mut input) {
                    if let Event::Packet { packet, .. } = ev {
                        packets += u32::from(packet.id() != 0);
                    }
                }
            }
            black_box(packets)
        })
    });
    g.finish();
}
