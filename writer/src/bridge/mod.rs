//! `ygg-writer bridge-zmq`: a live bridge from Spark-DSG's ZeroMQ stream (spark_dsg's
//! `DsgSender`, Hydra's C++ `ZmqSender`) into per-layer shared-memory updates.
//!
//! Spark-DSG publishes the whole graph in every message: one frame, the header-less
//! binary body of `to_binary()`. The bridge subscribes, decodes each message once,
//! builds it in the chosen layout, brings its live graph to equal it with
//! [`ygg_store::SceneGraph::sync_to_owned`] (only the differences become mutations; an
//! index that changes much takes over the built graph's tree instead of being patched
//! point by point) and publishes: only the layers that changed are resent to readers.
//!
//! Most of each message is what the last one held, so [`follow`] does not redo it: a
//! message equal to the last byte for byte is dropped, an unchanged mesh section is
//! compared rather than decoded, when only some node records changed only those are
//! decoded ([`ygg_dsg::BodyStream`]), and a message in which nodes
//! only moved becomes those nodes' mutations without building the layout ([`patch`]);
//! anything else takes the general path above. Each `update` line names the `path` taken.
//!
//! Like a `CONFLATE` subscriber it works on the newest frame: before decoding, it takes
//! every further message already received and keeps only the last (the skipped ones
//! are counted). A frame that does not decode is logged and skipped; readers keep the
//! last good graph.
//!
//! ZeroMQ comes from the pure-Rust `zeromq` crate 0.7 (ZMTP 3 over TCP, interoperating
//! with libzmq's PUB sockets; tested against pyzmq's), only its tokio runtime and TCP
//! transport, driven by a current-thread runtime. Why not `zmq` 0.10: it binds libzmq,
//! which a fresh machine (Rust, cargo, Python, gcc) lacks, so `cargo test --workspace`
//! would need a system package first. `zeromq` has no `CONFLATE` option; draining the
//! messages already received and keeping the newest gives the same behaviour for a
//! full-state stream (the skipped ones are counted in the `update` line's `skipped`).
//!
//! The scene is created (and readers can attach) when the first good graph arrives.

mod follow;
mod patch;

use std::time::{Duration, Instant};

use ygg_dsg::layout::Layout;
use ygg_writer::SceneWriter;
use zeromq::{Socket, SocketOptions, SocketRecv, SubSocket};

use self::follow::Follower;

/// How often the loop wakes without a message, to see signals and `--seconds` (SIGINT and
/// SIGTERM take effect within this time; each wake-up costs an idle bridge CPU).
const TICK: Duration = Duration::from_millis(500);

/// Arguments of `ygg-writer bridge-zmq`.
#[derive(clap::Parser, Debug)]
pub struct BridgeArgs {
    /// ZeroMQ endpoint of the Spark-DSG publisher, e.g. tcp://127.0.0.1:8001 (the URL
    /// given to spark_dsg's DsgSender or Hydra's ZmqSender, with the host to reach).
    #[arg(long)]
    connect: String,
    /// Scene name to publish under (ASCII letters, digits, '-', '_', '.').
    #[arg(long)]
    scene: String,
    /// Layout to build each received graph in (vanilla, chocolate, mint, saffron).
    #[arg(long, default_value = "mint")]
    layout: Layout,
    /// Seconds to wait for the publisher to accept the connection.
    #[arg(long, default_value_t = 30.0)]
    connect_timeout: f64,
    /// Stop after this many seconds; default: run until signalled.
    #[arg(long)]
    seconds: Option<f64>,
    /// Largest read from the socket, in bytes. The `zeromq` crate zero-fills the whole
    /// span before each read (however little arrives) and reserves a message's length
    /// plus one span, so a large span costs a memset per read and, once the buffer
    /// passes glibc's 32 MiB mmap threshold, fresh pages for every message; a small one
    /// costs more reads. Measured on the 31 MB office (one-object edits, bridge CPU):
    /// 8 MiB 634 ms, 1 MiB 434 ms, 256 KiB 287 ms, 128 KiB 279 ms per 10 s.
    #[arg(long, default_value_t = 256 << 10)]
    read_max_bytes: usize,
    /// Readers the scene supports at once.
    #[arg(long, default_value_t = ygg_transport::service::DEFAULT_MAX_READERS)]
    max_readers: usize,
    /// Most layers the bridged scene may grow to (a Hydra scene grows room by room and
    /// per-room layouts add layers per room); a lower bound makes readers attach faster.
    #[arg(long, default_value_t = ygg_transport::service::DEFAULT_MAX_SEGMENTS)]
    max_layers: usize,
}

