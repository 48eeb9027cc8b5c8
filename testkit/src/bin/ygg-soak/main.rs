//! `ygg-soak`: the demo's writer and reader roles run for minutes under churn,
//! checking that no answer goes wrong and that nothing leaks
//! (`cargo run --release -p ygg-testkit --bin ygg-soak -- --minutes 30`).
//!
//! * A writer (`ygg serve --rate 30`, started as the demo starts it) serves the
//!   built-in office with its SLAM-like stream, keeping a sliding window of what the
//!   stream adds ([`WINDOW`]) so that the scene's size stops growing after a few seconds
//!   and memory that keeps growing is a leak. It is SIGKILLed at [`KILL_AT`] of the run
//!   (at the earliest once the first writer was sampled after its warm-up) and stopped
//!   with SIGTERM [`TERM_AFTER`] of the run later; each time a new writer is started,
//!   and every reader alive then must pick it up (query a snapshot of its session) within
//!   [`PICKUP`] (DESIGN.md §5).
//! * One long-lived reader (the planner role) runs for the whole run; `--readers` more
//!   reader processes (roles drawn at random) attach, detach when their own time is up or
//!   on SIGTERM, get SIGKILLed, and are started again, all drawn from `--seed`.
//! * Every reader checks sampled answers against brute force on the same snapshot
//!   (`ygg demo-role`); one wrong answer fails the run.
//! * Usage is sampled in like states (one writer after its warm-up, the long-lived reader,
//!   no other reader: the churning ones are stopped first): at the start (the first
//!   writer), when the final writer has warmed up, and at the end. The run fails when the
//!   final writer's RSS grows by more than `--max-rss-growth` percent between its two
//!   samples, the long-lived reader's private memory by more than
//!   `--max-reader-anon-growth` percent between start and end, when open descriptors or
//!   `/dev/shm` files do not return to their start values (a reader's descriptors on the
//!   writer's pool segments, whose number depends on how that writer's pool grew, within
//!   the final writer's life; none may point to a removed segment), or when anything is
//!   left in `/dev/shm` after the last process exited.
//!
//! Progress is a JSON line every `--progress-secs`, the verdict a final JSON summary
//! line; the exit status is 0 only when every check held. Ctrl-C (or SIGTERM) stops
//! every process cleanly and removes the scene's files. There is no watchdog thread
//! (whose pid list would outlive reaped children in a long run): every wait has a
//! deadline, each child has a time limit of its own (`--seconds`), the readers die with
//! this process, and every child still running is killed when its [`Proc`] is dropped.

mod launch;
mod usage;

use clap::Parser;
use launch::{ROLES, stderr_tail};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustix::process::Signal;
use serde_json::{Value, json};
use std::os::unix::process::ExitStatusExt;
use std::process::ExitStatus;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use usage::{Usage, growth_pct, shm_files};
use ygg_testkit::{Proc, TestScene};

/// Options of `ygg-soak`.
#[derive(Parser, Debug)]
#[command(
    name = "ygg-soak",
    version,
    about = "Soak: the office stream for minutes while readers attach, detach, get killed and restart and the writer is restarted twice; fails on a wrong answer or on growth of memory, descriptors or /dev/shm files"
)]
struct SoakArgs {
    /// How long to run, minutes.
    #[arg(long, default_value_t = 30.0)]
    pub minutes: f64,
    /// Seed of the reader churn.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Reader processes (besides the long-lived one) that attach, detach and get killed.
    #[arg(long, default_value_t = 3)]
    pub readers: usize,
    /// Seconds between progress lines.
    #[arg(long, default_value_t = 10.0)]
    pub progress_secs: f64,
    /// Scale of the built-in office.
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Writer update ticks per second.
    #[arg(long, default_value_t = 30.0)]
    pub rate: f64,
    /// Seconds a writer runs before it is sampled (its scene fills the window in ~20 s).
    #[arg(long, default_value_t = 30.0)]
    pub warmup_secs: f64,
    /// Largest allowed growth of the final writer's RSS after its warm-up, percent.
    #[arg(long, default_value_t = 5.0)]
    pub max_rss_growth: f64,
    /// Largest allowed growth of the long-lived reader's private memory (RssAnon) from
    /// start to end, percent.
    #[arg(long, default_value_t = 10.0)]
    pub max_reader_anon_growth: f64,
}

