//! `ygg-bench mission`: the mission-length benchmark of issue 38.
//!
//! The demo's SLAM stream ([`ygg_dsg::replay::SlamReplay`] on the built-in office in
//! mint layout, as `ygg serve` and `ygg demo` publish it) runs for N ticks, as fast as
//! the writer can go or at a given rate, with K reader processes following it (the
//! `ipc` benchmark's reader, `ygg-bench ipc reader --mode latency`). Reported per window
//! of ticks (the first ones, around 10,000, 36,000 and 100,000, the last ones) and per
//! bin of about 1 % of the run for the plots: `publish()` per tick, bytes published per
//! tick, publish-to-visible latency in each reader, the readers' CPU per update, a late
//! reader's attach to its first answer, and the writer's and readers' memory.
//!
//! Each run is a process of its own (`mission --leaf`, [`leaf`]); the benchmark
//! ([`paired`]) starts the runs, alternating with another build's `ygg-bench` when given
//! one (`--against`), takes medians over repeats and writes the report ([`report`]).

mod args;
mod leaf;
mod paired;
mod procfs;
mod report;
mod spans;

use crate::ipc::error::run_or_exit;
use args::Config;
pub use args::MissionArgs;

/// Runs `ygg-bench mission` (or, with `--leaf`, one run of it).
///
/// Errors are printed here, after every child was stopped and every shared-memory file
/// removed, and end the process with status 1.
pub fn run(args: &MissionArgs) -> Result<(), Box<dyn std::error::Error>> {
    let who = match args.leaf {
        true => "ygg-bench mission --leaf",
        false => "ygg-bench mission",
    };
    run_or_exit(who, || {
        let cfg = Config::new(args)?;
        match args.leaf {
            true => leaf::main(&cfg),
            false => paired::run(args, &cfg),
        }
    });
    Ok(())
}
