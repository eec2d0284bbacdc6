//! What can go wrong when a dashboard starts or runs.

use std::net::SocketAddr;

#[derive(Debug, Clone, thiserror::Error)]
pub enum DashboardError {
    /// An address as the user wrote it, and what was expected.
    #[error("dashboard address {text:?}: {expected}")]
    Address {
        text: String,
        expected: &'static str,
    },
    /// No port could be bound (the last attempt's reason).
    #[error("dashboard: cannot listen on {addr}: {reason}")]
    Listen { addr: SocketAddr, reason: String },
    /// The feeder's shared-memory side: the instance, its services, the WaitSet.
    #[error("dashboard: {0}")]
    Feed(String),
    /// A thread of the dashboard could not start, or ended early.
    #[error("dashboard: {0}")]
    Thread(String),
}
