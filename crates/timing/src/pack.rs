//! SYNC WRITE packing: the goals of N servos in the fewest frames whose
//! length byte stays at or below 255, written into a reused buffer.
//!
//! A SYNC WRITE frame of L-byte blocks to n servos is `8 + n(L + 1)` bytes
//! long and its length byte is `n(L + 1) + 4`, so one frame carries at most
//! `floor(251 / (L + 1))` servos: 83 for goal position only (L = 2), 35 for
//! position + time + speed (L = 6), 31 with acceleration (L = 7). Beyond that
//! the servos are split over several frames, filled greedily in the caller's
//! order; every frame but the last is full, which gives the fewest frames
//! and so the fewest bytes (each frame costs 8 bytes of overhead).

use core::ops::Range;

use servobus_protocol::{encode, frame_len, EncodeError, MAX_LENGTH_BYTE};

use crate::Block;

/// Why [`pack_sync_write`] could not pack the goals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PackError {
    /// No servos, or a block of zero bytes.
    #[error("nothing to pack: {servos} servos with {len}-byte blocks")]
    Empty {
        /// Servos given.
        servos: usize,
        /// Block length given.
        len: u8,
    },
    /// The block is too long for even one servo per frame (L > 250).
    #[error("a {len}-byte block does not fit in a SYNC WRITE frame (at most 250 bytes)")]
    BlockTooLong {
        /// Block length given.
        len: u8,
    },
    /// `data` does not hold exactly one block per ID.
    #[error("goal data has {actual} bytes, expected {expected} ({servos} servos x {len} bytes)")]
    DataLength {
        /// Servos given.
        servos: usize,
        /// Block length.
        len: u8,
        /// `servos * len`.
        expected: usize,
        /// `data.len()`.
        actual: usize,
    },
    /// The caller's buffer cannot hold all the frames.
    #[error("buffer too small: the frames need {needed} bytes, the buffer has {available}")]
    BufferTooSmall {
        /// Bytes the frames need ([`sync_write_bytes`]).
        needed: usize,
        /// Bytes the buffer has.
        available: usize,
    },
    /// The protocol encoder refused a frame (an ID outside 0..=253).
    #[error(transparent)]
    Encode(#[from] EncodeError),
}

/// The largest number of servos one SYNC WRITE frame can carry with `len`-byte
/// blocks (0 for `len == 0` or `len > 250`).
pub const fn servos_per_frame(len: u8) -> usize {
    // A table lookup: a division costs tens of cycles, and the packer asks
    // every control cycle.
    SERVOS_PER_FRAME[len as usize] as usize
}

/// [`servos_per_frame`] for every block length.
const SERVOS_PER_FRAME: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut len = 1;
    while len < 256 {
        // Length byte = n(L + 1) + 4 <= 255.
        table[len] = ((MAX_LENGTH_BYTE - 4) / (len + 1)) as u8;
        len += 1;
    }
    table
};

/// The fewest SYNC WRITE frames that carry `servos` servos with `len`-byte
/// blocks (0 when nothing can be packed).
pub const fn sync_write_frames(servos: usize, len: u8) -> usize {
    let per = servos_per_frame(len);
    if per == 0 {
        return 0;
    }
    servos.div_ceil(per)
}

/// Total bytes of the frames that carry `servos` servos with `len`-byte
/// blocks: 8 per frame plus `L + 1` per servo. Size the packing buffer with it.
pub const fn sync_write_bytes(servos: usize, len: u8) -> usize {
    let frames = sync_write_frames(servos, len);
    if frames == 0 {
        return 0;
    }
    frames * frame_len(2) + servos * (len as usize + 1)
}

/// Where [`pack_sync_write`] put the frames: back to back from the start of
/// the buffer, so `&buf[..packed.len]` is what goes on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Packed {
    /// Total bytes written.
    pub len: usize,
    /// Number of frames.
    pub frames: usize,
    /// Length of every frame but the last (all are full).
    full_frame_len: usize,
}

