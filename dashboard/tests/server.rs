//! The dashboard's HTTP server against viewers that misbehave (issue 29), on a real server on
//! 127.0.0.1 (port 0) fed by the test itself: a viewer that pipelines requests and never
//! reads, a request head of tens of MB without a line end, an event viewer that stops
//! reading. None may keep another viewer from being served, nor the server from stopping.
//! Every wait is bounded by the hang guard; no test asserts a wall-clock time.

use dashboard::hub::Hub;
use dashboard::server::{self, Limits};
use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;
use testkit::{send_request, stalled_client, until, HANG_GUARD};

/// A server on 127.0.0.1 (any free port) within `limits`: its hub, the server, its address.
fn serve(limits: Limits) -> (Arc<Hub>, server::Server, String) {
    let hub = Arc::new(Hub::default());
    let listener = server::bind("127.0.0.1:0".parse().unwrap(), false).unwrap();
    let server = server::spawn(listener, hub.clone(), limits).unwrap();
    let addr = server.addr().to_string();
    (hub, server, addr)
}

/// One `GET path` (`Connection: close`): status and body.
fn get(addr: &str, path: &str) -> (u16, Vec<u8>) {
    let request = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    let mut stream = send_request(addr, &request);
    let mut raw = Vec::new();
    stream
        .read_to_end(&mut raw)
        .unwrap_or_else(|e| panic!("GET {path} on {addr}: {e}"));
    let split = raw
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .unwrap_or_else(|| panic!("GET {path}: no header end in {raw:?}"));
    let head = String::from_utf8_lossy(&raw[..split]).to_string();
    let status = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    (status, raw[split + 4..].to_vec())
}

#[test]
fn a_viewer_that_never_reads_blocks_neither_another_viewer_nor_the_stop() {
    let (hub, server, addr) = serve(Limits::default());
    hub.publish("{\"frames\":1}".into(), None);
    let stalled = stalled_client(&addr, "/app.js", 600);

    let (status, page) = get(&addr, "/");
    assert_eq!(status, 200);
    assert!(String::from_utf8(page).unwrap().contains("/app.js"));
    let (status, snapshot) = get(&addr, "/snapshot.json");
    assert_eq!((status, &snapshot[..]), (200, &b"{\"frames\":1}"[..]));

    // Stopping returns while the stalled client is still connected.
    let (stopped_tx, stopped_rx) = mpsc::channel();
    std::thread::spawn(move || {
        drop(server);
        let _ = stopped_tx.send(());
    });
    stopped_rx
        .recv_timeout(HANG_GUARD)
        .expect("the server's stop waited on a client that does not read");
    drop(stalled);
}

#[test]
fn a_huge_request_head_is_refused_without_being_read() {
    const HUGE_BYTES: usize = 64 << 20;
    let (_hub, _server, addr) = serve(Limits::default());
    let mut stream = TcpStream::connect(&addr).unwrap();
    stream.set_write_timeout(Some(HANG_GUARD)).unwrap();
    stream.set_read_timeout(Some(HANG_GUARD)).unwrap();
    stream.write_all(b"GET / HTTP/1.1\r\nX-Huge: ").unwrap();
    let chunk = vec![b'a'; 64 << 10];
    let mut sent = 0;
    let refused = loop {
        if sent >= HUGE_BYTES {
            break None;
        }
        match stream.write(&chunk) {
            Ok(n) => sent += n,
            Err(e) => break Some(e),
        }
    };
    // Closed by the server (not a write that timed out on a server that stopped reading).
    let refused = refused.unwrap_or_else(|| {
        panic!("the server took a {sent}-byte header line without closing the connection")
    });
    assert!(
        matches!(
            refused.kind(),
            ErrorKind::ConnectionReset | ErrorKind::BrokenPipe
        ),
        "after {sent} bytes: {refused}"
    );
    // Its answer, when the reset left it readable.
    let mut answer = Vec::new();
    let _ = stream.read_to_end(&mut answer);
    assert!(
        answer.is_empty() || answer.starts_with(b"HTTP/1.1 431 "),
        "{}",
        String::from_utf8_lossy(&answer)
    );
}

#[test]
fn a_head_not_finished_before_the_deadline_is_answered_408() {
    let (_hub, _server, addr) = serve(Limits {
        head_timeout: Duration::from_millis(300),
        ..Limits::default()
    });
    let mut stream = send_request(&addr, "GET / HTTP/1.1\r\nHo");
    let mut answer = Vec::new();
    stream.read_to_end(&mut answer).unwrap();
    let answer = String::from_utf8_lossy(&answer);
    assert!(answer.starts_with("HTTP/1.1 408 "), "{answer}");
    assert!(answer.contains("Connection: close\r\n"), "{answer}");
}

#[test]
fn a_stalled_event_viewer_is_dropped_while_another_keeps_receiving() {
    let (hub, server, addr) = serve(Limits {
        write_timeout: Duration::from_millis(500),
        ..Limits::default()
    });
    // Both viewers in before any snapshot: none can be dropped yet.
    let stalled = stalled_client(&addr, "/events", 1);
    until("the stalled viewer counted in", || {
        (hub.viewers() == 1).then_some(())
    });
    // A viewer that reads every event as it comes, counting the snapshots.
    let received = Arc::new(AtomicU64::new(0));
    let reader = {
        let received = received.clone();
        let stream = send_request(
            &addr,
            &format!("GET /events HTTP/1.1\r\nHost: {addr}\r\n\r\n"),
        );
        std::thread::spawn(move || {
            for line in BufReader::new(stream).lines() {
                match line {
                    Ok(l) if l == "event: snapshot" => {
                        received.fetch_add(1, Ordering::SeqCst);
                    }
                    Ok(_) => {}
                    Err(_) => return,
                }
            }
        })
    };
    until("two viewers", || (hub.viewers() == 2).then_some(()));
    // Snapshots of 64 KiB, many a second: the stalled viewer's socket buffers fill.
    let publishing = Arc::new(AtomicBool::new(true));
    let publisher = {
        let (hub, publishing) = (hub.clone(), publishing.clone());
        std::thread::spawn(move || {
            let pad = "x".repeat(64 << 10);
            let mut k = 0;
            while publishing.load(Ordering::SeqCst) {
                k += 1;
                hub.publish(format!("{{\"k\":{k},\"pad\":\"{pad}\"}}"), None);
                std::thread::sleep(Duration::from_millis(5));
            }
        })
    };
    until("the stalled viewer counted out", || {
        (hub.viewers() == 1).then_some(())
    });
    let before = received.load(Ordering::SeqCst);
    until("snapshots still received by the other viewer", || {
        (received.load(Ordering::SeqCst) > before + 3).then_some(())
    });
    publishing.store(false, Ordering::SeqCst);
    publisher.join().unwrap();
    drop(server);
    reader.join().unwrap();
    drop(stalled);
}
