//! CDR as rmw_zenoh carries it: XCDR1 plain, little endian, behind the
//! 4-byte encapsulation header.
//!
//! ```text
//! 00 01 00 00 | field field ...
//! header      | offset 0 for alignment: a value of n bytes (n = 2, 4, 8)
//!             | starts at a multiple of n, zero padding before it
//! string      = u32 length (counting the NUL) + bytes + 00
//! sequence<T> = u32 count + count elements (no padding when count is 0)
//! T[N]        = N elements, no count
//! ```
//!
//! The reader never panics: every way a payload can be wrong (too short, a
//! count larger than the bytes left, a string that is not UTF-8 or does not
//! end with a NUL, a boolean that is neither 0 nor 1) is a [`CdrError`] naming the
//! field, as a path such as `points[2].time_from_start.nanosec`. A count is
//! checked against the bytes left before anything is allocated for it, so
//! a payload of n bytes never makes the reader hold more than a small
//! multiple of n.

use super::hash::TypeDescription;

/// The encapsulation header of CDR, little endian, no options.
pub const ENCAPSULATION: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Why a CDR payload could not be read: the field, and what was wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("CDR field `{field}`: {kind}")]
pub struct CdrError {
    /// Where: field names from the message down, with sequence indices,
    /// e.g. `goal.trajectory.points[3].positions`.
    pub field: String,
    /// What.
    pub kind: CdrErrorKind,
}

/// What was wrong with a CDR field.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CdrErrorKind {
    /// The payload ends before the field does.
    #[error("the payload ends at byte {at}, {needed} more bytes needed")]
    Truncated {
        /// Offset from the end of the header where the field starts.
        at: usize,
        /// Bytes missing.
        needed: usize,
    },
    /// The payload does not start with the header of little-endian CDR.
    #[error("the encapsulation header is {found:02x?}, not 00 01 00 00 (CDR, little endian)")]
    Encapsulation {
        /// The first bytes of the payload (fewer than 4 when it is shorter).
        found: Vec<u8>,
    },
    /// A sequence or string claims more elements than the bytes left hold.
    #[error("a count of {count} cannot fit in the {remaining} bytes left")]
    Count {
        /// The count on the wire.
        count: u32,
        /// Bytes left after the count.
        remaining: usize,
    },
    /// A string whose bytes are not UTF-8.
    #[error("the string is not UTF-8")]
    NotUtf8,
    /// A string whose last byte is not NUL.
    #[error("the string does not end with a NUL")]
    NoNul,
    /// A boolean that is neither 0 nor 1.
    #[error("{value} is not a boolean (0 or 1)")]
    NotBool {
        /// The byte found.
        value: u8,
    },
}

/// A message type that CDR can carry.
pub trait CdrMessage: Sized {
    /// The type's description, which names it and gives its hash.
    fn description() -> &'static TypeDescription;

    /// The fewest bytes one value takes on the wire, padding aside: what
    /// bounds the elements a sequence count can claim.
    const MIN_WIRE_SIZE: usize;

    /// Writes the fields, in order.
    fn write(&self, w: &mut CdrWriter);

    /// Reads the fields, in order.
    ///
    /// # Errors
    /// The first field that cannot be read, as a [`CdrError`].
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError>;

    /// The whole payload: header, then the fields.
    fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        self.write(&mut w);
        w.finish()
    }

    /// A value from a whole payload (header first). Bytes after the value
    /// are left unread, as DDS readers do.
    ///
    /// # Errors
    /// A wrong header or the first field that cannot be read.
    fn decode(payload: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(payload)?;
        Self::read(&mut r)
    }
}

