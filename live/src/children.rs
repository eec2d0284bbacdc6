//! The bench's processes as children of `dicstream run`: spawned from the same binary, each
//! in its own process group (a Ctrl-C reaches only the supervisor, which then stops them in
//! order) and with a parent-death signal (a supervisor killed with SIGKILL takes them along).
//! Their stdout and stderr go, line by line, to `logs/<role>.log`; a line ending in `ready`
//! after the role's name marks the process ready. Exits are noticed as they happen and
//! reported with the exit status or signal and the last lines the process printed.

use crate::camera_events::{camera_event, CameraEvent};
use anyhow::Context;
use crossbeam::channel::{unbounded, Receiver, Sender};
use std::collections::VecDeque;
use std::io::{BufRead, Write};
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// The processes of the bench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Role {
    Rig,
    Producer,
    Correlator,
    Identifier,
    /// `dicstream link` to another host's instance, when `[link] start_with_run = true`.
    Link,
}

impl Role {
    pub const COUNT: usize = 5;
    pub const ALL: [Role; Role::COUNT] = [
        Role::Rig,
        Role::Producer,
        Role::Correlator,
        Role::Identifier,
        Role::Link,
    ];

    /// The `dicstream` subcommand, also the log file name and the prefix of its lines.
    pub fn name(self) -> &'static str {
        match self {
            Role::Rig => "rig",
            Role::Producer => "producer",
            Role::Correlator => "correlator",
            Role::Identifier => "identifier",
            Role::Link => "link",
        }
    }
}

/// Lines kept per process for the report of its death.
const LAST_LINES: usize = 6;

enum Event {
    Line {
        role: Role,
        generation: u32,
        line: String,
    },
}

struct Managed {
    role: Role,
    args: Vec<String>,
    child: Option<Child>,
    /// Starts so far; lines of older generations are stale.
    generation: u32,
    ready: bool,
    /// The process said its input reached it (the identifier's first field).
    heard_input: bool,
    last_lines: VecDeque<String>,
    /// CPU time (s) of earlier generations, and the last sample of the current one.
    cpu_s_ended: f64,
    cpu_s_current: f64,
}

/// A process that ended, and how.
#[derive(Clone, Debug)]
pub struct Exit {
    pub role: Role,
    pub pid: u32,
    /// `exit status 0`, `exit status 1`, `killed by signal 9 (SIGKILL)`.
    pub how: String,
    pub success: bool,
    /// The exit code, if it exited (not killed by a signal).
    pub code: Option<i32>,
    /// The last lines it printed, oldest first.
    pub last_lines: Vec<String>,
}

/// A child that ended before it said it was ready: its exit.
#[derive(Debug)]
pub struct StoppedBeforeReady(pub Exit);

impl std::fmt::Display for StoppedBeforeReady {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let exit = &self.0;
        write!(
            f,
            "{} (pid {}) stopped before it was ready ({}):\n  {}",
            exit.role.name(),
            exit.pid,
            exit.how,
            exit.last_lines.join("\n  ")
        )
    }
}

impl std::error::Error for StoppedBeforeReady {}

/// Describes an exit status the way a test engineer reads it.
pub fn describe_status(status: ExitStatus) -> String {
    if let Some(code) = status.code() {
        return format!("exit status {code}");
    }
    match status.signal() {
        Some(signal) => {
            let name = match signal {
                libc::SIGKILL => " (SIGKILL)",
                libc::SIGTERM => " (SIGTERM)",
                libc::SIGINT => " (SIGINT)",
                libc::SIGSEGV => " (SIGSEGV)",
                libc::SIGBUS => " (SIGBUS: out of shared memory?)",
                libc::SIGABRT => " (SIGABRT)",
                _ => "",
            };
            format!("killed by signal {signal}{name}")
        }
        None => "ended".into(),
    }
}

