//! The Zenoh session of a link, made from the plan alone: nothing of Zenoh's defaults that
//! would listen on every interface or look for peers on the network is left on.

use anyhow::Context;
use link::LinkPlan;
use zenoh::Wait;

/// How long a sample waits for room in Zenoh's queue before Zenoh drops it (Zenoh's default:
/// 1 ms, 50 ms for a message in fragments, a solve or a frame). With 1 ms, the rig's samples
/// were dropped in bursts of 15 to 19 whenever Zenoh's sending task was starved of CPU for a
/// few ms (2226 of 13002 in a default campaign split over two hosts on a loaded machine). Only
/// the link's sending thread of that service waits (`outbound.rs`). Not congestion control
/// `Block`: after its wait, Block closes the session, and in the 5 s outage test
/// (`tests/link.rs`) a session closed so delivered a field that was not the one sent under its
/// id (4 of 15 runs on a loaded machine; docs/link.md).
pub const WAIT_FOR_THE_NETWORK: std::time::Duration = std::time::Duration::from_secs(5);

/// The session: peer mode, the plan's endpoints, no scouting, user-password authentication,
/// samples waiting up to [`WAIT_FOR_THE_NETWORK`] for room in Zenoh's queue.
pub fn open(plan: &LinkPlan) -> anyhow::Result<zenoh::Session> {
    let password = std::fs::read_to_string(&plan.password_file)
        .with_context(|| format!("[link] password_file {}", plan.password_file.display()))?;
    let password = password.lines().next().unwrap_or("").trim();
    anyhow::ensure!(
        !password.is_empty(),
        "[link] password_file {}: the first line is empty (expected this host's password)",
        plan.password_file.display()
    );
    if let Some(peers) = &plan.peers_file {
        std::fs::metadata(peers)
            .with_context(|| format!("[link] peers_file {}", peers.display()))?;
    }
    let mut config = zenoh::Config::default();
    let json = |value: serde_json::Value| value.to_string();
    let endpoints = |list: &[link::Endpoint]| {
        json(serde_json::json!(list
            .iter()
            .map(|e| e.locator())
            .collect::<Vec<_>>()))
    };
    let mut settings = vec![
        ("mode", json(serde_json::json!("peer"))),
        // Zenoh's default for a peer is tcp/[::]:0, every interface: only the plan's.
        ("listen/endpoints", endpoints(&plan.listen)),
        ("connect/endpoints", endpoints(&plan.connect)),
        ("scouting/multicast/enabled", "false".into()),
        (
            "transport/link/tx/queue/congestion_control/drop/wait_before_drop",
            WAIT_FOR_THE_NETWORK.as_micros().to_string(),
        ),
        (
            "transport/link/tx/queue/congestion_control/drop/max_wait_before_drop_fragments",
            WAIT_FOR_THE_NETWORK.as_micros().to_string(),
        ),
        ("scouting/gossip/enabled", "false".into()),
        (
            "transport/auth/usrpwd/user",
            json(serde_json::json!(plan.user)),
        ),
        (
            "transport/auth/usrpwd/password",
            json(serde_json::json!(password)),
        ),
    ];
    if let Some(peers) = &plan.peers_file {
        settings.push((
            "transport/auth/usrpwd/dictionary_file",
            json(serde_json::json!(peers.display().to_string())),
        ));
    }
    for (key, value) in settings {
        config
            .insert_json5(key, &value)
            .map_err(|e| anyhow::anyhow!("Zenoh configuration {key}: {e}"))?;
    }
    zenoh::open(config)
        .wait()
        .map_err(|e| anyhow::anyhow!("{e}"))
}
