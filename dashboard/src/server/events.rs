//! `/events`: snapshots as server-sent events on the viewer's own connection, until the viewer
//! goes, stops reading (an event not taken within the write timeout drops it) or the hub
//! stops; then an `end` event tells the page the run is over (it stops reconnecting and says
//! so, rather than "reconnecting").

use super::limits::Limits;
use super::timed::Timed;
use crate::hub::Hub;
use std::io::{self, Write};
use std::net::TcpStream;

const HEAD: &str = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\n\
                    Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n\
                    Connection: close\r\nX-Accel-Buffering: no\r\n\r\n";
/// The browser reconnects 1 s after the stream ends.
const RETRY: &str = "retry: 1000\n\n";

/// Streams until the viewer or the hub is gone (only the head for HEAD).
pub fn stream(stream: &TcpStream, hub: &Hub, limits: &Limits, head_only: bool) {
    let mut out = Timed::new(stream, limits.write_timeout);
    if out.write_all(HEAD.as_bytes()).is_err()
        || head_only
        || out.write_all(RETRY.as_bytes()).is_err()
    {
        return;
    }
    let mut last = 0;
    while !hub.stopped() {
        let newer = hub.wait_newer(last, limits.keepalive_interval);
        out.renew(limits.write_timeout);
        let sent: io::Result<()> = match newer {
            Some((version, snapshot)) => {
                last = version;
                out.write_all(b"event: snapshot\ndata: ")
                    .and_then(|_| out.write_all(snapshot.as_bytes()))
                    .and_then(|_| out.write_all(b"\n\n"))
            }
            None => out.write_all(b": keepalive\n\n"),
        };
        if sent.is_err() {
            return;
        }
    }
    let _ = out.write_all(b"event: end\ndata: {}\n\n");
}