/// The children of one run.
pub struct Supervisor {
    exe: PathBuf,
    log_dir: PathBuf,
    children: Vec<Managed>,
    /// Exits noticed but not yet handed out by [`Supervisor::take_exits`]: an exit noticed
    /// while waiting for another child is kept, never lost.
    exited: Vec<Exit>,
    /// The producer's camera events with their lines, not yet handed out by
    /// [`Supervisor::take_camera_events`].
    camera_events: Vec<(CameraEvent, String)>,
    tx: Sender<Event>,
    rx: Receiver<Event>,
}

impl Supervisor {
    /// Children run `exe` (the `dicstream` binary) and log into `log_dir`.
    pub fn new(exe: &Path, log_dir: &Path) -> anyhow::Result<Supervisor> {
        std::fs::create_dir_all(log_dir)
            .with_context(|| format!("cannot create {}", log_dir.display()))?;
        let (tx, rx) = unbounded();
        Ok(Supervisor {
            exe: exe.to_path_buf(),
            log_dir: log_dir.to_path_buf(),
            children: Vec::new(),
            exited: Vec::new(),
            camera_events: Vec::new(),
            tx,
            rx,
        })
    }

    fn managed(&mut self, role: Role) -> &mut Managed {
        self.children
            .iter_mut()
            .find(|m| m.role == role)
            .expect("role was spawned")
    }

