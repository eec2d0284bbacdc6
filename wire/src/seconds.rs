//! A [`Duration`] in a settings file as its seconds (`idle_timeout_s = 2.5`), not serde's
//! `{secs, nanos}`: `#[serde(with = "wire::seconds")]`, or `wire::seconds::option` for an
//! `Option<Duration>`. A negative, infinite or NaN number of seconds is refused.

use serde::{Deserialize, Deserializer, Serializer};
use std::time::Duration;

pub fn serialize<S: Serializer>(duration: &Duration, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_f64(duration.as_secs_f64())
}

pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Duration, D::Error> {
    let seconds = f64::deserialize(deserializer)?;
    Duration::try_from_secs_f64(seconds).map_err(|_| {
        serde::de::Error::custom(format!(
            "{seconds} s is not a duration (a finite number of seconds ≥ 0)"
        ))
    })
}

/// The same for an `Option<Duration>` (absent or null: None).
pub mod option {
    use super::*;

    pub fn serialize<S: Serializer>(
        duration: &Option<Duration>,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        match duration {
            Some(d) => serializer.serialize_some(&d.as_secs_f64()),
            None => serializer.serialize_none(),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Option<Duration>, D::Error> {
        #[derive(Deserialize)]
        struct Seconds(#[serde(deserialize_with = "super::deserialize")] Duration);
        Ok(Option::<Seconds>::deserialize(deserializer)?.map(|Seconds(d)| d))
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    #[derive(serde::Serialize, serde::Deserialize, Debug, PartialEq)]
    struct Timeouts {
        #[serde(with = "super", rename = "interval_s")]
        interval: Duration,
        #[serde(with = "super::option", default, rename = "idle_s")]
        idle: Option<Duration>,
    }

    #[test]
    fn durations_are_seconds_and_bad_ones_are_refused() {
        let t = Timeouts {
            interval: Duration::from_millis(1500),
            idle: None,
        };
        let json = serde_json::to_string(&t).unwrap();
        assert_eq!(json, r#"{"interval_s":1.5,"idle_s":null}"#);
        assert_eq!(serde_json::from_str::<Timeouts>(&json).unwrap(), t);
        let back: Timeouts = serde_json::from_str(r#"{"interval_s":0.25,"idle_s":3}"#).unwrap();
        assert_eq!(back.idle, Some(Duration::from_secs(3)));
        assert_eq!(
            serde_json::from_str::<Timeouts>(r#"{"interval_s":1}"#)
                .unwrap()
                .idle,
            None
        );
        let error = serde_json::from_str::<Timeouts>(r#"{"interval_s":-1}"#).unwrap_err();
        assert!(
            error.to_string().contains("-1 s is not a duration"),
            "{error}"
        );
    }
}
