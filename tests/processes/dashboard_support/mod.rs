//! What only `tests/processes/dashboard.rs` needs, beside the test kit (`testkit`: child processes,
//! instances, [`until`](testkit::until), the hang guard) and `common` (the dashboard's address
//! from its stderr line): a plain HTTP/1.1 client and a server-sent-event reader over
//! `TcpStream`, and a WebDriver client of Debian's chromium (`webdriver.rs`).
//!
//! Every wait is bounded by [`HANG_GUARD`](testkit::HANG_GUARD), a guard against a hang only:
//! no test asserts a wall-clock time.

#![allow(dead_code)]

pub mod webdriver;

use serde_json::Value;
use std::io::{BufRead, BufReader, Read};
use std::net::TcpStream;
use testkit::send_request;

/// Starts `dicstream monitor` (child `monitor` of `bench`) on `instance` at a free loopback
/// port with `extra` arguments; its dashboard's address once it serves, and its stderr so far.
pub fn spawn_monitor(bench: &mut crate::common::Run, extra: &[&str]) -> (String, String) {
    let instance = bench.name().to_string();
    let mut args = vec![
        "monitor",
        "--instance",
        &instance,
        "--dashboard",
        "127.0.0.1:0",
    ];
    args.extend_from_slice(extra);
    let monitor = bench.spawn("monitor", &args);
    let line = monitor.wait_for_stderr("dashboard URL", |l| l.contains("http://"));
    (crate::common::dashboard_address(&line), monitor.stderr())
}

/// One HTTP/1.1 request (`Connection: close`): status and body.
pub fn http(addr: &str, method: &str, path: &str, body: Option<&Value>) -> (u16, Vec<u8>) {
    let body = body.map(|b| b.to_string()).unwrap_or_default();
    let request = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    );
    let mut stream = send_request(addr, &request);
    // The body ends at its Content-Length, at the last chunk, or when the server closes (a
    // keep-alive server, as chromedriver is, may not close).
    let mut raw = Vec::new();
    let mut buf = [0u8; 65536];
    let mut head_end = None;
    loop {
        if let Some(split) = head_end {
            let head = String::from_utf8_lossy(&raw[..split]).to_ascii_lowercase();
            let body = &raw[split + 4..];
            let length = head
                .lines()
                .find_map(|l| l.strip_prefix("content-length:"))
                .and_then(|v| v.trim().parse::<usize>().ok());
            let done = match length {
                Some(n) => body.len() >= n,
                None if head.contains("transfer-encoding: chunked") => body.ends_with(b"0\r\n\r\n"),
                None => false,
            };
            if done {
                break;
            }
        }
        let n = stream
            .read(&mut buf)
            .unwrap_or_else(|e| panic!("{method} {path} on {addr}: {e}"));
        if n == 0 {
            break;
        }
        raw.extend_from_slice(&buf[..n]);
        if head_end.is_none() {
            head_end = raw.windows(4).position(|w| w == b"\r\n\r\n");
        }
    }
    let split = head_end.unwrap_or_else(|| panic!("{method} {path}: no header end"));
    let head = String::from_utf8_lossy(&raw[..split]).to_ascii_lowercase();
    let status = head
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{method} {path}: bad status line {head}"));
    let mut body = raw[split + 4..].to_vec();
    if head.contains("transfer-encoding: chunked") {
        body = dechunk(&body);
    }
    (status, body)
}

fn dechunk(mut data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let Some(end) = data.windows(2).position(|w| w == b"\r\n") else {
            return out;
        };
        let size_text = String::from_utf8_lossy(&data[..end]);
        let size =
            usize::from_str_radix(size_text.split(';').next().unwrap().trim(), 16).unwrap_or(0);
        if size == 0 {
            return out;
        }
        out.extend_from_slice(&data[end + 2..end + 2 + size]);
        data = &data[end + 2 + size + 2..];
    }
}

pub fn get_json(addr: &str, path: &str) -> Value {
    let (status, body) = http(addr, "GET", path, None);
    assert_eq!(
        status,
        200,
        "GET {path}: {}",
        String::from_utf8_lossy(&body)
    );
    serde_json::from_slice(&body).unwrap()
}

/// `/snapshot.json`, or None before the dashboard's first snapshot (503).
pub fn try_snapshot(addr: &str) -> Option<Value> {
    let (status, body) = http(addr, "GET", "/snapshot.json", None);
    match status {
        503 => None,
        200 => Some(serde_json::from_slice(&body).unwrap()),
        _ => panic!(
            "GET /snapshot.json: {status} {}",
            String::from_utf8_lossy(&body)
        ),
    }
}

/// A viewer of `/events`, read from Rust.
pub struct Events {
    reader: BufReader<TcpStream>,
}

impl Events {
    pub fn connect(addr: &str) -> Events {
        let request =
            format!("GET /events HTTP/1.1\r\nHost: {addr}\r\nAccept: text/event-stream\r\n\r\n");
        let mut reader = BufReader::new(send_request(addr, &request));
        let mut status = String::new();
        reader.read_line(&mut status).unwrap();
        assert!(status.starts_with("HTTP/1.1 200"), "{status}");
        let mut content_type = String::new();
        loop {
            let mut line = String::new();
            reader.read_line(&mut line).unwrap();
            if line.to_ascii_lowercase().starts_with("content-type:") {
                content_type = line.clone();
            }
            if line == "\r\n" {
                break;
            }
        }
        assert!(content_type.contains("text/event-stream"), "{content_type}");
        Events { reader }
    }

    /// The next `snapshot` event's data.
    pub fn next_snapshot(&mut self) -> Value {
        let (mut event, mut data) = (String::new(), String::new());
        loop {
            let mut line = String::new();
            let n = self.reader.read_line(&mut line).unwrap();
            assert!(n > 0, "the event stream ended");
            let line = line.trim_end_matches(['\r', '\n']);
            if line.is_empty() {
                if event == "snapshot" && !data.is_empty() {
                    return serde_json::from_str(&data).unwrap();
                }
                (event, data) = (String::new(), String::new());
            } else if let Some(e) = line.strip_prefix("event: ") {
                event = e.to_string();
            } else if let Some(d) = line.strip_prefix("data: ") {
                data.push_str(d);
            }
        }
    }
}
