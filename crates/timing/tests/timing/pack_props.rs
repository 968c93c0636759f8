//! Properties of SYNC WRITE packing for any number of servos and block size.

use core::time::Duration;

use proptest::prelude::*;
use servobus_protocol::{parse_frame, Instruction, BROADCAST_ID, MAX_LENGTH_BYTE};
use servobus_timing::{
    pack_sync_write, plan, servos_per_frame, sync_write_bytes, sync_write_frames, Block, Link,
    Servo,
};

/// N distinct IDs in a random order, L, the goal data and a baud rate.
fn goals() -> impl Strategy<Value = (Vec<u8>, u8, Vec<u8>, u32)> {
    (1usize..=253, 1u8..=32, 1_200u32..=4_000_000).prop_flat_map(|(n, len, baud)| {
        let ids = Just((0..=253u8).collect::<Vec<u8>>())
            .prop_shuffle()
            .prop_map(move |mut all| {
                all.truncate(n);
                all
            });
        let data = proptest::collection::vec(any::<u8>(), n * usize::from(len));
        (ids, Just(len), data, Just(baud))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn every_servo_once_in_the_fewest_valid_frames((ids, len, data, baud) in goals()) {
        let n = ids.len();
        let block = Block::new(41, len);
        let mut buf = vec![0u8; sync_write_bytes(n, len)];
        let packed = pack_sync_write(&mut buf, block, &ids, &data).unwrap();
        prop_assert_eq!(packed.len, buf.len());

        // Decode the frames back to back with the protocol crate.
        let mut seen = Vec::with_capacity(n);
        let mut at = 0;
        let mut frames = 0;
        while at < packed.len {
            let (p, used) = parse_frame(&buf[at..]).unwrap();
            prop_assert_eq!(Some(at..at + used), packed.frame_range(frames));
            prop_assert_eq!(p.instruction(), Some(Instruction::SyncWrite));
            prop_assert_eq!(p.id(), BROADCAST_ID);
            prop_assert!(usize::from(p.length_byte()) <= MAX_LENGTH_BYTE);
            let params = p.params();
            prop_assert_eq!(params[0], block.address);
            prop_assert_eq!(params[1], len);
            let body = &params[2..];
            prop_assert_eq!(body.len() % (usize::from(len) + 1), 0);
            for item in body.chunks(usize::from(len) + 1) {
                seen.push((item[0], item[1..].to_vec()));
            }
            at += used;
            frames += 1;
        }
        prop_assert_eq!(at, packed.len);
        prop_assert_eq!(frames, packed.frames);

        // Every servo exactly once, in order, with its own block.
        let expected: Vec<(u8, Vec<u8>)> = ids
            .iter()
            .zip(data.chunks(usize::from(len)))
            .map(|(&id, d)| (id, d.to_vec()))
            .collect();
        prop_assert_eq!(seen, expected);

        // The fewest frames: one more servo would not fit a frame, so no
        // packing can use fewer than ceil(N / per-frame).
        let per = servos_per_frame(len);
        prop_assert!((per + 1) * (usize::from(len) + 1) + 4 > MAX_LENGTH_BYTE);
        prop_assert_eq!(frames, n.div_ceil(per));
        prop_assert_eq!(frames, sync_write_frames(n, len));
        // 8 bytes of overhead per frame, then each servo's ID and block.
        prop_assert_eq!(packed.len, 8 * frames + n * (usize::from(len) + 1));

        // The wire time is what the planner predicts for a write-only cycle.
        let link = Link::new(baud);
        let servos: Vec<Servo> = ids.iter().map(|&id| Servo::sts(id, Duration::ZERO)).collect();
        let p = plan(&link, &servos, Some(block), None, 1e-3).unwrap();
        prop_assert_eq!(p.bytes_per_cycle(), packed.len);
        prop_assert_eq!(p.full_cycle().wire_time, link.wire_time(packed.len));
        prop_assert_eq!(p.full_cycle().write_frames, frames);
    }
}
