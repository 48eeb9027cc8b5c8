//! Reader processes as seen from the writer: the benchmark's own executable re-executed
//! as `ygg-bench ipc reader`, controlled by lines over stdin and stdout, on top of
//! [`ygg_testkit::Proc`].
//!
//! A [`ReaderProc`] that is dropped without [`ReaderProc::finish`] (an error, a panic, an
//! interrupt) closes the child's stdin, gives it a moment to exit cleanly and then
//! SIGKILLs and reaps it. Children also ask the kernel for SIGTERM when the benchmark
//! dies ([`ygg_testkit::die_with_parent`]), so even a SIGKILLed benchmark leaves no
//! reader behind. Shared-memory files of a case are removed by prefix
//! ([`Scene::clean_up`]) once every process of the case has exited, and files of earlier,
//! killed runs by [`remove_stale`].

use super::error::Res;
use super::interrupt::check_interrupted;
use std::process::Command;
use std::time::{Duration, Instant};
use ygg_testkit::{Input, LineError, Proc};

/// A unique scene name and iceoryx2 file prefix for one case.
pub use ygg_testkit::TestScene as Scene;
/// Removes the files of earlier, killed runs.
pub use ygg_testkit::remove_stale;

/// One reader process, controlled by lines on its stdin and reporting lines on its stdout.
pub struct ReaderProc {
    proc: Proc,
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
            .args(args);
        scene.configure(&mut command);
        Ok(ReaderProc {
            proc: Proc::start(command, label, Input::Lines)?,
        })
    }

    /// Sends one command line.
    pub fn send(&mut self, line: &str) -> Res<()> {
        self.proc
            .send(line)
            .map_err(|e| self.died(&format!("cannot send {line:?}: {e}")).into())
    }

    /// The next stdout line, waiting until `deadline` (checking for interrupts meanwhile).
    pub fn line(&mut self, deadline: Instant) -> Res<String> {
        loop {
            check_interrupted()?;
            let slice = deadline.min(Instant::now() + Duration::from_millis(100));
            match self.proc.next_line(slice) {
                Ok(line) => return Ok(line),
                Err(LineError::Timeout) if Instant::now() < deadline => {}
                Err(LineError::Timeout) => {
                    return Err(self.died("no answer in time").into());
                }
                Err(LineError::Closed) => return Err(self.died("exited unexpectedly").into()),
            }
        }
    }

    /// Waits for a stdout line starting with `tag` (other lines are an error).
    pub fn expect(&mut self, tag: &str, deadline: Instant) -> Res<String> {
        let line = self.line(deadline)?;
        if line.split_whitespace().next() == Some(tag) {
            Ok(line)
        } else {
            Err(format!("{}: expected {tag:?}, got {line:?}", self.proc.label()).into())
        }
    }

    /// Closes stdin: the reader's signal to exit cleanly.
    /// The process id.
    pub fn pid(&self) -> u32 {
        self.proc.pid()
    }

    pub fn close_stdin(&mut self) {
        self.proc.close_stdin();
    }

    /// Closes stdin (the reader's signal to exit cleanly) and waits up to `grace`;
    /// kills the process after that. Errors if it did not exit cleanly by itself.
    pub fn finish(mut self, grace: Duration) -> Res<()> {
        match self.proc.stop(grace) {
            Some(status) if status.success() => Ok(()),
            Some(status) => Err(self.died(&format!("exited with {status}")).into()),
            None => Err(format!(
                "{}: did not exit within {grace:?} of being told to; killed",
                self.proc.label()
            )
            .into()),
        }
    }

    /// An error text with the child's exit status and stderr.
    fn died(&mut self, what: &str) -> String {
        let status = self
            .proc
            .try_status()
            .map_or(String::new(), |s| format!(" ({s})"));
        let stderr = self.proc.stderr();
        let note = if stderr.is_empty() {
            String::new()
        } else {
            let tail = &stderr[stderr.len().saturating_sub(50)..];
            format!("; its stderr:\n  {}", tail.join("\n  "))
        };
        format!("{}: {what}{status}{note}", self.proc.label())
    }
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
