//! Reader processes as seen from the writer: spawning (the benchmark's own executable,
//! re-executed), line-based control over stdin/stdout, and cleanup on every exit path.
//!
//! A [`ReaderProc`] that is dropped without [`ReaderProc::finish`] (an error, a panic, an
//! interrupt) closes the child's stdin, gives it a moment to exit cleanly and then
//! SIGKILLs and reaps it. Children also ask the kernel for SIGTERM when the benchmark
//! dies ([`super::reader`]), so even a SIGKILLed benchmark leaves no reader behind.
//! Shared-memory files of a case are removed by prefix ([`Scene::remove_files`]) once
//! every process of the case has exited, and files of earlier, killed runs by
//! [`remove_stale`].

use super::{Res, check_interrupted};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

/// Where iceoryx2 keeps node and service files besides `/dev/shm`.
const ICEORYX2_DIR: &str = "/tmp/iceoryx2";
/// The POSIX shared-memory directory.
const SHM_DIR: &str = "/dev/shm";
/// Start of every iceoryx2 prefix this benchmark uses: `yggb<pid>x<n>_`.
const PREFIX_TAG: &str = "yggb";

/// A unique scene name and iceoryx2 file prefix for one case.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene name.
    pub name: String,
    /// The iceoryx2 file-name prefix (writer and readers).
    pub prefix: String,
}

impl Scene {
    /// A scene unique to this process and call.
    pub fn new(tag: &str) -> Self {
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let pid = std::process::id();
        Scene {
            name: format!("ipcb-{tag}-{pid}-{n}"),
            prefix: format!("{PREFIX_TAG}{pid}x{n}_"),
        }
    }

