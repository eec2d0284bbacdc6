//! The Zenoh session of a link, made from the plan alone: nothing of Zenoh's defaults that
//! would listen on every interface or look for peers on the network is left on.

use anyhow::Context;
use link::LinkPlan;
use zenoh::Wait;

/// The session: peer mode, the plan's endpoints, no scouting, user-password authentication.
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
