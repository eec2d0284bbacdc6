//! The `[link]` section of a run's configuration, as written, and its check into a
//! [`LinkPlan`], the link's typed settings. Every refusal names the key.
//!
//! ```toml
//! [link]
//! listen = ["tcp/10.0.0.1:7447"]      # this host's address on the lab network; never all
//! connect = []                        # interfaces unless allow_any_interface = true
//! user = "rig-pc"                     # this host's name to its peers
//! password_file = "link.password"     # this host's password (one line)
//! peers_file = "link.peers"           # the peers let in: `user:password` lines
//! frames_max_hz = 5.0                 # frames, when carried out, at most this often
//! start_with_run = true               # `dicstream run` starts it as one of its children
//! services = [
//!   { name = "rig/state", direction = "out" },
//!   { name = "fields", direction = "in" },
//! ]
//! ```

use crate::endpoint::Endpoint;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::path::PathBuf;
use wire::linked::{LinkDirection, LinkedService};

/// `[link]` as written.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LinkSection {
    /// Endpoints this host listens on (`tcp/IP:PORT`).
    pub listen: Vec<String>,
    /// Peers' endpoints this host connects to.
    pub connect: Vec<String>,
    /// Lets `listen` name 0.0.0.0 or [::] (every interface of the host).
    pub allow_any_interface: bool,
    /// The services carried, each with its direction.
    pub services: Vec<ServiceEntry>,
    /// The most frames per second sent (required when frames go out).
    pub frames_max_hz: Option<f64>,
    /// This host's user name in Zenoh's user-password authentication.
    pub user: String,
    /// The file holding this host's password (its first line).
    pub password_file: PathBuf,
    /// The peers allowed in, Zenoh's dictionary file (`user:password` lines); required when
    /// listening.
    pub peers_file: Option<PathBuf>,
    /// `dicstream run` starts this link as one of its children (supervised, logged under the
    /// run's `logs/link.log`, stopped last) and counts what it lost in its verdict; false: the
    /// link is started beside the run (`dicstream link`).
    pub start_with_run: bool,
}

/// One entry of `services`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServiceEntry {
    pub name: LinkedService,
    pub direction: LinkDirection,
}

/// One service carried one way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Route {
    pub service: LinkedService,
    pub direction: LinkDirection,
}

/// The checked `[link]`: what `dicstream link` runs.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkPlan {
    pub listen: Vec<Endpoint>,
    pub connect: Vec<Endpoint>,
    pub routes: Vec<Route>,
    pub frames_max_hz: Option<f64>,
    pub user: String,
    pub password_file: PathBuf,
    pub peers_file: Option<PathBuf>,
}

/// A `[link]` refused, with the key.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("[link] {key}: {reason}")]
pub struct LinkConfigError {
    pub key: &'static str,
    pub reason: String,
}

fn refuse(key: &'static str, reason: impl Into<String>) -> LinkConfigError {
    LinkConfigError {
        key,
        reason: reason.into(),
    }
}

fn endpoints(key: &'static str, texts: &[String]) -> Result<Vec<Endpoint>, LinkConfigError> {
    texts
        .iter()
        .map(|text| text.parse().map_err(|e| refuse(key, format!("{e}"))))
        .collect()
}

impl LinkSection {
    /// The plan, or the first refusal.
    pub fn plan(&self) -> Result<LinkPlan, LinkConfigError> {
        let listen = endpoints("listen", &self.listen)?;
        let connect = endpoints("connect", &self.connect)?;
        if listen.is_empty() && connect.is_empty() {
            return Err(refuse(
                "listen",
                "neither listen nor connect names an endpoint: a link needs one of them",
            ));
        }
        if let Some(any) = listen.iter().find(|e| e.is_any_interface()) {
            if !self.allow_any_interface {
                return Err(refuse(
                    "listen",
                    format!(
                        "{any} listens on every interface of the host: name this host's \
                         address on the lab network, or set allow_any_interface = true"
                    ),
                ));
            }
        }
        if let Some(any) = connect.iter().find(|e| e.is_any_interface()) {
            return Err(refuse(
                "connect",
                format!("{any} is no peer's address: name the peer's address"),
            ));
        }
        let routes = self.routes()?;
        let frames_out = routes
            .iter()
            .any(|r| r.service == LinkedService::Frames && r.direction == LinkDirection::Out);
        match self.frames_max_hz {
            Some(hz) if !(hz.is_finite() && hz > 0.0) => {
                return Err(refuse(
                    "frames_max_hz",
                    format!("{hz}: expected a positive rate"),
                ));
            }
            Some(_) if !frames_out => {
                return Err(refuse(
                    "frames_max_hz",
                    "given, but frames are not carried out from this host",
                ));
            }
            None if frames_out => {
                return Err(refuse(
                    "frames_max_hz",
                    "frames go out: say how many per second at most (frames are large: a \
                     camera's full rate may not fit the network)",
                ));
            }
            _ => {}
        }
        if self.user.is_empty() || self.user.contains([':', ' ', '\t', '\n']) {
            return Err(refuse(
                "user",
                format!("{:?}: expected a name without ':' or blanks", self.user),
            ));
        }
        if self.password_file.as_os_str().is_empty() {
            return Err(refuse(
                "password_file",
                "missing: the file of this host's password",
            ));
        }
        if !listen.is_empty() && self.peers_file.is_none() {
            return Err(refuse(
                "peers_file",
                "missing: a host that listens names the peers it lets in (`user:password` \
                 lines)",
            ));
        }
        Ok(LinkPlan {
            listen,
            connect,
            routes,
            frames_max_hz: self.frames_max_hz,
            user: self.user.clone(),
            password_file: self.password_file.clone(),
            peers_file: self.peers_file.clone(),
        })
    }