impl Packed {
    /// Byte range of frame `i` in the buffer, or `None` past the last frame.
    pub fn frame_range(&self, i: usize) -> Option<Range<usize>> {
        if i >= self.frames {
            return None;
        }
        let start = i * self.full_frame_len;
        let end = if i + 1 == self.frames {
            self.len
        } else {
            start + self.full_frame_len
        };
        Some(start..end)
    }

    /// The frames, one slice each, from the buffer they were packed into.
    pub fn frames<'b>(&self, buf: &'b [u8]) -> impl Iterator<Item = &'b [u8]> + 'b {
        let this = *self;
        (0..this.frames).filter_map(move |i| this.frame_range(i).and_then(|r| buf.get(r)))
    }
}

/// Packs the goals of `ids.len()` servos into the fewest SYNC WRITE frames,
/// written back to back at the start of `buf`.
///
/// `data` holds one block of `block.len` bytes per ID, in the order of
/// `ids` (servo `ids[i]` gets `data[i * L..(i + 1) * L]`). Nothing allocates:
/// reuse the same buffer every cycle, sized with [`sync_write_bytes`].
///
/// ```
/// use servobus_timing::{pack_sync_write, sync_write_bytes, Block};
///
/// let ids = [1u8, 2, 3];
/// let goals = [0x00, 0x08, 0x00, 0x04, 0xFF, 0x0B]; // 2048, 1024, 3071 (little-endian)
/// let mut buf = [0u8; 64];
/// let packed = pack_sync_write(&mut buf, Block::GOAL_POSITION, &ids, &goals).unwrap();
/// assert_eq!(packed.frames, 1);
/// assert_eq!(packed.len, sync_write_bytes(3, 2)); // 8 + 3 x 3 = 17 bytes
/// assert_eq!(&buf[..5], &[0xFF, 0xFF, 0xFE, 13, 0x83]);
/// ```
///
/// # Errors
/// [`PackError::Empty`], [`PackError::BlockTooLong`], [`PackError::DataLength`],
/// [`PackError::BufferTooSmall`] (checked before anything is written), or
/// [`PackError::Encode`] for an invalid ID (the buffer's contents are then
/// unspecified).
pub fn pack_sync_write(
    buf: &mut [u8],
    block: Block,
    ids: &[u8],
    data: &[u8],
) -> Result<Packed, PackError> {
    let per = check(block, ids, data)?;
    // The same figures as `sync_write_frames` / `sync_write_bytes`, without
    // their divisions: this runs every control cycle.
    let len = usize::from(block.len);
    let stride = len + 1;
    let full_frame_len = frame_len(2) + per * stride;
    if ids.len() <= per {
        // One frame: the usual case (up to 35 servos with 6-byte blocks).
        let needed = frame_len(2) + ids.len() * stride;
        if buf.len() < needed {
            return Err(PackError::BufferTooSmall {
                needed,
                available: buf.len(),
            });
        }
        let at = encode::sync_write_flat(buf, block.address, block.len, ids, data)?;
        return Ok(Packed {
            len: at,
            frames: 1,
            full_frame_len,
        });
    }
    let frames = ids.len().div_ceil(per);
    let needed = frames * frame_len(2) + ids.len() * stride;
    if buf.len() < needed {
        return Err(PackError::BufferTooSmall {
            needed,
            available: buf.len(),
        });
    }
    let mut at = 0;
    for chunk in chunks(block, per, ids, data) {
        at += chunk.pack(&mut buf[at..])?;
    }
    debug_assert_eq!(at, needed);
    Ok(Packed {
        len: at,
        frames,
        full_frame_len,
    })
}

/// The servos of one SYNC WRITE frame, as [`sync_write_chunks`] cuts them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Chunk<'a> {
    /// The block every servo gets.
    pub block: Block,
    /// The servos of this frame, at most [`servos_per_frame`] of them.
    pub ids: &'a [u8],
    /// Their blocks, back to back in the order of `ids`.
    pub data: &'a [u8],
}

