//! `ygg-writer`: command-line front end of the writer.
//!
//! `serve` publishes a scene graph (a `.ygg` file or the built-in office, optionally with
//! a SLAM-like update stream); `import` converts Spark-DSG JSON; `serve-test` publishes
//! synthetic segments of chosen sizes, the driver of the transport tests in `tests/`;
//! `bridge-zmq` follows a Spark-DSG ZeroMQ stream (Hydra) and publishes what changes.

mod bridge;
mod import;
mod window;

use std::process::ExitCode;
use std::time::Duration;

use clap::{Parser, Subcommand};
use ygg_transport::protocol::ManifestEntry;
use ygg_transport::test_pattern;
use ygg_transport::{PublisherBuilder, SegmentPublisher};

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
    /// Serve a scene (a `.ygg` file or the built-in office) under a scene name, and
    /// optionally replay a SLAM-like stream of updates at a given rate.
    ///
    /// Prints a `{"event":"ready",...}` line naming the writer session once the scene is
    /// published, one JSON line per second (`{"event":"progress",...}`) and a final
    /// `{"event":"summary",...}` line. Exits cleanly, removing its shared memory, on
    /// SIGINT/SIGTERM or after --seconds.
    Serve(Serve),
    /// Import a Spark-DSG JSON file (.json or .json.gz) into a `.ygg` snapshot in one of
    /// the paper's layouts, with a progress bar.
    Import(import::ImportArgs),
    /// Bridge a Spark-DSG ZeroMQ stream (spark_dsg's DsgSender, Hydra's ZmqSender) into
    /// a scene: decode each message, apply only its differences, publish only the
    /// changed layers.
    ///
    /// Prints `{"event":"connected"}` once subscribed, `{"event":"ready",...}` after the
    /// first graph is published, one `{"event":"update",...}` line per message (the
    /// layers it changed) or `{"event":"bad-frame",...}` for one that does not decode
    /// (it is skipped; readers keep the last good graph), and a final
    /// `{"event":"summary",...}`. Exits cleanly, removing its shared memory, on
    /// SIGINT/SIGTERM or after --seconds.
    BridgeZmq(bridge::BridgeArgs),
}

