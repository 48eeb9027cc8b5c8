//! [`DemoScene`]: the scene of one demo run, with an iceoryx2 file-name prefix of its own,
//! so the run can tell its files in `/dev/shm` from anyone else's and remove them at the
//! end; and [`remove_stale`] for the files of runs that were killed.

use std::path::Path;
use std::process::Command;

use ygg_transport::run_files::{clean_up_prefix, remove_files, run_prefix, stale_run_files};
use ygg_transport::service::ENV_IOX2_PREFIX;

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
            prefix: std::env::var(ENV_IOX2_PREFIX).unwrap_or_else(|_| run_prefix(pid, 0)),
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
        clean_up_prefix(&self.name, &self.prefix)
    }
}

/// Removes the files below `/dev/shm` of run prefixes (`ygt<pid>x...`) whose process no
/// longer exists: what runs killed with SIGKILL could not clean up. Returns how many.
pub fn remove_stale() -> usize {
    remove_files(stale_run_files())
}
