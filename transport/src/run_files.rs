//! The shared-memory files of a *run prefix*: an iceoryx2 file-name prefix of the form
//! `ygt<pid>x<n>_` ([`ENV_IOX2_PREFIX`](crate::service::ENV_IOX2_PREFIX)) that a tool (the
//! demo, a benchmark, a test) gives every process it starts, so that it can find what the
//! run left in `/dev/shm` and remove it, and remove what runs killed with SIGKILL left.
//! CI's check of `/dev/shm` knows the same form. The demo (`ygg-cli`) and the test harness
//! (`ygg-testkit`) share this one implementation.

use std::path::{Path, PathBuf};

use crate::service::DEFAULT_SHM_DIR;

/// Start of every run prefix: `ygt<pid>x<n>_`.
pub const RUN_PREFIX_TAG: &str = "ygt";

/// The run prefix of process `pid`'s `n`-th scene: `ygt<pid>x<n>_`.
pub fn run_prefix(pid: u32, n: u32) -> String {
    format!("{RUN_PREFIX_TAG}{pid}x{n}_")
}

/// Every file below `dir` (recursively) whose name `keep` accepts.
pub fn files_below(dir: &Path, keep: &dyn Fn(&str) -> bool) -> Vec<PathBuf> {
    let mut found = Vec::new();
    collect(dir, keep, &mut found);
    found
}

fn collect(dir: &Path, keep: &dyn Fn(&str) -> bool, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if entry.file_type().is_ok_and(|t| t.is_dir()) {
            collect(&path, keep, found);
        } else if keep(&entry.file_name().to_string_lossy()) {
            found.push(path);
        }
    }
}

/// Every file of `prefix` below `/dev/shm`, iceoryx2's node and service files included
/// ([`ICEORYX2_ROOT`](crate::service::ICEORYX2_ROOT)).
pub fn prefix_files(prefix: &str) -> Vec<PathBuf> {
    files_below(Path::new(DEFAULT_SHM_DIR), &|n| n.starts_with(prefix))
}

/// [`prefix_files`] except iceoryx2's persistent per-prefix `*.global_mgmt` counter (16
/// bytes, kept by design): what a finished run must not leave behind.
pub fn prefix_leftovers(prefix: &str) -> Vec<PathBuf> {
    let mut found = prefix_files(prefix);
    found.retain(|p| !p.to_string_lossy().ends_with(".global_mgmt"));
    found
}

/// Whether `name` starts with the run prefix of a process that no longer exists (and is
/// not this one).
pub fn is_dead_run_file(name: &str) -> bool {
    let pid = name
        .strip_prefix(RUN_PREFIX_TAG)
        .and_then(|rest| rest.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|d| d.parse::<u32>().ok());
    pid.is_some_and(|pid| pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists())
}

/// The files below `/dev/shm` of run prefixes whose process no longer exists: what runs
/// killed with SIGKILL could not clean up.
pub fn stale_run_files() -> Vec<PathBuf> {
    files_below(Path::new(DEFAULT_SHM_DIR), &is_dead_run_file)
}

/// Removes `paths`, returning how many were removed.
pub fn remove_files(paths: impl IntoIterator<Item = PathBuf>) -> usize {
    paths
        .into_iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count()
}

/// Once every process of the run of `name` has exited: removes every file of `prefix` and
/// describes the ones left behind besides iceoryx2's `global_mgmt` counter (kept by
/// design; `None` when there were none).
pub fn clean_up_prefix(name: &str, prefix: &str) -> Option<String> {
    let left = prefix_leftovers(prefix);
    remove_files(prefix_files(prefix));
    (!left.is_empty()).then(|| {
        let first: Vec<String> = left
            .iter()
            .take(3)
            .map(|p| p.display().to_string())
            .collect();
        format!("{name}: {} files ({})", left.len(), first.join(", "))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_prefix_names_its_process_and_only_dead_ones_are_stale() {
        let me = std::process::id();
        assert_eq!(run_prefix(12, 3), "ygt12x3_");
        assert!(!is_dead_run_file(&format!("{}segments", run_prefix(me, 0))));
        // Pid 1 (init) always exists.
        assert!(!is_dead_run_file("ygt1x0_node"));
        // Above the kernel's largest pid (2^22): no such process.
        assert!(is_dead_run_file("ygt4194305x0_node"));
        assert!(!is_dead_run_file("other4194305x0_node"));
        assert!(!is_dead_run_file("ygtx0_node"));
    }

    #[test]
    fn files_below_walks_folders_and_keeps_what_is_asked() {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::create_dir(dir.path().join("nodes")).expect("mkdir");
        for name in ["ygt7x0_a", "nodes/ygt7x0_b", "ygt8x0_c", "nodes/other"] {
            std::fs::write(dir.path().join(name), b"x").expect("write");
        }
        let mut found = files_below(dir.path(), &|n| n.starts_with("ygt7x0_"));
        found.sort();
        assert_eq!(
            found,
            vec![
                dir.path().join("nodes/ygt7x0_b"),
                dir.path().join("ygt7x0_a")
            ]
        );
        assert_eq!(remove_files(found), 2);
        assert!(files_below(dir.path(), &|n| n.starts_with("ygt7x0_")).is_empty());
    }
}