/// Builds a CDR payload; alignment counts from after the header.
#[derive(Debug, Clone)]
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// A payload holding the header only.
    pub fn new() -> Self {
        CdrWriter {
            buf: ENCAPSULATION.to_vec(),
        }
    }

    /// The payload.
    pub fn finish(self) -> Vec<u8> {
        self.buf
    }

    fn align(&mut self, n: usize) {
        while !(self.buf.len() - ENCAPSULATION.len()).is_multiple_of(n) {
            self.buf.push(0);
        }
    }

    /// One byte.
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    /// One signed byte.
    pub fn i8(&mut self, v: i8) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A boolean as one byte, 0 or 1.
    pub fn bool(&mut self, v: bool) {
        self.buf.push(u8::from(v));
    }

    /// A u16, aligned to 2.
    pub fn u16(&mut self, v: u16) {
        self.align(2);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A u32, aligned to 4.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// An i32, aligned to 4.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// An i64, aligned to 8.
    pub fn i64(&mut self, v: i64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// An f64, aligned to 8.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// Bytes of a fixed-size array (no count, no alignment).
    pub fn bytes(&mut self, v: &[u8]) {
        self.buf.extend_from_slice(v);
    }

    /// A string: length with the NUL, the bytes, the NUL.
    pub fn string(&mut self, s: &str) {
        self.count(s.len() + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    /// The count of a sequence. A count beyond u32 cannot be written and
    /// is clamped; no message of this crate comes near it.
    pub fn count(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }

    /// A sequence of f64.
    pub fn f64_seq(&mut self, v: &[f64]) {
        self.count(v.len());
        for x in v {
            self.f64(*x);
        }
    }

    /// A sequence of strings.
    pub fn string_seq<S: AsRef<str>>(&mut self, v: &[S]) {
        self.count(v.len());
        for s in v {
            self.string(s.as_ref());
        }
    }

    /// A sequence of messages.
    pub fn seq<T: CdrMessage>(&mut self, v: &[T]) {
        self.count(v.len());
        for x in v {
            x.write(self);
        }
    }
}

/// One step of the path to the field being read.
#[derive(Debug, Clone, Copy)]
enum Step {
    Field(&'static str),
    Index(usize),
}

/// Reads a CDR payload; alignment counts from after the header.
#[derive(Debug)]
pub struct CdrReader<'a> {
    body: &'a [u8],
    pos: usize,
    path: Vec<Step>,
}

impl<'a> CdrReader<'a> {
    /// A reader past the header of `payload`. The header's last two bytes
    /// (options; some DDS writers count trailing padding there) change
    /// nothing in plain CDR and are not checked.
    ///
    /// # Errors
    /// [`CdrErrorKind::Encapsulation`] when the payload does not start
    /// with `00 01` (CDR, little endian) or is shorter than the header.
    pub fn new(payload: &'a [u8]) -> Result<Self, CdrError> {
        match payload.split_first_chunk::<4>() {
            Some((head, body)) if head[..2] == ENCAPSULATION[..2] => Ok(CdrReader {
                body,
                pos: 0,
                path: Vec::new(),
            }),
            _ => Err(CdrError {
                field: "(header)".into(),
                kind: CdrErrorKind::Encapsulation {
                    found: payload.iter().take(4).copied().collect(),
                },
            }),
        }
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.body.len().saturating_sub(self.pos)
    }

    fn error(&self, field: &'static str, kind: CdrErrorKind) -> CdrError {
        let mut path = String::new();
        for step in self.path.iter().copied().chain([Step::Field(field)]) {
            match step {
                Step::Field("") => {}
                Step::Field(name) => {
                    if !path.is_empty() {
                        path.push('.');
                    }
                    path.push_str(name);
                }
                Step::Index(i) => path.push_str(&format!("[{i}]")),
            }
        }
        CdrError { field: path, kind }
    }

    /// `n` bytes at the current position after aligning to `align`.
    fn take(&mut self, field: &'static str, n: usize, align: usize) -> Result<&'a [u8], CdrError> {
        let start = self.pos.next_multiple_of(align);
        match start.checked_add(n).filter(|end| *end <= self.body.len()) {
            Some(end) => {
                self.pos = end;
                Ok(&self.body[start..end])
            }
            None => Err(self.error(
                field,
                CdrErrorKind::Truncated {
                    at: start.min(self.body.len()),
                    needed: start.saturating_add(n).saturating_sub(self.body.len()),
                },
            )),
        }
    }

    fn array<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], CdrError> {
        let bytes = self.take(field, N, N.clamp(1, 8))?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        Ok(out)
    }

    /// One byte.
    pub fn u8(&mut self, field: &'static str) -> Result<u8, CdrError> {
        Ok(self.array::<1>(field)?[0])
    }

    /// One signed byte.
    pub fn i8(&mut self, field: &'static str) -> Result<i8, CdrError> {
        Ok(i8::from_le_bytes(self.array(field)?))
    }

    /// A boolean (0 or 1).
    pub fn bool(&mut self, field: &'static str) -> Result<bool, CdrError> {
        match self.u8(field)? {
            0 => Ok(false),
            1 => Ok(true),
            value => Err(self.error(field, CdrErrorKind::NotBool { value })),
        }
    }

    /// A u16.
    pub fn u16(&mut self, field: &'static str) -> Result<u16, CdrError> {
        Ok(u16::from_le_bytes(self.array(field)?))
    }

    /// A u32.
    pub fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        Ok(u32::from_le_bytes(self.array(field)?))
    }

    /// An i32.
    pub fn i32(&mut self, field: &'static str) -> Result<i32, CdrError> {
        Ok(i32::from_le_bytes(self.array(field)?))
    }

    /// An i64.
    pub fn i64(&mut self, field: &'static str) -> Result<i64, CdrError> {
        Ok(i64::from_le_bytes(self.array(field)?))
    }

    /// An f64.
    pub fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        Ok(f64::from_le_bytes(self.array(field)?))
    }

    /// A fixed array of 16 bytes (a UUID, a GID).
    pub fn bytes16(&mut self, field: &'static str) -> Result<[u8; 16], CdrError> {
        let bytes = self.take(field, 16, 1)?;
        let mut out = [0u8; 16];
        out.copy_from_slice(bytes);
        Ok(out)
    }

    /// A sequence's count, checked against the bytes left: each element
    /// takes at least `min_size` bytes.
    fn count(&mut self, field: &'static str, min_size: usize) -> Result<usize, CdrError> {
        let count = self.u32(field)?;
        let remaining = self.remaining();
        let fits = usize::try_from(count)
            .ok()
            .filter(|n| n.saturating_mul(min_size.max(1)) <= remaining);
        fits.ok_or_else(|| self.error(field, CdrErrorKind::Count { count, remaining }))
    }

    /// A string. A length of 0 (no bytes, not even the NUL) is read as
    /// the empty string, as Fast-CDR reads it.
    pub fn string(&mut self, field: &'static str) -> Result<String, CdrError> {
        let len = self.count(field, 1)?;
        let bytes = self.take(field, len, 1)?;
        match bytes.split_last() {
            None => Ok(String::new()),
            Some((0, text)) => match std::str::from_utf8(text) {
                Ok(s) => Ok(s.to_owned()),
                Err(_) => Err(self.error(field, CdrErrorKind::NotUtf8)),
            },
            Some(_) => Err(self.error(field, CdrErrorKind::NoNul)),
        }
    }

    /// A sequence of f64.
    pub fn f64_seq(&mut self, field: &'static str) -> Result<Vec<f64>, CdrError> {
        let n = self.count(field, 8)?;
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            out.push(self.f64(field)?);
        }
        Ok(out)
    }

    /// A sequence of strings.
    pub fn string_seq(&mut self, field: &'static str) -> Result<Vec<String>, CdrError> {
        let n = self.count(field, 5)?;
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            self.path.push(Step::Field(field));
            self.path.push(Step::Index(i));
            let s = self.string("");
            self.path.truncate(self.path.len() - 2);
            out.push(s?);
        }
        Ok(out)
    }

    /// A nested message.
    pub fn nested<T: CdrMessage>(&mut self, field: &'static str) -> Result<T, CdrError> {
        self.path.push(Step::Field(field));
        let out = T::read(self);
        self.path.pop();
        out
    }

    /// A sequence of messages.
    pub fn seq<T: CdrMessage>(&mut self, field: &'static str) -> Result<Vec<T>, CdrError> {
        let n = self.count(field, T::MIN_WIRE_SIZE)?;
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            self.path.push(Step::Field(field));
            self.path.push(Step::Index(i));
            let item = T::read(self);
            self.path.truncate(self.path.len() - 2);
            out.push(item?);
        }
        Ok(out)
    }
}
