//! What one viewer may take of the server: bytes and time to send a request, time to take an
//! answer, connections, event streams. A viewer beyond a limit is answered (431, 408, 503) or
//! dropped, so it never holds another viewer, the end of a run or a signal.

use std::time::Duration;

/// Event streams served at once; a viewer beyond is answered 503.
pub const MAX_VIEWERS: usize = 16;

#[derive(Debug, Clone)]
pub struct Limits {
    /// A request head (request line and headers) longer than this is answered 431 and the
    /// connection closed, the rest unread.
    pub max_head_bytes: usize,
    /// From waiting for a request to its last header line; a head begun and not finished in
    /// time is answered 408, a connection idle for as long is closed.
    pub head_timeout: Duration,
    /// To write one answer or one event; a viewer that does not take it in time is dropped.
    pub write_timeout: Duration,
    /// Connections served at once (event streams included); one beyond is answered 503.
    pub max_connections: usize,
    /// Event streams served at once, within `max_connections`.
    pub max_viewers: usize,
    /// Requests answered on one connection before it is closed.
    pub requests_per_connection: usize,
    /// A comment line is sent on an event stream when no snapshot came for this long.
    pub keepalive_interval: Duration,
    /// After the last answer: what is read and discarded of what the viewer still sends, so it
    /// reads the answer before the connection closes (at most this many bytes, for this long).
    pub linger_bytes: usize,
    pub linger_timeout: Duration,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            max_head_bytes: 8 << 10,
            head_timeout: Duration::from_secs(10),
            write_timeout: Duration::from_secs(10),
            max_connections: 64,
            max_viewers: MAX_VIEWERS,
            requests_per_connection: 1000,
            keepalive_interval: Duration::from_secs(5),
            linger_bytes: 64 << 10,
            linger_timeout: Duration::from_secs(1),
        }
    }
}
