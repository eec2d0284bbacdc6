//! Where a run's frames and rig samples come from, and where its dashboard listens.

use std::fmt;
use std::net::SocketAddr;
use std::str::FromStr;

/// Where a run's frames come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CameraSource {
    /// Rendered from the simulated rig's motion: ground truth in every frame.
    #[default]
    Simulated,
    /// Images another program writes into a folder.
    Watch,
    /// Image files sent at a fixed rate.
    Replay,
    /// A GenICam camera (a build with the `genicam` feature).
    Genicam,
}

wire::named!(CameraSource, "[camera] source", {
    Simulated => "simulated", Watch => "watch", Replay => "replay", Genicam => "genicam",
});

impl CameraSource {
    /// Only the simulated camera's frames carry the exact motion (truth columns, acceptance).
    pub fn has_truth(self) -> bool {
        self == CameraSource::Simulated
    }
}

/// Where a run's rig samples come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RigSource {
    /// The simulated machine runs the campaign of `[[rig.tests]]`.
    #[default]
    Simulated,
    /// A test machine's CSV log, followed as it grows (`[rig.csv]`).
    CsvFollow,
}

wire::named!(RigSource, "[rig] source", { Simulated => "simulated", CsvFollow => "csv-follow" });

/// A process of the bench that `dicstream run` starts on this host (`[run] processes`): all
/// four by default; on two hosts linked by `[link]`, each host's run starts its part (the rig
/// on the machine's PC, the camera, correlator and identifier on the camera's).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BenchProcess {
    Rig,
    Producer,
    Correlator,
    Identifier,
}

wire::named!(BenchProcess, "[run] processes", {
    Rig => "rig", Producer => "producer" | "camera", Correlator => "correlator",
    Identifier => "identifier",
});

/// `[run] dashboard`: an address (`ADDR:PORT`, `localhost:PORT`; port 0 takes any free port)
/// or `off`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DashboardListen {
    Off,
    At(SocketAddr),
}

impl DashboardListen {
    /// The address, if on.
    pub fn addr(self) -> Option<SocketAddr> {
        match self {
            DashboardListen::Off => None,
            DashboardListen::At(addr) => Some(addr),
        }
    }

    /// The default address moves to the next free port when taken (another run has it); a
    /// chosen one does not.
    pub fn is_default(self) -> bool {
        self == DashboardListen::default()
    }
}

impl Default for DashboardListen {
    fn default() -> Self {
        DashboardListen::At(
            dashboard::address::parse(dashboard::address::DEFAULT)
                .expect("the default dashboard address parses"),
        )
    }
}

impl FromStr for DashboardListen {
    type Err = dashboard::DashboardError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        if text.trim() == "off" {
            return Ok(DashboardListen::Off);
        }
        dashboard::address::parse(text).map(DashboardListen::At)
    }
}

impl fmt::Display for DashboardListen {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DashboardListen::Off => f.write_str("off"),
            DashboardListen::At(addr) => write!(f, "{addr}"),
        }
    }
}
