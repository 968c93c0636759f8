//! The fixed names of the protocol's small enums (instructions, series,
//! register access) and the `Display` that prints them, declared once.

/// Implements `name()`, a `const fn` giving each variant of a fieldless
/// enum its one fixed name, and a `Display` that prints that name.
macro_rules! named {
    ($(#[$doc:meta])* $ty:ident { $($variant:ident => $name:literal),* $(,)? }) => {
        impl $ty {
            $(#[$doc])*
            pub const fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)*
                }
            }
        }

        impl core::fmt::Display for $ty {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}
