//! A real camera's connection events, read off the producer's stderr lines (the formats of
//! `src/cmd/producer_genicam.rs`), so `dicstream run` shows them: each on its own stderr line,
//! and "CAMERA LOST" on the status line until the camera is back. Pure: the supervisor hands
//! every child line to [`camera_event`].

/// What a producer line says about its camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraEvent {
    /// `producer: camera ID lost: …; reconnecting …`
    Lost,
    /// `producer: camera reconnection attempt N failed: …`
    RetryFailed,
    /// `producer: camera ID reconnected after S s away`
    Reconnected,
}

impl CameraEvent {
    /// Whether the camera is away after this event.
    pub fn away(self) -> bool {
        !matches!(self, CameraEvent::Reconnected)
    }
}

/// The camera event a producer's line reports, if any.
pub fn camera_event(line: &str) -> Option<CameraEvent> {
    let rest = line.strip_prefix("producer: camera ")?;
    if rest.starts_with("reconnection attempt ") {
        return Some(CameraEvent::RetryFailed);
    }
    // Past the camera's id (which may hold spaces, never ": " or " reconnected after ").
    if rest.contains(" reconnected after ") {
        return Some(CameraEvent::Reconnected);
    }
    let (_, after_id) = rest.split_once(" lost: ")?;
    after_id
        .contains("reconnecting")
        .then_some(CameraEvent::Lost)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_producer_lines_are_read_and_others_ignored() {
        let lost = "producer: camera Aravis-Fake-GV01 lost: no buffer for 3.0 s; reconnecting \
                    (first attempt in 0.5 s, then backing off up to 8 s between attempts); \
                    frame ids will go on from 41";
        assert_eq!(camera_event(lost), Some(CameraEvent::Lost));
        let retry = "producer: camera reconnection attempt 2 failed: no camera; next in 1.0 s";
        assert_eq!(camera_event(retry), Some(CameraEvent::RetryFailed));
        let back = "producer: camera Aravis-Fake-GV01 reconnected after 2.4 s away";
        assert_eq!(camera_event(back), Some(CameraEvent::Reconnected));
        assert!(CameraEvent::Lost.away() && CameraEvent::RetryFailed.away());
        assert!(!CameraEvent::Reconnected.away());
        for other in [
            "producer: camera status: streaming, 40 frame(s) published",
            "producer: camera buffer skipped, not published (1 incomplete, 0 failed)",
            "correlator: camera lost: reconnecting",
            "producer: ready",
        ] {
            assert_eq!(camera_event(other), None, "{other}");
        }
    }
}
