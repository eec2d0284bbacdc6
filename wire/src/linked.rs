//! What a link between two hosts (`dicstream link`) may carry, and which way: the named
//! choices a `[link]` section writes, and each carried sample's id, whose gaps are what a link
//! lost.

use crate::plain::read_value;
use crate::services::{self, ServiceSpec};
use crate::{FieldHeader, FrameHeader, IdentificationReport, RigState, SpecimenHeader};

/// A service a link can carry to another host's instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LinkedService {
    RigState,
    Fields,
    Identification,
    Frames,
    /// The rig's finite-element solves, which a camera filming a structure renders from.
    Specimen,
}

crate::named!(LinkedService, "linked service", {
    RigState => "rig/state",
    Fields => "fields",
    Identification => "identification",
    Frames => "frames",
    Specimen => "specimen",
});

impl LinkedService {
    /// Its service: name and quality of service, the same on both hosts.
    pub fn spec(self) -> &'static ServiceSpec {
        match self {
            LinkedService::RigState => &services::RIG_STATE,
            LinkedService::Fields => &services::FIELDS,
            LinkedService::Identification => &services::IDENTIFICATION,
            LinkedService::Frames => &services::FRAMES,
            LinkedService::Specimen => &services::SPECIMEN,
        }
    }

    /// The size of a sample's fixed part: the header of a slice service, the value of the
    /// others.
    pub fn header_bytes(self) -> usize {
        match self {
            LinkedService::RigState => size_of::<RigState>(),
            LinkedService::Fields => size_of::<FieldHeader>(),
            LinkedService::Identification => size_of::<IdentificationReport>(),
            LinkedService::Frames => size_of::<FrameHeader>(),
            LinkedService::Specimen => size_of::<SpecimenHeader>(),
        }
    }

    /// The id a sample carries, from its header's (or value's) bytes: the rig's sample id, the
    /// frame id of a frame, of a field and of the field a refit was triggered by. Consecutive
    /// at the rig and the camera; a field or a report may skip ids at its source (a frame not
    /// correlated), a specimen's solve id jumps at each test (the test in its high 32 bits)
    /// and skips the solves no sample was published for: what the sender declares skipped.
    /// None for bytes that are not one header.
    pub fn sample_id(self, header: &[u8]) -> Option<u64> {
        match self {
            LinkedService::RigState => read_value::<RigState>(header).map(|s| s.sample_id),
            LinkedService::Fields => read_value::<FieldHeader>(header).map(|h| h.frame_id),
            LinkedService::Identification => {
                read_value::<IdentificationReport>(header).map(|r| r.frame_id)
            }
            LinkedService::Frames => read_value::<FrameHeader>(header).map(|h| h.frame_id),
            LinkedService::Specimen => read_value::<SpecimenHeader>(header).map(|h| h.solve_id),
        }
    }
}

/// Which way a link carries a service: `out` from this host's instance to the peers, `in`
/// from the peers into this host's instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LinkDirection {
    Out,
    In,
}

crate::named!(LinkDirection, "link direction", { Out => "out", In => "in" });

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plain::value_bytes;

    #[test]
    fn names_are_the_service_names() {
        for service in LinkedService::ALL {
            assert_eq!(service.name(), service.spec().name);
            assert_eq!(service.name().parse::<LinkedService>(), Ok(service));
        }
        let error = "rig/command".parse::<LinkedService>().unwrap_err();
        assert_eq!(
            error.to_string(),
            "linked service \"rig/command\": expected rig/state, fields, identification, frames \
             or specimen"
        );
    }

    #[test]
    fn the_id_is_read_from_the_header_bytes() {
        let state = RigState {
            sample_id: 17,
            ..RigState::default()
        };
        let id = LinkedService::RigState.sample_id(value_bytes(&state));
        assert_eq!(id, Some(17));
        let header = FieldHeader {
            frame_id: 9,
            ..FieldHeader::default()
        };
        assert_eq!(
            LinkedService::Fields.sample_id(value_bytes(&header)),
            Some(9)
        );
        assert_eq!(LinkedService::Frames.sample_id(value_bytes(&header)), None);
    }
}
