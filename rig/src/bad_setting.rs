//! A setting outside what it may be, as a library refuses it: its name, the value as given and
//! what is expected (`stale_s 0: expected a positive number`).

/// A setting refused with its name, its value and what would do.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{key} {value}: expected {expected}")]
pub struct BadSetting {
    pub key: &'static str,
    /// The value as given (`[0.1, 0.9]`, `NaN`).
    pub value: String,
    pub expected: &'static str,
}

impl BadSetting {
    pub fn new(key: &'static str, value: impl std::fmt::Debug, expected: &'static str) -> Self {
        BadSetting {
            key,
            value: format!("{value:?}"),
            expected,
        }
    }
}
