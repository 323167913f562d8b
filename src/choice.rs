//! Enumerations chosen by name, in scene files and on the command line: one list of variants
//! and their names, from which serde (TOML, JSON) and the command line both read.
//!
//! [`choice!`](macro@crate::choice) declares such an enum; the command-line crate turns
//! [`Choice::NAMES`] into the values a flag accepts, so the library needs no argument parser.

/// An enum whose variants are picked by name.
pub trait Choice: Sized + Copy + 'static {
    /// Every variant, in the order of [`Choice::NAMES`].
    const ALL: &'static [Self];
    /// The name of each variant as written in files and flags.
    const NAMES: &'static [&'static str];

    /// The name of this variant.
    fn name(self) -> &'static str;

    /// The variant called `name`, if any.
    fn from_name(name: &str) -> Option<Self> {
        Self::NAMES.iter().position(|&n| n == name).map(|i| Self::ALL[i])
    }
}

/// Declares a [`Choice`] enum: `choice! { /// doc  pub enum Kind { /// doc  A = "a", B = "b", } }`.
/// Derives `Clone, Copy, Debug, PartialEq, Eq`, and implements serde's traits and `Display`
/// through the names.
#[macro_export]
macro_rules! choice {
    ($(#[$meta:meta])* pub enum $name:ident { $($(#[$vmeta:meta])* $variant:ident = $text:literal,)+ }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum $name {
            $($(#[$vmeta])* $variant,)+
        }

        impl $crate::choice::Choice for $name {
            const ALL: &'static [Self] = &[$($name::$variant),+];
            const NAMES: &'static [&'static str] = &[$($text),+];
            fn name(self) -> &'static str {
                match self {
                    $($name::$variant => $text,)+
                }
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::choice::Choice::name(*self))
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str($crate::choice::Choice::name(*self))
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let text = <String as serde::Deserialize>::deserialize(d)?;
                <$name as $crate::choice::Choice>::from_name(&text).ok_or_else(|| {
                    <D::Error as serde::de::Error>::unknown_variant(
                        &text,
                        <$name as $crate::choice::Choice>::NAMES,
                    )
                })
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::Choice;

    crate::choice! {
        /// A test enum.
        pub enum Fruit {
            Apple = "apple",
            /// With a doc comment.
            BloodOrange = "blood-orange",
        }
    }

    #[test]
    fn names_round_trip_through_serde_and_from_name() {
        for &f in Fruit::ALL {
            let json = serde_json::to_string(&f).unwrap();
            assert_eq!(json, format!("\"{}\"", f.name()));
            assert_eq!(serde_json::from_str::<Fruit>(&json).unwrap(), f);
            assert_eq!(Fruit::from_name(f.name()), Some(f));
        }
        assert_eq!(Fruit::from_name("pear"), None);
        let err = serde_json::from_str::<Fruit>("\"pear\"").unwrap_err().to_string();
        assert!(err.contains("unknown variant `pear`, expected `apple` or `blood-orange`"), "{err}");
        assert_eq!(Fruit::BloodOrange.to_string(), "blood-orange");
    }
}