impl Chunk<'_> {
    /// Packs this frame at the start of `buf`; returns its length. The
    /// request was checked when it was cut, so only the buffer and the IDs
    /// remain to check.
    ///
    /// # Errors
    /// [`PackError::BufferTooSmall`] (nothing written), or
    /// [`PackError::Encode`] for an invalid ID.
    #[inline]
    pub fn pack(&self, buf: &mut [u8]) -> Result<usize, PackError> {
        let Block { address, len } = self.block;
        encode::sync_write_flat(buf, address, len, self.ids, self.data).map_err(|e| match e {
            EncodeError::BufferTooSmall { needed, available } => {
                PackError::BufferTooSmall { needed, available }
            }
            e => PackError::Encode(e),
        })
    }
}

/// The frames [`pack_sync_write`] writes, one [`Chunk`] each, in order: for
/// a sender that packs one frame at a time straight into its own send
/// buffer ([`Chunk::pack`]) instead of packing them all first.
///
/// ```
/// use servobus_timing::{sync_write_chunks, Block};
///
/// let ids: [u8; 40] = core::array::from_fn(|i| i as u8);
/// let data = [0u8; 40 * 6];
/// let mut buf = [0u8; 256];
/// let mut sizes = Vec::new();
/// for chunk in sync_write_chunks(Block::POSITION_TIME_SPEED, &ids, &data).unwrap() {
///     let len = chunk.pack(&mut buf).unwrap();
///     assert_eq!(len, 8 + chunk.ids.len() * 7);
///     sizes.push(chunk.ids.len());
/// }
/// assert_eq!(sizes, [35, 5]);
/// ```
///
/// # Errors
/// As [`pack_sync_write`], except those about the buffer or the IDs, which
/// [`Chunk::pack`] reports.
#[inline]
pub fn sync_write_chunks<'a>(
    block: Block,
    ids: &'a [u8],
    data: &'a [u8],
) -> Result<impl Iterator<Item = Chunk<'a>> + 'a, PackError> {
    let per = check(block, ids, data)?;
    Ok(chunks(block, per, ids, data))
}

/// `ids` and `data` cut into frames of `per` servos.
#[inline]
fn chunks<'a>(block: Block, per: usize, ids: &'a [u8], data: &'a [u8]) -> Chunks<'a> {
    Chunks {
        block,
        per,
        ids,
        data,
    }
}

/// The iterator of [`sync_write_chunks`]. Cutting by hand, not by zipping
/// two `slice::chunks`: their zip divides to size itself, and this runs
/// every control cycle.
#[derive(Debug, Clone)]
struct Chunks<'a> {
    block: Block,
    per: usize,
    ids: &'a [u8],
    data: &'a [u8],
}

impl<'a> Iterator for Chunks<'a> {
    type Item = Chunk<'a>;

    #[inline]
    fn next(&mut self) -> Option<Chunk<'a>> {
        let n = self.per.min(self.ids.len());
        if n == 0 {
            return None;
        }
        let (ids, rest) = self.ids.split_at_checked(n)?;
        let (data, rest_data) = self
            .data
            .split_at_checked(n * usize::from(self.block.len))?;
        (self.ids, self.data) = (rest, rest_data);
        Some(Chunk {
            block: self.block,
            ids,
            data,
        })
    }
}