/// The writer's window over what the stream adds: the newest 10 s of poses, 4 objects
/// (20 s) and 256 mesh points per room (4 patches, ~20 s in the office).
pub const WINDOW: [&str; 6] = [
    "--keep-poses",
    "300",
    "--keep-objects",
    "4",
    "--keep-mesh-points",
    "256",
];
/// When the writer is SIGKILLed, as a fraction of the run.
pub const KILL_AT: f64 = 0.25;
/// How long after the kill the (second) writer is stopped with SIGTERM, as a fraction of
/// the run (at least 10 s).
pub const TERM_AFTER: f64 = 0.2;
/// How long a reader may take to query a snapshot of a new writer once it is ready.
pub const PICKUP: Duration = Duration::from_secs(30);
/// How long a process may take to exit after SIGTERM.
const STOP_GRACE: Duration = Duration::from_secs(15);
/// Pause after the churning readers stopped, so the writer frees their resources (it
/// removes dead readers' resources every second).
const SETTLE: Duration = Duration::from_secs(3);
/// How long the end sample may take to return to the start's descriptor and file counts.
const SETTLE_LIMIT: Duration = Duration::from_secs(10);
/// The main loop's period.
const TICK: Duration = Duration::from_millis(100);
/// Time limits of the churning readers, seconds.
const CHURN_LIFETIME: std::ops::Range<f64> = 3.0..20.0;
/// Seconds between two churn actions.
const CHURN_PAUSE: std::ops::Range<f64> = 0.5..3.0;

