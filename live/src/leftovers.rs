//! What the processes of a run left in `/dev/shm` (and iceoryx2's folder) once they had all
//! stopped: named on stderr, counted in `summary.json` (`leftover_shm_files`), then removed.
//! A process that exits normally leaves nothing (`wire::Instance` removes iceoryx2's node
//! counter when its process is the last user of the instance), and the resources of a child
//! killed by a fault are cleaned as dead nodes first, so a file reported here is a defect.

use std::path::PathBuf;

/// Reports and removes the instance's leftover files. Call it once every child has stopped and
/// the monitor's node is dropped. Returns how many files were found.
pub fn report_and_remove(instance: &wire::Instance) -> usize {
    // Cleans the dead nodes, then removes the node counter if no node is left.
    instance.release_node_counter_if_unused();
    let left = instance.leftover_files();
    if let Some(text) = describe(instance.name(), &left) {
        eprintln!("{text}");
    }
    instance.remove_leftover_files();
    let kept = instance.leftover_files();
    if !kept.is_empty() {
        eprintln!(
            "run: warning: could not remove {} of them: {}",
            kept.len(),
            paths(&kept)
        );
    }
    left.len()
}

/// The stderr report of `left`, or `None` when nothing was left.
fn describe(instance: &str, left: &[PathBuf]) -> Option<String> {
    (!left.is_empty()).then(|| {
        format!(
            "run: warning: {} file(s) of instance {instance} left after every process stopped \
             (removing them): {}",
            left.len(),
            paths(left)
        )
    })
}

fn paths(list: &[PathBuf]) -> String {
    list.iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_left_says_nothing_and_leftovers_are_named() {
        assert_eq!(describe("run_1", &[]), None);
        let left = [
            PathBuf::from("/dev/shm/run_1_abc_node.0_10_0.global_mgmt"),
            PathBuf::from("/dev/shm/run_1_def.data"),
        ];
        let text = describe("run_1", &left).expect("a report");
        assert!(text.contains("2 file(s) of instance run_1"), "{text}");
        assert!(
            text.contains("/dev/shm/run_1_abc_node.0_10_0.global_mgmt, /dev/shm/run_1_def.data"),
            "{text}"
        );
    }
}