/// Checks a packing request; returns the servos one frame carries.
#[inline]
fn check(block: Block, ids: &[u8], data: &[u8]) -> Result<usize, PackError> {
    let len = usize::from(block.len);
    if ids.is_empty() || len == 0 {
        return Err(PackError::Empty {
            servos: ids.len(),
            len: block.len,
        });
    }
    let per = servos_per_frame(block.len);
    if per == 0 {
        return Err(PackError::BlockTooLong { len: block.len });
    }
    // Checked arithmetic is unneeded: `ids` is a real slice, so `ids.len() *
    // len` (len <= 250) is far below usize::MAX on any target that holds it.
    let expected = ids.len() * len;
    if data.len() != expected {
        return Err(PackError::DataLength {
            servos: ids.len(),
            len: block.len,
            expected,
            actual: data.len(),
        });
    }
    Ok(per)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn servos_per_frame_of_the_common_blocks() {
        assert_eq!(servos_per_frame(Block::GOAL_POSITION.len), 83);
        assert_eq!(servos_per_frame(Block::POSITION_TIME_SPEED.len), 35);
        assert_eq!(servos_per_frame(Block::ACCEL_POSITION_TIME_SPEED.len), 31);
        assert_eq!(servos_per_frame(1), 125);
        assert_eq!(servos_per_frame(250), 1);
        assert_eq!(servos_per_frame(251), 0);
        assert_eq!(servos_per_frame(0), 0);
    }

    #[test]
    fn frame_and_byte_counts() {
        // 6 servos, goal position: 8 + 6 x 3 = 26 bytes in one frame.
        assert_eq!(sync_write_bytes(6, 2), 26);
        // 84 servos x 2 bytes: 83 + 1 -> two frames, 16 + 84 x 3 = 268 bytes.
        assert_eq!(sync_write_frames(84, 2), 2);
        assert_eq!(sync_write_bytes(84, 2), 268);
        // 253 servos x 7 bytes: 31 per frame -> 9 frames.
        assert_eq!(sync_write_frames(253, 7), 9);
        assert_eq!(sync_write_bytes(253, 7), 9 * 8 + 253 * 8);
        assert_eq!(sync_write_bytes(0, 2), 0);
    }

    #[test]
    fn splits_at_the_length_limit() {
        let ids: [u8; 84] = core::array::from_fn(|i| i as u8);
        let data = [0x11u8; 84 * 2];
        let mut buf = [0u8; 300];
        let p = pack_sync_write(&mut buf, Block::GOAL_POSITION, &ids, &data).unwrap();
        assert_eq!(p.frames, 2);
        assert_eq!(p.frame_range(0), Some(0..257));
        assert_eq!(p.frame_range(1), Some(257..268));
        assert_eq!(p.frame_range(2), None);
        // 83 x 3 + 4 = 253; an 84th servo would make it 256.
        assert_eq!(buf[3], 253);
        assert_eq!(buf[257 + 3], 7);
        assert_eq!(p.frames(&buf).count(), 2);
    }

    #[test]
    fn a_250_byte_block_fills_the_length_byte_to_255() {
        let mut buf = [0u8; 2 * 259];
        let data = [7u8; 500];
        let p = pack_sync_write(&mut buf, Block::new(0, 250), &[1, 2], &data).unwrap();
        assert_eq!(p.frames, 2);
        assert_eq!(p.len, 2 * 259);
        assert_eq!((buf[3], buf[259 + 3]), (255, 255));
    }

    #[test]
    fn refuses_bad_input_before_writing() {
        let mut buf = [0u8; 16];
        let ids = [1u8, 2];
        assert_eq!(
            pack_sync_write(&mut buf, Block::GOAL_POSITION, &ids, &[0; 3]),
            Err(PackError::DataLength {
                servos: 2,
                len: 2,
                expected: 4,
                actual: 3
            })
        );
        assert_eq!(
            pack_sync_write(&mut buf, Block::POSITION_TIME_SPEED, &ids, &[0; 12]),
            Err(PackError::BufferTooSmall {
                needed: 22,
                available: 16
            })
        );
        assert_eq!(buf, [0u8; 16]);
        assert!(matches!(
            pack_sync_write(&mut buf, Block::GOAL_POSITION, &[], &[]),
            Err(PackError::Empty { .. })
        ));
        assert!(matches!(
            pack_sync_write(&mut buf, Block::GOAL_POSITION, &[254], &[0, 0]),
            Err(PackError::Encode(EncodeError::InvalidId { id: 254, .. }))
        ));
        assert_eq!(
            pack_sync_write(&mut buf, Block::new(0, 251), &[1], &[0; 251]),
            Err(PackError::BlockTooLong { len: 251 })
        );
    }
}