    /// Starts `dicstream <role> <args...>`.
    pub fn spawn(&mut self, role: Role, args: Vec<String>) -> anyhow::Result<u32> {
        let generation = self.next_generation(role, args);
        // Out of descriptors, the supervisor says so with its limit.
        let pipe = |e: std::io::Error| {
            let note = wire::descriptors::note_for(&e);
            anyhow::Error::from(e).context(format!("{}: cannot make a pipe{note}", role.name()))
        };
        let (reader, writer) = std::io::pipe().map_err(pipe)?;
        let writer_err = writer.try_clone().map_err(pipe)?;
        let mut command = Command::new(&self.exe);
        command
            .arg(role.name())
            .args(&self.managed(role).args)
            .stdin(Stdio::null())
            .stdout(writer)
            .stderr(writer_err)
            .process_group(0);
        with_parent_death_signal(&mut command);
        let child = command.spawn().map_err(|e| {
            let note = wire::descriptors::note_for(&e);
            let start = format!("cannot start {} {}{note}", self.exe.display(), role.name());
            anyhow::Error::from(e).context(start)
        })?;
        // The parent's copies of the pipe's writing ends: the log thread then sees the end of
        // the output when the child exits.
        drop(command);
        let pid = child.id();
        self.managed(role).child = Some(child);
        let log_path = self.log_dir.join(format!("{}.log", role.name()));
        let mut log = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&log_path)
            .with_context(|| log_path.display().to_string())?;
        let _ = writeln!(log, "--- start {generation} (pid {pid})");
        forward_lines(role, generation, reader, log, self.tx.clone())?;
        Ok(pid)
    }

    /// Makes `role` ready for a new start with `args` (its first, or a restart); returns the
    /// start's generation.
    fn next_generation(&mut self, role: Role, args: Vec<String>) -> u32 {
        if !self.children.iter().any(|m| m.role == role) {
            self.children.push(Managed {
                role,
                args: Vec::new(),
                child: None,
                generation: 0,
                ready: false,
                heard_input: false,
                last_lines: VecDeque::new(),
                cpu_s_ended: 0.0,
                cpu_s_current: 0.0,
            });
        }
        let managed = self.managed(role);
        assert!(
            managed.child.is_none(),
            "{} is already running",
            role.name()
        );
        managed.args = args;
        managed.generation += 1;
        managed.ready = false;
        managed.heard_input = false;
        managed.last_lines.clear();
        managed.cpu_s_ended += std::mem::take(&mut managed.cpu_s_current);
        managed.generation
    }

    /// Takes in one printed line: readiness, last lines.
    fn absorb(&mut self, event: Event) {
        let Event::Line {
            role,
            generation,
            line,
        } = event;
        let managed = self.managed(role);
        if generation != managed.generation {
            return;
        }
        if line.starts_with(&format!("{}: ready", role.name())) {
            managed.ready = true;
        }
        if role == Role::Identifier && line.starts_with(identifier::process::FIRST_FIELD_LINE) {
            managed.heard_input = true;
        }
        if role == Role::Producer {
            if let Some(event) = camera_event(&line) {
                self.camera_events.push((event, line.clone()));
            }
        }
        let managed = self.managed(role);
        if managed.last_lines.len() == LAST_LINES {
            managed.last_lines.pop_front();
        }
        managed.last_lines.push_back(line);
    }

    /// Takes in the lines printed so far.
    fn drain_lines(&mut self) {
        while let Ok(event) = self.rx.try_recv() {
            self.absorb(event);
        }
    }

    pub fn is_ready(&mut self, role: Role) -> bool {
        self.drain_lines();
        self.managed(role).ready
    }

    /// Whether the running `role` said its input reached it (only the identifier says so).
    pub fn heard_input(&mut self, role: Role) -> bool {
        self.drain_lines();
        // A process this host does not run (`[run] processes`) heard nothing here.
        self.children
            .iter()
            .any(|m| m.role == role && m.heard_input)
    }

    pub fn pid(&self, role: Role) -> Option<u32> {
        self.children
            .iter()
            .find(|m| m.role == role)
            .and_then(|m| m.child.as_ref())
            .map(Child::id)
    }

    /// Whether `role` was ever started in this run (a run without a link has none).
    pub fn started(&self, role: Role) -> bool {
        self.children.iter().any(|m| m.role == role)
    }

    pub fn is_running(&self, role: Role) -> bool {
        self.pid(role).is_some()
    }

    /// Waits (bounded) until `role` says it is ready: Ok(true). Ok(false) when a termination
    /// signal arrived first. Its exit or the timeout is an error with the process's last lines;
    /// exits of other children seen meanwhile stay queued for [`Supervisor::take_exits`].
    pub fn wait_ready(&mut self, role: Role, timeout: Duration) -> anyhow::Result<bool> {
        let deadline = Instant::now() + timeout;
        loop {
            if self.is_ready(role) {
                return Ok(true);
            }
            if wire::signals::requested().is_some() {
                return Ok(false);
            }
            self.reap();
            if let Some(at) = self.exited.iter().position(|e| e.role == role) {
                return Err(StoppedBeforeReady(self.exited.remove(at)).into());
            }
            let now = Instant::now();
            if now >= deadline {
                anyhow::bail!(
                    "{} was not ready after {:.0} s; its last lines:\n  {}",
                    role.name(),
                    timeout.as_secs_f64(),
                    self.managed(role)
                        .last_lines
                        .iter()
                        .cloned()
                        .collect::<Vec<_>>()
                        .join("\n  ")
                );
            }
            // Sleep on the line channel: a line (possibly "ready") wakes us at once.
            let slice = (deadline - now).min(Duration::from_millis(100));
            if let Ok(event) = self.rx.recv_timeout(slice) {
                self.absorb(event);
            }
        }
    }

    /// Reads the CPU time of every running child (call it now and then: the time of a process
    /// is known up to its last sample once it has ended).
    pub fn sample_cpu(&mut self) {
        for managed in &mut self.children {
            if let Some(cpu_s) = managed.child.as_ref().and_then(|c| process_cpu_s(c.id())) {
                managed.cpu_s_current = cpu_s;
            }
        }
    }

    /// CPU seconds (user + system, all threads) of `role` over all its starts, as last sampled.
    pub fn cpu_seconds(&self, role: Role) -> f64 {
        self.children
            .iter()
            .find(|m| m.role == role)
            .map_or(0.0, |m| m.cpu_s_ended + m.cpu_s_current)
    }

    /// The producer's camera events (lost, a failed reconnection, back) since the last call,
    /// each with the line that reported it.
    pub fn take_camera_events(&mut self) -> Vec<(CameraEvent, String)> {
        self.drain_lines();
        std::mem::take(&mut self.camera_events)
    }

    /// Children that have ended since the last call, in the order they were noticed
    /// (including those noticed while waiting for a child to be ready).
    pub fn take_exits(&mut self) -> Vec<Exit> {
        self.reap();
        std::mem::take(&mut self.exited)
    }

    /// Notices the children that have ended and queues their exits.
    fn reap(&mut self) {
        self.drain_lines();
        let mut exits = Vec::new();
        for managed in &mut self.children {
            let Some(child) = managed.child.as_mut() else {
                continue;
            };
            if let Ok(Some(status)) = child.try_wait() {
                exits.push(Exit {
                    role: managed.role,
                    pid: child.id(),
                    how: describe_status(status),
                    success: status.success(),
                    code: status.code(),
                    last_lines: managed.last_lines.iter().cloned().collect(),
                });
                managed.child = None;
            }
        }
        if !exits.is_empty() {
            // Lines printed just before the exit may still be in the pipe.
            std::thread::sleep(Duration::from_millis(20));
            self.drain_lines();
            for exit in &mut exits {
                let m = self.managed(exit.role);
                exit.last_lines = m.last_lines.iter().cloned().collect();
            }
        }
        self.exited.extend(exits);
    }

    /// Kills `role` at once (SIGKILL works on a stopped process too) and queues its exit,
    /// described as `why`. False if it was not running.
    pub fn kill(&mut self, role: Role, why: &str) -> bool {
        let Some(managed) = self.children.iter_mut().find(|m| m.role == role) else {
            return false;
        };
        let Some(mut child) = managed.child.take() else {
            return false;
        };
        let _ = child.kill();
        let _ = child.wait();
        let exit = Exit {
            role,
            pid: child.id(),
            how: format!("{why}; killed by the supervisor (SIGKILL)"),
            success: false,
            code: None,
            last_lines: managed.last_lines.iter().cloned().collect(),
        };
        self.exited.push(exit);
        true
    }

    /// Starts `role` again with the arguments of its last start, or `args` if given.
    pub fn restart(&mut self, role: Role, args: Option<Vec<String>>) -> anyhow::Result<u32> {
        let args = args.unwrap_or_else(|| self.managed(role).args.clone());
        self.spawn(role, args)
    }

    /// Sends SIGTERM, waits up to `timeout`, then SIGKILL. Returns how it ended, or None if it
    /// was not running.
    pub fn stop(&mut self, role: Role, timeout: Duration) -> Option<String> {
        let managed = self.children.iter_mut().find(|m| m.role == role)?;
        let mut child = managed.child.take()?;
        let pid = child.id() as libc::pid_t;
        // SAFETY: signalling our own child by pid; it has not been reaped yet, so the pid is ours.
        unsafe {
            libc::kill(pid, libc::SIGTERM);
        }
        let deadline = Instant::now() + timeout;
        loop {
            match child.try_wait() {
                Ok(Some(status)) => return Some(describe_status(status)),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(20));
                }
                _ => {
                    let _ = child.kill();
                    let status = child.wait().ok()?;
                    return Some(format!("{} {SIGTERM_TIMED_OUT}", describe_status(status)));
                }
            }
        }
    }

    /// Stops every child, in the given order: each one's end, described (ending with
    /// [`SIGTERM_TIMED_OUT`] when it had to be killed).
    pub fn stop_all(&mut self, order: &[Role], timeout: Duration) -> Vec<(Role, String)> {
        order
            .iter()
            .filter_map(|&role| self.stop(role, timeout).map(|how| (role, how)))
            .collect()
    }
}