    fn routes(&self) -> Result<Vec<Route>, LinkConfigError> {
        if self.services.is_empty() {
            return Err(refuse(
                "services",
                format!(
                    "empty: name at least one of {} with its direction (out or in)",
                    wire::names::expected_list(LinkedService::ALL.iter().map(|s| s.name()))
                ),
            ));
        }
        let mut seen = HashSet::new();
        self.services
            .iter()
            .map(|entry| {
                if !seen.insert(entry.name) {
                    return Err(refuse(
                        "services",
                        format!("{} is named twice (one direction per service)", entry.name),
                    ));
                }
                Ok(Route {
                    service: entry.name,
                    direction: entry.direction,
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn section(text: &str) -> LinkSection {
        toml::from_str(text).unwrap()
    }

    const GOOD: &str = r#"
        listen = ["tcp/10.0.0.1:7447"]
        user = "rig-pc"
        password_file = "pw"
        peers_file = "peers"
        frames_max_hz = 5.0
        services = [
            { name = "rig/state", direction = "out" },
            { name = "frames", direction = "out" },
            { name = "fields", direction = "in" },
        ]
    "#;

    #[test]
    fn a_good_section_plans_its_routes() {
        let plan = section(GOOD).plan().unwrap();
        assert_eq!(plan.listen[0].to_string(), "tcp/10.0.0.1:7447");
        assert_eq!(plan.routes.len(), 3);
        assert_eq!(
            plan.routes[2],
            Route {
                service: LinkedService::Fields,
                direction: LinkDirection::In
            }
        );
    }

    fn refusal(edit: impl FnOnce(&mut LinkSection)) -> String {
        let mut s = section(GOOD);
        edit(&mut s);
        s.plan().unwrap_err().to_string()
    }

    #[test]
    fn every_interface_is_refused_unless_allowed() {
        let error = refusal(|s| s.listen = vec!["tcp/0.0.0.0:7447".into()]);
        assert!(
            error.starts_with("[link] listen: tcp/0.0.0.0:7447 listens on every"),
            "{error}"
        );
        assert!(refusal(|s| s.listen = vec!["tcp/[::]:7447".into()]).contains("every interface"));
        let mut s = section(GOOD);
        s.listen = vec!["tcp/0.0.0.0:7447".into()];
        s.allow_any_interface = true;
        assert!(s.plan().is_ok());
    }

    #[test]
    fn bad_sections_are_refused_with_their_key() {
        type Edit = Box<dyn FnOnce(&mut LinkSection)>;
        let cases: Vec<(Edit, &str)> = vec![
            (
                Box::new(|s| s.listen = vec!["udp/10.0.0.1:7447".into()]),
                "[link] listen: endpoint",
            ),
            (Box::new(|s| s.listen.clear()), "[link] listen: neither"),
            (
                Box::new(|s| s.connect = vec!["tcp/0.0.0.0:1".into()]),
                "[link] connect:",
            ),
            (Box::new(|s| s.services.clear()), "[link] services: empty"),
            (
                Box::new(|s| s.services[1].direction = LinkDirection::In),
                "[link] frames_max_hz: given",
            ),
            (
                Box::new(|s| s.frames_max_hz = None),
                "[link] frames_max_hz: frames go out",
            ),
            (
                Box::new(|s| s.frames_max_hz = Some(0.0)),
                "[link] frames_max_hz: 0",
            ),
            (Box::new(|s| s.user = "a:b".into()), "[link] user:"),
            (
                Box::new(|s| s.password_file = PathBuf::new()),
                "[link] password_file",
            ),
            (Box::new(|s| s.peers_file = None), "[link] peers_file"),
        ];
        for (edit, start) in cases {
            let error = refusal(edit);
            assert!(
                error.starts_with(start),
                "{error:?} should start with {start:?}"
            );
        }
        let twice = refusal(|s| s.services[2].name = LinkedService::RigState);
        assert_eq!(
            twice,
            "[link] services: rig/state is named twice (one direction per service)"
        );
    }

    #[test]
    fn unknown_keys_and_services_are_refused_by_the_reader() {
        assert!(toml::from_str::<LinkSection>("listn = []").is_err());
        let error = toml::from_str::<LinkSection>(
            r#"services = [{ name = "rig/command", direction = "out" }]"#,
        )
        .unwrap_err();
        assert!(
            error.to_string().contains("expected rig/state, fields"),
            "{error}"
        );
    }
}
