//! Helpers of `tests/dashboard.rs` (its own, small): `dicstream` child processes whose stderr
//! is read as it comes, a plain HTTP/1.1 client and a server-sent-event reader over
//! `TcpStream`, and a WebDriver client of Debian's chromium (`webdriver.rs`).
//!
//! Every wait is bounded by [`HANG_GUARD`], a guard against a hang only: no test asserts a
//! wall-clock time.

#![allow(dead_code)]

pub mod webdriver;

use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub const HANG_GUARD: Duration = Duration::from_secs(150);

/// A unique instance name for this test.
pub fn unique_instance(test: &str) -> String {
    format!("td{}_{test}", std::process::id())
}

/// Calls `probe` every 200 ms until it gives a value; panics naming `what` after the guard.
pub fn until<T>(what: &str, mut probe: impl FnMut() -> Option<T>) -> T {
    let give_up = Instant::now() + HANG_GUARD;
    loop {
        if let Some(v) = probe() {
            return v;
        }
        assert!(Instant::now() < give_up, "no {what} within {HANG_GUARD:?}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// A `dicstream` child; killed (SIGKILL) when dropped if still running.
pub struct Proc {
    pub name: String,
    child: Child,
    lines: Receiver<String>,
    log: Arc<Mutex<Vec<String>>>,
    /// Says when stderr reached its end (every line is in `log`).
    stderr_done: Receiver<()>,
}

impl Proc {
    pub fn spawn(name: &str, args: &[&str]) -> Proc {
        let mut child = Command::new(env!("CARGO_BIN_EXE_dicstream"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("{name}: cannot start dicstream: {e}"));
        let (tx, lines) = channel();
        let log = Arc::new(Mutex::new(Vec::new()));
        let stderr = child.stderr.take().expect("piped stderr");
        let (done_tx, stderr_done) = channel();
        {
            let log = log.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                    log.lock().unwrap().push(line.clone());
                    let _ = tx.send(line);
                }
                let _ = done_tx.send(());
            });
        }
        Proc {
            name: name.to_string(),
            child,
            lines,
            log,
            stderr_done,
        }
    }

    pub fn pid(&self) -> i32 {
        self.child.id() as i32
    }

    pub fn stderr_so_far(&self) -> String {
        self.log.lock().unwrap().join("\n")
    }

    /// The first stderr line (from now) that matches; panics with the log on exit or hang.
    pub fn wait_line(&mut self, what: &str, matches: impl Fn(&str) -> bool) -> String {
        loop {
            match self.lines.recv_timeout(HANG_GUARD) {
                Ok(line) if matches(&line) => return line,
                Ok(_) => {}
                Err(_) => panic!(
                    "{}: no {what}; stderr:\n{}",
                    self.name,
                    self.stderr_so_far()
                ),
            }
        }
    }

    /// The URL the process printed (`... at http://ADDR:PORT/ ...`), as `ADDR:PORT`.
    pub fn dashboard_address(&mut self) -> String {
        let line = self.wait_line("dashboard URL", |l| l.contains("http://"));
        let url = line.split("http://").nth(1).unwrap();
        let addr = url.split('/').next().unwrap().to_string();
        assert!(addr.starts_with("127.0.0.1:"), "{line}");
        addr
    }

    pub fn signal(&self, signal: i32) {
        // SAFETY: kill(2) on the pid of a child this test started and has not reaped.
        unsafe {
            libc::kill(self.pid(), signal);
        }
    }

    /// Waits for the exit (hang guard), returning the exit code.
    pub fn wait_exit(&mut self) -> Option<i32> {
        let give_up = Instant::now() + HANG_GUARD;
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                // Its last lines too (the reader may not have had them yet).
                let _ = self.stderr_done.recv_timeout(Duration::from_secs(10));
                return status.code();
            }
            assert!(
                Instant::now() < give_up,
                "{} did not exit; stderr:\n{}",
                self.name,
                self.stderr_so_far()
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Removes an instance's files when dropped (after the processes, declared before them).
pub struct InstanceFiles(pub String);

impl Drop for InstanceFiles {
    fn drop(&mut self) {
        if let Ok(instance) = wire::Instance::new(&self.0) {
            instance.cleanup_dead_nodes();
            instance.remove_leftover_files();
        }
    }
}

/// One HTTP/1.1 request (`Connection: close`): status and body.
pub fn http(addr: &str, method: &str, path: &str, body: Option<&Value>) -> (u16, Vec<u8>) {
    let mut stream = TcpStream::connect(addr).unwrap_or_else(|e| panic!("connect {addr}: {e}"));
    stream.set_read_timeout(Some(HANG_GUARD)).unwrap();
    let body = body.map(|b| b.to_string()).unwrap_or_default();
    let request = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    );
    stream.write_all(request.as_bytes()).unwrap();
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

/// A viewer of `/events`, read from Rust.
pub struct Events {
    reader: BufReader<TcpStream>,
}

impl Events {
    pub fn connect(addr: &str) -> Events {
        let mut stream = TcpStream::connect(addr).unwrap();
        stream.set_read_timeout(Some(HANG_GUARD)).unwrap();
        write!(
            stream,
            "GET /events HTTP/1.1\r\nHost: {addr}\r\nAccept: text/event-stream\r\n\r\n"
        )
        .unwrap();
        let mut reader = BufReader::new(stream);
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
