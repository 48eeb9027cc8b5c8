//! [`Proc`]: a child process with line-based stdout (and optional stdin control), killed
//! and reaped when dropped, and dying with its parent when it asks to
//! ([`die_with_parent`]); what `/proc` tells about a process ([`catches_signal`],
//! [`Proc::children`]).

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::fd::OwnedFd;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use rustix::event::{PollFd, PollFlags, Timespec, poll};
use rustix::process::{Pid, PidfdFlags, Signal, pidfd_open};

use crate::signal::send_signal;
use crate::{POLL_INTERVAL, Watchdog};

/// Env var [`Proc::start`] sets to the parent's pid, for [`die_with_parent`] (and for
/// `ygg demo-role`, which reads the same variable).
pub const ENV_PARENT_PID: &str = "YGG_PARENT_PID";

/// How long a dropped [`Proc`] whose stdin was piped may take to exit after stdin closed,
/// before it is killed.
pub const DROP_GRACE: Duration = Duration::from_millis(500);

/// Stderr lines kept per process (the newest).
const STDERR_LINES: usize = 1000;

/// For a child started by [`Proc::start`] that links this crate: asks the kernel to send
/// SIGTERM when the parent dies (`prctl(PR_SET_PDEATHSIG)`), so even a SIGKILLed parent
/// leaves no child behind. Returns `false` (and does nothing) when the process was not
/// started by the harness ([`ENV_PARENT_PID`] unset).
///
/// The signal follows the parent *thread* that spawned the child; the harness spawns from
/// the thread that owns the [`Proc`].
///
/// # Errors
///
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

/// What a child's stdin is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// `/dev/null`.
    Null,
    /// A pipe for [`Proc::send`]; closing it ([`Proc::close_stdin`]) asks the child to exit.
    Lines,
}

/// Why [`Proc::next_line`] returned no line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LineError {
    /// The deadline passed.
    #[error("no line in time")]
    Timeout,
    /// Stdout closed (the process exited) with no further line.
    #[error("stdout closed")]
    Closed,
}

#[derive(Debug, Default)]
struct Output {
    stdout: Vec<String>,
    stderr: VecDeque<String>,
    /// Streams (stdout, stderr) still open.
    open: usize,
    /// Stdout reached its end.
    stdout_closed: bool,
}

type Shared = Arc<(Mutex<Output>, Condvar)>;

/// A spawned child process whose output is collected line by line.
///
/// Stdout lines are kept (read them by index with [`Proc::wait_line_after`], or in order
/// with [`Proc::next_line`]); the newest stderr lines are kept for error messages.
/// Dropping it closes stdin, waits up to [`DROP_GRACE`] if stdin was piped, then
/// SIGKILLs and reaps the child.
#[derive(Debug)]
pub struct Proc {
    label: String,
    child: Child,
    stdin: Option<ChildStdin>,
    piped: bool,
    status: Option<ExitStatus>,
    /// A pidfd on the child: polls readable once it exited (`None` before Linux 5.3).
    exit_fd: Option<OwnedFd>,
    output: Shared,
    /// Stdout lines consumed by [`Proc::next_line`] and [`Proc::new_lines`].
    cursor: usize,
}

