//! [`TestScene`]: a unique scene name and iceoryx2 prefix per test or run, and the scan
//! of `/dev/shm` (iceoryx2's shared memory and, below
//! [`ygg_transport::service::ICEORYX2_ROOT`], its node and service files) for the files of a
//! prefix.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use ygg_transport::run_files::{
    clean_up_prefix, files_below, is_dead_run_file, prefix_files, prefix_leftovers, remove_files,
    run_prefix, stale_run_files,
};
use ygg_transport::service::{ENV_IOX2_PREFIX, ICEORYX2_ROOT};

use crate::{Proc, Watchdog, binary, poll_until};

/// The POSIX shared-memory directory.
pub use ygg_transport::service::DEFAULT_SHM_DIR as SHM_DIR;

/// Start of every prefix [`TestScene::new`] makes: `ygt<pid>x<n>_`.
pub use ygg_transport::run_files::RUN_PREFIX_TAG as PREFIX_TAG;

/// A unique scene name and iceoryx2 prefix for one test (or one case of a bench).
#[derive(Debug)]
pub struct TestScene {
    /// The scene name.
    pub name: String,
    /// The iceoryx2 file-name prefix (also set in every spawned child's environment).
    pub prefix: String,
}

impl TestScene {
    /// A scene unique to this process and call: `<tag>-<pid>-<n>`, prefix `ygt<pid>x<n>_`.
    pub fn new(tag: &str) -> Self {
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let pid = std::process::id();
        Self {
            name: format!("{tag}-{pid}-{n}"),
            prefix: run_prefix(pid, n),
        }
    }

    /// The scene of a tool's run (a bench, the soak): [`TestScene::new`], but under the
    /// prefix a caller set in [`ENV_IOX2_PREFIX`] if any (tests do, to check what the run
    /// leaves), after removing what killed earlier runs left ([`remove_stale`]).
    pub fn for_run(tag: &str) -> Self {
        let removed = remove_stale();
        if removed > 0 {
            eprintln!("removed {removed} files left by earlier, killed runs");
        }
        let mut scene = Self::new(tag);
        if let Ok(prefix) = std::env::var(ENV_IOX2_PREFIX) {
            scene.prefix = prefix;
        }
        scene
    }

    /// Sets this scene's prefix in `command`'s environment (and clears `IOX2_LOG_LEVEL`).
    pub fn configure<'c>(&self, command: &'c mut Command) -> &'c mut Command {
        command
            .env(ENV_IOX2_PREFIX, &self.prefix)
            .env_remove("IOX2_LOG_LEVEL")
    }

    /// A command for the executable at `program` with this scene's prefix and `args`.
    pub fn command_for(&self, program: &Path, args: &[&str]) -> Command {
        let mut command = Command::new(program);
        self.configure(command.args(args));
        command
    }

    /// A command for the workspace binary `binary_name` (see [`binary`]) with this
    /// scene's prefix in its environment and `args`.
    pub fn command(&self, binary_name: &str, args: &[&str]) -> Command {
        self.command_for(&binary(binary_name), args)
    }

    /// Spawns `ygg-test-writer --scene <name> <args>` (synthetic segments).
    pub fn spawn_writer(&self, args: &[&str], watchdog: &Watchdog) -> Proc {
        let mut all = vec!["--scene", &self.name];
        all.extend_from_slice(args);
        Proc::spawn(self.command("ygg-test-writer", &all), "writer", watchdog)
    }

    /// Spawns `ygg-test-reader <sub> --scene <name> <args>` (`watch` or `dump`).
    pub fn spawn_reader(&self, sub: &str, args: &[&str], watchdog: &Watchdog) -> Proc {
        let mut all = vec![sub, "--scene", &self.name];
        all.extend_from_slice(args);
        Proc::spawn(self.command("ygg-test-reader", &all), "reader", watchdog)
    }

    /// Every file of this scene's prefix below `/dev/shm` (iceoryx2's node and service
    /// files included: [`ygg_transport::service::ICEORYX2_ROOT`]).
    pub fn files(&self) -> Vec<PathBuf> {
        prefix_files(&self.prefix)
    }

    /// [`TestScene::files`] except iceoryx2's persistent per-prefix `*.global_mgmt`
    /// counter (16 bytes, kept by design).
    pub fn leftovers(&self) -> Vec<PathBuf> {
        prefix_leftovers(&self.prefix)
    }

    /// Asserts that the scene left nothing behind, waiting up to `grace` for processes that are
    /// still exiting, then removes the `global_mgmt` counter too.
    ///
    /// # Panics
    ///
    /// If files remain after `grace`.
    pub fn assert_no_leftovers(&self, grace: Duration) {
        // No event tells when another process removed its files: poll them.
        if poll_until(grace, || self.leftovers().is_empty()).is_none() {
            panic!(
                "scene {} left files behind: {:#?}",
                self.name,
                self.leftovers()
            );
        }
        self.remove_all();
    }

    /// How many iceoryx2 nodes of this scene's prefix exist: each process (or in-process
    /// reader or writer) has one, from its creation until it is dropped or, after a
    /// crash, until another process removes its resources.
    pub fn node_count(&self) -> usize {
        let nodes = Path::new(ICEORYX2_ROOT).join("nodes");
        let Ok(entries) = std::fs::read_dir(nodes) else {
            return 0;
        };
        entries
            .flatten()
            .filter(|node| !files_below(&node.path(), &|n| n.starts_with(&self.prefix)).is_empty())
            .count()
    }

    /// Once every process of the scene has exited: removes every file of the prefix and
    /// describes the ones left behind besides `global_mgmt` (`None` when there were none).
    pub fn clean_up(&self) -> Option<String> {
        clean_up_prefix(&self.name, &self.prefix)
    }

    /// Removes every file of this prefix (used after a failed test, and for `global_mgmt`).
    pub fn remove_all(&self) {
        for path in self.files() {
            let _ = std::fs::remove_file(path);
        }
    }
}

impl Drop for TestScene {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.remove_all();
        }
    }
}

/// Removes the files of [`TestScene`] prefixes (below `/dev/shm`, iceoryx2's node files
/// included, and directly in the temp dir: sockets named after a prefix) whose process no longer
/// exists: what runs killed with SIGKILL could not clean up. Returns how many files were
/// removed.
pub fn remove_stale() -> usize {
    let mut found = stale_run_files();
    if let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) {
        found.extend(
            entries
                .flatten()
                .filter(|e| is_dead_run_file(&e.file_name().to_string_lossy()))
                .map(|e| e.path()),
        );
    }
    remove_files(found)
}
