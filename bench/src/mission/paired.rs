//! The benchmark itself: starts the runs (this build's and, with `--against`, another
//! build's, alternating ABBA), each a child process under a watchdog, and writes the
//! report.

use super::args::{Config, FORMAT, MissionArgs};
use super::report::{self, Side};
use crate::ipc::child::remove_stale;
use crate::ipc::error::Res;
use crate::ipc::interrupt::{check_interrupted, install_signal_handler};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use ygg_testkit::{Input, LineError, Proc, Watchdog};

/// How long a run may take to exit after its result line (or after an interrupt).
const EXIT_GRACE: Duration = Duration::from_secs(30);

/// Runs the benchmark and writes its report.
pub fn run(args: &MissionArgs, cfg: &Config) -> Res<()> {
    install_signal_handler();
    if !args
        .name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
        || args.name.is_empty()
    {
        return Err(format!(
            "--name must be letters, digits, '-', '_' or '.', got {:?}",
            args.name
        )
        .into());
    }
    let limit = match args.timeout_min {
        Some(m) if m.is_finite() && m > 0.0 => Duration::from_secs_f64(m * 60.0),
        Some(m) => return Err(format!("--timeout-min must be a positive number, got {m}").into()),
        None => default_limit(cfg),
    };
    if let Some(dir) = &args.out_dir {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let own = std::env::current_exe()
        .map_err(|e| format!("cannot find the benchmark's own executable: {e}"))?;
    let mut sides = Vec::new();
    if let Some(path) = &args.against {
        sides.push(Side::new("baseline", against_binary(path)?));
    }
    sides.push(Side::new(
        if sides.is_empty() {
            "this build"
        } else {
            "new"
        },
        own,
    ));
    let started = Instant::now();
    for r in 0..args.repeats {
        let mut order: Vec<usize> = (0..sides.len()).collect();
        if r % 2 == 1 {
            order.reverse();
        }
        for i in order {
            let side = &mut sides[i];
            let label = format!("{} run {} of {}", side.label, r + 1, args.repeats);
            eprintln!("{label}: {}", side.binary.display());
            let result = run_one(&side.binary, cfg, &label, limit)?;
            side.runs.push(result);
        }
    }
    let hand_written = args
        .out_dir
        .as_ref()
        .and_then(|dir| std::fs::read_to_string(dir.join(format!("{}.md", args.name))).ok())
        .and_then(|md| report::notes(&md));
    let command = std::iter::once("ygg-bench".to_owned())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    let r = report::Report::new(sides, cfg, command, started.elapsed());
    let md = r.markdown(&args.name, hand_written.as_deref());
    if let Some(dir) = &args.out_dir {
        let path = |ext: &str| dir.join(format!("{}.{ext}", args.name));
        let json = serde_json::to_string_pretty(&r.to_json())?;
        for (p, text) in [(path("md"), &md), (path("json"), &json)] {
            std::fs::write(&p, text).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
        }
        r.plot_svg(&path("svg"))?;
        eprintln!("wrote {}.{{md,json,svg}}", dir.join(&args.name).display());
    }
    println!("{md}");
    Ok(())
}

/// The default watchdog: 10 minutes, 60 ms a tick, and the ticks' own time at a rate.
fn default_limit(cfg: &Config) -> Duration {
    let paced = if cfg.rate > 0.0 {
        cfg.ticks as f64 / cfg.rate
    } else {
        0.0
    };
    Duration::from_secs_f64(600.0 + 0.06 * cfg.ticks as f64 + paced)
}

/// The `ygg-bench` of `--against`: the file, or in a folder `ygg-bench-mission` or
/// `ygg-bench`; checked to have the `mission` command.
fn against_binary(path: &Path) -> Res<PathBuf> {
    let binary = if path.is_dir() {
        ["ygg-bench-mission", "ygg-bench"]
            .iter()
            .map(|n| path.join(n))
            .find(|p| p.is_file())
            .ok_or_else(|| {
                format!(
                    "--against {}: no ygg-bench-mission or ygg-bench in that folder",
                    path.display()
                )
            })?
    } else if path.is_file() {
        path.to_owned()
    } else {
        return Err(format!("--against {}: no such file or folder", path.display()).into());
    };
    let help = Command::new(&binary)
        .args(["mission", "--help"])
        .output()
        .map_err(|e| format!("--against: cannot run {}: {e}", binary.display()))?;
    if !help.status.success() {
        return Err(format!(
            "--against: {} has no `mission` command; build ygg-bench from a branch that has it (bench/results/mission.md says how)",
            binary.display()
        )
        .into());
    }
    Ok(binary)
}

/// Runs `binary mission --leaf ...` under a watchdog of `limit`, echoing its progress;
/// its result.
fn run_one(binary: &Path, cfg: &Config, label: &str, limit: Duration) -> Res<Value> {
    let mut command = Command::new(binary);
    command.args(cfg.to_args());
    let watchdog = Watchdog::new(limit);
    let mut p = Proc::start(command, label, Input::Null)?;
    watchdog.register(p.pid());
    let result = follow(&mut p, label);
    let status = p.wait_timeout(EXIT_GRACE);
    drop(p);
    drop(watchdog);
    if result.is_err() || status.is_none_or(|s| !s.success()) {
        // What a killed run could not remove.
        remove_stale();
    }
    let result = result?;
    match status {
        Some(s) if s.success() => Ok(result),
        Some(s) => Err(format!("{label}: exited with {s} after its result").into()),
        None => Err(format!("{label}: did not exit within {EXIT_GRACE:?} of its result").into()),
    }
}

/// Reads the run's lines until its result; an error with its stderr if it ends without.
fn follow(p: &mut Proc, label: &str) -> Res<Value> {
    loop {
        if let Err(e) = check_interrupted() {
            // The run got the signal too: give it time to clean up.
            let _ = p.wait_timeout(EXIT_GRACE);
            return Err(e);
        }
        match p.next_line(Instant::now() + Duration::from_millis(200)) {
            Ok(line) => {
                if let Some(text) = line.strip_prefix("progress ") {
                    eprintln!("  {label}: {text}");
                } else if let Some(json) = line.strip_prefix("result ") {
                    let v: Value = serde_json::from_str(json)
                        .map_err(|e| format!("{label}: unreadable result: {e}"))?;
                    if v["format"] != FORMAT {
                        return Err(format!(
                            "{label}: result format {} is not {FORMAT} (a build of other benchmark code)",
                            v["format"]
                        )
                        .into());
                    }
                    return Ok(v);
                }
            }
            Err(LineError::Timeout) => {}
            Err(LineError::Closed) => {
                let status = p
                    .wait_timeout(EXIT_GRACE)
                    .map_or("still running".to_owned(), |s| s.to_string());
                let stderr = p.stderr();
                let tail = &stderr[stderr.len().saturating_sub(30)..];
                return Err(format!(
                    "{label}: ended without a result ({status}; killed by the watchdog if SIGKILL); its stderr:\n  {}",
                    tail.join("\n  ")
                )
                .into());
            }
        }
    }
}
