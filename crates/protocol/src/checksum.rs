//! The packet checksum.

/// The checksum of a frame body: the bitwise NOT of the low byte of the sum of
/// `bytes`, which are the ID, length, instruction (or error) and parameters,
/// i.e. everything between the header and the checksum byte.
///
/// ```
/// // PING to servo 1: FF FF 01 02 01 FB
/// assert_eq!(servobus_protocol::checksum(&[0x01, 0x02, 0x01]), 0xFB);
/// ```
#[inline]
pub fn checksum(bytes: &[u8]) -> u8 {
    !bytes.iter().fold(0u8, |acc, &b| acc.wrapping_add(b))
}
