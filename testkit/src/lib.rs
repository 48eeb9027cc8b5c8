//! Multi-process integration tests: the harness.
//!
//! * [`binary`] finds (and if needed builds) the `ygg-writer` / `ygg-reader` executables.
//! * [`TestScene`] gives each test a unique scene name and iceoryx2 prefix, so tests can run in
//!   parallel and each one can check that it left nothing in `/dev/shm`
//!   ([`TestScene::assert_no_leftovers`]).
//! * [`Proc`] is a spawned child whose output lines can be awaited; it is killed when dropped
//!   and when the test's [`Watchdog`] fires.
//! * [`fingerprint`] gives canonical forms of archived segments, to compare incremental
//!   builds with fresh ones.

pub mod fingerprint;

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock, PoisonError};
use std::time::{Duration, Instant};

use rustix::process::{Pid, Signal, kill_process};
use ygg_transport::protocol::ENV_IOX2_PREFIX;

/// Where iceoryx2 keeps node and service files (besides `/dev/shm`).
pub const ICEORYX2_DIR: &str = "/tmp/iceoryx2";

/// The POSIX shared-memory directory.
pub const SHM_DIR: &str = "/dev/shm";

/// Env var naming a directory that holds prebuilt `ygg-writer` / `ygg-reader` binaries.
pub const ENV_BIN_DIR: &str = "YGG_BIN_DIR";

/// Path of the executable `name` (`ygg-writer` or `ygg-reader`).
///
/// Binaries of other packages are not exposed to this package by cargo
/// (`CARGO_BIN_EXE_*` is per package), so the harness takes them from [`ENV_BIN_DIR`] if set,
/// else from the profile directory of the running test executable
/// (`target/<profile>/deps/ipc-…` -> `target/<profile>/`). When run by cargo, it first runs
/// `cargo build -p ygg-writer -p ygg-reader --bins` for that profile and target directory once
/// (a no-op when they are up to date; cargo releases its lock while tests run).
///
/// # Panics
///
/// If the binary cannot be found or built.
pub fn binary(name: &str) -> PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| {
        if let Some(dir) = std::env::var_os(ENV_BIN_DIR) {
            return PathBuf::from(dir);
        }
        let exe = std::env::current_exe().expect("path of the test executable");
        let deps = exe.parent().expect("test executable lives in a directory");
        let profile_dir = if deps.ends_with("deps") {
            deps.parent().expect("deps has a parent")
        } else {
            deps
        };
        if let Some(cargo) = std::env::var_os("CARGO") {
            build_binaries(Path::new(&cargo), profile_dir);
        }
        profile_dir.to_owned()
    });
    let path = dir.join(name);
    assert!(
        path.is_file(),
        "{} not found; build it (cargo build -p ygg-writer -p ygg-reader) or set {ENV_BIN_DIR}",
        path.display()
    );
    path
}

