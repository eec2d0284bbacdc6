//! Helpers of the multi-process tests: a [`Run`] owns a unique instance, its child processes
//! and a scratch folder; dropping it (test passed or panicked) kills the children that are
//! still alive and removes the instance's files from `/dev/shm` and iceoryx2's folder.
//!
//! Timeouts here only guard against a hang (a test that would otherwise never end); no test
//! asserts a wall-clock time.

#![allow(dead_code)]

pub mod bench_run;

use std::io::{BufRead, BufReader, Read};
use std::path::PathBuf;
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Generous bound for anything a test waits for (start-up, a count of frames): a hang guard.
pub const HANG_GUARD: Duration = Duration::from_secs(180);

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A unique instance name: pid, test name and a counter (at most 48 characters).
pub fn unique_instance(test: &str) -> String {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let test: String = test
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .take(24)
        .collect();
    format!("t{}_{test}_{n}", std::process::id())
}

/// A child `dicstream` process whose stderr is read line by line as it comes and whose stdout
/// is collected; a waiter thread reaps it, so waiting needs no polling.
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
    pub fn pid(&self) -> i32 {
        self.pid
    }

    /// Every stderr line so far, for failure messages.
    pub fn stderr_so_far(&self) -> String {
        self.stderr_log.lock().unwrap().join("\n")
    }

    /// Waits for a stderr line matching `matches`; panics with the process's log on exit or
    /// after the hang guard.
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
                    self.stderr_so_far()
                ),
                Err(RecvTimeoutError::Disconnected) => panic!(
                    "{}: exited before {what}; stderr:\n{}",
                    self.name,
                    self.stderr_so_far()
                ),
            }
        }
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
        if self.is_running() {
            // SAFETY: plain kill(2) on our own child, which the waiter thread has not reaped.
            let rc = unsafe { libc::kill(self.pid, signal) };
            assert_eq!(rc, 0, "kill({}, {signal}) failed", self.pid);
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
                        self.stderr_so_far()
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
        (status, stdout, self.stderr_so_far())
    }
}

/// One test's instance, children and scratch folder; cleaned on drop.
pub struct Run {
    pub instance: wire::Instance,
    pub dir: PathBuf,
    children: Vec<Proc>,
}

impl Run {
    pub fn new(test: &str) -> Run {
        let instance = wire::Instance::new(&unique_instance(test)).expect("valid instance name");
        let dir = std::env::temp_dir().join(format!("dicstream-test-{}", instance.name()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch folder");
        Run {
            instance,
            dir,
            children: Vec::new(),
        }
    }

    pub fn name(&self) -> &str {
        self.instance.name()
    }

    /// Starts `dicstream ARGS` (add `--instance` yourself where the subcommand takes it).
    pub fn spawn(&mut self, name: &str, args: &[&str]) -> &mut Proc {
        let mut child = Command::new(env!("CARGO_BIN_EXE_dicstream"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("spawning dicstream {args:?}: {e}"));
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
        std::thread::spawn(move || {
            for line in BufReader::new(stderr_pipe).lines() {
                let Ok(line) = line else { break };
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
        self.children.push(Proc {
            name: name.to_string(),
            pid,
            exited,
            status: None,
            stderr_lines,
            stderr_log,
            stdout: Some(stdout),
        });
        self.children.last_mut().unwrap()
    }

    /// The child started as `name`.
    pub fn child(&mut self, name: &str) -> &mut Proc {
        self.children
            .iter_mut()
            .find(|p| p.name == name)
            .unwrap_or_else(|| panic!("no child named {name}"))
    }

    /// Runs `dicstream ARGS` to its end; returns status, stdout, stderr.
    pub fn run_to_end(&mut self, name: &str, args: &[&str]) -> (ExitStatus, String, String) {
        self.spawn(name, args).wait()
    }

    /// Files the instance left, apart from iceoryx2's per-prefix node counter
    /// (`<prefix>…node.<version>.global_mgmt`, 16 bytes), which iceoryx2 0.10 keeps on purpose
    /// (created without ownership, never removed by a node) so that node ids stay unique.
    pub fn leftovers_after_clean_shutdown(&self) -> Vec<PathBuf> {
        self.instance
            .leftover_files()
            .into_iter()
            .filter(|p| {
                !p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.ends_with(".global_mgmt"))
            })
            .collect()
    }

    /// Kills what still runs, cleans dead nodes, removes the instance's files and the scratch
    /// folder. Called by drop; call it explicitly to check the result.
    pub fn teardown(&mut self) {
        for child in &mut self.children {
            if child.is_running() {
                child.signal(libc::SIGKILL);
                let _ = child.exited.recv_timeout(Duration::from_secs(30));
            }
        }
        self.instance.cleanup_dead_nodes();
        self.instance.remove_leftover_files();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        self.teardown();
    }
}

/// Parses the one JSON object a `tap --json` prints.
pub fn tap_json(stdout: &str) -> serde_json::Value {
    serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("tap --json printed no JSON object ({e}):\n{stdout}"))
}
