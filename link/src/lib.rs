//! The link between two hosts' instances (`dicstream link`), its pure parts: the `[link]`
//! section of a run's configuration and its checks (`config`, `endpoint`), the rate limit of
//! frames (`rate`), the ids a link lost (`gaps`) and its counts as written and read back
//! (`counts`), the link process's settings (`settings`), and what travels beside a sample's
//! bytes (`key`: where, `envelope`: what the sender knowingly did not send). The process that
//! carries samples over Zenoh is the binary's (`src/link_zenoh/`, feature `link`); nothing here
//! touches iceoryx2 or the network.

#![forbid(unsafe_code)]

pub mod config;
pub mod counts;
pub mod endpoint;
pub mod envelope;
pub mod gaps;
pub mod key;
pub mod rate;
pub mod settings;

pub use config::{LinkConfigError, LinkPlan, LinkSection, Route};
pub use counts::{InCounts, LinkCounts, OutCounts};
pub use endpoint::Endpoint;
pub use gaps::{ReceiveGaps, SendGaps};
pub use rate::RateLimit;
pub use settings::LinkSettings;
pub use wire::linked::{LinkDirection, LinkedService};
