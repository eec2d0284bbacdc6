//! Service names and quality of service, one constant per service. Every process opens a service
//! through these specs, so publisher and subscribers always agree on its settings.

/// Settings of one publish-subscribe service (plus its event service of the same name, used
/// to wake subscribers without polling).
#[derive(Debug, Clone, Copy)]
pub struct ServiceSpec {
    pub name: &'static str,
    pub max_publishers: usize,
    pub max_subscribers: usize,
    /// Samples a subscriber's queue holds before the oldest is dropped (safe overflow).
    pub subscriber_buffer: usize,
    /// Samples a subscriber may hold at once while it works on them.
    pub subscriber_borrowed: usize,
    /// Samples kept for late joiners.
    pub history: usize,
    /// Samples a publisher may loan at once.
    pub publisher_loans: usize,
    /// true: a full subscriber queue drops its oldest sample; the publisher never blocks.
    pub safe_overflow: bool,
}

impl ServiceSpec {
    /// Samples in one publisher's pool: every subscriber's queue and borrows, the history and
    /// the publisher's own loans.
    pub fn pool_samples(&self) -> usize {
        self.max_subscribers * (self.subscriber_buffer + self.subscriber_borrowed)
            + self.history
            + self.publisher_loans
    }

    /// Shared memory this service needs at most (bytes) for payloads of `payload_bytes` behind
    /// a header of `header_bytes`, for all its publishers, with a margin for iceoryx2's own
    /// bookkeeping.
    pub fn shm_bytes(&self, header_bytes: usize, payload_bytes: usize) -> u64 {
        let per_sample = (header_bytes + payload_bytes + 256) as u64;
        let pools = self.max_publishers as u64 * self.pool_samples() as u64 * per_sample;
        pools + pools / 8 + (1 << 20)
    }
}

/// Camera images: big, so a slow consumer must never hold the camera (safe overflow, small queues).
pub const FRAMES: ServiceSpec = ServiceSpec {
    name: "frames",
    max_publishers: 2,
    max_subscribers: 8,
    subscriber_buffer: 2,
    subscriber_borrowed: 2,
    history: 0,
    publisher_loans: 2,
    safe_overflow: true,
};

/// Measured fields, one per correlated frame.
pub const FIELDS: ServiceSpec = ServiceSpec {
    name: "fields",
    max_publishers: 2,
    max_subscribers: 8,
    subscriber_buffer: 8,
    subscriber_borrowed: 2,
    history: 1,
    publisher_loans: 2,
    safe_overflow: true,
};

/// Decimated rig samples (hundreds per second, small).
pub const RIG_STATE: ServiceSpec = ServiceSpec {
    name: "rig/state",
    max_publishers: 2,
    max_subscribers: 8,
    subscriber_buffer: 256,
    subscriber_borrowed: 4,
    history: 1,
    publisher_loans: 2,
    safe_overflow: true,
};

/// Identification reports, one per refit.
pub const IDENTIFICATION: ServiceSpec = ServiceSpec {
    name: "identification",
    max_publishers: 2,
    max_subscribers: 8,
    subscriber_buffer: 16,
    subscriber_borrowed: 2,
    history: 1,
    publisher_loans: 2,
    safe_overflow: true,
};

/// The finite-element specimen's solved states (a few per second, a few hundred kB each):
/// the latest is kept for late joiners. Readers copy what they keep (the camera and the
/// recorder: the solves frames still name), so small queues do.
pub const SPECIMEN: ServiceSpec = ServiceSpec {
    name: "specimen",
    max_publishers: 1,
    max_subscribers: 4,
    subscriber_buffer: 4,
    subscriber_borrowed: 1,
    history: 1,
    publisher_loans: 2,
    safe_overflow: true,
};

/// Request-response name of the rig's command port.
pub const RIG_COMMAND: &str = "rig/command";

/// The services a user can `tap`, by name.
pub const TAPPABLE: [&ServiceSpec; 4] = [&FRAMES, &FIELDS, &RIG_STATE, &IDENTIFICATION];

pub fn by_name(name: &str) -> Option<&'static ServiceSpec> {
    TAPPABLE.into_iter().find(|spec| spec.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_service_size_grows_with_the_frame() {
        let small = FRAMES.shm_bytes(256, 2 * 64 * 64);
        let big = FRAMES.shm_bytes(256, 2 * 1024 * 1024);
        assert!(big > small);
        // 2 publishers x (8 x 4 + 2) samples of 2 MiB each, plus margin.
        assert!(big >= 2 * 34 * 2 * 1024 * 1024);
        assert_eq!(by_name("rig/state").unwrap().name, "rig/state");
        assert!(by_name("nope").is_none());
    }
}
