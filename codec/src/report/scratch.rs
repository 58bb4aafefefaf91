//! Scratch folders for the video baselines' ffmpeg runs:
//! `<temp>/<prefix>-<pid>-<encoder>-<n>` (`n` counts this process's
//! folders, so threads never share one), removed when dropped (errors and
//! panics included). A run that was killed cannot remove its own, so each
//! new one first removes the folders of its prefix whose process is gone
//! (where `/proc` says so; elsewhere nothing is swept).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::ffmpeg::err;
use crate::error::Result;

pub(super) struct Scratch {
    path: PathBuf,
}

impl Scratch {
    /// A fresh, empty folder of this process for `name`; `prefix`'s
    /// folders left by dead processes are removed first.
    pub(super) fn new(prefix: &str, name: &str) -> Result<Self> {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let temp = std::env::temp_dir();
        sweep(&temp, prefix);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let path = temp.join(format!("{prefix}-{}-{name}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path).map_err(|e| err(format!("{}: {e}", path.display())))?;
        Ok(Self { path })
    }

    pub(super) fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// Removes `<dir>/<prefix>-<pid>-…` folders whose process no longer runs.
fn sweep(dir: &Path, prefix: &str) {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(prefix)?.strip_prefix('-'))
            .and_then(|rest| rest.split('-').next()?.parse::<u32>().ok())
        else {
            continue;
        };
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if is_dir && pid != std::process::id() && !proc.join(pid.to_string()).exists() {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A killed run's folder goes, a live process's stays, ours is removed
    /// on drop.
    #[test]
    fn folders_of_dead_runs_are_swept_and_ours_dropped() {
        let temp = std::env::temp_dir();
        let prefix = "codec-scratch-test";
        // Above any pid_max (2^22), so no such process can run.
        let dead = temp.join(format!("{prefix}-4294967-x264"));
        let live = temp.join(format!("{prefix}-1-x264"));
        for d in [&dead, &live] {
            std::fs::create_dir_all(d).expect("make folder");
            std::fs::write(d.join("v.mp4"), b"partial").expect("write");
        }
        let scratch = Scratch::new(prefix, "x265").expect("scratch");
        let ours = scratch.path().to_path_buf();
        assert!(ours.is_dir());
        let other = Scratch::new(prefix, "x265").expect("a second one");
        assert_ne!(
            other.path(),
            ours,
            "two runs of one encoder never share a folder"
        );
        drop(other);
        assert!(ours.is_dir(), "dropping another leaves ours");
        assert!(!dead.exists(), "a dead run's folder is swept");
        assert!(live.exists(), "pid 1 runs: its folder stays");
        drop(scratch);
        assert!(!ours.exists(), "removed on drop");
        std::fs::remove_dir_all(&live).expect("clean up");
    }
}
