//! A child process whose stderr is read line by line as it comes (and echoed, so a failing
//! test shows it) and whose stdout is collected; a waiter thread reaps it, so waiting for a
//! line or for the exit needs no polling.

use crate::HANG_GUARD;
use std::io::{BufRead, BufReader, Read};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Sends `signal` to `pid` (a process of the test's own tree, e.g. a child of a child);
/// panics if kill(2) fails.
pub fn signal(pid: i32, signal: i32) {
    // SAFETY: plain kill(2), no memory is involved.
    let rc = unsafe { libc::kill(pid, signal) };
    assert_eq!(rc, 0, "kill -{signal} {pid}");
}

pub struct Proc {
    pub name: String,
    pid: i32,
    exited: Receiver<ExitStatus>,
    status: Option<ExitStatus>,
    stderr_lines: Receiver<String>,
    stderr_log: Arc<Mutex<Vec<String>>>,
    stdout: Option<JoinHandle<String>>,
}

impl Proc {
    /// Starts `command` (stdin null, stdout and stderr piped) as `name`.
    pub fn spawn(name: &str, mut command: Command) -> Proc {
        let mut child = command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("{name}: spawning {command:?}: {e}"));
        let pid = child.id() as i32;
        let mut stdout_pipe = child.stdout.take().expect("piped stdout");
        let stdout = std::thread::spawn(move || {
            let mut text = String::new();
            let _ = stdout_pipe.read_to_string(&mut text);
            text
        });
        let stderr_pipe = child.stderr.take().expect("piped stderr");
        let (line_tx, stderr_lines) = channel();
        let stderr_log = Arc::new(Mutex::new(Vec::new()));
        let log = Arc::clone(&stderr_log);
        let label = name.to_string();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr_pipe).lines() {
                let Ok(line) = line else { break };
                eprintln!("  [{label}] {line}");
                log.lock().unwrap().push(line.clone());
                let _ = line_tx.send(line);
            }
        });
        let (exit_tx, exited) = channel();
        std::thread::spawn(move || {
            if let Ok(status) = child.wait() {
                let _ = exit_tx.send(status);
            }
        });
        Proc {
            name: name.to_string(),
            pid,
            exited,
            status: None,
            stderr_lines,
            stderr_log,
            stdout: Some(stdout),
        }
    }

    pub fn pid(&self) -> i32 {
        self.pid
    }

    /// Every stderr line so far, for failure messages.
    pub fn stderr(&self) -> String {
        self.stderr_log.lock().unwrap().join("\n")
    }

    /// Waits for a stderr line matching `matches` (readiness, a status line); panics with the
    /// process's stderr on exit or after the hang guard.
    pub fn wait_for_stderr(&mut self, what: &str, matches: impl Fn(&str) -> bool) -> String {
        let give_up = Instant::now() + HANG_GUARD;
        loop {
            let left = give_up.saturating_duration_since(Instant::now());
            match self.stderr_lines.recv_timeout(left) {
                Ok(line) if matches(&line) => return line,
                Ok(_) => {}
                Err(RecvTimeoutError::Timeout) => panic!(
                    "{}: no {what} within {HANG_GUARD:?}; stderr:\n{}",
                    self.name,
                    self.stderr()
                ),
                Err(RecvTimeoutError::Disconnected) => panic!(
                    "{}: exited before {what}; stderr:\n{}",
                    self.name,
                    self.stderr()
                ),
            }
        }
    }

    /// Waits for a stderr line containing `needle`; returns it.
    pub fn wait_line(&mut self, needle: &str) -> String {
        self.wait_for_stderr(&format!("line with {needle:?}"), |line| {
            line.contains(needle)
        })
    }

    /// The first stderr line so far starting with `prefix` (a final summary line).
    pub fn line_starting(&self, prefix: &str) -> Option<String> {
        self.stderr_log
            .lock()
            .unwrap()
            .iter()
            .find(|l| l.starts_with(prefix))
            .cloned()
    }

    /// Whether the process is still running.
    pub fn is_running(&mut self) -> bool {
        if self.status.is_none() {
            self.status = self.exited.try_recv().ok();
        }
        self.status.is_none()
    }

    /// Sends `signal` (e.g. `libc::SIGTERM`) if the process is still running.
    pub fn signal(&mut self, signal: i32) {
        // Our own child, which the waiter thread has not reaped: its pid is still its own.
        if self.is_running() {
            self::signal(self.pid, signal);
        }
    }

    /// Waits for the exit (hang guard: SIGKILL and panic); returns status, stdout, stderr.
    pub fn wait(&mut self) -> (ExitStatus, String, String) {
        let status = match self.status {
            Some(status) => status,
            None => match self.exited.recv_timeout(HANG_GUARD) {
                Ok(status) => status,
                Err(_) => {
                    self.signal(libc::SIGKILL);
                    panic!(
                        "{}: still running after {HANG_GUARD:?}; stderr:\n{}",
                        self.name,
                        self.stderr()
                    );
                }
            },
        };
        self.status = Some(status);
        let stdout = self
            .stdout
            .take()
            .map(|h| h.join().expect("stdout reader"))
            .unwrap_or_default();
        // The stderr reader ends with the process; drain what it still holds.
        while self
            .stderr_lines
            .recv_timeout(Duration::from_secs(5))
            .is_ok()
        {}
        (status, stdout, self.stderr())
    }

    /// Waits for the exit as [`Proc::wait`] does; returns the status alone.
    pub fn wait_exit(&mut self) -> ExitStatus {
        self.wait().0
    }

    /// SIGKILL if still running, then waits (bounded) for the waiter to reap it.
    pub fn kill(&mut self) {
        if self.is_running() {
            self.signal(libc::SIGKILL);
            if let Ok(status) = self.exited.recv_timeout(Duration::from_secs(30)) {
                self.status = Some(status);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shell(script: &str) -> Command {
        let mut command = Command::new("sh");
        command.args(["-c", script]);
        command
    }

    #[test]
    fn lines_stdout_and_exit_status_are_collected() {
        let mut p = Proc::spawn(
            "sh",
            shell("echo out; echo one >&2; echo ready now >&2; exit 3"),
        );
        assert_eq!(p.wait_line("ready"), "ready now");
        let (status, stdout, stderr) = p.wait();
        assert_eq!(status.code(), Some(3));
        assert_eq!(stdout, "out\n");
        assert_eq!(stderr, "one\nready now");
        assert_eq!(p.line_starting("one").as_deref(), Some("one"));
        assert!(!p.is_running());
    }

    #[test]
    fn a_signal_ends_a_running_child() {
        use std::os::unix::process::ExitStatusExt;
        let mut p = Proc::spawn("sleeper", shell("echo up >&2; exec sleep 60"));
        p.wait_line("up");
        assert!(p.is_running());
        p.signal(libc::SIGTERM);
        assert_eq!(p.wait_exit().signal(), Some(libc::SIGTERM));
        p.kill(); // already gone: nothing to do
    }
}