    /// Once every process of the scene has exited: describes the files it left behind
    /// (`None` when there are none) and removes them.
    pub fn clean_up(&self) -> Option<String> {
        let left = self.leftovers();
        self.remove_files();
        (!left.is_empty()).then(|| {
            format!(
                "{}: {} files ({})",
                self.name,
                left.len(),
                left.iter()
                    .take(3)
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
    }

    /// Every file of this scene's prefix in /dev/shm and iceoryx2's folder.
    fn files(&self) -> Vec<PathBuf> {
        let mut found = Vec::new();
        for dir in [SHM_DIR, ICEORYX2_DIR] {
            collect(Path::new(dir), &|n| n.starts_with(&self.prefix), &mut found);
        }
        found
    }

    /// Files of this scene's prefix, except iceoryx2's per-prefix `*.global_mgmt` counter
    /// (kept by iceoryx2 by design).
    fn leftovers(&self) -> Vec<PathBuf> {
        let mut found = self.files();
        found.retain(|p| !p.to_string_lossy().ends_with(".global_mgmt"));
        found
    }

    /// Removes every file of this prefix (once every process of the scene has exited).
    fn remove_files(&self) {
        for path in self.files() {
            let _ = std::fs::remove_file(path);
        }
    }
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

/// Removes shared-memory files, iceoryx2 files and sockets left by earlier runs of this
/// benchmark whose process no longer exists (a run killed with SIGKILL cannot clean up).
/// Returns how many files were removed.
pub fn remove_stale() -> usize {
    let dead_run = |name: &str| -> bool {
        let digits = name
            .strip_prefix(PREFIX_TAG)
            .or_else(|| name.strip_prefix(super::socket::SOCKET_TAG))
            .map(|rest| rest.split(|c: char| !c.is_ascii_digit()).next());
        match digits.flatten().and_then(|d| d.parse::<u32>().ok()) {
            Some(pid) => pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists(),
            None => false,
        }
    };
    let mut found = Vec::new();
    collect(Path::new(SHM_DIR), &dead_run, &mut found);
    collect(Path::new(ICEORYX2_DIR), &dead_run, &mut found);
    if let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) {
        for e in entries.flatten() {
            if dead_run(&e.file_name().to_string_lossy()) {
                found.push(e.path());
            }
        }
    }
    found
        .into_iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count()
}

/// A line from a child, or the end of one of its streams.
enum Msg {
    Out(String),
    Err(String),
    Closed,
}

/// One reader process, controlled by lines on its stdin and reporting lines on its stdout.
pub struct ReaderProc {
    label: String,
    child: Child,
    stdin: Option<ChildStdin>,
    rx: Receiver<Msg>,
    stderr: Vec<String>,
    open_streams: usize,
    reaped: bool,
}

impl ReaderProc {
    /// Spawns `ygg-bench ipc reader <args>` for `scene`.
    pub fn spawn(label: String, scene: &Scene, args: &[String]) -> Res<Self> {
        let exe = std::env::current_exe()
            .map_err(|e| format!("cannot find the benchmark's own executable: {e}"))?;
        let mut command = Command::new(&exe);
        command
            .args(["ipc", "reader", "--scene", &scene.name, "--prefix"])
            .arg(&scene.prefix)
            .args(["--parent", &std::process::id().to_string()])
            .args(args)
            .env(ygg_transport::protocol::ENV_IOX2_PREFIX, &scene.prefix)
            .env_remove("IOX2_LOG_LEVEL")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = command
            .spawn()
            .map_err(|e| format!("cannot start {label} ({}): {e}", exe.display()))?;
        let (tx, rx) = mpsc::channel();
        if let Some(out) = child.stdout.take() {
            forward(out, tx.clone(), Msg::Out);
        }
        if let Some(err) = child.stderr.take() {
            forward(err, tx, Msg::Err);
        }
        let stdin = child.stdin.take();
        Ok(ReaderProc {
            label,
            child,
            stdin,
            rx,
            stderr: Vec::new(),
            open_streams: 2,
            reaped: false,
        })
    }

    /// Sends one command line.
    pub fn send(&mut self, line: &str) -> Res<()> {
        let Some(stdin) = self.stdin.as_mut() else {
            return Err(format!("{}: stdin already closed", self.label).into());
        };
        writeln!(stdin, "{line}")
            .and_then(|()| stdin.flush())
            .map_err(|e| self.died(&format!("cannot send {line:?}: {e}")).into())
    }

    /// The next stdout line, waiting until `deadline` (checking for interrupts meanwhile).
    pub fn line(&mut self, deadline: Instant) -> Res<String> {
        loop {
            check_interrupted()?;
            let now = Instant::now();
            if now >= deadline {
                return Err(
                    format!("{}: no answer in time{}", self.label, self.stderr_note()).into(),
                );
            }
            match self
                .rx
                .recv_timeout((deadline - now).min(Duration::from_millis(100)))
            {
                Ok(Msg::Out(line)) => return Ok(line),
                Ok(Msg::Err(line)) => {
                    if self.stderr.len() < 50 {
                        self.stderr.push(line);
                    }
                }
                Ok(Msg::Closed) => {
                    self.open_streams -= 1;
                    if self.open_streams == 0 {
                        return Err(self.died("exited unexpectedly").into());
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(self.died("exited unexpectedly").into());
                }
            }
        }
    }

    /// Waits for a stdout line starting with `tag` (other lines are an error).
    pub fn expect(&mut self, tag: &str, deadline: Instant) -> Res<String> {
        let line = self.line(deadline)?;
        if line.split_whitespace().next() == Some(tag) {
            Ok(line)
        } else {
            Err(format!("{}: expected {tag:?}, got {line:?}", self.label).into())
        }
    }

    /// Closes stdin: the reader's signal to exit cleanly.
    pub fn close_stdin(&mut self) {
        self.stdin = None;
    }

    /// Closes stdin (the reader's signal to exit cleanly) and waits up to `grace`;
    /// kills the process after that. Errors if it did not exit cleanly by itself.
    pub fn finish(mut self, grace: Duration) -> Res<()> {
        self.stdin = None;
        let start = Instant::now();
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => {
                    self.reaped = true;
                    if status.success() {
                        return Ok(());
                    }
                    return Err(self.died(&format!("exited with {status}")).into());
                }
                Ok(None) if start.elapsed() < grace => {
                    std::thread::sleep(Duration::from_millis(2));
                }
                _ => {
                    self.kill();
                    return Err(format!(
                        "{}: did not exit within {grace:?} of being told to; killed",
                        self.label
                    )
                    .into());
                }
            }
        }
    }

    fn kill(&mut self) {
        if !self.reaped {
            let _ = self.child.kill();
            let _ = self.child.wait();
            self.reaped = true;
        }
    }

    /// An error text with the child's exit status and stderr.
    fn died(&mut self, what: &str) -> String {
        let status = match self.child.try_wait() {
            Ok(Some(s)) => format!(" ({s})"),
            _ => String::new(),
        };
        // Collect what is left of stderr without waiting long.
        while let Ok(msg) = self.rx.recv_timeout(Duration::from_millis(20)) {
            if let Msg::Err(line) = msg
                && self.stderr.len() < 50
            {
                self.stderr.push(line);
            }
        }
        format!("{}: {what}{status}{}", self.label, self.stderr_note())
    }

    fn stderr_note(&self) -> String {
        if self.stderr.is_empty() {
            String::new()
        } else {
            format!("; its stderr:\n  {}", self.stderr.join("\n  "))
        }
    }
}

impl Drop for ReaderProc {
    fn drop(&mut self) {
        if self.reaped {
            return;
        }
        // Closing stdin asks the reader to exit cleanly (dropping its iceoryx2 ports).
        self.stdin = None;
        let start = Instant::now();
        while start.elapsed() < Duration::from_millis(500) {
            if let Ok(Some(_)) = self.child.try_wait() {
                self.reaped = true;
                return;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        self.kill();
    }
}

fn forward<R: Read + Send + 'static>(stream: R, tx: Sender<Msg>, wrap: fn(String) -> Msg) {
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines() {
            let Ok(line) = line else { break };
            if tx.send(wrap(line)).is_err() {
                return;
            }
        }
        let _ = tx.send(Msg::Closed);
    });
}

/// Several reader processes of one case.
pub struct Readers {
    /// The processes, in spawn order.
    pub procs: Vec<ReaderProc>,
}

impl Readers {
    /// Spawns `n` readers with the same arguments (plus `--index i`), then waits until
    /// each has its first snapshot (`ready`).
    pub fn spawn(n: usize, scene: &Scene, args: &[String], timeout: Duration) -> Res<Self> {
        let mut procs = Vec::with_capacity(n);
        for i in 0..n {
            let mut a = args.to_vec();
            a.extend(["--index".to_owned(), i.to_string()]);
            procs.push(ReaderProc::spawn(format!("reader {i}"), scene, &a)?);
        }
        let deadline = Instant::now() + timeout;
        for p in &mut procs {
            p.expect("ready", deadline)?;
        }
        Ok(Readers { procs })
    }

    /// Sends `line` to every reader.
    pub fn send_all(&mut self, line: &str) -> Res<()> {
        self.procs.iter_mut().try_for_each(|p| p.send(line))
    }

    /// Tells every reader to exit and waits for them.
    pub fn finish(mut self, grace: Duration) -> Res<()> {
        for p in &mut self.procs {
            p.close_stdin();
        }
        let mut first = None;
        for p in self.procs {
            if let Err(e) = p.finish(grace) {
                first.get_or_insert(e);
            }
        }
        first.map_or(Ok(()), Err)
    }
}
