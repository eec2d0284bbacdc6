//! `dicstream run`'s dashboard: the `dashboard` crate attached to the run's instance (its own
//! node and thread, in this process, never in a child), plus what only the run knows: each
//! process's pid, CPU time and restarts, and the deaths with their reason.

use crate::children::{Role, Supervisor};
use crate::config::RunConfig;
use dashboard::{address, Dashboard, Mode};
use serde_json::json;
use std::time::Instant;

/// Starts the dashboard unless `[run] dashboard = "off"`, printing its URL.
pub fn start(
    config: &RunConfig,
    instance: &str,
) -> Result<Option<Dashboard>, dashboard::DashboardError> {
    let Some(addr) = config.run.dashboard.addr() else {
        return Ok(None);
    };
    if let Some(warning) = address::exposure_warning(&addr) {
        eprintln!("run: {warning}");
    }
    // The default port moves to the next free one (another run has it); a chosen one does not.
    // The run's recorder reads the user's gauges (for frames.csv) and hands them over.
    let dashboard = Dashboard::start(
        instance,
        Mode::Run,
        addr,
        config.run.dashboard.is_default(),
        None,
    )?;
    eprintln!("run: dashboard at {} (read-only)", dashboard.url());
    Ok(Some(dashboard))
}

/// Hands the processes' state to the page (pid, running, CPU, restarts; deaths and restarts
/// with their reason, as the run noted them).
pub fn update(
    dashboard: &Option<Dashboard>,
    supervisor: &Supervisor,
    faults: &[String],
    restarts: &[String],
    restart_counts: &[u32; Role::COUNT],
    started: Instant,
) {
    let Some(dashboard) = dashboard else {
        return;
    };
    let wall_s = started.elapsed().as_secs_f64().max(1e-9);
    let roles: Vec<_> = Role::ALL
        .iter()
        .filter(|&&role| supervisor.started(role))
        .map(|&role| {
            let cpu_s = supervisor.cpu_seconds(role);
            json!({
                "role": role.name(),
                "pid": supervisor.pid(role),
                "alive": supervisor.is_running(role),
                "cpu_s": cpu_s,
                "cpu_share": cpu_s / wall_s,
                "restarts": restart_counts[role as usize],
            })
        })
        .collect();
    dashboard.set_processes(json!({
        "wall_s": wall_s,
        "roles": roles,
        "faults": faults,
        "restarts": restarts,
    }));
}

/// Hands the user's named gauges' readings to the page (one chart per gauge).
pub fn update_gauges(dashboard: &Option<Dashboard>, gauges: &crate::gauge_history::GaugeHistory) {
    if let Some(dashboard) = dashboard {
        dashboard.set_user_gauges(gauges.to_json());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_serves_nothing_and_a_bad_address_is_refused_before_the_run() {
        let config = RunConfig::from_toml("[run]\ndashboard = \"off\"\n", "t.toml").unwrap();
        config.validate().unwrap();
        assert!(start(&config, "never_started").unwrap().is_none());
        let refusal =
            RunConfig::from_toml("[run]\ndashboard = \"nowhere\"\n", "t.toml").unwrap_err();
        let refusal = format!("{refusal:#}");
        assert!(
            refusal.contains("dashboard address \"nowhere\"") && refusal.contains("dashboard ="),
            "{refusal}"
        );
    }
}
