//! The options of `ygg-bench ipc`: the run's ([`IpcArgs`], its case groups [`Group`]) or a
//! reader process's ([`Role`]).

use super::reader::ReaderArgs;
use std::path::PathBuf;

/// Options of `ygg-bench ipc`.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true)]
pub struct IpcArgs {
    /// The reader process (internal: the benchmark starts it itself).
    #[command(subcommand)]
    pub(super) role: Option<Role>,
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
    pub only: Vec<Group>,
}

/// The process `ygg-bench ipc` runs as, when not the benchmark itself.
#[derive(clap::Subcommand, Debug)]
pub(super) enum Role {
    /// A reader process of the benchmark.
    #[command(hide = true)]
    Reader(ReaderArgs),
}

/// Groups of cases (`--only`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    /// Segment size sweep, 1 reader.
    Sizes,
    /// Reader count 1, 2, 4, 8 with a small update.
    Readers,
    /// One agent pose vs the whole office.
    Office,
    /// The same ~40 MB graph through shared memory and through a Unix socket.
    Socket,
    /// Reader queries per second while the writer publishes.
    Qps,
    /// Writer updates per second with no reader, 4 idle and 4 busy readers.
    Throughput,
}

/// Every group, in the order a run measures them.
pub(super) const ALL_GROUPS: [Group; 6] = [
    Group::Sizes,
    Group::Readers,
    Group::Office,
    Group::Socket,
    Group::Qps,
    Group::Throughput,
];
