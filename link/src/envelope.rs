//! What travels beside a sample's bytes (Zenoh's attachment): how many ids right before this
//! sample its sender knowingly did not send (missing at its source, or held back by the rate
//! limit), so that the receiver counts as lost only what the link lost.

/// The attachment: `skipped_ids` as 8 little-endian bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Envelope {
    pub skipped_ids: u64,
}

/// An attachment of the wrong size (a sender of another version, or not dicstream's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("a link sample's attachment has {0} bytes, expected 8")]
pub struct EnvelopeError(pub usize);

impl Envelope {
    pub fn to_bytes(self) -> [u8; 8] {
        self.skipped_ids.to_le_bytes()
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Envelope, EnvelopeError> {
        let bytes: [u8; 8] = bytes.try_into().map_err(|_| EnvelopeError(bytes.len()))?;
        Ok(Envelope {
            skipped_ids: u64::from_le_bytes(bytes),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_a_wrong_size_refused() {
        let envelope = Envelope { skipped_ids: 3 };
        assert_eq!(Envelope::from_bytes(&envelope.to_bytes()), Ok(envelope));
        assert_eq!(Envelope::from_bytes(&[0; 4]), Err(EnvelopeError(4)));
    }
}
