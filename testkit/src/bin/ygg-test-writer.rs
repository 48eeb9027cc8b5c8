//! `ygg-test-writer`: publishes synthetic layer segments of chosen sizes
//! ([`ygg_testkit::test_pattern`]), the driver of the transport tests in `tests/`.
//!
//! Publishes every layer once, then on each tick changes one layer (round robin) and
//! publishes a new manifest. Prints `ready scene=<name> session=<hex>` once created, a
//! `published generation=<n>` line per snapshot (unless `--quiet`) and a final
//! `stopped: <why>; published <n> snapshots` line. Exits cleanly, removing its shared
//! memory, on SIGINT/SIGTERM.

use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use ygg_testkit::test_pattern;
use ygg_transport::protocol::ManifestEntry;
use ygg_transport::{PublishError, PublisherBuilder, SegmentPublisher};

#[derive(Parser, Debug)]
#[command(
    name = "ygg-test-writer",
    version,
    about = "Publishes synthetic layer segments (a test driver for the transport)"
)]
struct Args {
    /// Scene name (ASCII letters, digits, '-', '_', '.').
    #[arg(long)]
    scene: String,
    /// Number of layers.
    #[arg(long, default_value_t = 4)]
    layers: u32,
    /// Bytes per layer segment (at least 16).
    #[arg(long, default_value_t = 4096)]
    bytes: usize,
    /// Snapshots per second after the first; 0 publishes once and then idles.
    #[arg(long, default_value_t = 10.0)]
    rate: f64,
    /// Stop after this many snapshots (and exit); default: run until signalled.
    #[arg(long)]
    count: Option<u64>,
    /// Keep serving (idle) after --count snapshots instead of exiting.
    #[arg(long)]
    linger: bool,
    /// Readers the scene supports at once.
    #[arg(long, default_value_t = ygg_transport::service::DEFAULT_MAX_READERS)]
    max_readers: usize,
    /// Print only errors and the final line.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    ygg_transport::init_iceoryx_logging();
    let args = Args::parse();
    // A process may attach to many scenes (about 40 descriptors each); do not stop at a soft limit of 1024.
    let _ = ygg_transport::limits::raise_open_file_limit();
    match serve_test(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ygg-test-writer: error: {}", error_chain(e.as_ref()));
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

fn serve_test(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    if args.layers == 0 {
        return Err("--layers must be at least 1".into());
    }
    if args.bytes < test_pattern::MIN_LEN {
        return Err(format!("--bytes must be at least {}", test_pattern::MIN_LEN).into());
    }
    if !(args.rate.is_finite() && args.rate >= 0.0) {
        return Err("--rate must be a non-negative number".into());
    }
    let period = if args.rate > 0.0 {
        Duration::from_secs_f64(1.0 / args.rate)
    } else {
        Duration::from_millis(100)
    };
    let mut writer = PublisherBuilder::new(&args.scene)
        .max_readers(args.max_readers)
        .initial_segment_bytes(args.bytes)
        .create()?;
    println!(
        "ready scene={} session={:#x}",
        writer.scene(),
        writer.session()
    );

    let mut generation = 0u64;
    let mut published = 0u64;
    let stop_reason = loop {
        let due = args.count.is_none_or(|count| published < count);
        if due && (published == 0 || args.rate > 0.0) {
            generation += 1;
            if published == 0 {
                for layer in 0..u64::from(args.layers) {
                    publish_test_layer(&mut writer, layer, generation, args.bytes)?;
                }
            } else {
                let layer = generation % u64::from(args.layers);
                publish_test_layer(&mut writer, layer, generation, args.bytes)?;
            }
            let entries: Vec<ManifestEntry> = (0..u64::from(args.layers))
                .filter_map(|layer_id| {
                    writer
                        .layer_generation(layer_id)
                        .map(|generation| ManifestEntry {
                            layer_id,
                            generation,
                        })
                })
                .collect();
            let text = format!("serve-test generation {generation}");
            writer.publish_manifest(generation, &entries, text.len(), |buf| {
                buf.copy_from_slice(text.as_bytes());
            })?;
            published += 1;
            if !args.quiet {
                println!("published generation={generation}");
            }
        } else if !due && !args.linger {
            break "count reached".to_owned();
        }
        if let Err(e) = writer.wait(period) {
            break e.to_string();
        }
    };
    drop(writer);
    println!("stopped: {stop_reason}; published {published} snapshots");
    Ok(())
}

fn publish_test_layer(
    writer: &mut SegmentPublisher,
    layer: u64,
    generation: u64,
    bytes: usize,
) -> Result<(), PublishError> {
    writer.publish_layer(layer, generation, bytes, |buf| {
        test_pattern::write(buf, layer, generation);
    })
}
