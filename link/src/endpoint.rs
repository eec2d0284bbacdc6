//! A Zenoh endpoint as the `[link]` section writes it: `tcp/IP:PORT`, an address literal (no
//! host name: where a link listens must be visible in the file, and checked).

use std::fmt;
use std::net::SocketAddr;
use std::str::FromStr;

/// `tcp/IP:PORT`: the only transport this build carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Endpoint {
    pub addr: SocketAddr,
}

/// Why a text is no endpoint.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EndpointError {
    #[error("endpoint {0:?}: expected tcp/IP:PORT (e.g. tcp/10.0.0.1:7447, tcp/[fd00::1]:7447)")]
    Syntax(String),
    #[error(
        "endpoint {0:?}: only the tcp transport is built in (write tcp/IP:PORT; TLS: \
         docs/link.md)"
    )]
    Transport(String),
}

impl Endpoint {
    /// 0.0.0.0 or [::]: every interface of the host.
    pub fn is_any_interface(&self) -> bool {
        self.addr.ip().is_unspecified()
    }

    /// Zenoh's locator of it.
    pub fn locator(&self) -> String {
        self.to_string()
    }
}

impl FromStr for Endpoint {
    type Err = EndpointError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let text = text.trim();
        let Some((transport, address)) = text.split_once('/') else {
            return Err(EndpointError::Syntax(text.to_string()));
        };
        if transport != "tcp" {
            return Err(EndpointError::Transport(text.to_string()));
        }
        let addr: SocketAddr = address
            .parse()
            .map_err(|_| EndpointError::Syntax(text.to_string()))?;
        Ok(Endpoint { addr })
    }
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "tcp/{}", self.addr)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tcp_addresses_parse_and_print_as_written() {
        for text in ["tcp/10.0.0.1:7447", "tcp/[fd00::1]:7447"] {
            let endpoint: Endpoint = text.parse().unwrap();
            assert_eq!(endpoint.to_string(), text);
            assert!(!endpoint.is_any_interface());
        }
        assert!("tcp/0.0.0.0:7447"
            .parse::<Endpoint>()
            .unwrap()
            .is_any_interface());
        assert!("tcp/[::]:7447"
            .parse::<Endpoint>()
            .unwrap()
            .is_any_interface());
    }

    #[test]
    fn other_transports_and_host_names_are_refused() {
        assert!(matches!(
            "udp/10.0.0.1:7447".parse::<Endpoint>(),
            Err(EndpointError::Transport(_))
        ));
        for text in ["10.0.0.1:7447", "tcp/localhost:7447", "tcp/10.0.0.1"] {
            assert!(
                matches!(text.parse::<Endpoint>(), Err(EndpointError::Syntax(_))),
                "{text}"
            );
        }
    }
}
