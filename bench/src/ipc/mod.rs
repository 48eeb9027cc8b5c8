//! `ygg-bench ipc`: the multi-process latency benchmark of issue 5.
//!
//! The benchmark process is the writer. Readers are real processes: the same executable
//! re-executed with the hidden `ipc reader` subcommand ([`reader`]). Every case gets a
//! fresh scene name and iceoryx2 prefix (pid-based), and every child is killed on every
//! exit path ([`child`]); a run checks that it left nothing in `/dev/shm`.
//!
//! Latency is *publish-to-visible*: from the writer's `publish()` call (Unix ns, taken in
//! the writer just before the call) to the reader holding the validated snapshot (Unix
//! ns, taken in the reader; same host clock), and for the office cases to a first query
//! answered on it. From `publish()` returning to visible is the transport-and-validation
//! part alone.

mod bare;
pub(crate) mod cases;
pub(crate) mod child;
mod commands;
mod reader;
mod report;
mod scenes;
mod socket;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// Errors of the benchmark: a message for the user.
pub(crate) type BenchError = Box<dyn std::error::Error>;
/// Result of the benchmark's steps.
pub(crate) type Res<T> = Result<T, BenchError>;

/// Options of `ygg-bench ipc`.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true)]
pub struct IpcArgs {
    /// The reader process (internal: the benchmark starts it itself).
    #[command(subcommand)]
    role: Option<Role>,
    /// Fewer samples and segments up to 40 MB only: the whole run in under a minute.
    #[arg(long)]
    pub quick: bool,
    /// Write the results as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write `ipc.md` and `ipc.json` into this folder.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Run every case this many times and report the median of the per-round medians and
    /// p99s (default 1 with --quick, else 3).
    #[arg(long)]
    pub rounds: Option<usize>,
    /// Pause between publishes in the latency cases, ms (default 3 with --quick, else 4;
    /// at least twice the last publish call).
    #[arg(long)]
    pub gap_ms: Option<f64>,
    /// Only these case groups, comma-separated: sizes, readers, office, socket, qps,
    /// throughput (default: all).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<cases::Group>,
}

#[derive(clap::Subcommand, Debug)]
enum Role {
    /// A reader process of the benchmark.
    #[command(hide = true)]
    Reader(reader::ReaderArgs),
}

/// Runs `ygg-bench ipc` (or, re-executed, one of its reader processes).
///
/// Errors are printed here, after every child was stopped and every shared-memory file
/// removed, and end the process with status 1.
pub fn run(args: &IpcArgs) -> Result<(), Box<dyn std::error::Error>> {
    // iceoryx2 warns on stderr that it found no config file; errors only, unless
    // IOX2_LOG_LEVEL says otherwise.
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let result = match &args.role {
        Some(Role::Reader(r)) => reader::main(r),
        None => cases::run(args),
    };
    if let Err(e) = result {
        let who = if args.role.is_some() {
            "ygg-bench ipc reader"
        } else {
            "ygg-bench ipc"
        };
        eprintln!("{who}: error: {e}");
        std::process::exit(1);
    }
    Ok(())
}

/// Whether SIGINT or SIGTERM arrived since [`install_signal_handler`] (sticky).
pub(crate) fn interrupted() -> bool {
    static SEEN: AtomicBool = AtomicBool::new(false);
    if iceoryx2_bb_posix::signal::SignalHandler::termination_requested() {
        SEEN.store(true, Ordering::SeqCst);
    }
    SEEN.load(Ordering::SeqCst)
}

/// Takes over SIGINT and SIGTERM (iceoryx2's handler), so that an interrupted run stops
/// its children and removes its shared memory before exiting; see [`interrupted`].
pub(crate) fn install_signal_handler() {
    let _ = interrupted();
}

/// An error unless the run was interrupted.
pub(crate) fn check_interrupted() -> Res<()> {
    if interrupted() {
        Err("interrupted (SIGINT/SIGTERM): children stopped, shared memory removed".into())
    } else {
        Ok(())
    }
}

/// Nanoseconds since the Unix epoch: the clock shared by the writer and its readers.
pub(crate) use ygg_transport::protocol::unix_ns;

/// CPU time the calling thread has used, ns (`CLOCK_THREAD_CPUTIME_ID`): what one reader
/// spends, whatever else runs on the machine.
pub(crate) fn thread_cpu_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    u64::try_from(t.tv_sec).unwrap_or(0) * 1_000_000_000 + u64::try_from(t.tv_nsec).unwrap_or(0)
}
