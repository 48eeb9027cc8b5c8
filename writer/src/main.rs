//! `ygg-writer`: command-line front end of the writer.
//!
//! `serve-test` is a temporary driver that publishes synthetic segments; the real `serve`
//! (publishing a scene graph) replaces it once the store lands.

mod import;

use std::process::ExitCode;
use std::time::Duration;

use clap::{Parser, Subcommand};
use ygg_reader::protocol::ManifestEntry;
use ygg_reader::test_pattern;
use ygg_writer::{SegmentPublisher, WriterBuilder};

#[derive(Parser, Debug)]
#[command(
    name = "ygg-writer",
    version,
    about = "Publishes a Yggdrasil scene through iceoryx2 shared memory"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Publish synthetic layer segments (a test driver for the transport).
    ///
    /// Publishes every layer once, then on each tick changes one layer (round robin) and
    /// publishes a new manifest. Exits cleanly, removing its shared memory, on SIGINT/SIGTERM.
    ServeTest(ServeTest),
    /// Import a Spark-DSG JSON file (.json or .json.gz) into a `.ygg` snapshot in one of
    /// the paper's layouts, with a progress bar.
    Import(import::ImportArgs),
}

#[derive(Parser, Debug)]
struct ServeTest {
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
    #[arg(long, default_value_t = ygg_reader::protocol::DEFAULT_MAX_READERS)]
    max_readers: usize,
    /// Print only errors and the final line.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    // iceoryx2 logs warnings (for example "no config file") on stderr; keep them for
    // IOX2_LOG_LEVEL=warn and show errors only by default.
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let cli = Cli::parse();
    // Each layer costs about six descriptors; do not stop at a soft limit of 1024.
    let _ = ygg_reader::limits::raise_open_file_limit();
    let result = match cli.command {
        Command::ServeTest(args) => serve_test(&args),
        Command::Import(args) => import::run(&args).map_err(Into::into),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ygg-writer: error: {}", error_chain(e.as_ref()));
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

fn serve_test(args: &ServeTest) -> Result<(), Box<dyn std::error::Error>> {
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
    let mut writer = WriterBuilder::new(&args.scene)
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
                for layer in 0..args.layers {
                    publish_test_layer(&mut writer, layer, generation, args.bytes)?;
                }
            } else {
                let layer = u32::try_from(generation % u64::from(args.layers))?;
                publish_test_layer(&mut writer, layer, generation, args.bytes)?;
            }
            let entries: Vec<ManifestEntry> = (0..args.layers)
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
    layer: u32,
    generation: u64,
    bytes: usize,
) -> Result<(), ygg_writer::PublishError> {
    writer.publish_layer(layer, generation, bytes, |buf| {
        test_pattern::write(buf, layer, generation);
    })
}
