//! What travels beside a sample's bytes (Zenoh's attachment): which sender it is (a number
//! drawn at its start) and how many ids, in all since that start, it knowingly did not send
//! (missing at its source, or held back by the rate limit), so that the receiver counts as
//! lost only what the link lost. A running total, not the count before this sample: a sample
//! dropped on the way does not take its sender's declaration with it.

/// The attachment: `sender` then `skipped_total`, 8 little-endian bytes each.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Envelope {
    /// The sending link, drawn at its start: a new number is a sender started again.
    pub sender: u64,
    /// Ids the sender knowingly did not send, in all since its start.
    pub skipped_total: u64,
}

/// An attachment of the wrong size (a sender of another version, or not dicstream's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("a link sample's attachment has {0} bytes, expected 16")]
pub struct EnvelopeError(pub usize);

impl Envelope {
    pub fn to_bytes(self) -> [u8; 16] {
        let mut bytes = [0; 16];
        bytes[..8].copy_from_slice(&self.sender.to_le_bytes());
        bytes[8..].copy_from_slice(&self.skipped_total.to_le_bytes());
        bytes
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Envelope, EnvelopeError> {
        let bytes: [u8; 16] = bytes.try_into().map_err(|_| EnvelopeError(bytes.len()))?;
        let word = |k: usize| u64::from_le_bytes(bytes[k..k + 8].try_into().expect("8 bytes"));
        Ok(Envelope {
            sender: word(0),
            skipped_total: word(8),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_a_wrong_size_refused() {
        let envelope = Envelope {
            sender: 7,
            skipped_total: 3,
        };
        assert_eq!(Envelope::from_bytes(&envelope.to_bytes()), Ok(envelope));
        assert_eq!(Envelope::from_bytes(&[0; 8]), Err(EnvelopeError(8)));
    }
}
