//! Enums with a fixed name per variant, parsed from and printed as that name (command-line
//! options, scene files, script commands): one macro instead of a hand-written `FromStr` and
//! `name()` per enum.

/// A name that matches no variant.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} {given:?} (expected one of: {})", choices.join(", "))]
pub struct UnknownName {
    /// What the enum names ("render mode", ...).
    pub what: &'static str,
    pub given: String,
    pub choices: &'static [&'static str],
}

/// Declares an enum whose variants each have a name: `ALL` lists the variants, `name()` gives
/// a variant's name, and `FromStr` / `Display` parse and print it.
///
/// ```
/// foundation::named_enum! {
///     /// A colour.
///     pub enum Colour ("colour") {
///         Red = "red",
///         Green = "green",
///     }
/// }
/// assert_eq!("green".parse::<Colour>(), Ok(Colour::Green));
/// assert_eq!(Colour::Red.name(), "red");
/// assert!("blue".parse::<Colour>().unwrap_err().to_string().contains("red, green"));
/// ```
#[macro_export]
macro_rules! named_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident ($what:literal) {
            $( $(#[$variant_meta:meta])* $variant:ident = $text:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        $vis enum $name {
            $( $(#[$variant_meta])* $variant ),+
        }

        impl $name {
            /// Every variant, in declaration order.
            pub const ALL: [$name; [$($text),+].len()] = [$($name::$variant),+];

            /// The variant's name (what `FromStr` accepts).
            pub fn name(self) -> &'static str {
                match self {
                    $( $name::$variant => $text ),+
                }
            }
        }

        impl ::std::str::FromStr for $name {
            type Err = $crate::infra::named_enum::UnknownName;
            fn from_str(s: &str) -> ::std::result::Result<Self, Self::Err> {
                $name::ALL
                    .iter()
                    .copied()
                    .find(|v| v.name() == s)
                    .ok_or_else(|| $crate::infra::named_enum::UnknownName {
                        what: $what,
                        given: s.to_owned(),
                        choices: &[$($text),+],
                    })
            }
        }

        impl ::std::fmt::Display for $name {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}