impl Proc {
    /// Starts `command` with piped stdout and stderr and `input` as stdin, and
    /// [`ENV_PARENT_PID`] set to this process.
    ///
    /// # Errors
    ///
    /// If the process cannot be spawned (the message names `label` and the program).
    pub fn start(
        mut command: Command,
        label: impl Into<String>,
        input: Input,
    ) -> std::io::Result<Self> {
        let label = label.into();
        command
            .env(ENV_PARENT_PID, std::process::id().to_string())
            .stdin(match input {
                Input::Null => Stdio::null(),
                Input::Lines => Stdio::piped(),
            })
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = command.spawn().map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!("cannot start {label} ({:?}): {e}", command.get_program()),
            )
        })?;
        let output: Shared = Arc::new((Mutex::new(Output::default()), Condvar::new()));
        if let Some(stdout) = child.stdout.take() {
            collect_lines(stdout, Arc::clone(&output), false);
        }
        if let Some(stderr) = child.stderr.take() {
            collect_lines(stderr, Arc::clone(&output), true);
        }
        let stdin = child.stdin.take();
        // The child is not reaped before `Proc` is dropped, so its pid cannot be reused.
        let exit_fd = i32::try_from(child.id())
            .ok()
            .and_then(Pid::from_raw)
            .and_then(|pid| pidfd_open(pid, PidfdFlags::empty()).ok());
        Ok(Self {
            label,
            child,
            piped: stdin.is_some(),
            stdin,
            status: None,
            exit_fd,
            output,
            cursor: 0,
        })
    }

    /// Spawns `command` (stdin `/dev/null`) registered with `watchdog`.
    ///
    /// # Panics
    ///
    /// If the process cannot be spawned.
    pub fn spawn(command: Command, label: impl Into<String>, watchdog: &Watchdog) -> Self {
        let proc = Self::start(command, label, Input::Null).unwrap_or_else(|e| panic!("{e}"));
        watchdog.register(proc.pid());
        proc
    }

    /// The label given at start.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Sends `signal` (e.g. `Signal::INT`) to the process.
    pub fn signal(&self, signal: Signal) {
        send_signal(self.child.id(), signal);
    }

    /// Writes one line to the child's stdin ([`Input::Lines`]).
    ///
    /// # Errors
    ///
    /// If stdin is closed or the child stopped reading.
    pub fn send(&mut self, line: &str) -> std::io::Result<()> {
        let stdin = self
            .stdin
            .as_mut()
            .ok_or_else(|| std::io::Error::other("stdin is closed"))?;
        writeln!(stdin, "{line}").and_then(|()| stdin.flush())
    }

    /// Closes stdin: for a child controlled by lines, the signal to exit cleanly.
    pub fn close_stdin(&mut self) {
        self.stdin = None;
    }

    /// Stdout lines so far.
    pub fn stdout(&self) -> Vec<String> {
        self.lock().stdout.clone()
    }

    /// The newest stderr lines so far.
    pub fn stderr(&self) -> Vec<String> {
        self.lock().stderr.iter().cloned().collect()
    }

    fn lock(&self) -> MutexGuard<'_, Output> {
        self.output.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Waits until a stdout line after the first `skip` lines satisfies `pred`; returns it
    /// with its index. `None` after `timeout`, or as soon as stdout closed (the process
    /// exited) with no such line.
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
            if output.stdout_closed {
                return None;
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
                "{}: expected line not seen within {timeout:?} (or before stdout closed)",
                self.describe()
            ),
        }
    }

    /// Number of stdout lines satisfying `pred` so far.
    pub fn count_lines(&self, pred: impl Fn(&str) -> bool) -> usize {
        self.lock().stdout.iter().filter(|l| pred(l)).count()
    }

    /// The next stdout line not yet returned by this method or [`Proc::new_lines`],
    /// waiting until `deadline`.
    ///
    /// # Errors
    ///
    /// [`LineError::Timeout`] at the deadline, [`LineError::Closed`] once stdout closed
    /// with no further line.
    pub fn next_line(&mut self, deadline: Instant) -> Result<String, LineError> {
        let (lock, cvar) = &*self.output;
        let mut output = lock.lock().unwrap_or_else(PoisonError::into_inner);
        loop {
            if let Some(line) = output.stdout.get(self.cursor) {
                self.cursor += 1;
                return Ok(line.clone());
            }
            if output.stdout_closed {
                return Err(LineError::Closed);
            }
            let remaining = deadline
                .checked_duration_since(Instant::now())
                .filter(|d| !d.is_zero())
                .ok_or(LineError::Timeout)?;
            output = cvar
                .wait_timeout(output, remaining)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
    }

    /// Every stdout line not yet returned by this method or [`Proc::next_line`].
    pub fn new_lines(&mut self) -> Vec<String> {
        let output = self.output.0.lock().unwrap_or_else(PoisonError::into_inner);
        let lines = output.stdout[self.cursor.min(output.stdout.len())..].to_vec();
        self.cursor = output.stdout.len();
        lines
    }

    /// The exit status, if the process has exited (then its output is complete).
    pub fn try_status(&mut self) -> Option<ExitStatus> {
        if self.status.is_none() {
            self.status = self.child.try_wait().ok().flatten();
            if self.status.is_some() {
                self.drain();
            }
        }
        self.status
    }

    /// Waits up to `timeout` for the process to exit; its status, or `None` if it still
    /// runs.
    pub fn wait_timeout(&mut self, timeout: Duration) -> Option<ExitStatus> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(status) = self.try_status() {
                return Some(status);
            }
            let remaining = deadline
                .checked_duration_since(Instant::now())
                .filter(|d| !d.is_zero())?;
            self.block_until_exit(remaining);
        }
    }

    /// Blocks until the process exits or `timeout` passes: on its pidfd, or (where the
    /// kernel has none) for one [`POLL_INTERVAL`] of a bounded poll.
    fn block_until_exit(&self, timeout: Duration) {
        match &self.exit_fd {
            Some(fd) => {
                let mut fds = [PollFd::new(fd, PollFlags::IN)];
                let timeout = Timespec::try_from(timeout).ok();
                // An error (EINTR) just means "check again".
                let _ = poll(&mut fds, timeout.as_ref());
            }
            None => std::thread::sleep(POLL_INTERVAL.min(timeout)),
        }
    }

    /// Whether the process has a handler for `signal` installed (see [`catches_signal`]).
    pub fn catches(&self, signal: Signal) -> bool {
        catches_signal(self.pid(), signal)
    }

    /// The pids of the process's own children (its grandchildren are theirs), read from
    /// `/proc`.
    pub fn children(&self) -> Vec<u32> {
        child_pids(self.pid())
    }

    /// Waits for the process to exit.
    ///
    /// # Panics
    ///
    /// If it does not exit within `timeout` (it is then killed).
    pub fn wait_exit(&mut self, timeout: Duration) -> ExitStatus {
        match self.wait_timeout(timeout) {
            Some(status) => status,
            None => {
                self.kill();
                panic!("{} did not exit within {timeout:?}", self.describe());
            }
        }
    }

    /// Closes stdin and waits up to `grace` for the process to exit by itself; kills it
    /// after that. Its status if it exited by itself.
    pub fn stop(&mut self, grace: Duration) -> Option<ExitStatus> {
        self.close_stdin();
        let status = self.wait_timeout(grace);
        if status.is_none() {
            self.kill();
        }
        status
    }

    /// SIGKILLs the process and reaps it.
    pub fn kill(&mut self) {
        if self.status.is_none() {
            let _ = self.child.kill();
            self.status = self.child.wait().ok();
        }
    }

    /// The label, pid, exit status (if exited) and output so far, for error messages.
    pub fn describe(&self) -> String {
        let status = self
            .status
            .map_or(String::new(), |s| format!(", exited with {s}"));
        let output = self.lock();
        format!(
            "{} (pid {}{status})\nstdout: {:#?}\nstderr: {:#?}",
            self.label,
            self.pid(),
            output.stdout,
            output.stderr
        )
    }

    /// Waits (briefly) until the output threads saw both streams close, so the last
    /// lines of an exited process are in.
    fn drain(&self) {
        let (lock, cvar) = &*self.output;
        let output = lock.lock().unwrap_or_else(PoisonError::into_inner);
        // A grandchild holding the pipes open must not stall us.
        let _ = cvar.wait_timeout_while(output, Duration::from_millis(500), |o| o.open > 0);
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if self.status.is_some() {
            return;
        }
        self.close_stdin();
        if self.piped {
            let _ = self.wait_timeout(DROP_GRACE);
        }
        self.kill();
    }
}

