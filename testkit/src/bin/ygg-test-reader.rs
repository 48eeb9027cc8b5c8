//! `ygg-test-reader`: a reader at the transport level (segments and manifests, no
//! archive validation), the counterpart of `ygg-test-writer` in the transport tests.
//!
//! `watch` prints a line per snapshot (`snapshot session=.. generation=.. layers=..
//! bytes=.. manifest_bytes=.. check=..`, the check of [`ygg_testkit::test_pattern`]:
//! `ok`, `MISMATCH(..)` or `n/a` for segments that are not synthetic), writer exits and
//! restarts; `dump` prints the current snapshot once with each segment's first bytes.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::{Parser, Subcommand};
use ygg_testkit::test_pattern;
use ygg_transport::{
    ReaderOpenError, ReceiveError, SegmentSubscriber, Snapshot, SubscriberBuilder,
};

#[derive(Parser, Debug)]
#[command(
    name = "ygg-test-reader",
    version,
    about = "Watches a scene at the transport level and checks synthetic segments (a test driver)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Print every snapshot generation as it arrives, and writer exits and restarts.
    Watch(Watch),
    /// Print the current snapshot once and exit.
    Dump(Dump),
}

#[derive(Parser, Debug)]
struct Watch {
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

#[derive(Parser, Debug)]
struct Dump {
    /// Scene name.
    #[arg(long)]
    scene: String,
    /// Seconds to wait for a complete snapshot.
    #[arg(long, default_value_t = 5.0)]
    timeout: f64,
    /// Seconds to wait for the scene's writer to appear before giving up.
    #[arg(long, default_value_t = 0.0)]
    wait_for_writer: f64,
}

/// Exit code when a segment broke the protocol.
const EXIT_CORRUPT: u8 = 3;
/// Exit code when no snapshot arrived in time.
const EXIT_TIMEOUT: u8 = 4;

fn main() -> ExitCode {
    ygg_transport::init_iceoryx_logging();
    let cli = Cli::parse();
    // A process may attach to many scenes (about 40 descriptors each); do not stop at a soft limit of 1024.
    let _ = ygg_transport::limits::raise_open_file_limit();
    let result = match cli.command {
        Command::Watch(args) => watch(&args),
        Command::Dump(args) => dump(&args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("ygg-test-reader: error: {}", error_chain(e.as_ref()));
            ExitCode::FAILURE
        }
    }
}

fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// `value` seconds as a duration, for the option `name`.
fn seconds(value: f64, name: &str) -> Result<Duration, String> {
    Duration::try_from_secs_f64(value)
        .map_err(|_| format!("{name} must be a non-negative number of seconds"))
}

/// Opens the reader, waiting up to `wait` for the scene to exist.
fn open(scene: &str, wait: Duration) -> Result<SegmentSubscriber, ReaderOpenError> {
    SubscriberBuilder::new(scene)
        .handle_termination_signals(true)
        .wait_for_writer(wait)
        .open()
}

/// One line describing a snapshot, with the synthetic-content check.
fn describe(snapshot: &Snapshot) -> String {
    let layers: Vec<String> = snapshot
        .entries()
        .map(|e| format!("{}:{}", e.layer_id, e.generation))
        .collect();
    let bytes: usize = snapshot.layers().map(|(_, b)| b.len()).sum();
    let mut check = "n/a".to_owned();
    if snapshot
        .layers()
        .all(|(_, b)| test_pattern::is_synthetic(b))
        && snapshot.layer_count() > 0
    {
        check = "ok".to_owned();
        for (entry, bytes) in snapshot.layers() {
            if let Err(e) = test_pattern::check(bytes, entry) {
                check = format!("MISMATCH({e})");
                break;
            }
        }
    }
    format!(
        "snapshot session={:#x} generation={} layers={} bytes={} manifest_bytes={} check={}",
        snapshot.session(),
        snapshot.generation(),
        layers.join(","),
        bytes,
        snapshot.manifest_bytes().len(),
        check
    )
}

fn watch(args: &Watch) -> Result<ExitCode, Box<dyn std::error::Error>> {
    let mut reader = open(
        &args.scene,
        seconds(args.wait_for_writer, "--wait-for-writer")?,
    )?;
    println!("attached scene={}", reader.scene());
    let mut received = 0u64;
    let mut held = Vec::new();
    loop {
        match reader.wait_next(Duration::from_secs(1)) {
            Ok(Some(snapshot)) => {
                println!("{}", describe(&snapshot));
                received += 1;
                if args.count.is_some_and(|count| received >= count) {
                    break;
                }
                if args.hold_ms > 0 {
                    held.push(snapshot);
                    let until = Instant::now() + Duration::from_millis(args.hold_ms);
                    while Instant::now() < until {
                        if reader.termination_requested() {
                            println!("terminated");
                            println!("received {received} snapshots");
                            return Ok(ExitCode::SUCCESS);
                        }
                        std::thread::sleep(Duration::from_millis(10));
                    }
                    // Keep the borrow count of a slow reader bounded: hold the newest two.
                    if held.len() > 2 {
                        held.remove(0);
                    }
                }
            }
            Ok(None) => {}
            Err(ReceiveError::WriterGone { .. }) => {
                let last = reader
                    .current()
                    .map_or("none".to_owned(), |s| s.generation().to_string());
                println!("writer gone; keeping generation={last}");
            }
            Err(ReceiveError::Terminated) => {
                println!("terminated");
                break;
            }
            Err(e @ (ReceiveError::Corrupt { .. } | ReceiveError::BorrowLimit { .. })) => {
                eprintln!("ygg-test-reader: warning: {}", error_chain(&e));
            }
            Err(e) => return Err(e.into()),
        }
    }
    println!("received {received} snapshots");
    Ok(ExitCode::SUCCESS)
}

fn dump(args: &Dump) -> Result<ExitCode, Box<dyn std::error::Error>> {
    let mut reader = open(
        &args.scene,
        seconds(args.wait_for_writer, "--wait-for-writer")?,
    )?;
    let timeout = seconds(args.timeout, "--timeout")?;
    let start = Instant::now();
    loop {
        let remaining = timeout.saturating_sub(start.elapsed());
        match reader.wait_next(remaining) {
            Ok(Some(snapshot)) => {
                println!("{}", describe(&snapshot));
                println!(
                    "manifest: {:?}",
                    String::from_utf8_lossy(
                        &snapshot.manifest_bytes()[..snapshot.manifest_bytes().len().min(64)]
                    )
                );
                for (entry, bytes) in snapshot.layers() {
                    let head: Vec<String> =
                        bytes.iter().take(16).map(|b| format!("{b:02x}")).collect();
                    println!(
                        "layer {} generation={} bytes={} head={}",
                        entry.layer_id,
                        entry.generation,
                        bytes.len(),
                        head.join("")
                    );
                }
                return Ok(ExitCode::SUCCESS);
            }
            Ok(None) => {
                eprintln!("ygg-test-reader: no complete snapshot within {timeout:?}");
                return Ok(ExitCode::from(EXIT_TIMEOUT));
            }
            Err(e @ ReceiveError::Corrupt { .. }) => {
                eprintln!("ygg-test-reader: error: {}", error_chain(&e));
                return Ok(ExitCode::from(EXIT_CORRUPT));
            }
            Err(ReceiveError::WriterGone { .. }) if start.elapsed() < timeout => {}
            Err(ReceiveError::Terminated) => return Ok(ExitCode::SUCCESS),
            Err(e) => return Err(e.into()),
        }
    }
}
