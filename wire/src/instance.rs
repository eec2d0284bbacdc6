//! An instance is one run of the bench: every process of the run shares its name, which becomes
//! the iceoryx2 file prefix, so two runs (or two tests) on one machine never meet.

use iceoryx2::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// Longest instance name accepted (the prefix lands in file names of `/dev/shm`).
pub const MAX_NAME_LEN: usize = 48;

/// Why an instance, its node, a service or the claim of a role could not be had.
#[derive(Debug, thiserror::Error)]
pub enum InstanceError {
    #[error("instance name {name:?}: {reason}")]
    BadName { name: String, reason: String },
    #[error("cannot create the {role} node: {detail}")]
    Node { role: String, detail: String },
    #[error("cannot open service {service:?}: {detail}")]
    Service { service: String, detail: String },
    #[error(
        "{path} has {:.1} MiB free but the services need about {:.1} MiB: free some space \
         (old runs: `ls {path}`), use a smaller frame, or enlarge {path} \
         (mount -o remount,size=... {path})",
        *.free_bytes as f64 / 1048576.0,
        *.needed_bytes as f64 / 1048576.0
    )]
    ShmSpace {
        needed_bytes: u64,
        free_bytes: u64,
        path: String,
    },
    /// The role already has a process on this instance.
    #[error(
        "instance {instance} already has a {role} ({}): stop it, or use another --instance",
        .pid.map_or("pid unknown".into(), |pid| format!("pid {pid}"))
    )]
    Owned {
        instance: String,
        role: String,
        pid: Option<u32>,
    },
    #[error("{0}")]
    Io(String),
    /// A node or a service that could not be made while the process's descriptors were
    /// exhausted (exit code [`crate::exit::RESOURCES`]: a restart would fail the same way).
    /// `what` says what, e.g. `open service "frames"`.
    #[error("cannot {what}: {detail}; {resources}")]
    OutOfResources {
        what: String,
        detail: String,
        resources: crate::resources::Resources,
    },
    /// A subscriber that could not connect to a publisher (exit code
    /// [`crate::exit::RESOURCES`]).
    #[error(transparent)]
    Connection(#[from] crate::resources::ConnectionError),
}

/// One run's name and the iceoryx2 configuration that isolates it. Dropped after the nodes it
/// created (declare it first), it removes iceoryx2's node counter of the instance when no node
/// of the instance is left ([`Instance::release_node_counter_if_unused`]), so a process that
/// exits normally leaves nothing in `/dev/shm`.
#[derive(Debug)]
pub struct Instance {
    name: String,
    config: Config,
    /// A node was created through this value: its drop then cleans up after it.
    created_node: AtomicBool,
}

impl Instance {
    /// The default instance name: `dicstream_<user>`, so one user's runs share it by default.
    pub fn default_name() -> String {
        let user = std::env::var("USER")
            .or_else(|_| std::env::var("LOGNAME"))
            .unwrap_or_else(|_| "user".to_string());
        let user: String = user
            .chars()
            .filter(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '-')
            .take(24)
            .collect();
        format!("dicstream_{}", if user.is_empty() { "user" } else { &user })
    }

    /// Validates `name` (ASCII letters, digits, `_`, `-`; at most [`MAX_NAME_LEN`]).
    pub fn new(name: &str) -> Result<Instance, InstanceError> {
        let bad = |reason: &str| InstanceError::BadName {
            name: name.to_string(),
            reason: reason.to_string(),
        };
        if name.is_empty() {
            return Err(bad("must not be empty"));
        }
        if name.len() > MAX_NAME_LEN {
            return Err(bad(&format!("longer than {MAX_NAME_LEN} characters")));
        }
        if !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        {
            return Err(bad("use only ASCII letters, digits, '_' and '-'"));
        }
        let mut config = Config::default();
        let prefix = Self::prefix_of(name);
        config.global.prefix =
            FileName::new(prefix.as_bytes()).map_err(|e| bad(&format!("{e:?}")))?;
        Ok(Instance {
            name: name.to_string(),
            config,
            created_node: AtomicBool::new(false),
        })
    }

    fn prefix_of(name: &str) -> String {
        format!("{name}_")
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The file prefix of this instance's shared-memory and bookkeeping files.
    pub fn prefix(&self) -> String {
        Self::prefix_of(&self.name)
    }

    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Creates the node of one process role (`producer`, `tap`, ...). Dead nodes of this
    /// instance are cleaned first (iceoryx2 also does it on creation; doing it here lets the
    /// caller know how many it found).
    pub fn create_node(&self, role: &str) -> Result<(Node<ipc::Service>, usize), InstanceError> {
        let removed = self.cleanup_dead_nodes();
        let node_error = |detail: String| InstanceError::Node {
            role: role.to_string(),
            detail,
        };
        let node_name = NodeName::new(role).map_err(|e| node_error(format!("{e:?}")))?;
        self.created_node.store(true, Ordering::Relaxed);
        let node = NodeBuilder::new()
            .name(&node_name)
            .config(&self.config)
            // Signals are handled by `crate::signals` (installed first thing in `main`).
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|e| {
                let resources = crate::resources::Resources::now();
                if resources.descriptors_exhausted() {
                    InstanceError::OutOfResources {
                        what: format!("create the {role} node"),
                        detail: format!("{e:?}"),
                        resources,
                    }
                } else {
                    node_error(format!("{e:?}; {resources}"))
                }
            })?;
        Ok((node, removed))
    }