fn collect_lines(stream: impl Read + Send + 'static, output: Shared, is_stderr: bool) {
    output.0.lock().unwrap_or_else(PoisonError::into_inner).open += 1;
    std::thread::spawn(move || {
        let (lock, cvar) = &*output;
        for line in BufReader::new(stream).lines() {
            let Ok(line) = line else { break };
            let mut output = lock.lock().unwrap_or_else(PoisonError::into_inner);
            if is_stderr {
                if output.stderr.len() == STDERR_LINES {
                    output.stderr.pop_front();
                }
                output.stderr.push_back(line);
            } else {
                output.stdout.push(line);
            }
            cvar.notify_all();
        }
        let mut output = lock.lock().unwrap_or_else(PoisonError::into_inner);
        output.open -= 1;
        output.stdout_closed |= !is_stderr;
        cvar.notify_all();
    });
}

/// Parses `key=value` out of an output line.
pub fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split_whitespace()
        .find_map(|part| part.strip_prefix(key)?.strip_prefix('='))
}

/// Whether process `pid` has a handler installed for `signal` (the `SigCgt` mask of
/// `/proc/<pid>/status`): a process that catches SIGINT or SIGTERM can stop cleanly, one
/// that does not yet dies of it. `false` when the process is gone.
pub fn catches_signal(pid: u32, signal: Signal) -> bool {
    let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else {
        return false;
    };
    let caught = status
        .lines()
        .find_map(|l| l.strip_prefix("SigCgt:"))
        .and_then(|mask| u64::from_str_radix(mask.trim(), 16).ok())
        .unwrap_or(0);
    let bit = signal.as_raw() - 1;
    (0..64).contains(&bit) && caught & (1 << bit) != 0
}

