//! Settings written as one line of text in TOML and JSON: `text_serde!(T)` serializes a type
//! by its `Display` and deserializes it by its `FromStr`, whose error message is the one the
//! user reads (a region's polygon, a gauge, the control gauge).

macro_rules! text_serde {
    ($t:ty) => {
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.collect_str(self)
            }
        }

        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                use serde::de::Error as _;
                String::deserialize(d)?.parse().map_err(D::Error::custom)
            }
        }
    };
}
