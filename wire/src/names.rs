//! Named choices: an enum whose values a user writes as words (`method = "icgn1"`,
//! `--strain green`, `source = "csv-follow"`). One definition per enum, [`named!`], gives its
//! names and aliases, `Display`, `FromStr` (an [`UnknownName`] listing what is expected), and
//! serde's `Serialize`/`Deserialize` as the same words, so the configuration file, the command
//! line and the results spell a choice one way and refuse a typo with the same message.

use thiserror::Error;

/// An enum of named choices (implemented by [`named!`]).
pub trait Named: Copy + Sized + 'static {
    /// What the choice is, for messages (`"method"`).
    const WHAT: &'static str;
    /// Every value, in the order they are listed to a user.
    const ALL: &'static [Self];
    /// The name a value is written as (also its `Display`).
    fn name(self) -> &'static str;
    /// Other spellings accepted on input.
    fn aliases(self) -> &'static [&'static str];
    /// Whether input is matched regardless of ASCII case (`mono12`); units are not.
    const IGNORE_CASE: bool = false;

    /// The value written `text` (its name or an alias, surrounding blanks ignored).
    fn parse_name(text: &str) -> Result<Self, UnknownName> {
        let text = text.trim();
        Self::ALL
            .iter()
            .copied()
            .find(|v| {
                let same = |name: &&str| match Self::IGNORE_CASE {
                    true => name.eq_ignore_ascii_case(text),
                    false => *name == text,
                };
                same(&v.name()) || v.aliases().iter().any(same)
            })
            .ok_or_else(|| UnknownName {
                what: Self::WHAT,
                given: text.to_string(),
                expected: Self::expected(),
            })
    }

    /// The names, as a user reads them: `a, b or c`.
    fn expected() -> String {
        expected_list(Self::ALL.iter().map(|v| v.name()))
    }
}

/// A word that names none of a choice's values.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
#[error("{what} {given:?}: expected {expected}")]
pub struct UnknownName {
    pub what: &'static str,
    pub given: String,
    pub expected: String,
}

/// `a`, `a or b`, `a, b or c`.
pub fn expected_list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let names: Vec<&str> = names.collect();
    match names.split_last() {
        None => String::new(),
        Some((last, [])) => (*last).to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

#[doc(hidden)]
pub use serde as __serde;

/// Implements [`Named`], `Display`, `FromStr` and serde for a field-less enum:
/// `wire::named!(Method, "method", { Correli => "correli", Icgn1 => "icgn1" | "icgn" });`
/// (the first word is the name, the others aliases accepted on input); with `ignore_case`
/// after the description, input is matched regardless of ASCII case.
#[macro_export]
macro_rules! named {
    ($t:ty, $what:literal, ignore_case, { $($body:tt)* }) => {
        $crate::named!(@impl $t, $what, true, { $($body)* });
    };
    ($t:ty, $what:literal, { $($body:tt)* }) => {
        $crate::named!(@impl $t, $what, false, { $($body)* });
    };
    (@unit $v:ident) => { () };
    (@impl $t:ty, $what:literal, $ignore_case:literal,
     { $($v:ident => $name:literal $(| $alias:literal)*),+ $(,)? }) => {
        impl $crate::names::Named for $t {
            const WHAT: &'static str = $what;
            const IGNORE_CASE: bool = $ignore_case;
            const ALL: &'static [Self] = &<$t>::ALL;
            fn name(self) -> &'static str {
                match self { $(<$t>::$v => $name),+ }
            }
            fn aliases(self) -> &'static [&'static str] {
                match self { $(<$t>::$v => &[$($alias),*]),+ }
            }
        }
        impl $t {
            /// Every value, in the order they are listed to a user.
            #[allow(dead_code)]
            pub const ALL: [Self; <[()]>::len(&[$($crate::named!(@unit $v)),+])] = [$(<$t>::$v),+];
            /// The name a value is written as.
            #[allow(dead_code)]
            pub fn name(self) -> &'static str {
                <$t as $crate::names::Named>::name(self)
            }
        }
        impl ::std::fmt::Display for $t {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str($crate::names::Named::name(*self))
            }
        }
        impl ::std::str::FromStr for $t {
            type Err = $crate::names::UnknownName;
            fn from_str(text: &str) -> Result<Self, Self::Err> {
                <$t as $crate::names::Named>::parse_name(text)
            }
        }
        impl $crate::names::__serde::Serialize for $t {
            fn serialize<S: $crate::names::__serde::Serializer>(
                &self,
                s: S,
            ) -> Result<S::Ok, S::Error> {
                s.serialize_str($crate::names::Named::name(*self))
            }
        }
        impl<'de> $crate::names::__serde::Deserialize<'de> for $t {
            fn deserialize<D: $crate::names::__serde::Deserializer<'de>>(
                d: D,
            ) -> Result<Self, D::Error> {
                let text = <String as $crate::names::__serde::Deserialize>::deserialize(d)?;
                <$t as $crate::names::Named>::parse_name(&text)
                    .map_err(<D::Error as $crate::names::__serde::de::Error>::custom)
            }
        }
    };
}

