//! One owner per role and instance: a second `dicstream run`, producer, correlator, rig or
//! identifier on an instance that already has one is refused at start, naming the running
//! one's pid (two would write each other's frames). The claim is an exclusive `flock` on a
//! small file in `<tmp>/dicstream-owners/` holding the owner's pid: the kernel drops it when
//! the owner dies, however it dies, so a restarted process claims it again at once. The file
//! is removed when the claim is dropped (while still locked; a claimant that locked a file
//! already removed tries again).

use std::io::{Read, Seek, Write};
use std::os::unix::fs::MetadataExt;
use std::os::unix::io::AsRawFd;
use std::path::{Path, PathBuf};

/// The held claim of a role on an instance; released when dropped (or when the process ends).
#[derive(Debug)]
pub struct Owner {
    file: std::fs::File,
    path: PathBuf,
}

/// Why a claim was not granted.
#[derive(Debug)]
pub enum ClaimError {
    /// Another process holds it (its pid, if it could be read).
    Owned { pid: Option<u32> },
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
}

/// Folder of the claim files.
pub fn owners_dir() -> PathBuf {
    std::env::temp_dir().join("dicstream-owners")
}

/// Claims `role` on instance `instance`.
pub fn claim(instance: &str, role: &str) -> Result<Owner, ClaimError> {
    claim_in(&owners_dir(), instance, role)
}

fn claim_in(dir: &Path, instance: &str, role: &str) -> Result<Owner, ClaimError> {
    let io = |path: &Path, error| ClaimError::Io {
        path: path.to_path_buf(),
        error,
    };
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let path = dir.join(format!("{instance}.{role}"));
    loop {
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| io(&path, e))?;
        // SAFETY: flock on a descriptor we own.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            let error = std::io::Error::last_os_error();
            if error.raw_os_error() != Some(libc::EWOULDBLOCK) {
                return Err(io(&path, error));
            }
            let mut text = String::new();
            let _ = file.read_to_string(&mut text);
            return Err(ClaimError::Owned {
                pid: text.trim().parse().ok(),
            });
        }
        // The previous owner may have removed the file between our open and our lock: then
        // the lock is on a file nobody else will look at. Try again with the path's file.
        let same = match (file.metadata(), std::fs::metadata(&path)) {
            (Ok(held), Ok(named)) => held.ino() == named.ino() && held.dev() == named.dev(),
            _ => false,
        };
        if !same {
            continue;
        }
        file.set_len(0)
            .and_then(|()| file.rewind())
            .and_then(|()| write!(file, "{}", std::process::id()))
            .map_err(|e| io(&path, e))?;
        return Ok(Owner { file, path });
    }
}

/// A role held on an instance by a live process.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Held {
    pub instance: String,
    pub role: String,
    pub pid: u32,
}

/// Every role held by a live process, sorted by instance then role. A claim file whose pid is
/// gone (its owner was killed before it could remove it) is not listed.
pub fn held() -> Vec<Held> {
    held_in(&owners_dir())
}

fn held_in(dir: &Path) -> Vec<Held> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut held: Vec<Held> = entries
        .flatten()
        .filter_map(|entry| {
            let name = entry.file_name().into_string().ok()?;
            let (instance, role) = name.rsplit_once('.')?;
            let pid: u32 = std::fs::read_to_string(entry.path())
                .ok()?
                .trim()
                .parse()
                .ok()?;
            Path::new(&format!("/proc/{pid}")).exists().then(|| Held {
                instance: instance.to_string(),
                role: role.to_string(),
                pid,
            })
        })
        .collect();
    held.sort_by(|a, b| (&a.instance, &a.role).cmp(&(&b.instance, &b.role)));
    held
}

impl Drop for Owner {
    fn drop(&mut self) {
        // Removed while locked; the lock goes with the descriptor.
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.flush();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_claim_is_refused_with_the_owner_pid_until_the_first_is_dropped() {
        let dir = std::env::temp_dir().join(format!("owner_test_{}", std::process::id()));
        let first = claim_in(&dir, "inst", "producer").unwrap();
        match claim_in(&dir, "inst", "producer") {
            Err(ClaimError::Owned { pid }) => assert_eq!(pid, Some(std::process::id())),
            other => panic!("second claim: {other:?}"),
        }
        // Another role, or another instance, is free.
        let other_role = claim_in(&dir, "inst", "rig").unwrap();
        let other_instance = claim_in(&dir, "inst2", "producer").unwrap();
        drop(first);
        assert!(!dir.join("inst.producer").exists());
        let again = claim_in(&dir, "inst", "producer").unwrap();
        let listed = held_in(&dir);
        assert_eq!(listed.len(), 3, "{listed:?}");
        assert_eq!(
            listed[0],
            Held {
                instance: "inst".into(),
                role: "producer".into(),
                pid: std::process::id()
            }
        );
        assert_eq!(listed[2].instance, "inst2");
        // A file left by a process that is gone is not a holder.
        std::fs::write(dir.join("dead.rig"), "4294967295").unwrap();
        assert_eq!(held_in(&dir).len(), 3);
        std::fs::remove_file(dir.join("dead.rig")).unwrap();
        drop((again, other_role, other_instance));
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