/// How [`Supervisor::stop`] ends the description of a child killed after its SIGTERM's
/// timeout.
pub const SIGTERM_TIMED_OUT: &str = "after SIGTERM timed out";

/// The child gets SIGTERM when this process dies (a supervisor killed with SIGKILL takes its
/// children along).
fn with_parent_death_signal(command: &mut Command) {
    // SAFETY: prctl is async-signal-safe; it only sets this child's parent-death signal.
    unsafe {
        command.pre_exec(|| {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

/// A thread that copies each line the child prints into its log and hands it to the
/// supervisor, until the child closes its output (or the supervisor is gone).
fn forward_lines(
    role: Role,
    generation: u32,
    reader: std::io::PipeReader,
    mut log: std::fs::File,
    tx: Sender<Event>,
) -> anyhow::Result<()> {
    std::thread::Builder::new()
        .name(format!("{}-log", role.name()))
        .spawn(move || {
            for line in std::io::BufReader::new(reader).lines() {
                let Ok(line) = line else { break };
                let _ = writeln!(log, "{line}");
                let event = Event::Line {
                    role,
                    generation,
                    line,
                };
                if tx.send(event).is_err() {
                    break;
                }
            }
        })
        .context("cannot start a log thread")?;
    Ok(())
}

/// The fields of `/proc/<pid>/stat` from the third on (state, ppid, ...; stat(5)): those after
/// the command name, which may hold spaces, so they start after its last ')'.
fn stat_fields(pid: u32) -> Option<Vec<String>> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    Some(rest.split_whitespace().map(str::to_string).collect())
}

/// User + system CPU time of process `pid` (s), from `/proc/<pid>/stat`.
pub fn process_cpu_s(pid: u32) -> Option<f64> {
    let fields = stat_fields(pid)?;
    // utime and stime are fields 14 and 15 of stat(5); the list starts at field 3.
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    // SAFETY: sysconf has no preconditions.
    let ticks = unsafe { libc::sysconf(libc::_SC_CLK_TCK) } as f64;
    (ticks > 0.0).then(|| (utime + stime) / ticks)
}

/// Whether process `pid` is stopped (state `T`, e.g. by SIGSTOP or Ctrl-Z), from
/// `/proc/<pid>/stat`.
pub fn process_stopped(pid: u32) -> bool {
    stat_fields(pid).is_some_and(|fields| fields.first().is_some_and(|state| state == "T"))
}

/// CPU time of this process so far (s).
pub fn own_cpu_s() -> f64 {
    process_cpu_s(std::process::id()).unwrap_or(0.0)
}

impl Drop for Supervisor {
    fn drop(&mut self) {
        for managed in &mut self.children {
            if let Some(mut child) = managed.child.take() {
                let _ = child.kill();
                let _ = child.wait();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_of_this_process_grows() {
        let before = own_cpu_s();
        let mut x = 0u64;
        let start = Instant::now();
        while start.elapsed() < Duration::from_millis(200) {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
        }
        assert!(x != 1);
        assert!(own_cpu_s() > before);
        assert!(process_cpu_s(u32::MAX).is_none());
    }

    #[test]
    fn a_stopped_process_reads_as_stopped() {
        let mut child = Command::new("sleep").arg("30").spawn().unwrap();
        let pid = child.id();
        assert!(!process_stopped(pid));
        // SAFETY: signalling our own unreaped child.
        unsafe { libc::kill(pid as libc::pid_t, libc::SIGSTOP) };
        let deadline = Instant::now() + Duration::from_secs(5);
        while !process_stopped(pid) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
        assert!(process_stopped(pid));
        child.kill().unwrap();
        child.wait().unwrap();
    }

    #[test]
    fn statuses_read_like_a_shell() {
        let status = Command::new("sh").args(["-c", "exit 3"]).status().unwrap();
        assert_eq!(describe_status(status), "exit status 3");
        let status = Command::new("sh")
            .args(["-c", "kill -9 $$"])
            .status()
            .unwrap();
        assert_eq!(describe_status(status), "killed by signal 9 (SIGKILL)");
    }
}