fn main() -> std::process::ExitCode {
    match run(&SoakArgs::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ygg-soak: error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Runs the soak.
///
/// # Errors
/// When a check failed (after the summary line), when interrupted, or when the run could
/// not start.
fn run(args: &SoakArgs) -> Result<(), Box<dyn std::error::Error>> {
    if !(args.minutes.is_finite() && args.minutes > 0.0) {
        return Err("--minutes must be a positive number".into());
    }
    if args.readers == 0 || args.readers > 6 {
        return Err("--readers must be between 1 and 6 (the writer serves 8 at once)".into());
    }
    if !(args.progress_secs.is_finite() && args.progress_secs > 0.0) {
        return Err("--progress-secs must be a positive number".into());
    }
    if !(args.warmup_secs.is_finite() && args.warmup_secs >= 0.0) {
        return Err("--warmup-secs must be a non-negative number".into());
    }
    let stop = launch::stop_on_ctrl_c()?;
    let scene = TestScene::for_run("soak");
    let mut soak = Soak::new(args, scene, stop);
    let started = Instant::now();
    let outcome = soak.run();
    if let Err(why) = &outcome {
        soak.fail(why.clone());
    }
    let verdict = soak.finish(started);
    println!("{verdict}");
    if soak.interrupted() {
        return Err("interrupted: every process stopped, no verdict".into());
    }
    if !soak.failures.is_empty() {
        return Err(format!("soak failed:\n  {}", soak.failures.join("\n  ")).into());
    }
    Ok(())
}

/// A sample of the processes being watched, in one like state.
#[derive(Clone, Copy, Debug, serde::Serialize)]
struct Sample {
    /// Seconds since the first writer was ready.
    seconds: f64,
    writer_pid: u32,
    writer: Usage,
    reader: Usage,
    /// Files of the scene's prefix in `/dev/shm`.
    shm_files: usize,
}

/// A writer process and what it reported.
struct Writer {
    proc: Proc,
    /// Its session and when it was seen ready.
    ready: Option<(u64, Instant)>,
    /// The signal the soak sent it.
    sent: Option<Signal>,
    summary: bool,
    started: Instant,
}

/// A reader process and what it reported.
struct Reader {
    proc: Proc,
    /// Answers checked against brute force and answers that matched (its newest progress
    /// or summary line).
    checked: u64,
    matched: u64,
    /// The signal the soak sent it.
    sent: Option<Signal>,
    summary: bool,
    /// A writer session it has to pick up, and since when.
    due: Option<(u64, Instant)>,
}

impl Reader {
    fn new(proc: Proc) -> Self {
        Self {
            proc,
            checked: 0,
            matched: 0,
            sent: None,
            summary: false,
            due: None,
        }
    }

    fn signal(&mut self, signal: Signal) {
        self.proc.signal(signal);
        self.sent = Some(signal);
    }
}

/// Counts over the run.
#[derive(Debug, Default, serde::Serialize)]
struct Tally {
    readers_started: u64,
    readers_killed: u64,
    readers_stopped: u64,
    readers_timed_out: u64,
    /// Answers checked and matched by readers that have exited.
    checked: u64,
    matched: u64,
    writer_restarts: u64,
    pickups: u64,
    pickup_max_s: f64,
}

struct Soak<'a> {
    args: &'a SoakArgs,
    scene: TestScene,
    stop: Arc<AtomicBool>,
    rng: ChaCha8Rng,
    run: Duration,
    warmup: Duration,
    /// When the first writer was ready: the run's clock.
    t0: Option<Instant>,
    writer: Option<Writer>,
    long: Option<Reader>,
    churn: Vec<Reader>,
    next_churn: Instant,
    tally: Tally,
    start: Option<Sample>,
    final_early: Option<Sample>,
    end: Option<Sample>,
    failures: Vec<String>,
    /// A failure after which the run cannot go on was recorded.
    fatal: bool,
    left_behind: Option<String>,
}

impl<'a> Soak<'a> {
    fn new(args: &'a SoakArgs, scene: TestScene, stop: Arc<AtomicBool>) -> Self {
        let run = Duration::from_secs_f64(args.minutes * 60.0);
        Self {
            args,
            scene,
            stop,
            rng: ChaCha8Rng::seed_from_u64(args.seed),
            run,
            warmup: Duration::from_secs_f64(args.warmup_secs),
            t0: None,
            writer: None,
            long: None,
            churn: Vec::new(),
            next_churn: Instant::now(),
            tally: Tally::default(),
            start: None,
            final_early: None,
            end: None,
            failures: Vec::new(),
            fatal: false,
            left_behind: None,
        }
    }

    fn interrupted(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }

    /// Records a failed check (none once interrupted: processes then exit on their own).
    fn fail(&mut self, why: String) {
        if !self.interrupted() {
            self.failures.push(why);
        }
    }

    /// Records a failure after which the run stops.
    fn fatal(&mut self, why: String) {
        self.fatal = true;
        self.fail(why);
    }

    fn seconds(&self) -> f64 {
        self.t0.map_or(0.0, |t| t.elapsed().as_secs_f64())
    }

    /// Starts a writer that stops by itself a while after the run should have ended.
    fn start_writer(&mut self) -> Result<(), String> {
        let n = self.tally.writer_restarts + 1;
        let left = self
            .run
            .saturating_sub(self.t0.map_or(Duration::ZERO, |t| t.elapsed()));
        let limit = (left + Duration::from_secs(300)).as_secs_f64();
        let proc = launch::start_writer(
            &self.scene,
            self.args.rate,
            self.args.scale,
            limit,
            &WINDOW,
            &format!("writer-{n}"),
        )
        .map_err(|e| e.to_string())?;
        self.writer = Some(Writer {
            proc,
            ready: None,
            sent: None,
            summary: false,
            started: Instant::now(),
        });
        Ok(())
    }

    fn start_reader(&mut self, role: &str, seconds: f64, label: &str) -> Result<Reader, String> {
        let proc = launch::start_role(
            &self.scene,
            role,
            seconds,
            &["--wait-for-writer", "120"],
            label,
        )
        .map_err(|e| e.to_string())?;
        self.tally.readers_started += 1;
        Ok(Reader::new(proc))
    }

    /// The run: every phase up to the end sample.
    fn run(&mut self) -> Result<(), String> {
        self.start_writer()?;
        let writer = self.writer.as_mut().ok_or("no writer")?;
        let ready = launch::wait_ready(&mut writer.proc, &self.stop)?;
        let t0 = Instant::now();
        self.t0 = Some(t0);
        let kill_after = self
            .run
            .mul_f64(KILL_AT)
            .max(self.warmup + Duration::from_secs(5));
        let term_after = kill_after + self.run.mul_f64(TERM_AFTER).max(Duration::from_secs(10));
        println!(
            "{}",
            json!({"event": "start", "scene": self.scene.name, "minutes": self.args.minutes,
                "seed": self.args.seed, "readers": self.args.readers, "nodes": ready["nodes"],
                "warmup_s": self.warmup.as_secs_f64(), "writer_kill_s": kill_after.as_secs_f64(),
                "writer_term_s": term_after.as_secs_f64(), "writer_window": WINDOW.join(" ")})
        );
        let long_seconds = (self.run + Duration::from_secs(600)).as_secs_f64();
        let long = self.start_reader("planner", long_seconds, "long-lived")?;
        self.long = Some(long);
        // The long-lived reader picks up the first writer like any later one.
        self.pump();
        self.pump_until(t0 + self.warmup)?;
        if self.long.as_ref().is_some_and(|r| r.due.is_some()) {
            return Err("the long-lived reader got no snapshot during the warm-up".into());
        }
        self.start = Some(self.sample()?);
        let (kill_at, term_at) = (t0 + kill_after, t0 + term_after);
        let end = t0 + self.run;
        let mut next_progress = Instant::now();
        let mut killed = false;
        let mut stopped = false;
        while Instant::now() < end {
            self.check_stop()?;
            self.pump();
            if self.fatal {
                return Err("stopped after the failure above".into());
            }
            let now = Instant::now();
            if !killed && now >= kill_at {
                killed = true;
                self.restart_writer(Signal::KILL)?;
            } else if killed && !stopped && now >= term_at && self.writer_ready().is_some() {
                stopped = true;
                self.restart_writer(Signal::TERM)?;
            } else if stopped
                && self.final_early.is_none()
                && self.writer_ready().is_some_and(|t| now >= t + self.warmup)
            {
                self.quiesce()?;
                self.final_early = Some(self.sample()?);
            }
            self.churn_step();
            if now >= next_progress {
                next_progress = now + Duration::from_secs_f64(self.args.progress_secs);
                self.progress();
            }
            std::thread::sleep(TICK);
        }
        if self.final_early.is_none() {
            return Err(format!(
                "the final writer had not warmed up before the end ({:.0} s): run longer",
                self.run.as_secs_f64()
            ));
        }
        self.quiesce()?;
        self.end = Some(self.settled_end_sample()?);
        Ok(())
    }

    fn check_stop(&self) -> Result<(), String> {
        if self.interrupted() {
            Err("interrupted".into())
        } else {
            Ok(())
        }
    }

    /// When the current writer was seen ready.
    fn writer_ready(&self) -> Option<Instant> {
        self.writer.as_ref()?.ready.map(|(_, t)| t)
    }

    /// Pumps for `until`, handling lines and exits (churn paused).
    fn pump_until(&mut self, until: Instant) -> Result<(), String> {
        while Instant::now() < until {
            self.check_stop()?;
            self.pump();
            std::thread::sleep(TICK);
        }
        Ok(())
    }

    /// Stops the writer with `signal`, checks how it ended and starts the next one.
    fn restart_writer(&mut self, signal: Signal) -> Result<(), String> {
        let mut old = self.writer.take().ok_or("no writer to restart")?;
        old.proc.signal(signal);
        old.sent = Some(signal);
        let status = old.proc.wait_timeout(STOP_GRACE);
        self.writer_lines(&mut old);
        match status {
            None => {
                old.proc.kill();
                self.fail(format!(
                    "{} did not exit after {signal:?}",
                    old.proc.label()
                ));
            }
            Some(s) if signal == Signal::KILL && s.signal() == Some(Signal::KILL.as_raw()) => {}
            Some(s) if signal == Signal::TERM && s.success() && old.summary => {}
            Some(s) => self.fail(format!(
                "{} ended badly after {signal:?} ({s}, summary {}):\n{}",
                old.proc.label(),
                old.summary,
                stderr_tail(&old.proc)
            )),
        }
        self.tally.writer_restarts += 1;
        self.start_writer()
    }

    /// Handles the lines of every process and the exits of the readers.
    fn pump(&mut self) {
        if let Some(mut w) = self.writer.take() {
            self.writer_lines(&mut w);
            if w.sent.is_none()
                && let Some(s) = w.proc.try_status()
            {
                self.fatal(format!(
                    "{} exited by itself ({s}):\n{}",
                    w.proc.label(),
                    stderr_tail(&w.proc)
                ));
            } else if w.ready.is_none() && w.started.elapsed() > launch::WRITER_READY {
                self.fatal(format!(
                    "{} was not ready within {:?}:\n{}",
                    w.proc.label(),
                    launch::WRITER_READY,
                    stderr_tail(&w.proc)
                ));
            }
            self.writer = Some(w);
        }
        if let Some(mut r) = self.long.take() {
            self.reader_lines(&mut r);
            if r.proc.try_status().is_some() {
                self.reader_lines(&mut r);
                self.fatal(format!(
                    "the long-lived reader exited:\n{}",
                    stderr_tail(&r.proc)
                ));
                self.finished(r);
            } else {
                self.long = Some(r);
            }
        }
        let churn = std::mem::take(&mut self.churn);
        for mut r in churn {
            self.reader_lines(&mut r);
            if r.proc.try_status().is_some() {
                self.reader_lines(&mut r);
                self.finished(r);
            } else {
                self.churn.push(r);
            }
        }
    }

    /// Handles the writer's new lines; on its `ready` line every live reader has to pick
    /// it up.
    fn writer_lines(&mut self, w: &mut Writer) {
        for line in w.proc.new_lines() {
            let Ok(v) = serde_json::from_str::<Value>(&line) else {
                continue;
            };
            match v["event"].as_str() {
                Some("ready") => {
                    let Some(session) = v["session"].as_u64() else {
                        self.fatal(format!("a ready line without a session: {line}"));
                        continue;
                    };
                    let due = Some((session, Instant::now()));
                    w.ready = due;
                    for r in self.long.iter_mut().chain(self.churn.iter_mut()) {
                        r.due = due;
                    }
                }
                Some("summary") => w.summary = true,
                _ => {}
            }
        }
    }

    /// Handles a reader's new lines: answer counts, pickups of a new writer.
    fn reader_lines(&mut self, r: &mut Reader) {
        for line in r.proc.new_lines() {
            let Ok(v) = serde_json::from_str::<Value>(&line) else {
                continue;
            };
            let event = v["event"].as_str();
            if !matches!(event, Some("progress" | "summary")) {
                continue;
            }
            let (checked, matched) = (
                v["checked"].as_u64().unwrap_or(0),
                v["matched"].as_u64().unwrap_or(0),
            );
            if matched < checked && r.matched == r.checked {
                self.fail(format!(
                    "{}: {} of {checked} answers differ from brute force: {line}",
                    r.proc.label(),
                    checked - matched
                ));
            }
            (r.checked, r.matched) = (checked, matched);
            r.summary |= event == Some("summary");
            if let Some((session, since)) = r.due
                && v["session"].as_u64() == Some(session)
            {
                r.due = None;
                self.tally.pickups += 1;
                self.tally.pickup_max_s =
                    self.tally.pickup_max_s.max(since.elapsed().as_secs_f64());
            }
        }
        if let Some((_, since)) = r.due
            && since.elapsed() > PICKUP
        {
            r.due = None;
            self.fail(format!(
                "{} did not pick up the new writer within {PICKUP:?}",
                r.proc.label()
            ));
        }
    }

    /// Accounts for a reader that exited.
    fn finished(&mut self, mut r: Reader) {
        let status = r.proc.try_status();
        self.tally.checked += r.checked;
        self.tally.matched += r.matched;
        let label = r.proc.label().to_owned();
        match (r.sent, status) {
            (Some(Signal::KILL), Some(s)) if s.signal() == Some(Signal::KILL.as_raw()) => {
                self.tally.readers_killed += 1;
            }
            (sent, Some(s)) if s.success() && r.summary => {
                if sent.is_some() {
                    self.tally.readers_stopped += 1;
                } else {
                    self.tally.readers_timed_out += 1;
                }
            }
            (sent, status) => self.fail(format!(
                "{label} ended badly (sent {sent:?}, {}, summary {}):\n{}",
                describe(status),
                r.summary,
                stderr_tail(&r.proc)
            )),
        }
    }

    /// One churn action when it is due: start a reader, or SIGKILL or SIGTERM one.
    fn churn_step(&mut self) {
        let now = Instant::now();
        if now < self.next_churn {
            return;
        }
        self.next_churn = now + Duration::from_secs_f64(self.rng.gen_range(CHURN_PAUSE));
        let live = self.churn.len();
        if live < self.args.readers && (live == 0 || self.rng.gen_bool(0.5)) {
            let role = ROLES[self.rng.gen_range(0..ROLES.len())];
            let seconds = self.rng.gen_range(CHURN_LIFETIME);
            let label = format!("{role}-{}", self.tally.readers_started);
            match self.start_reader(role, seconds, &label) {
                Ok(r) => self.churn.push(r),
                Err(e) => self.fatal(e),
            }
        } else if live > 0 {
            let i = self.rng.gen_range(0..live);
            let signal = if self.rng.gen_bool(0.5) {
                Signal::KILL
            } else {
                Signal::TERM
            };
            self.churn[i].signal(signal);
        }
    }

    /// Stops every churning reader (SIGTERM) and lets the writer free their resources.
    fn quiesce(&mut self) -> Result<(), String> {
        for r in &mut self.churn {
            if r.sent.is_none() {
                r.signal(Signal::TERM);
            }
        }
        let until = Instant::now() + STOP_GRACE;
        while !self.churn.is_empty() && Instant::now() < until {
            self.check_stop()?;
            self.pump();
            std::thread::sleep(TICK);
        }
        for mut r in std::mem::take(&mut self.churn) {
            r.proc.kill();
            self.fail(format!("{} did not exit on SIGTERM", r.proc.label()));
            self.finished(r);
        }
        self.pump_until(Instant::now() + SETTLE)?;
        // The churn resumes a pause after the sample.
        self.next_churn = Instant::now() + Duration::from_secs(1);
        Ok(())
    }

    fn sample(&self) -> Result<Sample, String> {
        let writer = self.writer.as_ref().ok_or("no writer")?.proc.pid();
        let reader = self.long.as_ref().ok_or("no long-lived reader")?.proc.pid();
        let usage = |pid| Usage::of(pid).map_err(|e| format!("/proc/{pid}: {e}"));
        Ok(Sample {
            seconds: self.seconds(),
            writer_pid: writer,
            writer: usage(writer)?,
            reader: usage(reader)?,
            shm_files: shm_files(&self.scene),
        })
    }

    /// The end sample, re-taken for up to [`SETTLE_LIMIT`] until descriptors and files
    /// are back to their start values (freeing resources is asynchronous).
    fn settled_end_sample(&mut self) -> Result<Sample, String> {
        let until = Instant::now() + SETTLE_LIMIT;
        loop {
            let sample = self.sample()?;
            if self.counts_back(&sample).is_empty() || Instant::now() >= until {
                return Ok(sample);
            }
            self.pump_until(Instant::now() + Duration::from_millis(500))?;
        }
    }

    /// What in `end` did not return to the start values.
    fn counts_back(&self, end: &Sample) -> Vec<String> {
        let mut out = Vec::new();
        if let (Some(s), Some(f)) = (&self.start, &self.final_early) {
            if end.writer.fds != f.writer.fds {
                out.push(format!(
                    "final writer's open descriptors {} after warm-up, {} at the end",
                    f.writer.fds, end.writer.fds
                ));
            }
            // Data segments follow the writer's pool (see `Usage`): the reader's other
            // descriptors across the whole run, its data segments within one writer's life.
            let other = |u: &Usage| u.fds - u.pool_fds;
            if other(&end.reader) != other(&s.reader) {
                out.push(format!(
                    "long-lived reader's open descriptors other than data segments {} at the \
                     start, {} at the end",
                    other(&s.reader),
                    other(&end.reader)
                ));
            }
            if end.reader.pool_fds != f.reader.pool_fds {
                out.push(format!(
                    "long-lived reader's data segments {} after the final writer's warm-up, {} \
                     at the end",
                    f.reader.pool_fds, end.reader.pool_fds
                ));
            }
            if end.reader.removed_pool_fds > 0 {
                out.push(format!(
                    "long-lived reader keeps {} data segments of a writer that is gone",
                    end.reader.removed_pool_fds
                ));
            }
            for (when, n) in [
                ("after the final writer's warm-up", f.shm_files),
                ("at the end", end.shm_files),
            ] {
                if n != s.shm_files {
                    out.push(format!(
                        "/dev/shm files: {} at the start, {n} {when}",
                        s.shm_files
                    ));
                }
            }
        }
        out
    }

    /// A progress line.
    fn progress(&self) {
        let mb = |u: Option<Usage>| u.map(|u| u.rss_kb as f64 / 1024.0);
        let writer = self
            .writer
            .as_ref()
            .and_then(|w| Usage::of(w.proc.pid()).ok());
        let reader = self
            .long
            .as_ref()
            .and_then(|r| Usage::of(r.proc.pid()).ok());
        let (checked, matched) = self.answers();
        println!(
            "{}",
            json!({"event": "progress", "seconds": self.seconds(),
                "writer_rss_mb": mb(writer), "writer_fds": writer.map(|u| u.fds),
                "reader_rss_mb": mb(reader), "reader_fds": reader.map(|u| u.fds),
                "shm_files": shm_files(&self.scene), "readers_live": self.churn.len(),
                "readers_started": self.tally.readers_started, "readers_killed": self.tally.readers_killed,
                "writer_restarts": self.tally.writer_restarts, "checked": checked, "matched": matched})
        );
    }

    /// Answers checked and matched so far, by every reader.
    fn answers(&self) -> (u64, u64) {
        self.long
            .iter()
            .chain(&self.churn)
            .fold((self.tally.checked, self.tally.matched), |(c, m), r| {
                (c + r.checked, m + r.matched)
            })
    }

    /// Stops what still runs, checks the end state and returns the summary line.
    fn finish(&mut self, started: Instant) -> Value {
        for r in self.churn.iter_mut().chain(self.long.iter_mut()) {
            r.signal(Signal::TERM);
        }
        if let Some(w) = &mut self.writer {
            w.proc.signal(Signal::TERM);
            w.sent = Some(Signal::TERM);
        }
        let until = Instant::now() + STOP_GRACE;
        for r in std::mem::take(&mut self.churn)
            .into_iter()
            .chain(self.long.take())
        {
            let mut r = r;
            if r.proc
                .wait_timeout(until.saturating_duration_since(Instant::now()))
                .is_none()
            {
                r.proc.kill();
            }
            self.reader_lines(&mut r);
            self.finished(r);
        }
        if let Some(mut w) = self.writer.take() {
            let status = w
                .proc
                .wait_timeout(until.saturating_duration_since(Instant::now()));
            self.writer_lines(&mut w);
            if !(status.is_some_and(|s| s.success()) && w.summary) {
                w.proc.kill();
                self.fail(format!(
                    "{} did not stop cleanly on SIGTERM ({}):\n{}",
                    w.proc.label(),
                    describe(status),
                    stderr_tail(&w.proc)
                ));
            }
        }
        let until = Instant::now() + Duration::from_secs(5);
        while !self.scene.leftovers().is_empty() && Instant::now() < until {
            std::thread::sleep(TICK);
        }
        self.left_behind = self.scene.clean_up();
        if let Some(left) = &self.left_behind {
            self.fail(format!(
                "left in /dev/shm after every process exited: {left}"
            ));
        }
        self.verdict(started)
    }

    /// Checks the samples and answers, and builds the summary line.
    fn verdict(&mut self, started: Instant) -> Value {
        let (checked, matched) = self.answers();
        let bounds = json!({"writer_rss_growth_pct": self.args.max_rss_growth,
            "reader_anon_growth_pct": self.args.max_reader_anon_growth,
            "fds_and_shm_files": "back to their start values (a reader's pool segments: within the final writer's life)"});
        let (mut writer_growth, mut reader_growth) = (None, None);
        if let (Some(s), Some(f), Some(e)) = (self.start, self.final_early, self.end) {
            let wg = growth_pct(f.writer.rss_kb, e.writer.rss_kb);
            let rg = growth_pct(s.reader.anon_kb, e.reader.anon_kb);
            (writer_growth, reader_growth) = (Some(wg), Some(rg));
            if wg > self.args.max_rss_growth {
                self.fail(format!(
                    "the final writer's RSS grew {wg:.1} % after warm-up ({} -> {} kB), bound {} %",
                    f.writer.rss_kb, e.writer.rss_kb, self.args.max_rss_growth
                ));
            }
            if rg > self.args.max_reader_anon_growth {
                self.fail(format!(
                    "the long-lived reader's private memory grew {rg:.1} % ({} -> {} kB), bound {} %",
                    s.reader.anon_kb, e.reader.anon_kb, self.args.max_reader_anon_growth
                ));
            }
            for why in self.counts_back(&e) {
                self.fail(why);
            }
        }
        if checked == 0 {
            self.fail("no answer was checked against brute force".into());
        }
        if checked != matched {
            self.fail(format!(
                "{} of {checked} checked answers were wrong",
                checked - matched
            ));
        }
        json!({"event": "summary", "ok": self.failures.is_empty() && !self.interrupted(),
            "interrupted": self.interrupted(), "scene": self.scene.name,
            "seconds": started.elapsed().as_secs_f64(), "seed": self.args.seed,
            "answers_checked": checked, "answers_matched": matched, "tally": self.tally,
            "samples": {"start": self.start, "final_writer_warm": self.final_early, "end": self.end},
            "final_writer_rss_growth_pct": writer_growth, "reader_anon_growth_pct": reader_growth,
            "bounds": bounds, "left_in_dev_shm": self.left_behind, "failures": self.failures})
    }
}

fn describe(status: Option<ExitStatus>) -> String {
    status.map_or("still running".to_owned(), |s| s.to_string())
}
