//! Option enums whose command-line, viewer and scene-file spelling is written once, beside the
//! variant: [`named_enum!`] derives `ALL`, `name()`, `FromStr`, `Display`, serde and (with the `clap`
//! feature) clap's `ValueEnum` from it.

/// Declares an option enum with each variant's spelling:
///
/// ```ignore
/// named_enum! {
///     /// Doc.
///     pub enum Mode { #[default] /// Doc. Fast = "fast", Slow = "slow" }
/// }
/// ```
///
/// A variant may carry a discriminant shared with WGSL: `Fast(0) = "fast"`.
#[macro_export]
macro_rules! named_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident {
            $( $(#[$vmeta:meta])* $variant:ident $(($disc:expr))? = $spelling:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
        $vis enum $name {
            $( $(#[$vmeta])* $variant $(= $disc)? ),+
        }

        impl $name {
            pub const ALL: [$name; [$(stringify!($variant)),+].len()] = [$($name::$variant),+];

            /// The spelling on the command line, in the viewer and in scene files.
            pub fn name(self) -> &'static str {
                match self {
                    $($name::$variant => $spelling),+
                }
            }
        }

        impl $crate::settings::named::Named for $name {
            fn all() -> &'static [Self] {
                &Self::ALL
            }

            fn name(self) -> &'static str {
                $name::name(self)
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $name {
            type Err = String;

            /// The variant spelled `s`; the error lists the spellings.
            fn from_str(s: &str) -> Result<Self, String> {
                use $crate::settings::named::Named;
                Self::named(s).ok_or_else(|| format!("{s:?}: use {}", Self::choices("\"")))
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                serializer.serialize_str(self.name())
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                let s = <std::borrow::Cow<'de, str>>::deserialize(deserializer)?;
                s.parse().map_err(serde::de::Error::custom)
            }
        }

        #[cfg(feature = "clap")]
        impl clap::ValueEnum for $name {
            fn value_variants<'a>() -> &'a [Self] {
                &Self::ALL
            }

            fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
                Some(clap::builder::PossibleValue::new(self.name()))
            }
        }
    };
}

/// An option enum declared with [`named_enum!`].
pub trait Named: Copy + 'static {
    /// Every variant, in the order of the declaration.
    fn all() -> &'static [Self];
    /// The variant's spelling.
    fn name(self) -> &'static str;

    /// Every spelling, each between `quote`s, as a list: "a, b or c".
    fn choices(quote: &str) -> String {
        let names: Vec<String> = Self::all().iter().map(|v| format!("{quote}{}{quote}", v.name())).collect();
        match names.as_slice() {
            [] => String::new(),
            [only] => only.clone(),
            [init @ .., last] => format!("{} or {last}", init.join(", ")),
        }
    }

    /// The variant spelled `s`.
    fn named(s: &str) -> Option<Self> {
        Self::all().iter().copied().find(|v| v.name() == s)
    }
}
