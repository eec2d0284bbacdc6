//! Unique instance names and a test's own instance, cleaned on drop.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A unique instance name: `t`, the pid, the test name (alphanumerics, at most 24) and a
/// counter, within `wire::instance::MAX_NAME_LEN`.
pub fn unique_instance(test: &str) -> String {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let test: String = test
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .take(24)
        .collect();
    let mut name = format!("t{}_{test}_{n}", std::process::id());
    name.truncate(wire::instance::MAX_NAME_LEN);
    name
}

/// A test's instance under a unique name: files left by an earlier run of the same name are
/// removed at start, and dead nodes and every file of the instance when dropped (test passed
/// or panicked).
pub struct TestInstance {
    pub instance: wire::Instance,
}

impl TestInstance {
    pub fn new(test: &str) -> TestInstance {
        let instance = wire::Instance::new(&unique_instance(test)).expect("valid instance name");
        instance.remove_leftover_files();
        TestInstance { instance }
    }

    pub fn name(&self) -> &str {
        self.instance.name()
    }

    /// Cleans dead nodes and removes every file of the instance in `/dev/shm` and iceoryx2's
    /// folder (idempotent).
    pub fn clean(&self) {
        self.instance.cleanup_dead_nodes();
        self.instance.remove_leftover_files();
    }

    /// Files the instance left once its processes ended and the test dropped its own nodes.
    /// Every process removes what it owns when it is the last user of the instance (iceoryx2's
    /// node counter included), so after a normal shutdown this is empty. The test is a user
    /// too when it made a node: as the last one, it releases the counter first.
    pub fn leftovers_after_clean_shutdown(&self) -> Vec<PathBuf> {
        self.instance.release_node_counter_if_unused();
        self.instance.leftover_files()
    }
}

impl std::ops::Deref for TestInstance {
    type Target = wire::Instance;
    fn deref(&self) -> &wire::Instance {
        &self.instance
    }
}

impl Drop for TestInstance {
    fn drop(&mut self) {
        self.clean();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_valid_and_bounded() {
        let long = "a test name far longer than any instance name may be";
        let (a, b) = (unique_instance(long), unique_instance(long));
        assert_ne!(a, b);
        assert!(a.len() <= wire::instance::MAX_NAME_LEN, "{a}");
        assert!(wire::Instance::new(&a).is_ok(), "{a}");
        assert!(unique_instance("x/y z").contains("x_y_z"));
    }
}
