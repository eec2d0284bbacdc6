//! The read-only HTTP server, on std: one thread accepts; each connection has a thread of its
//! own (at most `max_connections`), reads request heads of bounded size before a deadline and
//! writes each answer or event before another (`Limits`). A viewer beyond a limit is answered
//! (408, 431, 503) or dropped, so no viewer holds another, the run's end or a signal.
//! Stopping wakes the accept thread and waits for it only: connection threads end by their
//! own deadlines. Only GET and HEAD are served; nothing a viewer sends reaches the instance.

mod connection;
mod events;
mod head;
mod limits;
mod reply;
mod route;
mod timed;

pub use limits::{Limits, MAX_VIEWERS};

use crate::hub::Hub;
use crate::slots::Slots;
use std::net::{Ipv4Addr, Ipv6Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// How long stopping tries to connect to the server to wake its accept thread.
const WAKE_TIMEOUT: Duration = Duration::from_secs(1);
/// After a failed accept (no file descriptor left): the pause before the next.
const ACCEPT_RETRY: Duration = Duration::from_millis(100);

/// Binds `addr`; with `fallback`, a taken port is followed by the next ones, then any port.
pub fn bind(addr: SocketAddr, fallback: bool) -> Result<TcpListener, crate::DashboardError> {
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
        match TcpListener::bind(candidate) {
            Ok(listener) => return Ok(listener),
            Err(e) => last_error = e.to_string(),
        }
    }
    Err(crate::DashboardError::Listen {
        addr,
        reason: last_error,
    })
}

/// A running server; dropping it stops the hub and the server.
pub struct Server {
    hub: Arc<Hub>,
    addr: SocketAddr,
    accept: Option<JoinHandle<()>>,
}

/// Serves `listener` until the returned server is dropped.
pub fn spawn(listener: TcpListener, hub: Arc<Hub>, limits: Limits) -> std::io::Result<Server> {
    let addr = listener.local_addr()?;
    let accept = {
        let hub = hub.clone();
        std::thread::Builder::new()
            .name("dashboard-accept".into())
            .spawn(move || accept(listener, &hub, Arc::new(limits)))?
    };
    Ok(Server {
        hub,
        addr,
        accept: Some(accept),
    })
}

impl Server {
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.hub.stop();
        // A connection of its own wakes the accept thread, which then sees the stop; if none
        // can be made, the thread is left to end with the process rather than waited for.
        let woken = TcpStream::connect_timeout(&wake_address(self.addr), WAKE_TIMEOUT).is_ok();
        if let (true, Some(accept)) = (woken, self.accept.take()) {
            let _ = accept.join();
        }
    }
}

/// Where the server can be reached from this machine (loopback for an unspecified address).
fn wake_address(addr: SocketAddr) -> SocketAddr {
    match addr.ip() {
        ip if !ip.is_unspecified() => addr,
        std::net::IpAddr::V4(_) => SocketAddr::new(Ipv4Addr::LOCALHOST.into(), addr.port()),
        std::net::IpAddr::V6(_) => SocketAddr::new(Ipv6Addr::LOCALHOST.into(), addr.port()),
    }
}

fn accept(listener: TcpListener, hub: &Arc<Hub>, limits: Arc<Limits>) {
    let connections = Arc::new(Slots::default());
    for stream in listener.incoming() {
        if hub.stopped() {
            return;
        }
        let Ok(stream) = stream else {
            // Out of file descriptors, say: a pause lets connections end.
            std::thread::sleep(ACCEPT_RETRY);
            continue;
        };
        let Some(slot) = connections.take(limits.max_connections) else {
            connection::refuse_busy(stream, &limits);
            continue;
        };
        let (hub, limits) = (hub.clone(), limits.clone());
        let spawned = std::thread::Builder::new()
            .name("dashboard-conn".into())
            .spawn(move || {
                let _slot = slot;
                connection::serve(stream, &hub, &limits)
            });
        if let Err(e) = spawned {
            eprintln!("dashboard: cannot serve a viewer: {e}");
        }
    }
}