fn build_binaries(cargo: &Path, profile_dir: &Path) {
    let Some(target_dir) = profile_dir.parent() else {
        return;
    };
    let mut command = Command::new(cargo);
    command.args([
        "build",
        "-p",
        "ygg-writer",
        "-p",
        "ygg-reader",
        "-p",
        "ygg-bench",
        "--bins",
    ]);
    match profile_dir.file_name().and_then(|n| n.to_str()) {
        Some("debug") | None => {}
        Some("release") => {
            command.arg("--release");
        }
        Some(profile) => {
            command.args(["--profile", profile]);
        }
    }
    command.env("CARGO_TARGET_DIR", target_dir);
    if let Ok(manifest_dir) = std::env::var("CARGO_MANIFEST_DIR") {
        command.current_dir(manifest_dir);
    }
    let output = command.output().expect("run cargo build for the binaries");
    assert!(
        output.status.success(),
        "building ygg-writer / ygg-reader failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// A unique scene name and iceoryx2 prefix for one test.
#[derive(Debug)]
pub struct TestScene {
    /// The scene name.
    pub name: String,
    /// The iceoryx2 file-name prefix (also set in every spawned child's environment).
    pub prefix: String,
}

impl TestScene {
    /// A scene unique to this process and call.
    pub fn new(tag: &str) -> Self {
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let pid = std::process::id();
        Self {
            name: format!("{tag}-{pid}-{n}"),
            prefix: format!("ygt{pid}x{n}_"),
        }
    }

    /// A command for `binary` with this scene's prefix in its environment and `args`.
    pub fn command(&self, binary_name: &str, args: &[&str]) -> Command {
        let mut command = Command::new(binary(binary_name));
        command
            .args(args)
            .env(ENV_IOX2_PREFIX, &self.prefix)
            .env_remove("IOX2_LOG_LEVEL");
        command
    }

    /// Spawns `ygg-writer serve-test --scene <name> <args>`.
    pub fn spawn_writer(&self, args: &[&str], watchdog: &Watchdog) -> Proc {
        let mut all = vec!["serve-test", "--scene", &self.name];
        all.extend_from_slice(args);
        Proc::spawn(self.command("ygg-writer", &all), "writer", watchdog)
    }

    /// Spawns `ygg-reader <sub> --scene <name> <args>`.
    pub fn spawn_reader(&self, sub: &str, args: &[&str], watchdog: &Watchdog) -> Proc {
        let mut all = vec![sub, "--scene", &self.name];
        all.extend_from_slice(args);
        Proc::spawn(self.command("ygg-reader", &all), "reader", watchdog)
    }

    /// Files of this scene's prefix in `/dev/shm` and under `/tmp/iceoryx2`, except iceoryx2's
    /// persistent per-prefix `*.global_mgmt` counter (16 bytes, kept by design).
    pub fn leftovers(&self) -> Vec<PathBuf> {
        let mut found = Vec::new();
        collect_prefixed(Path::new(SHM_DIR), &self.prefix, &mut found);
        collect_prefixed(Path::new(ICEORYX2_DIR), &self.prefix, &mut found);
        found.retain(|p| !p.to_string_lossy().ends_with(".global_mgmt"));
        found
    }

    /// Asserts that the scene left nothing behind, waiting up to `grace` for processes that are
    /// still exiting, then removes the `global_mgmt` counter too.
    ///
    /// # Panics
    ///
    /// If files remain after `grace`.
    pub fn assert_no_leftovers(&self, grace: Duration) {
        let start = Instant::now();
        let mut left = self.leftovers();
        while !left.is_empty() && start.elapsed() < grace {
            std::thread::sleep(Duration::from_millis(20));
            left = self.leftovers();
        }
        assert!(
            left.is_empty(),
            "scene {} left files behind: {left:#?}",
            self.name
        );
        self.remove_all();
    }

    /// Removes every file of this prefix (used after a failed test, and for `global_mgmt`).
    pub fn remove_all(&self) {
        let mut found = Vec::new();
        collect_prefixed(Path::new(SHM_DIR), &self.prefix, &mut found);
        collect_prefixed(Path::new(ICEORYX2_DIR), &self.prefix, &mut found);
        for path in found {
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

fn collect_prefixed(dir: &Path, prefix: &str, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if entry.file_type().is_ok_and(|t| t.is_dir()) {
            collect_prefixed(&path, prefix, found);
        } else if entry.file_name().to_string_lossy().starts_with(prefix) {
            found.push(path);
        }
    }
}

/// Kills registered children when a test runs past its deadline, so no test hangs forever.
#[derive(Debug)]
pub struct Watchdog {
    pids: Arc<Mutex<Vec<u32>>>,
    done: Arc<(Mutex<bool>, Condvar)>,
}

impl Watchdog {
    /// Starts a watchdog that SIGKILLs every registered child after `limit`.
    pub fn new(limit: Duration) -> Self {
        let watchdog = Self {
            pids: Arc::new(Mutex::new(Vec::new())),
            done: Arc::new((Mutex::new(false), Condvar::new())),
        };
        let pids = Arc::clone(&watchdog.pids);
        let done = Arc::clone(&watchdog.done);
        std::thread::spawn(move || {
            let (lock, cvar) = &*done;
            let guard = lock.lock().unwrap_or_else(PoisonError::into_inner);
            let (guard, timeout) = cvar
                .wait_timeout_while(guard, limit, |finished| !*finished)
                .unwrap_or_else(PoisonError::into_inner);
            drop(guard);
            if timeout.timed_out() {
                eprintln!("watchdog: test exceeded {limit:?}, killing its children");
                for pid in pids.lock().unwrap_or_else(PoisonError::into_inner).iter() {
                    send(*pid, Signal::KILL);
                }
            }
        });
        watchdog
    }

    fn register(&self, pid: u32) {
        self.pids
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(pid);
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        let (lock, cvar) = &*self.done;
        *lock.lock().unwrap_or_else(PoisonError::into_inner) = true;
        cvar.notify_all();
    }
}

fn send(pid: u32, signal: Signal) {
    if let Some(pid) = i32::try_from(pid).ok().and_then(Pid::from_raw) {
        let _ = kill_process(pid, signal);
    }
}

#[derive(Debug, Default)]
struct Output {
    stdout: Vec<String>,
    stderr: Vec<String>,
}

/// A spawned child process whose output is collected line by line.
#[derive(Debug)]
pub struct Proc {
    label: &'static str,
    child: Child,
    status: Option<ExitStatus>,
    output: Arc<(Mutex<Output>, Condvar)>,
}

impl Proc {
    /// Spawns `command` with piped stdout/stderr, registered with `watchdog`.
    ///
    /// # Panics
    ///
    /// If the process cannot be spawned.
    pub fn spawn(mut command: Command, label: &'static str, watchdog: &Watchdog) -> Self {
        command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = command
            .spawn()
            .unwrap_or_else(|e| panic!("spawn {label}: {e}"));
        watchdog.register(child.id());
        let output = Arc::new((Mutex::new(Output::default()), Condvar::new()));
        if let Some(stdout) = child.stdout.take() {
            collect_lines(stdout, Arc::clone(&output), false);
        }
        if let Some(stderr) = child.stderr.take() {
            collect_lines(stderr, Arc::clone(&output), true);
        }
        Self {
            label,
            child,
            status: None,
            output,
        }
    }

    /// The process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Sends `signal` (e.g. `Signal::INT`) to the process.
    pub fn signal(&self, signal: Signal) {
        send(self.child.id(), signal);
    }

    /// Stdout lines so far.
    pub fn stdout(&self) -> Vec<String> {
        self.lock().stdout.clone()
    }

    /// Stderr lines so far.
    pub fn stderr(&self) -> Vec<String> {
        self.lock().stderr.clone()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Output> {
        self.output.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Waits until a stdout line after the first `skip` lines satisfies `pred`; returns it
    /// with its index.
    pub fn wait_line_after(
        &self,
        skip: usize,
        timeout: Duration,
        pred: impl Fn(&str) -> bool,
    ) -> Option<(usize, String)> {
        let (lock, cvar) = &*self.output;
        let start = Instant::now();
        let mut output = lock.lock().unwrap_or_else(PoisonError::into_inner);
        loop {
            if let Some((i, line)) = output
                .stdout
                .iter()
                .enumerate()
                .skip(skip)
                .find(|(_, l)| pred(l))
            {
                return Some((i, line.clone()));
            }
            let remaining = timeout.checked_sub(start.elapsed())?;
            output = cvar
                .wait_timeout(output, remaining)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
    }

    /// Waits until a stdout line satisfies `pred`.
    ///
    /// # Panics
    ///
    /// With the output so far, if none does within `timeout`.
    pub fn expect_line(&self, timeout: Duration, pred: impl Fn(&str) -> bool) -> String {
        match self.wait_line_after(0, timeout, pred) {
            Some((_, line)) => line,
            None => panic!(
                "{} (pid {}): expected line not seen within {timeout:?}\nstdout: {:#?}\nstderr: {:#?}",
                self.label,
                self.pid(),
                self.stdout(),
                self.stderr()
            ),
        }
    }

    /// Number of stdout lines satisfying `pred` so far.
    pub fn count_lines(&self, pred: impl Fn(&str) -> bool) -> usize {
        self.lock().stdout.iter().filter(|l| pred(l)).count()
    }

    /// The exit status, if the process has exited.
    pub fn try_status(&mut self) -> Option<ExitStatus> {
        if self.status.is_none() {
            self.status = self.child.try_wait().ok().flatten();
            if self.status.is_some() {
                // Let the reader threads see EOF and publish the last lines.
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        self.status
    }

    /// Waits for the process to exit.
    ///
    /// # Panics
    ///
    /// If it does not exit within `timeout` (it is then killed).
    pub fn wait_exit(&mut self, timeout: Duration) -> ExitStatus {
        let start = Instant::now();
        loop {
            if let Some(status) = self.status {
                return status;
            }
            match self.child.try_wait() {
                Ok(Some(status)) => {
                    self.status = Some(status);
                    // Let the reader threads see EOF and publish the last lines.
                    std::thread::sleep(Duration::from_millis(20));
                    return status;
                }
                Ok(None) if start.elapsed() < timeout => {
                    std::thread::sleep(Duration::from_millis(10));
                }
                other => {
                    let _ = self.child.kill();
                    let _ = self.child.wait();
                    panic!(
                        "{} (pid {}) did not exit within {timeout:?} ({other:?})\nstdout: {:#?}\nstderr: {:#?}",
                        self.label,
                        self.pid(),
                        self.stdout(),
                        self.stderr()
                    );
                }
            }
        }
    }

    /// SIGKILLs the process and reaps it.
    pub fn kill(&mut self) {
        if self.status.is_none() {
            let _ = self.child.kill();
            self.status = self.child.wait().ok();
        }
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        self.kill();
    }
}

fn collect_lines(
    stream: impl Read + Send + 'static,
    output: Arc<(Mutex<Output>, Condvar)>,
    is_stderr: bool,
) {
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines() {
            let Ok(line) = line else { break };
            let (lock, cvar) = &*output;
            let mut output = lock.lock().unwrap_or_else(PoisonError::into_inner);
            if is_stderr {
                output.stderr.push(line);
            } else {
                output.stdout.push(line);
            }
            cvar.notify_all();
        }
    });
}

/// Parses `key=value` out of an output line.
pub fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split_whitespace()
        .find_map(|part| part.strip_prefix(key)?.strip_prefix('='))
}
