//! Where the dashboard listens. Loopback by default; a non-loopback address is served only
//! when written out by the user (`--dashboard 0.0.0.0:8421`, `[run] dashboard`), and then with
//! a warning on stderr: the page is read-only but anyone who reaches the port can watch.

use crate::DashboardError;
use std::net::{SocketAddr, ToSocketAddrs};

/// The default address of `dicstream run` and `dicstream monitor`.
pub const DEFAULT: &str = "127.0.0.1:8421";
/// When the default port is taken (another run), the next ones are tried, then any free port.
pub const DEFAULT_PORT_TRIES: u16 = 16;

/// `ADDR:PORT` (an IP address, or `localhost`); port 0 takes any free port.
pub fn parse(text: &str) -> Result<SocketAddr, DashboardError> {
    let text = text.trim();
    if let Ok(addr) = text.parse::<SocketAddr>() {
        return Ok(addr);
    }
    match text.rsplit_once(':') {
        Some(("localhost", port)) => port
            .parse::<u16>()
            .map(|p| SocketAddr::from(([127, 0, 0, 1], p)))
            .map_err(|_| DashboardError::Address {
                text: text.into(),
                expected: "the port is not a number 0..65535",
            }),
        _ => match text.to_socket_addrs().map(|mut a| a.next()) {
            Ok(Some(addr)) => Ok(addr),
            _ => Err(DashboardError::Address {
                text: text.into(),
                expected: "expected ADDR:PORT, e.g. 127.0.0.1:8421",
            }),
        },
    }
}

/// The warning printed when `addr` is reachable from other machines, `None` on loopback.
pub fn exposure_warning(addr: &SocketAddr) -> Option<String> {
    (!addr.ip().is_loopback()).then(|| {
        format!(
            "dashboard: warning: listening on {addr}, reachable from other machines; the page \
             is read-only but has no password (use 127.0.0.1 and ssh -L to keep it private)"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_and_the_exposure_warning() {
        let a = parse(DEFAULT).unwrap();
        assert!(a.ip().is_loopback() && a.port() == 8421);
        assert!(exposure_warning(&a).is_none());
        assert_eq!(parse("localhost:0").unwrap().port(), 0);
        assert!(parse("[::1]:9000").unwrap().ip().is_loopback());
        let open = parse("0.0.0.0:8421").unwrap();
        assert!(exposure_warning(&open).unwrap().contains("other machines"));
        assert!(parse("127.0.0.1")
            .unwrap_err()
            .to_string()
            .contains("ADDR:PORT"));
        assert!(parse("localhost:http")
            .unwrap_err()
            .to_string()
            .contains("port"));
    }
}
