//! The live dashboard of a dicstream instance, served in a browser by the monitoring side:
//! `dicstream run` (with what it knows of its processes) or `dicstream monitor` (attached
//! read-only to any running instance). Never by the camera, the correlator, the rig or the
//! identifier: nothing here is on their path.
//!
//! - [`state`] (pure): what is kept of the four services and the snapshot sent to viewers;
//!   [`image`] the capped thumbnail, [`series`] and [`latency`] the bounded histories;
//!   [`test_clock`] the test's time of a field, [`forces`] each loaded actuator's force,
//!   [`stretch_states`] the field's (λ1, λ2) states; [`map_ranges`] the strain map's colour
//!   ranges (`wire::colour_range`'s, per quantity shown); [`user_gauges`] what reads a monitor's
//!   named gauges on every field;
//! - [`hub`]: the latest snapshot and image, shared with the viewers' threads;
//! - [`server`]: read-only HTTP on std with server-sent events, assets compiled in, a
//!   deadline on every read and write so no viewer holds another or the stop;
//! - [`feed`]: the IPC shell, a node of its own subscribing to the four services.

#![forbid(unsafe_code)]

pub mod address;
mod error;
pub mod feed;
pub mod forces;
pub mod hub;
pub mod image;
pub mod latency;
pub mod map_ranges;
pub mod series;
pub mod server;
mod slots;
pub mod state;
pub mod stretch_states;
pub mod test_clock;
pub mod user_gauges;

pub use error::DashboardError;
pub use state::{Mode, Settings};
pub use user_gauges::{FieldTime, UserGauges};

use hub::Hub;
use std::net::SocketAddr;
use std::sync::Arc;
use std::thread::JoinHandle;

/// A running dashboard: the HTTP server and the feeder. Dropping it stops both.
pub struct Dashboard {
    hub: Arc<Hub>,
    addr: SocketAddr,
    server: Option<server::Server>,
    feeder: Option<JoinHandle<Result<(), DashboardError>>>,
}

impl Dashboard {
    /// Listens on `addr` (with `fallback`, the next free port when it is taken) and attaches
    /// the feeder to `instance`; with `user_gauges`, the feeder reads them on every field
    /// (`dicstream monitor --config`; without, the page shows what `set_user_gauges` gives).
    /// Fails when neither can start.
    pub fn start(
        instance: &str,
        mode: Mode,
        addr: SocketAddr,
        fallback: bool,
        user_gauges: Option<Box<dyn UserGauges>>,
    ) -> Result<Dashboard, DashboardError> {
        let listener = server::bind(addr, fallback)?;
        let addr = listener.local_addr().map_err(|e| DashboardError::Listen {
            addr,
            reason: e.to_string(),
        })?;
        let hub = Arc::new(Hub::default());
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let feeder = {
            let hub = hub.clone();
            let instance = instance.to_string();
            std::thread::Builder::new()
                .name("dashboard-feed".into())
                .spawn(move || {
                    let settings = Settings::new(&instance, mode);
                    let mut started = false;
                    let fed = feed::feed(&instance, settings, hub, user_gauges, |r| {
                        started = r.is_ok();
                        let _ = ready_tx.send(r);
                    });
                    // (An error before it started is returned by `start`.)
                    if let (Err(e), true) = (&fed, started) {
                        // Said at once: the page stops updating (a monitor also exits with it).
                        eprintln!("{e}; the dashboard's page no longer updates");
                    }
                    fed
                })
                .map_err(|e| DashboardError::Thread(e.to_string()))?
        };
        ready_rx
            .recv()
            .map_err(|_| DashboardError::Thread("the feeder ended before it was ready".into()))??;
        let mut dashboard = Dashboard {
            hub: hub.clone(),
            addr,
            server: None,
            feeder: Some(feeder),
        };
        let server = server::spawn(listener, hub, server::Limits::default())
            .map_err(|e| DashboardError::Thread(e.to_string()))?;
        dashboard.server = Some(server);
        Ok(dashboard)
    }

    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// What `dicstream run` knows of its processes, shown on the page as is.
    pub fn set_processes(&self, processes: serde_json::Value) {
        self.hub.set_processes(processes);
    }

    /// The user's named gauges against the test's time (`dicstream run`: each gauge's name,
    /// kind, quantity, unit, times and series), shown as one chart per gauge.
    pub fn set_user_gauges(&self, gauges: serde_json::Value) {
        self.hub.set_user_gauges(gauges);
    }

    /// Serves until a termination signal (the feeder notes it), then stops.
    pub fn wait(mut self) -> Result<(), DashboardError> {
        let result = match self.feeder.take() {
            Some(f) => f
                .join()
                .unwrap_or_else(|_| Err(DashboardError::Thread("the feeder panicked".into()))),
            None => Ok(()),
        };
        drop(self);
        result
    }
}

impl Drop for Dashboard {
    fn drop(&mut self) {
        self.hub.stop();
        if let Some(f) = self.feeder.take() {
            let _ = f.join();
        }
        // Waits for the accept thread only, never for a viewer.
        drop(self.server.take());
    }
}
