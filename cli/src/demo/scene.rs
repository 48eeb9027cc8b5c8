//! [`DemoScene`]: the scene of one demo run, with an iceoryx2 file-name prefix of its own,
//! so the run can tell its files in `/dev/shm` from anyone else's and remove them at the
//! end; and [`remove_stale`] for the files of runs that were killed.

use std::path::{Path, PathBuf};
use std::process::Command;

use ygg_transport::service::ENV_IOX2_PREFIX;

/// The POSIX shared-memory directory (iceoryx2's files, node and service files included).
const SHM_DIR: &str = "/dev/shm";

/// Start of every run's prefix, `ygt<pid>x<n>_`: the form of the test harness's scenes,
/// which CI's check of `/dev/shm` knows.
const PREFIX_TAG: &str = "ygt";

/// The scene name and iceoryx2 prefix of one run.
pub struct DemoScene {
    /// The scene name: `<tag>-<pid>`.
    pub name: String,
    /// The iceoryx2 file-name prefix, set in every process the run starts.
    prefix: String,
}

impl DemoScene {
    /// The scene of this process's run, `<tag>-<pid>`, under the prefix a caller set in
    /// [`ENV_IOX2_PREFIX`] (tests do), else `ygt<pid>x0_`.
    pub fn new(tag: &str) -> Self {
        let pid = std::process::id();
        Self {
            name: format!("{tag}-{pid}"),
            prefix: std::env::var(ENV_IOX2_PREFIX)
                .unwrap_or_else(|_| format!("{PREFIX_TAG}{pid}x0_")),
        }
    }

    /// A command running `program` with `args` under this run's prefix (iceoryx2's log
    /// level left to its default).
    pub fn command(&self, program: &Path, args: &[&str]) -> Command {
        let mut command = Command::new(program);
        command
            .args(args)
            .env(ENV_IOX2_PREFIX, &self.prefix)
            .env_remove("IOX2_LOG_LEVEL");
        command
    }

    /// Once every process of the run has exited: removes every file of the prefix and
    /// describes the ones left behind besides iceoryx2's `global_mgmt` counter (kept by
    /// design; `None` when there were none).
    pub fn clean_up(&self) -> Option<String> {
        let mut files = Vec::new();
        collect(
            Path::new(SHM_DIR),
            &|n| n.starts_with(&self.prefix),
            &mut files,
        );
        let left: Vec<String> = files
            .iter()
            .filter(|p| !p.to_string_lossy().ends_with(".global_mgmt"))
            .map(|p| p.display().to_string())
            .collect();
        for path in &files {
            let _ = std::fs::remove_file(path);
        }
        (!left.is_empty()).then(|| {
            let first = left[..left.len().min(3)].join(", ");
            format!("{}: {} files ({first})", self.name, left.len())
        })
    }
}

/// Removes the files below `/dev/shm` of run prefixes (`ygt<pid>x...`) whose process no
/// longer exists: what runs killed with SIGKILL could not clean up. Returns how many.
pub fn remove_stale() -> usize {
    let dead_run = |name: &str| -> bool {
        let pid = name
            .strip_prefix(PREFIX_TAG)
            .and_then(|rest| rest.split(|c: char| !c.is_ascii_digit()).next())
            .and_then(|d| d.parse::<u32>().ok());
        pid.is_some_and(|pid| {
            pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists()
        })
    };
    let mut found = Vec::new();
    collect(Path::new(SHM_DIR), &dead_run, &mut found);
    found
        .into_iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count()
}

/// Adds the files below `dir` (recursively) whose name `keep` accepts to `found`.
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