#[derive(Parser, Debug)]
struct Serve {
    /// Scene name (ASCII letters, digits, '-', '_', '.').
    #[arg(long)]
    scene: String,
    /// A `.ygg` snapshot to serve; default: the built-in office.
    #[arg(long)]
    file: Option<std::path::PathBuf>,
    /// Scale of the built-in office.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// Layout of the built-in office (vanilla, chocolate, mint, saffron).
    #[arg(long, default_value = "mint")]
    layout: ygg_dsg::layout::Layout,
    /// Split the built-in office into this many rooms (at least as many as it has, 9 at
    /// scale 1; 103 gives the 418-layer building of `ygg-bench ipc`): a scene with many
    /// layers.
    #[arg(long, conflicts_with = "file")]
    rooms: Option<usize>,
    /// Update ticks per second (agent poses, object moves, mesh growth); 0 serves the
    /// scene unchanged.
    #[arg(long, default_value_t = 30.0)]
    rate: f64,
    /// Stop after this many seconds; default: run until signalled.
    #[arg(long)]
    seconds: Option<f64>,
    /// How much of what the stream adds to keep (a sliding window; default: all).
    #[command(flatten)]
    keep: window::Keep,
    /// Readers the scene supports at once.
    #[arg(long, default_value_t = ygg_transport::service::DEFAULT_MAX_READERS)]
    max_readers: usize,
    /// Most layers the scene may grow to (default: a quarter more than the served graph's,
    /// at least 64 more);
    /// a lower bound makes readers attach faster.
    #[arg(long)]
    max_layers: Option<usize>,
    /// Points per chunk of a layer published in chunks (a power of two; layers of more
    /// points send their point column in chunks, each resent only when it changes).
    #[arg(long, default_value_t = ygg_store::snapshot::POINT_CHUNK_LEN as u64,
          value_parser = clap::value_parser!(u64).range(1..=65536))]
    point_chunk_len: u64,
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
    #[arg(long, default_value_t = ygg_transport::service::DEFAULT_MAX_READERS)]
    max_readers: usize,
    /// Print only errors and the final line.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    ygg_transport::init_iceoryx_logging();
    let cli = Cli::parse();
    // A process may attach to many scenes (about 40 descriptors each); do not stop at a soft limit of 1024.
    let _ = ygg_transport::limits::raise_open_file_limit();
    let result = match cli.command {
        Command::ServeTest(args) => serve_test(&args),
        Command::Serve(args) => serve(&args),
        Command::Import(args) => import::run(&args).map_err(Into::into),
        Command::BridgeZmq(args) => bridge::run(&args),
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

fn serve(args: &Serve) -> Result<(), Box<dyn std::error::Error>> {
    use std::time::Instant;
    use ygg_dsg::replay::SlamReplay;
    use ygg_store::{SceneView, SnapshotFile};
    use ygg_writer::SceneWriter;
    if !(args.rate.is_finite() && args.rate >= 0.0) {
        return Err("--rate must be a non-negative number".into());
    }
    if args.seconds.is_some_and(|s| !(s.is_finite() && s > 0.0)) {
        return Err("--seconds must be a positive number".into());
    }
    let t = Instant::now();
    let graph = match &args.file {
        Some(path) => {
            let file = SnapshotFile::open(path)?;
            let view = file.view();
            let all: Vec<ygg_store::NodeId> = view
                .layers()
                .flat_map(|l| {
                    view.layer_nodes(l)
                        .map(|n| view.node_id(n))
                        .collect::<Vec<_>>()
                })
                .collect();
            ygg_store::query::subgraph(&view, &all)
        }
        None => {
            let mut dsg = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams {
                seed: 7,
                scale: args.scale,
            });
            if let Some(rooms) = args.rooms {
                dsg = ygg_dsg::office::split_rooms(&dsg, rooms)
                    .map_err(|e| format!("--rooms {rooms}: {e}"))?;
            }
            ygg_dsg::layout::build(&dsg, args.layout)?
        }
    };
    let loaded = t.elapsed();
    let builder = SceneWriter::builder(&args.scene)
        .max_readers(args.max_readers)
        .point_chunk_len(args.point_chunk_len as usize);
    let builder = match args.max_layers {
        Some(n) => builder.max_layers(n),
        None => builder,
    };
    let mut writer = builder.create(graph)?;
    let mut replay = SlamReplay::new(writer.graph(), 7);
    let first = writer.publish()?;
    println!(
        "{}",
        serde_json::json!({"event": "ready", "scene": args.scene, "session": writer.publisher().session(),
            "nodes": writer.graph().node_count(),
            "load_ms": loaded.as_secs_f64() * 1e3, "first_publish_bytes": first.bytes_sent})
    );
    let period = if args.rate > 0.0 {
        Duration::from_secs_f64(1.0 / args.rate)
    } else {
        Duration::from_millis(200)
    };
    let start = Instant::now();
    let mut next = start + period;
    let (mut ticks, mut update_ns, mut publish_ns, mut bytes) = (0u64, 0u128, 0u128, 0usize);
    let (mut layers_sent, mut chunks_sent) = (0usize, 0usize);
    let mut last_report = start;
    let mut window = window::Window::new(writer.graph(), args.keep);
    let stop_reason = loop {
        if args
            .seconds
            .is_some_and(|s| start.elapsed().as_secs_f64() >= s)
        {
            break "time limit".to_owned();
        }
        if args.rate > 0.0 {
            let t0 = Instant::now();
            let report = replay.step(writer.graph_mut())?;
            window.trim(writer.graph_mut(), &replay, report)?;
            let t1 = Instant::now();
            let r = writer.publish()?;
            update_ns += (t1 - t0).as_nanos();
            publish_ns += t1.elapsed().as_nanos();
            bytes += r.bytes_sent;
            layers_sent += r.layers_sent;
            chunks_sent += r.chunks_sent;
            ticks += 1;
        }
        if last_report.elapsed() >= Duration::from_secs(1) {
            last_report = Instant::now();
            println!(
                "{}",
                serde_json::json!({"event": "progress", "generation": writer.generation(), "ticks": ticks,
                    "nodes": writer.graph().node_count(), "seconds": start.elapsed().as_secs_f64()})
            );
        }
        let now = Instant::now();
        let wait = next.saturating_duration_since(now);
        next = next.max(now) + period;
        if let Err(e) = writer.publisher().wait(wait) {
            break e.to_string();
        }
    };
    let secs = start.elapsed().as_secs_f64();
    let per = |ns: u128| {
        if ticks == 0 {
            0.0
        } else {
            ns as f64 / ticks as f64 / 1e3
        }
    };
    println!(
        "{}",
        serde_json::json!({"event": "summary", "stop": stop_reason, "ticks": ticks, "seconds": secs,
            "updates_per_s": ticks as f64 / secs, "update_us": per(update_ns), "publish_us": per(publish_ns),
            "bytes_published": bytes, "layers_sent": layers_sent, "chunks_sent": chunks_sent,
            "generation": writer.generation(), "nodes": writer.graph().node_count(),
            "rss_mb": rss_mb()})
    );
    Ok(())
}

/// Resident memory of this process, MB (0 where /proc is unavailable).
fn rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| {
            s.split_whitespace()
                .nth(1)
                .and_then(|p| p.parse::<f64>().ok())
        })
        .map_or(0.0, |pages| pages * 4096.0 / 1e6)
}
