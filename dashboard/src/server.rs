//! The read-only HTTP server (tiny_http, one thread, plus one thread per event stream): the
//! page and its script and style (compiled into the binary), the latest image, the latest
//! snapshot, and `/events`, a server-sent-event stream of snapshots. Only GET and HEAD are
//! served; nothing a viewer sends reaches the instance.

use crate::hub::Hub;
use std::io::Write as _;
use std::net::SocketAddr;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;
use tiny_http::{Header, Method, Request, Response, Server};

/// Event streams served at once; a viewer beyond is answered 503.
pub const MAX_VIEWERS: usize = 16;
/// A comment line is sent when no snapshot came for this long (detects gone viewers).
const KEEPALIVE: Duration = Duration::from_secs(5);

const INDEX_HTML: &str = include_str!("assets/index.html");
const APP_JS: &str = include_str!("assets/app.js");
const STYLE_CSS: &str = include_str!("assets/style.css");

/// Binds `addr`; with `fallback`, a taken port is followed by the next ones, then any port.
pub fn bind(addr: SocketAddr, fallback: bool) -> Result<Server, crate::DashboardError> {
    let mut candidates = vec![addr];
    if fallback && addr.port() != 0 {
        let next = (1..=crate::address::DEFAULT_PORT_TRIES)
            .filter_map(|i| addr.port().checked_add(i))
            .map(|p| SocketAddr::new(addr.ip(), p));
        candidates.extend(next);
        candidates.push(SocketAddr::new(addr.ip(), 0));
    }
    let mut last_error = String::new();
    for candidate in candidates {
        match Server::http(candidate) {
            Ok(server) => return Ok(server),
            Err(e) => last_error = e.to_string(),
        }
    }
    Err(crate::DashboardError::Listen {
        addr,
        reason: last_error,
    })
}

/// Serves until the hub is stopped.
pub fn spawn(server: Server, hub: Arc<Hub>) -> std::io::Result<JoinHandle<()>> {
    std::thread::Builder::new()
        .name("dashboard-http".into())
        .spawn(move || {
            while !hub.stopped() {
                match server.recv_timeout(Duration::from_millis(250)) {
                    Ok(Some(request)) => handle(request, &hub),
                    Ok(None) => {}
                    Err(_) => break,
                }
            }
        })
}

fn header(name: &str, value: &str) -> Header {
    Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("valid header")
}

fn respond(request: Request, status: u16, content_type: &str, body: impl Into<Vec<u8>>) {
    let response = Response::from_data(body.into())
        .with_status_code(status)
        .with_header(header("Content-Type", content_type))
        .with_header(header("Cache-Control", "no-store"))
        .with_header(header("X-Content-Type-Options", "nosniff"));
    // A viewer gone before the answer is not an error of the server.
    let _ = request.respond(response);
}

fn handle(request: Request, hub: &Arc<Hub>) {
    if !matches!(request.method(), Method::Get | Method::Head) {
        return respond(request, 405, "text/plain", "read-only: GET only\n");
    }
    let path = request.url().split('?').next().unwrap_or("/").to_string();
    match path.as_str() {
        "/" | "/index.html" => respond(request, 200, "text/html; charset=utf-8", INDEX_HTML),
        "/app.js" => respond(request, 200, "text/javascript; charset=utf-8", APP_JS),
        "/style.css" => respond(request, 200, "text/css; charset=utf-8", STYLE_CSS),
        "/image.png" => match hub.png() {
            Some(png) => respond(request, 200, "image/png", png.to_vec()),
            None => respond(request, 404, "text/plain", "no image yet\n"),
        },
        "/snapshot.json" => match hub.latest() {
            Some(s) => respond(request, 200, "application/json", s.as_bytes()),
            None => respond(request, 503, "text/plain", "no snapshot yet\n"),
        },
        "/events" => match hub.join(MAX_VIEWERS) {
            Some(viewer) => {
                let hub = hub.clone();
                let writer = request.into_writer();
                let spawned = std::thread::Builder::new()
                    .name("dashboard-viewer".into())
                    .spawn(move || {
                        let _viewer = viewer;
                        stream_events(writer, &hub)
                    });
                if let Err(e) = spawned {
                    eprintln!("dashboard: cannot serve a viewer: {e}");
                }
            }
            None => respond(
                request,
                503,
                "text/plain",
                format!("{MAX_VIEWERS} viewers already connected\n"),
            ),
        },
        _ => respond(request, 404, "text/plain", "not found\n"),
    }
}

/// Writes snapshots as server-sent events until the viewer goes or the hub stops.
fn stream_events(mut writer: Box<dyn std::io::Write + Send>, hub: &Hub) {
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
                Connection: close\r\nX-Accel-Buffering: no\r\n\r\nretry: 1000\n\n";
    if writer
        .write_all(head.as_bytes())
        .and_then(|_| writer.flush())
        .is_err()
    {
        return;
    }
    let mut last = 0;
    while !hub.stopped() {
        let sent = match hub.wait_newer(last, KEEPALIVE) {
            Some((version, snapshot)) => {
                last = version;
                writer
                    .write_all(b"event: snapshot\ndata: ")
                    .and_then(|_| writer.write_all(snapshot.as_bytes()))
                    .and_then(|_| writer.write_all(b"\n\n"))
            }
            None => writer.write_all(b": keepalive\n\n"),
        };
        if sent.and_then(|_| writer.flush()).is_err() {
            return;
        }
    }
}
