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

mod args;
pub(crate) mod bare;
pub(crate) mod cases;
pub(crate) mod child;
pub(crate) mod clock;
mod commands;
pub(crate) mod error;
pub(crate) mod interrupt;
mod reader;
pub(crate) mod report;
pub(crate) mod scenes;
mod socket;

pub use args::IpcArgs;
use args::Role;

/// Runs `ygg-bench ipc` (or, re-executed, one of its reader processes).
///
/// Errors are printed here, after every child was stopped and every shared-memory file
/// removed, and end the process with status 1.
pub fn run(args: &IpcArgs) -> Result<(), Box<dyn std::error::Error>> {
    let who = match args.role {
        Some(_) => "ygg-bench ipc reader",
        None => "ygg-bench ipc",
    };
    error::run_or_exit(who, || match &args.role {
        Some(Role::Reader(r)) => reader::main(r),
        None => cases::run(args),
    });
    Ok(())
}
