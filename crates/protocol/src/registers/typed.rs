//! Typed registers: [`Reg<T>`] is a [`Register`] that knows the Rust type of
//! its value, so that a program reads `present_position` as an `i16` and can
//! neither forget the sign bit nor write a value of the wrong width.

use core::marker::PhantomData;
use core::ops::Deref;

use super::{ByteOrder, Register, ValueError};

mod sealed {
    pub trait Sealed {}
    impl Sealed for u8 {}
    impl Sealed for u16 {}
    impl Sealed for i16 {}
}

/// A Rust type a register's value is read as: `u8` for one-byte registers,
/// `u16` for unsigned two-byte registers, `i16` for sign-magnitude ones.
///
/// Sealed: the register tables decide which type each register has.
pub trait RegisterValue:
    Copy + PartialEq + core::fmt::Debug + core::fmt::Display + sealed::Sealed
{
    /// Bytes of a register of this type.
    const SIZE: u8;
    /// Whether registers of this type are sign-magnitude.
    const SIGNED: bool;
    /// The value as the register tables count it.
    fn to_i32(self) -> i32;
    /// The value from a decoded register value (always in range: a decoded
    /// value fits its register, and its register fits this type).
    fn from_i32(value: i32) -> Self;
}

/// Implements [`RegisterValue`] for an integer type of `$size` bytes.
macro_rules! register_value {
    ($($ty:ty: $size:literal, $signed:literal;)*) => {$(
        impl RegisterValue for $ty {
            const SIZE: u8 = $size;
            const SIGNED: bool = $signed;
            fn to_i32(self) -> i32 {
                i32::from(self)
            }
            fn from_i32(value: i32) -> Self {
                value as $ty
            }
        }
    )*};
}

register_value! {
    u8: 1, false;
    u16: 2, false;
    i16: 2, true;
}

/// A register whose value is a `T`: one of the constants of
/// [`sts`](super::sts) and [`scs`](super::scs).
///
/// It dereferences to its [`Register`] (address, size, access, ...).
///
/// ```
/// use servobus_protocol::registers::{sts, ByteOrder};
///
/// let pos = sts::PRESENT_POSITION;
/// assert_eq!((pos.address, pos.size), (56, 2));
/// // Sign-magnitude: bit 15 set, magnitude 100.
/// assert_eq!(pos.decode_value(&[0x64, 0x80], ByteOrder::Little), Ok(-100i16));
/// let mut out = [0u8; 2];
/// sts::GOAL_POSITION.encode_value(-100, ByteOrder::Little, &mut out).unwrap();
/// assert_eq!(out, [0x64, 0x80]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Reg<T> {
    pub(crate) register: Register,
    value: PhantomData<fn() -> T>,
}

impl<T: RegisterValue> Reg<T> {
    /// The register `register`, read as a `T`.
    ///
    /// # Panics
    /// When the register's size or signedness does not match `T` (at
    /// compile time, for the constants of the tables).
    pub const fn new(register: Register) -> Self {
        assert!(
            register.size == T::SIZE,
            "register size does not match its type"
        );
        assert!(
            register.sign_bit.is_some() == T::SIGNED,
            "register signedness does not match its type"
        );
        Reg {
            register,
            value: PhantomData,
        }
    }

    /// The untyped register.
    pub const fn register(&self) -> &Register {
        &self.register
    }

    /// The factory value as a `T`.
    pub fn factory_value(&self) -> T {
        T::from_i32(self.register.from_raw(u32::from(self.register.factory)))
    }

    /// Decodes the register's bytes as a `T`.
    ///
    /// # Errors
    /// [`ValueError::Length`] when `bytes` is not the register's size.
    pub fn decode_value(&self, bytes: &[u8], order: ByteOrder) -> Result<T, ValueError> {
        self.register.decode(bytes, order).map(T::from_i32)
    }

    /// Encodes `value` into `out` (the register's size).
    ///
    /// # Errors
    /// [`ValueError::OutOfRange`] when `value` does not fit (e.g. an offset
    /// beyond +-2047), [`ValueError::Length`] when `out` is not the
    /// register's size.
    pub fn encode_value(
        &self,
        value: T,
        order: ByteOrder,
        out: &mut [u8],
    ) -> Result<(), ValueError> {
        self.register.encode(value.to_i32(), order, out)
    }
}

impl<T> Deref for Reg<T> {
    type Target = Register;

    fn deref(&self) -> &Register {
        &self.register
    }
}