    /// Claims `role` on this instance for as long as the returned [`crate::owner::Owner`]
    /// lives: a second process of the role is refused, naming the first one's pid.
    pub fn claim(&self, role: &str) -> Result<crate::owner::Owner, InstanceError> {
        crate::owner::claim(&self.name, role).map_err(|e| match e {
            crate::owner::ClaimError::Owned { pid } => InstanceError::Owned {
                instance: self.name.clone(),
                role: role.to_string(),
                pid,
            },
            crate::owner::ClaimError::Io { path, error } => {
                InstanceError::Io(format!("cannot claim {}: {error}", path.display()))
            }
        })
    }

    /// Removes the stale resources of this instance's nodes whose process died (e.g. SIGKILL).
    /// Returns how many dead nodes were cleaned.
    pub fn cleanup_dead_nodes(&self) -> usize {
        let mut removed = 0;
        let _ = Node::<ipc::Service>::list(&self.config, |state| {
            if let NodeState::<ipc::Service>::Dead(view) = state {
                if view.try_remove_stale_resources().is_ok() {
                    removed += 1;
                }
            }
            CallbackProgression::Continue
        });
        removed
    }

    /// Removes iceoryx2's node counter of this instance when no node of the instance is left
    /// (after cleaning the dead ones). The counter, `/dev/shm/<prefix>…_node.<version>.global_mgmt`,
    /// is created by the first node of a prefix and never removed by iceoryx2 0.10 (it is made
    /// without ownership; only `iceoryx2::testing` removes it), so without this every process
    /// left it behind even at a normal exit. Returns whether it was removed.
    ///
    /// Harmless against a process starting meanwhile: the counter is only open while a node is
    /// being created, a process holding it keeps its mapping after the unlink, and a node id is
    /// unique without it (pid, creation time and counter), so a counter that restarts from zero
    /// collides with nothing.
    pub fn release_node_counter_if_unused(&self) -> bool {
        self.cleanup_dead_nodes();
        let mut nodes = 0usize;
        let listed = Node::<ipc::Service>::list(&self.config, |_| {
            nodes += 1;
            CallbackProgression::Continue
        });
        if listed.is_err() || nodes > 0 {
            return false;
        }
        // SAFETY: iceoryx2 asks that no other process use the instance; none has a node on it
        // (listed above), and one that is creating its first node meanwhile is safe as said in
        // this function's documentation. The removal only unlinks the counter's file.
        let removed =
            unsafe { iceoryx2::testing::remove_global_mgmt_segment::<ipc::Service>(&self.config) };
        matches!(removed, Ok(true))
    }

    /// Files of this instance left in `/dev/shm` and in iceoryx2's bookkeeping folder.
    pub fn leftover_files(&self) -> Vec<PathBuf> {
        let prefix = self.prefix();
        let mut found = Vec::new();
        let mut roots = vec![PathBuf::from("/dev/shm")];
        roots.push(PathBuf::from(self.config.global.root_path().to_string()));
        for root in roots {
            collect_with_prefix(&root, &prefix, 3, &mut found);
        }
        found.sort();
        found
    }

    /// Deletes [`Instance::leftover_files`]. Only for tests and for `dicstream run` after every
    /// child has stopped: removing files under a live process breaks it.
    pub fn remove_leftover_files(&self) -> usize {
        let files = self.leftover_files();
        files
            .iter()
            .filter(|path| std::fs::remove_file(path).is_ok())
            .count()
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        if self.created_node.load(Ordering::Relaxed) {
            self.release_node_counter_if_unused();
        }
    }
}

fn collect_with_prefix(dir: &std::path::Path, prefix: &str, depth: u32, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let is_dir = entry.file_type().map(|t| t.is_dir()).unwrap_or(false);
        if is_dir && depth > 0 {
            collect_with_prefix(&path, prefix, depth - 1, found);
        } else if !is_dir && entry.file_name().to_string_lossy().starts_with(prefix) {
            found.push(path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_validated() {
        assert!(Instance::new("bench_1-a").is_ok());
        assert!(Instance::new("").is_err());
        assert!(Instance::new("has space")
            .unwrap_err()
            .to_string()
            .contains("letters"));
        assert!(Instance::new(&"x".repeat(MAX_NAME_LEN + 1)).is_err());
        assert!(Instance::default_name().starts_with("dicstream_"));
        assert!(Instance::new(&Instance::default_name()).is_ok());
    }

    fn counter_files(name: &str) -> Vec<PathBuf> {
        let probe = Instance::new(name).unwrap();
        probe
            .leftover_files()
            .into_iter()
            .filter(|p| p.to_string_lossy().ends_with(".global_mgmt"))
            .collect()
    }

    #[test]
    fn the_last_user_of_an_instance_removes_its_node_counter() {
        let name = format!("wire_counter_{}", std::process::id());
        let first = Instance::new(&name).unwrap();
        let second = Instance::new(&name).unwrap();
        let (node, _) = first.create_node("first").unwrap();
        let (other, _) = second.create_node("second").unwrap();
        assert_eq!(
            counter_files(&name).len(),
            1,
            "iceoryx2 made its node counter"
        );
        drop(node);
        drop(first);
        assert_eq!(
            counter_files(&name).len(),
            1,
            "another node still uses the instance"
        );
        drop(other);
        drop(second);
        assert!(counter_files(&name).is_empty());
        assert!(Instance::new(&name).unwrap().leftover_files().is_empty());
    }
}