/// Runs the bridge until a signal, `--seconds`, or a fatal error.
pub fn run(args: &BridgeArgs) -> Result<(), Box<dyn std::error::Error>> {
    if !(args.connect_timeout.is_finite() && args.connect_timeout > 0.0) {
        return Err("--connect-timeout must be a positive number of seconds".into());
    }
    if args.seconds.is_some_and(|s| !(s.is_finite() && s > 0.0)) {
        return Err("--seconds must be a positive number".into());
    }
    // Check the scene name before connecting (creating the writer checks it again).
    ygg_transport::service::SceneServices::new(&args.scene)?;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let mut options = SocketOptions::default();
    options
        .connect_timeout(Duration::from_secs_f64(args.connect_timeout))
        .read_buffer(64 * 1024, args.read_max_bytes.max(64 * 1024), 2);
    let mut socket = SubSocket::with_options(options);
    rt.block_on(async {
        socket.connect(&args.connect).await?;
        socket.subscribe("").await
    })
    .map_err(|e| format!("cannot subscribe to {}: {e}", args.connect))?;
    println!(
        "{}",
        serde_json::json!({"event": "connected", "endpoint": args.connect})
    );

    let start = Instant::now();
    let mut writer: Option<SceneWriter> = None;
    let mut follower = Follower::new(args.layout);
    let (mut received, mut skipped, mut bad, mut published) = (0u64, 0u64, 0u64, 0u64);
    let stop = loop {
        if let Some(w) = &writer
            && let Err(e) = w.publisher().wait(Duration::ZERO)
        {
            break e.to_string();
        }
        if args
            .seconds
            .is_some_and(|s| start.elapsed().as_secs_f64() >= s)
        {
            break "time limit".to_owned();
        }
        // The next message, then every one already here (keep the newest).
        let next = rt.block_on(async {
            let first = match tokio::time::timeout(TICK, socket.recv()).await {
                Err(_) => return Ok(None),
                Ok(m) => m?,
            };
            let mut newest = first;
            let mut stale = 0u64;
            while let Ok(m) = tokio::time::timeout(Duration::ZERO, socket.recv()).await {
                newest = m?;
                stale += 1;
            }
            Ok::<_, zeromq::ZmqError>(Some((newest, stale)))
        });
        let (message, stale) = match next {
            Ok(Some(m)) => m,
            Ok(None) => continue,
            Err(e) => {
                // The publisher went away; the socket reconnects by itself.
                eprintln!("ygg-writer: bridge: receive: {e}");
                std::thread::sleep(TICK);
                continue;
            }
        };
        let t0 = Instant::now();
        received += 1 + stale;
        skipped += stale;
        let bytes: usize = message.iter().map(|f| f.len()).sum();
        let frames = message.into_vec();
        let bad_frame = |e: &dyn std::fmt::Display| {
            eprintln!("ygg-writer: bridge: skipped a bad frame ({bytes} bytes): {e}");
            println!(
                "{}",
                serde_json::json!({"event": "bad-frame", "bytes": bytes, "error": e.to_string()})
            );
        };
        let Some(w) = writer.as_mut() else {
            let target = match follower.first(frames) {
                Ok(Some(g)) => g,
                Ok(None) => continue,
                Err(e) => {
                    bad += 1;
                    bad_frame(&e);
                    continue;
                }
            };
            let t1 = Instant::now();
            let nodes = target.node_count();
            let layers = ygg_store::SceneView::layers(&target).count();
            let mut w = SceneWriter::builder(&args.scene)
                .max_readers(args.max_readers)
                .max_layers(args.max_layers)
                .create(target)?;
            let r = w.publish()?;
            published += 1;
            println!(
                "{}",
                serde_json::json!({"event": "ready", "scene": args.scene,
                    "session": w.publisher().session(), "generation": r.generation,
                    "nodes": nodes, "layers": layers, "bytes": bytes,
                    "decode_us": (t1 - t0).as_secs_f64() * 1e6,
                    "publish_us": t1.elapsed().as_secs_f64() * 1e6})
            );
            writer = Some(w);
            continue;
        };
        let applied = match follower.apply(frames, w.graph_mut()) {
            Ok(a) => a,
            Err(e) => {
                bad += 1;
                bad_frame(&e);
                continue;
            }
        };
        let t2 = Instant::now();
        let report = &applied.report;
        let generation = if report.is_empty() {
            w.generation()
        } else {
            published += 1;
            w.publish()?.generation
        };
        println!(
            "{}",
            serde_json::json!({"event": "update", "generation": generation, "bytes": bytes,
                "skipped": stale, "path": applied.path.name(), "mesh_reused": applied.mesh_reused,
                "changed_layers": report.changed_layers,
                "nodes_added": report.nodes_added, "nodes_removed": report.nodes_removed,
                "nodes_moved": report.nodes_moved, "nodes_changed": report.nodes_changed,
                "decode_us": applied.decode.as_secs_f64() * 1e6,
                "sync_us": applied.sync.as_secs_f64() * 1e6,
                "publish_us": t2.elapsed().as_secs_f64() * 1e6,
                "total_us": t0.elapsed().as_secs_f64() * 1e6})
        );
    };
    drop(writer);
    println!(
        "{}",
        serde_json::json!({"event": "summary", "stop": stop, "received": received,
            "skipped_stale": skipped, "bad_frames": bad, "published": published,
            "seconds": start.elapsed().as_secs_f64()})
    );
    Ok(())
}
