//! The options of `ygg-bench mission` ([`MissionArgs`]) and what one run of it does
//! ([`Config`]).

use serde_json::{Value, json};
use std::path::PathBuf;

/// The format of a run's result line; a build whose runs print another is refused.
pub(crate) const FORMAT: &str = "ygg-bench-mission/1";

/// Ticks of a `--quick` run.
const QUICK_TICKS: u64 = 3_000;

/// Options of `ygg-bench mission`.
#[derive(clap::Args, Debug)]
pub struct MissionArgs {
    /// Ticks to run: each a step of the demo's SLAM stream and a publish (default 100,000;
    /// 3,000 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    pub ticks: Option<u64>,
    /// Reader processes following the stream.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=64))]
    pub readers: u64,
    /// Ticks per second; 0: as fast as the writer can go.
    #[arg(long, default_value_t = 0.0)]
    pub rate: f64,
    /// Keep only this many of the agent poses the stream appends (a sliding-window
    /// trajectory, as `ygg serve --keep-poses`); default: keep all.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub keep_poses: Option<u64>,
    /// Beside each tick's publish, send as many bytes through a bare iceoryx2 publisher
    /// (no Yggdrasil code) to a subscriber process, half a tick later at a rate: the floor
    /// that `publish()` and publish → visible are set against, per window, in the same
    /// run. This build only (not with --against).
    #[arg(long)]
    pub bare: bool,
    /// Ticks per window.
    #[arg(long, default_value_t = 1_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub window: u64,
    /// Late readers started at the end of each window, one after the other (the report
    /// gives their median; default 3, 1 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=100))]
    pub attach_samples: Option<u64>,
    /// A smoke run: 3,000 ticks (unless --ticks says otherwise), one late reader a window.
    #[arg(long)]
    pub quick: bool,
    /// Write `<name>.md`, `<name>.json` and `<name>.svg` into this folder (a section
    /// `## Notes` of an existing `<name>.md` is kept).
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Base name of the files written into --out-dir.
    #[arg(long, default_value = "mission")]
    pub name: String,
    /// Another build to run against (the baseline): its `ygg-bench` binary, or a folder
    /// holding it as `ygg-bench-mission` or `ygg-bench`. Its runs alternate with this
    /// build's; the report sets the two side by side.
    #[arg(long)]
    pub against: Option<PathBuf>,
    /// Runs of each build (alternating ABBA with --against); the report gives medians.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=99))]
    pub repeats: u64,
    /// Kill a run that takes longer than this, minutes (default: 10 plus 60 ms a tick,
    /// plus the ticks' time at --rate).
    #[arg(long)]
    pub timeout_min: Option<f64>,
    /// Be one run (internal: the benchmark starts its runs itself).
    #[arg(long, hide = true)]
    pub leaf: bool,
}

/// What one run does: the options every run of an invocation shares.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Config {
    /// Ticks to run.
    pub(crate) ticks: u64,
    /// Reader processes.
    pub(crate) readers: usize,
    /// Ticks per second (0: as fast as the writer goes).
    pub(crate) rate: f64,
    /// Agent poses kept (`None`: all).
    pub(crate) keep_poses: Option<usize>,
    /// Ticks per window.
    pub(crate) window: u64,
    /// Late readers per window.
    pub(crate) attach_samples: usize,
    /// Whether a bare iceoryx2 pair runs beside the writer.
    pub(crate) bare: bool,
}

impl Config {
    /// The run's options from the command line's, checked.
    pub(crate) fn new(args: &MissionArgs) -> Result<Config, String> {
        if !(args.rate.is_finite() && args.rate >= 0.0) {
            return Err(format!(
                "--rate must be a non-negative number of ticks per second, got {}",
                args.rate
            ));
        }
        if args.bare && args.against.is_some() {
            return Err(
                "--bare measures this build's floor in the same run; use it without --against"
                    .into(),
            );
        }
        let ticks = args
            .ticks
            .unwrap_or(if args.quick { QUICK_TICKS } else { 100_000 });
        let count = |v: u64, what: &str| {
            usize::try_from(v).map_err(|_| format!("{what} {v} is too large for this machine"))
        };
        Ok(Config {
            ticks,
            readers: count(args.readers, "--readers")?,
            rate: args.rate,
            keep_poses: args
                .keep_poses
                .map(|k| count(k, "--keep-poses"))
                .transpose()?,
            window: args.window.min(ticks),
            attach_samples: count(
                args.attach_samples
                    .unwrap_or(if args.quick { 1 } else { 3 }),
                "--attach-samples",
            )?,
            bare: args.bare,
        })
    }

    /// The arguments that make a run (`mission --leaf ...`) do this.
    pub(crate) fn to_args(&self) -> Vec<String> {
        let mut a = vec![
            "mission".to_owned(),
            "--leaf".to_owned(),
            "--ticks".to_owned(),
            self.ticks.to_string(),
            "--readers".to_owned(),
            self.readers.to_string(),
            "--rate".to_owned(),
            self.rate.to_string(),
            "--window".to_owned(),
            self.window.to_string(),
            "--attach-samples".to_owned(),
            self.attach_samples.to_string(),
        ];
        if let Some(k) = self.keep_poses {
            a.extend(["--keep-poses".to_owned(), k.to_string()]);
        }
        if self.bare {
            a.push("--bare".to_owned());
        }
        a
    }

    /// The options as JSON, for the results.
    pub(crate) fn to_json(&self) -> Value {
        json!({
            "ticks": self.ticks,
            "readers": self.readers,
            "rate": self.rate,
            "keep_poses": self.keep_poses,
            "window": self.window,
            "attach_samples": self.attach_samples,
            "bare": self.bare,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        args: MissionArgs,
    }

    fn parse(line: &str) -> Result<Config, String> {
        let cli = Cli::try_parse_from(std::iter::once("mission").chain(line.split_whitespace()))
            .map_err(|e| e.to_string())?;
        Config::new(&cli.args)
    }

    #[test]
    fn a_run_is_told_exactly_what_the_benchmark_was() {
        let cfg = parse("--ticks 500 --readers 3 --rate 30 --keep-poses 100 --bare").unwrap();
        let line = cfg.to_args().join(" ");
        assert!(line.starts_with("mission --leaf "), "{line}");
        let back = parse(line.trim_start_matches("mission ")).unwrap();
        assert_eq!(back, cfg);
        assert_eq!(cfg.window, 500);
        assert_eq!(parse("--quick").unwrap().ticks, QUICK_TICKS);
        assert_eq!(parse("").unwrap().ticks, 100_000);
    }

    #[test]
    fn bad_options_are_errors_not_panics() {
        for bad in [
            "--ticks 0",
            "--ticks -3",
            "--readers 0",
            "--readers 65",
            "--rate -1",
            "--rate nan",
            "--rate inf",
            "--keep-poses 0",
            "--window x",
            "--repeats 0",
            "--bare --against /bin/true",
        ] {
            assert!(parse(bad).is_err(), "{bad}");
        }
    }
}