/// serde for a value written as its `Display` and read by its `FromStr` (an address, a
/// region `x,y,w,h`, a list of models): `#[serde(with = "wire::names::text")]`.
pub mod text {
    use serde::{de::Error as _, Deserialize, Deserializer, Serializer};
    use std::fmt::Display;
    use std::str::FromStr;

    pub fn serialize<T: Display, S: Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(value)
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<T, D::Error>
    where
        T: FromStr,
        T::Err: Display,
        D: Deserializer<'de>,
    {
        String::deserialize(d)?.parse().map_err(D::Error::custom)
    }
}

/// serde for an `Option` written `""` when absent (`force_unit = ""`: as the header says):
/// `#[serde(with = "wire::names::empty_is_none")]`; a value as in [`text`].
pub mod empty_is_none {
    use serde::{de::Error as _, Deserialize, Deserializer, Serializer};
    use std::fmt::Display;
    use std::str::FromStr;

    pub fn serialize<T: Display, S: Serializer>(
        value: &Option<T>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        match value {
            Some(v) => s.collect_str(v),
            None => s.serialize_str(""),
        }
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<Option<T>, D::Error>
    where
        T: FromStr,
        T::Err: Display,
        D: Deserializer<'de>,
    {
        let text = String::deserialize(d)?;
        if text.trim().is_empty() {
            return Ok(None);
        }
        text.parse().map(Some).map_err(D::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Colour {
        Red,
        DarkBlue,
    }
    crate::named!(Colour, "colour", { Red => "red", DarkBlue => "dark_blue" | "navy" });

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Format {
        Mono8,
    }
    crate::named!(Format, "pixel format", ignore_case, { Mono8 => "Mono8" });

    #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    struct Holder {
        colour: Colour,
        #[serde(with = "empty_is_none")]
        other: Option<Colour>,
    }

    #[test]
    fn names_aliases_and_refusals() {
        assert_eq!("navy".parse::<Colour>(), Ok(Colour::DarkBlue));
        assert_eq!(" red ".parse::<Colour>(), Ok(Colour::Red));
        assert!("RED".parse::<Colour>().is_err());
        assert_eq!("mono8".parse::<Format>(), Ok(Format::Mono8));
        assert_eq!(Colour::DarkBlue.to_string(), "dark_blue");
        let refused = "blue".parse::<Colour>().unwrap_err().to_string();
        assert_eq!(refused, "colour \"blue\": expected red or dark_blue");
        assert_eq!(expected_list(["a", "b", "c"].into_iter()), "a, b or c");
    }

    #[test]
    fn serde_writes_and_reads_the_names() {
        let h: Holder = serde_json::from_str(r#"{"colour":"navy","other":""}"#).unwrap();
        assert_eq!(
            h,
            Holder {
                colour: Colour::DarkBlue,
                other: None
            }
        );
        let back = serde_json::to_string(&Holder {
            colour: Colour::Red,
            other: Some(Colour::DarkBlue),
        })
        .unwrap();
        assert_eq!(back, r#"{"colour":"red","other":"dark_blue"}"#);
        let e = serde_json::from_str::<Holder>(r#"{"colour":"blue","other":""}"#).unwrap_err();
        assert!(e.to_string().contains("expected red or dark_blue"), "{e}");
    }
}
