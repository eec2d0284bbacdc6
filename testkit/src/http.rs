//! HTTP clients of the dashboard's tests: a connection that has sent its request (reads and
//! writes bounded by the hang guard), and a client that stops reading, as a laptop asleep at
//! the end of an `ssh -L` tunnel looks to a server (issue 29).

use crate::HANG_GUARD;
use std::io::Write;
use std::net::TcpStream;
use std::os::fd::AsRawFd;

/// The receive buffer a stalled client asks of the kernel (it doubles it, to at least a few
/// KiB): the server's writes block after a few kilobytes.
const STALLED_RECEIVE_BUFFER_BYTES: libc::c_int = 4096;

/// Connects to `addr` and sends `request` (the whole text: request line, headers, body).
pub fn send_request(addr: &str, request: &str) -> TcpStream {
    let stream = TcpStream::connect(addr).unwrap_or_else(|e| panic!("connect {addr}: {e}"));
    stream.set_read_timeout(Some(HANG_GUARD)).unwrap();
    stream.set_write_timeout(Some(HANG_GUARD)).unwrap();
    (&stream)
        .write_all(request.as_bytes())
        .unwrap_or_else(|e| panic!("send to {addr}: {e}"));
    stream
}

/// Connects to `addr`, sends `count` pipelined `GET path` requests and returns the connection
/// without reading anything; dropping it closes the connection.
pub fn stalled_client(addr: &str, path: &str, count: usize) -> TcpStream {
    let stream = send_request(addr, "");
    let size = STALLED_RECEIVE_BUFFER_BYTES;
    // SAFETY: setsockopt(2) on a socket this function owns, reading `size` (a c_int that
    // outlives the call) through a pointer and length that describe it exactly.
    let rc = unsafe {
        libc::setsockopt(
            stream.as_raw_fd(),
            libc::SOL_SOCKET,
            libc::SO_RCVBUF,
            (&size as *const libc::c_int).cast(),
            std::mem::size_of::<libc::c_int>() as libc::socklen_t,
        )
    };
    assert_eq!(rc, 0, "setsockopt SO_RCVBUF on the stalled client");
    let request = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\n\r\n");
    (&stream)
        .write_all(request.repeat(count).as_bytes())
        .unwrap_or_else(|e| panic!("{count} x GET {path} to {addr}: {e}"));
    stream
}
