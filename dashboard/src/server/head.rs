//! A request head (request line and headers) read from a connection, at most a given number
//! of bytes: the method, the path and whether the connection must close after the answer.
//! Pure over any `BufRead`; the deadline is the reader's (`timed.rs`).

use super::timed::timed_out;
use std::io::{BufRead, Read as _};

#[derive(Debug, PartialEq)]
pub struct Request {
    pub method: String,
    /// The target without its query.
    pub path: String,
    /// HTTP/1.0, `Connection: close`, or a body this server does not read.
    pub close: bool,
}

/// Why no request was read; all but `Gone` are answered before the connection closes.
#[derive(Debug, PartialEq)]
pub enum NoRequest {
    /// The viewer closed the connection, or sent nothing before the deadline.
    Gone,
    /// The head did not end before the deadline (408).
    Slow,
    /// The head is longer than the cap (431).
    TooLarge,
    /// Not a request line or a header line (400).
    Malformed,
}

impl NoRequest {
    /// The status it is answered with, `None` when nobody is left to answer.
    pub fn status(&self) -> Option<u16> {
        match self {
            NoRequest::Gone => None,
            NoRequest::Slow => Some(408),
            NoRequest::TooLarge => Some(431),
            NoRequest::Malformed => Some(400),
        }
    }
}

/// Reads one request head of at most `max_bytes` from `reader` (blank lines before it
/// included); never reads past its end, nor past the cap.
pub fn read(reader: &mut impl BufRead, max_bytes: usize) -> Result<Request, NoRequest> {
    let mut left = max_bytes;
    let mut request: Option<Request> = None;
    let mut started = false;
    loop {
        let mut line = Vec::new();
        let read = reader
            .by_ref()
            .take(left as u64)
            .read_until(b'\n', &mut line);
        started |= !line.is_empty();
        let n = match read {
            Ok(n) => n,
            Err(e) if started && timed_out(&e) => return Err(NoRequest::Slow),
            Err(_) => return Err(NoRequest::Gone),
        };
        if !line.ends_with(b"\n") {
            return Err(match n == left {
                true => NoRequest::TooLarge,
                // The end of the connection, mid-line.
                false => NoRequest::Gone,
            });
        }
        left -= n;
        let text = std::str::from_utf8(&line).map_err(|_| NoRequest::Malformed)?;
        let text = text.trim_end_matches(['\r', '\n']);
        match (&mut request, text.is_empty()) {
            // Blank lines before a request line are allowed (RFC 9112, 2.2).
            (None, true) => {}
            (None, false) => request = Some(request_line(text)?),
            (Some(_), true) => return request.ok_or(NoRequest::Malformed),
            (Some(request), false) => header(request, text)?,
        }
    }
}

fn request_line(text: &str) -> Result<Request, NoRequest> {
    let mut parts = text.split(' ');
    let (Some(method), Some(target), Some(version), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(NoRequest::Malformed);
    };
    if method.is_empty() || !version.starts_with("HTTP/1.") {
        return Err(NoRequest::Malformed);
    }
    Ok(Request {
        method: method.to_string(),
        path: target.split('?').next().unwrap_or("/").to_string(),
        close: version != "HTTP/1.1",
    })
}

fn header(request: &mut Request, text: &str) -> Result<(), NoRequest> {
    let (name, value) = text.split_once(':').ok_or(NoRequest::Malformed)?;
    let value = value.trim().to_ascii_lowercase();
    request.close |= match name.trim().to_ascii_lowercase().as_str() {
        "connection" => value.split(',').any(|v| v.trim() == "close"),
        // A body is never read here: the connection closes after the answer.
        "content-length" => value != "0",
        "transfer-encoding" => true,
        _ => false,
    };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{BufReader, Cursor, Read};

    fn get(path: &str, close: bool) -> Request {
        Request {
            method: "GET".into(),
            path: path.into(),
            close,
        }
    }

    #[test]
    fn pipelined_requests_are_read_one_head_at_a_time() {
        let text = "\r\nGET /app.js?v=2 HTTP/1.1\r\nHost: x\r\n\r\n\
                    HEAD / HTTP/1.0\r\n\r\n\
                    GET /events HTTP/1.1\nConnection: keep-alive, Close\n\n\
                    POST / HTTP/1.1\r\nContent-Length: 4\r\n\r\nnull";
        let mut reader = BufReader::new(text.as_bytes());
        assert_eq!(read(&mut reader, 8192), Ok(get("/app.js", false)));
        let head = read(&mut reader, 8192).unwrap();
        assert_eq!((head.method.as_str(), head.close), ("HEAD", true));
        assert_eq!(read(&mut reader, 8192), Ok(get("/events", true)));
        assert!(read(&mut reader, 8192).unwrap().close, "a body is not read");
        let mut rest = String::new();
        reader.read_to_string(&mut rest).unwrap();
        assert_eq!(rest, "null");
    }

    #[test]
    fn a_head_beyond_the_cap_is_refused_having_read_the_cap_only() {
        // Ten megabytes without a line end; and a head of many short lines.
        let huge = [&b"GET / HTTP/1.1\r\nX: "[..], &vec![b'a'; 10 << 20]].concat();
        let mut cursor = Cursor::new(&huge[..]);
        let mut reader = BufReader::with_capacity(1024, &mut cursor);
        assert_eq!(read(&mut reader, 8192), Err(NoRequest::TooLarge));
        let consumed = reader.buffer().len() as u64;
        assert!(
            cursor.position() - consumed <= 8192,
            "{}",
            cursor.position()
        );
        let many = format!("GET / HTTP/1.1\r\n{}\r\n", "X: y\r\n".repeat(2000));
        let mut reader = BufReader::new(many.as_bytes());
        assert_eq!(read(&mut reader, 8192), Err(NoRequest::TooLarge));
        // Exactly at the cap is served.
        let exact = "GET / HTTP/1.1\r\n\r\n";
        assert!(read(&mut BufReader::new(exact.as_bytes()), exact.len()).is_ok());
    }

    #[test]
    fn bad_and_cut_heads() {
        let bad = |text: &str| read(&mut BufReader::new(text.as_bytes()), 8192);
        assert_eq!(bad(""), Err(NoRequest::Gone));
        assert_eq!(bad("GET / HTTP/1.1\r\nHost"), Err(NoRequest::Gone));
        assert_eq!(bad("GET /\r\n\r\n"), Err(NoRequest::Malformed));
        assert_eq!(bad("GET / SPDY/3\r\n\r\n"), Err(NoRequest::Malformed));
        assert_eq!(
            bad("GET / HTTP/1.1\r\nno colon\r\n\r\n"),
            Err(NoRequest::Malformed)
        );
        let not_text = read(&mut BufReader::new(&b"\xff / HTTP/1.1\r\n"[..]), 8192);
        assert_eq!(not_text, Err(NoRequest::Malformed));
        // A deadline passed (Linux says WouldBlock) mid-head, or before a byte.
        let cut =
            |text: &'static str| read(&mut BufReader::new(text.as_bytes().chain(Stalled)), 8192);
        assert_eq!(cut("GET / HTTP/1.1\r\nHo"), Err(NoRequest::Slow));
        assert_eq!(cut(""), Err(NoRequest::Gone));
        assert_eq!(NoRequest::TooLarge.status(), Some(431));
    }

    /// A connection whose deadline has passed.
    struct Stalled;

    impl Read for Stalled {
        fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
            Err(std::io::ErrorKind::WouldBlock.into())
        }
    }
}
