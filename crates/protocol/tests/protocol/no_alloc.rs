//! Encoding a SYNC WRITE and streaming status packets through the decoder
//! allocate nothing: a counting global allocator sees zero allocations
//! between the two marks. Only the measuring thread's allocations count: the
//! test harness's own threads may allocate at any time.

use servobus_alloc_count::{allocations, Counting};
use servobus_protocol::{encode, Decoder, Event, StatusFlags, MAX_FRAME_LEN};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn hot_paths_do_not_allocate() {
    // Set-up (allowed to allocate): 18 blocks and a stream of 1000 replies.
    let blocks: Vec<[u8; 7]> = (0..18u8).map(|i| [20, i, 0x08, 0, 0, 0xDC, 0x05]).collect();
    let mut stream = Vec::new();
    let mut frame = [0u8; MAX_FRAME_LEN];
    for i in 0..1000u32 {
        let id = (i % 18) as u8 + 1;
        let n = encode::status(&mut frame, id, StatusFlags(0), &[i as u8, 0x08, 0x10, 0])
            .expect("valid status");
        stream.extend_from_slice(&frame[..n]);
    }
    let mut buf = [0u8; MAX_FRAME_LEN];
    let ids: [u8; 18] = core::array::from_fn(|i| i as u8 + 1);
    let mut dec = Decoder::new();

    let before = allocations();
    let mut frames = 0;
    for _ in 0..100 {
        let items = blocks
            .iter()
            .enumerate()
            .map(|(i, d)| (i as u8 + 1, &d[..]));
        let n = encode::sync_write(&mut buf, 41, 7, items).expect("fits");
        frames += usize::from(n == 8 + 18 * 8);
        let n =
            encode::sync_write_flat(&mut buf, 41, 7, &ids, blocks.as_flattened()).expect("fits");
        frames += usize::from(n == 8 + 18 * 8);
    }
    let mut packets = 0;
    for chunk in stream.chunks(61) {
        let mut input = chunk;
        while let Some(ev) = dec.decode(&mut input) {
            packets += usize::from(matches!(ev, Event::Packet { .. }));
        }
    }
    let after = allocations();

    assert_eq!(after - before, 0, "allocations on the hot path");

    // The counter does see this thread's allocations.
    let v = std::hint::black_box(vec![0u8; 64]);
    drop(v);
    assert_eq!(allocations() - after, 1);
    assert_eq!((frames, packets), (200, 1000));
}
