//! `ygg watch`: follows a live scene through [`SceneReader`], one line per validated
//! snapshot, and reports the writer going away and coming back.
//!
//! Lines: `attached scene=<name>` once attached; per snapshot
//! `snapshot session=<hex> generation=<n> layers=<id>:<generation>,... bytes=<n>
//! manifest_bytes=<n> nodes=<n>`; `writer gone; keeping generation=<n>` when the writer
//! exits (the last snapshot stays current; a restarted writer is picked up);
//! `terminated` on SIGINT/SIGTERM; a final `received <n> snapshots`. A snapshot that
//! fails validation is a warning on stderr (the previous one stays current).

use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use ygg_reader::{ReceiveError, SceneReader, SceneReceiveError, SceneSnapshot};
use ygg_store::SceneView;

use crate::error_chain::error_chain;
use crate::query::seconds;

/// Arguments of `ygg watch`.
#[derive(Parser, Debug)]
pub struct WatchArgs {
    /// Scene name.
    #[arg(long)]
    scene: String,
    /// Exit after this many snapshots.
    #[arg(long)]
    count: Option<u64>,
    /// Seconds to wait for the scene's writer to appear before giving up.
    #[arg(long, default_value_t = 0.0)]
    wait_for_writer: f64,
    /// Hold every snapshot this many milliseconds before waiting for the next (simulates a
    /// slow reader).
    #[arg(long, default_value_t = 0)]
    hold_ms: u64,
}

/// One line describing a snapshot.
fn describe(snapshot: &SceneSnapshot) -> String {
    let raw = snapshot.raw();
    let layers: Vec<String> = raw
        .entries()
        .map(|e| format!("{}:{}", e.layer_id, e.generation))
        .collect();
    let bytes: usize = raw.layers().map(|(_, b)| b.len()).sum();
    format!(
        "snapshot session={:#x} generation={} layers={} bytes={} manifest_bytes={} nodes={}",
        raw.session(),
        snapshot.generation(),
        layers.join(","),
        bytes,
        raw.manifest_bytes().len(),
        snapshot.view().node_count()
    )
}

/// Runs `ygg watch`.
///
/// # Errors
/// When the scene cannot be opened, or receiving fails other than by the writer going
/// away or a snapshot failing validation.
pub fn run(args: &WatchArgs) -> Result<ExitCode, Box<dyn std::error::Error>> {
    let mut reader = SceneReader::builder(&args.scene)
        .handle_termination_signals(true)
        .wait_for_writer(seconds(args.wait_for_writer, "--wait-for-writer")?)
        .open()?;
    println!("attached scene={}", reader.scene());
    let mut received = 0u64;
    let mut last: Option<u64> = None;
    let mut held = Vec::new();
    loop {
        match reader.wait_next(Duration::from_secs(1)) {
            Ok(Some(snapshot)) => {
                println!("{}", describe(&snapshot));
                last = Some(snapshot.generation());
                received += 1;
                if args.count.is_some_and(|count| received >= count) {
                    break;
                }
                if args.hold_ms > 0 {
                    held.push(snapshot);
                    if hold(&reader, Duration::from_millis(args.hold_ms)) {
                        println!("terminated");
                        break;
                    }
                    // Keep the borrow count of a slow reader bounded: hold the newest two.
                    if held.len() > 2 {
                        held.remove(0);
                    }
                }
            }
            Ok(None) => {}
            Err(SceneReceiveError::Receive(ReceiveError::WriterGone { .. })) => {
                let last = last.map_or("none".to_owned(), |g| g.to_string());
                println!("writer gone; keeping generation={last}");
            }
            Err(SceneReceiveError::Receive(ReceiveError::Terminated)) => {
                println!("terminated");
                break;
            }
            Err(
                e @ (SceneReceiveError::Invalid { .. }
                | SceneReceiveError::Receive(
                    ReceiveError::Corrupt { .. } | ReceiveError::BorrowLimit { .. },
                )),
            ) => {
                eprintln!("ygg watch: warning: {}", error_chain(&e));
            }
            Err(e) => return Err(e.into()),
        }
    }
    println!("received {received} snapshots");
    Ok(ExitCode::SUCCESS)
}

/// Holds the current snapshots for `duration`; `true` when a termination signal came.
fn hold(reader: &SceneReader, duration: Duration) -> bool {
    let until = Instant::now() + duration;
    while Instant::now() < until {
        if reader.termination_requested() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    false
}
