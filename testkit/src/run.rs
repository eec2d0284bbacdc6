//! One test's instance, child processes and scratch folder, cleaned on drop.

use crate::{Proc, TestInstance};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus};

/// A test's bench: a [`TestInstance`], the children started from one program (the package's
/// binary, `env!("CARGO_BIN_EXE_…")`), and a scratch folder. Dropping it (test passed or
/// panicked) kills the children still alive, removes the instance's files from `/dev/shm` and
/// iceoryx2's folder, and removes the scratch folder.
pub struct Run {
    pub instance: TestInstance,
    /// The scratch folder, `$TMPDIR/dicstream-test-<instance>`.
    pub dir: PathBuf,
    program: PathBuf,
    children: Vec<Proc>,
}

impl Run {
    /// A bench named after `test` whose children run `program`.
    pub fn new(test: &str, program: impl AsRef<Path>) -> Run {
        let instance = TestInstance::new(test);
        let dir = std::env::temp_dir().join(format!("dicstream-test-{}", instance.name()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch folder");
        Run {
            instance,
            dir,
            program: program.as_ref().to_path_buf(),
            children: Vec::new(),
        }
    }

    pub fn name(&self) -> &str {
        self.instance.name()
    }

    /// A fresh folder `label` inside the scratch folder.
    pub fn temp_dir(&self, label: &str) -> PathBuf {
        let dir = self.dir.join(label);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch sub-folder");
        dir
    }

    /// Starts `program ARGS` as `name` (add `--instance` yourself where the subcommand takes it).
    pub fn spawn(&mut self, name: &str, args: &[&str]) -> &mut Proc {
        let mut command = Command::new(&self.program);
        command.args(args);
        self.children.push(Proc::spawn(name, command));
        self.children.last_mut().unwrap()
    }

    /// The child started as `name` (the last one of that name).
    pub fn child(&mut self, name: &str) -> &mut Proc {
        self.children
            .iter_mut()
            .rev()
            .find(|p| p.name == name)
            .unwrap_or_else(|| panic!("no child named {name}"))
    }

    /// The `index`-th child started (from 0).
    pub fn proc(&mut self, index: usize) -> &mut Proc {
        &mut self.children[index]
    }

    /// How many children were started.
    pub fn children_started(&self) -> usize {
        self.children.len()
    }

    /// Every child's stderr, separated, for failure messages.
    pub fn all_stderr(&self) -> String {
        self.children
            .iter()
            .map(|p| format!("[{}]\n{}", p.name, p.stderr()))
            .collect::<Vec<_>>()
            .join("\n---\n")
    }

    /// Runs `program ARGS` to its end; returns status, stdout, stderr.
    pub fn run_to_end(&mut self, name: &str, args: &[&str]) -> (ExitStatus, String, String) {
        self.spawn(name, args).wait()
    }

    /// Files the instance left once its processes ended (see
    /// [`TestInstance::leftovers_after_clean_shutdown`]).
    pub fn leftovers_after_clean_shutdown(&self) -> Vec<PathBuf> {
        self.instance.leftovers_after_clean_shutdown()
    }

    /// Kills every child still running (SIGKILL) and reaps it.
    pub fn kill_children(&mut self) {
        for child in &mut self.children {
            child.kill();
        }
    }

    /// Kills what still runs, cleans dead nodes, removes the instance's files and the scratch
    /// folder. Called by drop; call it explicitly to check the result.
    pub fn teardown(&mut self) {
        self.kill_children();
        self.instance.clean();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        self.teardown();
    }
}
