//! An answer: status, type and body, with the headers every answer carries (`no-store`,
//! `nosniff`, its length, whether the connection stays open).

use std::io::{self, Write};
use std::sync::Arc;

pub enum Body {
    Static(&'static str),
    Text(String),
    Shared(Arc<str>),
    Bytes(Arc<[u8]>),
}

impl Body {
    fn bytes(&self) -> &[u8] {
        match self {
            Body::Static(s) => s.as_bytes(),
            Body::Text(s) => s.as_bytes(),
            Body::Shared(s) => s.as_bytes(),
            Body::Bytes(b) => b,
        }
    }
}

pub struct Reply {
    pub status: u16,
    pub content_type: &'static str,
    pub body: Body,
}

impl Reply {
    pub fn new(status: u16, content_type: &'static str, body: Body) -> Reply {
        Reply {
            status,
            content_type,
            body,
        }
    }

    /// A plain-text answer (errors, refusals).
    pub fn text(status: u16, text: impl Into<String>) -> Reply {
        Reply::new(status, "text/plain; charset=utf-8", Body::Text(text.into()))
    }

    /// Writes the answer (its head only, for HEAD), saying whether the connection stays open.
    pub fn write(&self, out: &mut impl Write, head_only: bool, keep_open: bool) -> io::Result<()> {
        let body = self.body.bytes();
        let head = format!(
            "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\n\
             Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n{}Connection: {}\r\n\r\n",
            self.status,
            reason(self.status),
            self.content_type,
            body.len(),
            if self.status == 405 { "Allow: GET, HEAD\r\n" } else { "" },
            if keep_open { "keep-alive" } else { "close" },
        );
        out.write_all(head.as_bytes())?;
        if !head_only {
            out.write_all(body)?;
        }
        out.flush()
    }
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heads_say_length_type_and_connection_and_head_has_no_body() {
        let mut out = Vec::new();
        let reply = Reply::new(200, "application/json", Body::Static("{}"));
        reply.write(&mut out, false, true).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.starts_with("HTTP/1.1 200 OK\r\n"), "{text}");
        for header in [
            "Content-Type: application/json\r\n",
            "Content-Length: 2\r\n",
            "Cache-Control: no-store\r\n",
            "X-Content-Type-Options: nosniff\r\n",
            "Connection: keep-alive\r\n",
        ] {
            assert!(text.contains(header), "{header} in {text}");
        }
        assert!(text.ends_with("\r\n\r\n{}"), "{text}");
        let mut out = Vec::new();
        Reply::text(405, "read-only\n")
            .write(&mut out, true, false)
            .unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("Allow: GET, HEAD\r\n") && text.contains("Connection: close\r\n"));
        assert!(
            text.contains("Content-Length: 10\r\n") && text.ends_with("\r\n\r\n"),
            "{text}"
        );
    }
}
