//! A child that died: reported with how and its last lines, counted as a fault, and restarted
//! with arguments that resume it while the restarts allow (a camera continues the frame ids);
//! an exit that a restart would repeat ends the run.

use super::launch::waits_for_ready;
use super::open::Run;
use super::READY_TIMEOUT;
use crate::children::Exit;
use anyhow::bail;

/// Exits not restarted, and why: the child would fail the same way, or start its test over.
const NOT_RESTARTED: [(u8, &str); 4] = [
    (
        wire::exit::OUTPUT_FAILED,
        "a results file could not be written",
    ),
    (
        wire::exit::CANNOT_RESUME,
        "it could not resume its test safely",
    ),
    (
        wire::exit::RESOURCES,
        "it could not get a system resource it needs: not restarted",
    ),
    (
        wire::exit::CONFIG,
        "its configuration does not fit its input: not restarted",
    ),
];

/// Why an exit of code `code` is not restarted, if it is not.
pub(super) fn not_restarted_why(code: Option<i32>) -> Option<&'static str> {
    NOT_RESTARTED
        .iter()
        .find(|(c, _)| code == Some(i32::from(*c)))
        .map(|(_, why)| *why)
}

/// `<role> (pid N) died: <how>`, with its last lines.
fn death_report(exit: &Exit) -> String {
    let last_lines = match exit.last_lines.is_empty() {
        true => String::new(),
        false => format!("; its last lines:\n    {}", exit.last_lines.join("\n    ")),
    };
    format!(
        "{} (pid {}) died: {}{last_lines}",
        exit.role.name(),
        exit.pid,
        exit.how
    )
}

impl Run<'_> {
    /// Reports the death of `exit`'s child and restarts it; an error ends the run (an exit
    /// not restarted, no restart left, a restart that failed).
    pub(super) fn handle_death(&mut self, exit: Exit) -> anyhow::Result<()> {
        let role = exit.role;
        let report = death_report(&exit);
        eprintln!("run: {report}");
        self.incidents
            .faults
            .push(format!("{} {}", role.name(), exit.how));
        if let Some(why) = not_restarted_why(exit.code) {
            bail!("{report}\n({why})");
        }
        let config = self.config();
        let count = self.incidents.restart_counts[role as usize];
        if !config.run.restart || count >= config.run.max_restarts {
            let restart = if config.run.restart { "on" } else { "off" };
            bail!(
                "{report}\n(restart {restart}; {count} of {} restarts used)",
                config.run.max_restarts
            );
        }
        self.incidents.restart_counts[role as usize] += 1;
        let next_frame_id = self.recorder.last_frame_id.map_or(0, |id| id + 1);
        let args = self.child_args(role, next_frame_id)?;
        let pid = self.supervisor.restart(role, Some(args))?;
        if waits_for_ready(role, config) && !self.supervisor.wait_ready(role, READY_TIMEOUT)? {
            return Ok(());
        }
        let note = format!(
            "{} restarted (pid {pid}, restart {} of {}) after: {}",
            role.name(),
            count + 1,
            config.run.max_restarts,
            exit.how
        );
        eprintln!("run: {note}");
        self.incidents.restarts.push(note);
        Ok(())
    }
}
