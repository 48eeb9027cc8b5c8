//! [`Child`]: a process of the demo (the writer or a reader role) whose stdout lines are
//! collected by a thread, killed and reaped when dropped; and [`die_with_parent`], which
//! a role calls so that it never outlives the demo that started it.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

use rustix::process::{Pid, Signal};

/// Env var holding the pid of the process that started this one, for
/// [`die_with_parent`]. The demo sets it for its processes, and so does the test
/// harness (`ygg_testkit::Proc`) for every child.
pub const ENV_PARENT_PID: &str = "YGG_PARENT_PID";

/// Stderr lines kept per process (the newest), for error messages.
const STDERR_LINES: usize = 20;

/// Asks the kernel to send SIGTERM to this process when its parent dies
/// (`prctl(PR_SET_PDEATHSIG)`), if it was started with [`ENV_PARENT_PID`]: even a
/// SIGKILLed demo leaves no reader behind. Returns `false` (and does nothing) without it.
///
/// # Errors
/// If the signal cannot be set, or the parent already exited before it was.
pub fn die_with_parent() -> std::io::Result<bool> {
    let Some(parent) = std::env::var(ENV_PARENT_PID)
        .ok()
        .and_then(|p| p.parse::<i32>().ok())
    else {
        return Ok(false);
    };
    rustix::process::set_parent_process_death_signal(Some(Signal::TERM))?;
    if rustix::process::getppid().map(Pid::as_raw_pid) != Some(parent) {
        return Err(std::io::Error::other(
            "the parent exited before this process started",
        ));
    }
    Ok(true)
}

/// A started process of the demo.
pub struct Child {
    label: String,
    child: std::process::Child,
    status: Option<ExitStatus>,
    stdout: Receiver<String>,
    stderr: Arc<Mutex<VecDeque<String>>>,
    readers: Vec<JoinHandle<()>>,
}

impl Child {
    /// Starts `command` (stdin `/dev/null`, stdout and stderr piped) with
    /// [`ENV_PARENT_PID`] set to this process.
    ///
    /// # Errors
    /// If it cannot be spawned (the message names `label` and the program).
    pub fn start(mut command: Command, label: &str) -> std::io::Result<Self> {
        command
            .env(ENV_PARENT_PID, std::process::id().to_string())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = command.spawn().map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!("cannot start {label} ({:?}): {e}", command.get_program()),
            )
        })?;
        let (tx, stdout) = std::sync::mpsc::channel();
        let stderr = Arc::new(Mutex::new(VecDeque::new()));
        let mut readers = Vec::new();
        if let Some(out) = child.stdout.take() {
            readers.push(forward_lines(out, tx));
        }
        if let Some(err) = child.stderr.take() {
            let kept = Arc::clone(&stderr);
            readers.push(std::thread::spawn(move || {
                for line in BufReader::new(err).lines().map_while(Result::ok) {
                    let mut kept = kept.lock().unwrap_or_else(PoisonError::into_inner);
                    if kept.len() == STDERR_LINES {
                        kept.pop_front();
                    }
                    kept.push_back(line);
                }
            }));
        }
        Ok(Self {
            label: label.to_owned(),
            child,
            status: None,
            stdout,
            stderr,
            readers,
        })
    }

    /// The name the demo gave this process.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The next stdout line, waiting up to `timeout`; `None` when none came (or stdout
    /// closed).
    pub fn next_line(&self, timeout: Duration) -> Option<String> {
        self.stdout.recv_timeout(timeout).ok()
    }

    /// Every stdout line that arrived since the last call (or [`Child::next_line`]).
    pub fn new_lines(&self) -> Vec<String> {
        self.stdout.try_iter().collect()
    }

    /// Sends `signal` (ignored when the process is gone).
    pub fn signal(&self, signal: Signal) {
        if self.status.is_none()
            && let Some(pid) = i32::try_from(self.child.id()).ok().and_then(Pid::from_raw)
        {
            let _ = rustix::process::kill_process(pid, signal);
        }
    }

    /// The exit status once the process exited; its output is then complete.
    pub fn try_status(&mut self) -> Option<ExitStatus> {
        if self.status.is_none() {
            self.status = self.child.try_wait().ok().flatten();
            if self.status.is_some() {
                for reader in self.readers.drain(..) {
                    let _ = reader.join();
                }
            }
        }
        self.status
    }

    /// The newest lines of its stderr, for an error message.
    pub fn stderr_tail(&self) -> String {
        let kept = self.stderr.lock().unwrap_or_else(PoisonError::into_inner);
        kept.iter().cloned().collect::<Vec<_>>().join("\n")
    }
}

impl Drop for Child {
    fn drop(&mut self) {
        if self.status.is_none() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Sends each line of `stream` to `tx` from a thread of its own.
fn forward_lines(stream: impl Read + Send + 'static, tx: Sender<String>) -> JoinHandle<()> {
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    })
}
