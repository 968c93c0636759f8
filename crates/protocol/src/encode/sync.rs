//! The SYNC WRITE encoders: one block per servo in one broadcast frame, the
//! request of every control cycle, so both are written for speed.

use super::{check_buf, check_id, check_params, finish, start, EncodeError};
use crate::{is_servo_id, Instruction, BROADCAST_ID};

/// Parameter bytes of a SYNC WRITE to `servos` servos with `len` bytes each.
#[inline]
pub const fn sync_write_params(servos: usize, len: usize) -> usize {
    2 + servos * (len + 1)
}

/// SYNC WRITE a block of `len` bytes at `address` to every `(id, data)` of
/// `items`; each `data` must be exactly `len` bytes long.
///
/// The frame is built in place; on error the buffer's contents are
/// unspecified.
///
/// # Errors
/// [`EncodeError::Empty`] for `len == 0` or no items, [`EncodeError::InvalidId`],
/// [`EncodeError::DataLength`], [`EncodeError::FrameTooLong`] (the length byte
/// would pass 255: split the servos over several frames) or
/// [`EncodeError::BufferTooSmall`].
#[inline]
pub fn sync_write<'d, I>(
    buf: &mut [u8],
    address: u8,
    len: u8,
    items: I,
) -> Result<usize, EncodeError>
where
    I: IntoIterator<Item = (u8, &'d [u8])>,
{
    if len == 0 {
        return Err(EncodeError::Empty { what: "SYNC WRITE" });
    }
    let block = usize::from(len) + 1;
    let mut params = 2usize;
    let mut servos = 0usize;
    // Once the buffer is too small, the remaining items are still checked and
    // counted (not written) so that the error gives the exact size needed.
    let mut overflow = false;
    for (id, data) in items {
        check_id(id, false)?;
        if data.len() != usize::from(len) {
            return Err(EncodeError::DataLength {
                id,
                expected: usize::from(len),
                actual: data.len(),
            });
        }
        let at = 5 + params;
        params += block;
        // Length errors take precedence over buffer errors so that callers
        // learn the frame must be split, whatever their buffer size.
        let length = params + 2;
        if length > crate::MAX_LENGTH_BYTE {
            return Err(EncodeError::FrameTooLong {
                length,
                excess: length - crate::MAX_LENGTH_BYTE,
            });
        }
        servos += 1;
        // The block ends at `at + block`; the checksum needs one more byte.
        overflow |= at + block >= buf.len();
        if !overflow {
            buf[at] = id;
            copy_block(&mut buf[at + 1..at + block], data);
        }
    }
    if servos == 0 {
        return Err(EncodeError::Empty { what: "SYNC WRITE" });
    }
    check_buf(buf, params)?;
    start(buf, BROADCAST_ID, params, Instruction::SyncWrite.code());
    buf[5] = address;
    buf[6] = len;
    // One pass over the finished frame: the sum vectorises, which is faster
    // than summing byte by byte while copying each short block.
    Ok(finish(buf, params))
}

/// Copies a SYNC WRITE block (`dst` and `src` have the same length).
///
/// Blocks are usually 1 to 8 bytes: a copy of constant length compiles to a
/// couple of moves, where a `memcpy` call per servo would dominate the cost
/// of the whole frame.
#[inline(always)]
fn copy_block(dst: &mut [u8], src: &[u8]) {
    macro_rules! fixed {
        ($($n:literal)*) => {
            match src.len() {
                $($n => dst[..$n].copy_from_slice(&src[..$n]),)*
                _ => dst.copy_from_slice(src),
            }
        };
    }
    fixed!(1 2 3 4 5 6 7 8);
}

/// SYNC WRITE from flat slices, the shape a control loop keeps its goals
/// in: servo `ids[i]` gets `data[i * len..(i + 1) * len]`.
///
/// The frame is byte for byte the one [`sync_write`] builds from the same
/// servos; this form checks the whole request before writing and then
/// copies with no per-servo checks, which makes it the faster of the two.
/// On error the buffer is untouched.
///
/// # Errors
/// [`EncodeError::Empty`] for `len == 0` or no IDs;
/// [`EncodeError::DataLength`] when `data` is not `ids.len()` blocks of
/// `len` bytes (naming the first servo whose block is incomplete, or the
/// last one when there are bytes to spare); [`EncodeError::FrameTooLong`]
/// with the length byte the whole frame would need;
/// [`EncodeError::InvalidId`] for the first invalid ID;
/// [`EncodeError::BufferTooSmall`].
pub fn sync_write_flat(
    buf: &mut [u8],
    address: u8,
    len: u8,
    ids: &[u8],
    data: &[u8],
) -> Result<usize, EncodeError> {
    let l = usize::from(len);
    if l == 0 || ids.is_empty() {
        return Err(EncodeError::Empty { what: "SYNC WRITE" });
    }
    if data.len() != ids.len() * l {
        // Servo `k` is the first whose block is incomplete; with bytes to
        // spare, the last servo's block is the one that is too long.
        let k = (data.len() / l).min(ids.len() - 1);
        return Err(EncodeError::DataLength {
            id: ids[k],
            expected: l,
            actual: data.len() - k * l,
        });
    }
    let params = sync_write_params(ids.len(), l);
    check_params(params)?;
    // The largest ID decides validity: a branch-free pass.
    if !is_servo_id(ids.iter().fold(0, |m, &id| m.max(id))) {
        if let Some(&id) = ids.iter().find(|&&id| !is_servo_id(id)) {
            return Err(EncodeError::InvalidId {
                id,
                broadcast_allowed: false,
            });
        }
    }
    check_buf(buf, params)?;
    start(buf, BROADCAST_ID, params, Instruction::SyncWrite.code());
    buf[5] = address;
    buf[6] = len;
    let body = &mut buf[7..5 + params];
    // One loop per common block length, each with copies of constant size.
    match l {
        1 => interleave::<1>(body, ids, data),
        2 => interleave::<2>(body, ids, data),
        3 => interleave::<3>(body, ids, data),
        4 => interleave::<4>(body, ids, data),
        5 => interleave::<5>(body, ids, data),
        6 => interleave::<6>(body, ids, data),
        7 => interleave::<7>(body, ids, data),
        8 => interleave::<8>(body, ids, data),
        _ => {
            for ((slot, &id), block) in body
                .chunks_exact_mut(l + 1)
                .zip(ids)
                .zip(data.chunks_exact(l))
            {
                slot[0] = id;
                slot[1..].copy_from_slice(block);
            }
        }
    }
    Ok(finish(buf, params))
}

/// Writes `id, block` for every servo into `body` (blocks of `N` bytes;
/// `body` holds `ids.len()` slots of `N + 1` bytes).
#[inline(always)]
fn interleave<const N: usize>(body: &mut [u8], ids: &[u8], data: &[u8]) {
    for ((slot, &id), block) in body
        .chunks_exact_mut(N + 1)
        .zip(ids)
        .zip(data.chunks_exact(N))
    {
        slot[0] = id;
        slot[1..=N].copy_from_slice(&block[..N]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sync_write_refuses_wrong_block_and_long_frames() {
        let mut buf = [0u8; 300];
        let err = sync_write(&mut buf, 42, 2, [(1u8, &[0u8, 1][..]), (2, &[0u8][..])]);
        assert_eq!(
            err,
            Err(EncodeError::DataLength {
                id: 2,
                expected: 2,
                actual: 1
            })
        );
        // 84 servos x 3 bytes + 2 = 254 params: length byte 256.
        let data = [0u8; 2];
        let items = (0..84u8).map(|id| (id, &data[..]));
        assert_eq!(
            sync_write(&mut buf, 42, 2, items),
            Err(EncodeError::FrameTooLong {
                length: 256,
                excess: 1
            })
        );
        let items = (0..83u8).map(|id| (id, &data[..]));
        assert_eq!(sync_write(&mut buf, 42, 2, items), Ok(6 + 2 + 83 * 3));
        assert_eq!(
            sync_write(&mut buf, 42, 2, [(254u8, &data[..])]),
            Err(EncodeError::InvalidId {
                id: 254,
                broadcast_allowed: false
            })
        );
    }

    #[test]
    fn flat_sync_write_checks_the_whole_request_first() {
        let mut buf = [0u8; 300];
        let e = |id, actual| {
            Err(EncodeError::DataLength {
                id,
                expected: 2,
                actual,
            })
        };
        // Servo 2's block is incomplete; servo 3 has no data at all.
        assert_eq!(
            sync_write_flat(&mut buf, 42, 2, &[1, 2, 3], &[0; 3]),
            e(2, 1)
        );
        assert_eq!(
            sync_write_flat(&mut buf, 42, 2, &[1, 2, 3], &[0; 4]),
            e(3, 0)
        );
        // A byte to spare: the last servo's block is too long.
        assert_eq!(sync_write_flat(&mut buf, 42, 2, &[1, 2], &[0; 5]), e(2, 3));
        let empty = Err(EncodeError::Empty { what: "SYNC WRITE" });
        assert_eq!(sync_write_flat(&mut buf, 42, 0, &[1], &[]), empty);
        assert_eq!(sync_write_flat(&mut buf, 42, 2, &[], &[]), empty);
        let mut ids = [0u8; 84];
        for (i, id) in ids.iter_mut().enumerate() {
            *id = i as u8;
        }
        assert_eq!(
            sync_write_flat(&mut buf, 42, 2, &ids, &[0; 168]),
            Err(EncodeError::FrameTooLong {
                length: 256,
                excess: 1
            })
        );
        // Nothing is written when an ID is invalid.
        let before = buf;
        assert_eq!(
            sync_write_flat(&mut buf, 42, 2, &[1, 255], &[0; 4]),
            Err(EncodeError::InvalidId {
                id: 255,
                broadcast_allowed: false
            })
        );
        assert_eq!(buf, before);
        assert_eq!(
            sync_write_flat(&mut buf[..10], 42, 2, &[1, 2], &[0; 4]),
            Err(EncodeError::BufferTooSmall {
                needed: 14,
                available: 10
            })
        );
        // The manual's example: the same bytes as the iterator form.
        let data = [
            0x00, 0x08, 0x00, 0x00, 0xE8, 0x03, 0x00, 0x08, 0x00, 0x00, 0xE8, 0x03,
        ];
        let n = sync_write_flat(&mut buf, 0x2A, 6, &[1, 2], &data).expect("valid");
        let mut other = [0u8; 64];
        let items = [(1u8, &data[..6]), (2, &data[6..])];
        let m = sync_write(&mut other, 0x2A, 6, items).expect("valid");
        assert_eq!(buf[..n], other[..m]);
    }
}