/// The pids of the processes whose parent is `pid` (the `ppid` field of every
/// `/proc/<pid>/stat`).
fn child_pids(pid: u32) -> Vec<u32> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(|&child| {
            std::fs::read_to_string(format!("/proc/{child}/stat")).is_ok_and(|stat| {
                // `pid (comm) state ppid ...`; comm may hold spaces and parentheses.
                stat.rsplit_once(')')
                    .and_then(|(_, rest)| rest.split_whitespace().nth(1)?.parse::<u32>().ok())
                    == Some(pid)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_never_printed_is_given_up_on_when_stdout_closes_and_the_exit_is_seen() {
        let watchdog = Watchdog::new(Duration::from_secs(60));
        let mut command = Command::new("sh");
        command.args(["-c", "echo a; exit 3"]);
        let mut shell = Proc::spawn(command, "sh", &watchdog);
        let start = Instant::now();
        assert_eq!(
            shell.wait_line_after(0, Duration::from_secs(50), |l| l == "b"),
            None
        );
        assert!(start.elapsed() < Duration::from_secs(50), "waited it out");
        assert_eq!(shell.wait_exit(Duration::from_secs(50)).code(), Some(3));
        assert_eq!(shell.stdout(), ["a"]);
    }

    #[test]
    fn a_shell_trapping_term_is_seen_catching_it_and_its_sleep_as_its_child() {
        let watchdog = Watchdog::new(Duration::from_secs(60));
        let mut command = Command::new("sh");
        // `trap` installs the handler before `ready` is printed; `sleep` is a child.
        command.args(["-c", "trap 'exit 0' TERM; echo ready; sleep 60 & wait"]);
        let mut shell = Proc::spawn(command, "sh", &watchdog);
        shell.expect_line(Duration::from_secs(30), |l| l == "ready");
        assert!(shell.catches(Signal::TERM));
        assert!(!shell.catches(Signal::USR2));
        // Between fork and exec the child is still a copy of sh, trap included: wait for
        // the exec (its command name becomes `sleep`), which resets the caught signals.
        let is_sleep = |pid: u32| {
            std::fs::read_to_string(format!("/proc/{pid}/comm")).is_ok_and(|c| c.trim() == "sleep")
        };
        crate::wait_until(Duration::from_secs(30), "sh started sleep", || {
            shell.children().first().is_some_and(|&pid| is_sleep(pid))
        });
        let sleep = shell.children();
        assert_eq!(sleep.len(), 1, "{sleep:?}");
        assert!(!catches_signal(sleep[0], Signal::TERM));
        shell.signal(Signal::TERM);
        assert!(shell.wait_exit(Duration::from_secs(30)).success());
        send_signal(sleep[0], Signal::KILL);
    }
}
