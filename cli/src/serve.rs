//! `ygg serve`: serves a scene (a `.ygg` file or the built-in office) under a scene
//! name, optionally replaying a SLAM-like stream of updates at a given rate.
//!
//! Prints a `{"event":"ready",...}` line naming the writer session once the scene is
//! published, one JSON line per second (`{"event":"progress",...}`) and a final
//! `{"event":"summary",...}` line. Exits cleanly, removing its shared memory, on
//! SIGINT/SIGTERM or after `--seconds`.

use std::time::{Duration, Instant};

use clap::Parser;
use ygg_dsg::replay::SlamReplay;
use ygg_dsg::replay::window::{Keep, Window};
use ygg_store::SnapshotFile;
use ygg_writer::SceneWriter;

/// Arguments of `ygg serve`.
#[derive(Parser, Debug)]
pub struct ServeArgs {
    /// Scene name (ASCII letters, digits, '-', '_', '.').
    #[arg(long)]
    scene: String,
    /// A `.ygg` snapshot to serve; default: the built-in office.
    #[arg(long, conflicts_with = "recording")]
    file: Option<std::path::PathBuf>,
    /// Replay a recording (a folder written by `ygg record`) instead: its cuts are
    /// published with their recorded timing, as a live writer would.
    #[arg(long)]
    recording: Option<std::path::PathBuf>,
    /// With --recording: playback speed (2 plays twice as fast).
    #[arg(long, default_value_t = 1.0, requires = "recording")]
    speed: f64,
    /// With --recording: where to start (see `ygg query --time`: +S after the first cut).
    #[arg(long, requires = "recording", allow_hyphen_values = true)]
    from: Option<crate::moment::TimeSpec>,
    /// With --recording: start again after the last cut, until signalled.
    #[arg(long = "loop", requires = "recording")]
    looped: bool,
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
    keep: KeepArgs,
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
    /// Rows the newest part of a layer takes before a new part starts: appending a node
    /// resends at most this many rows of its layer.
    #[arg(long, default_value_t = ygg_store::snapshot::PART_ROWS as u64,
          value_parser = clap::value_parser!(u64).range(1..=65536))]
    part_rows: u64,
}

/// The `--keep-*` options: a sliding window over what the stream adds ([`Window`]).
#[derive(Clone, Copy, Debug, Default, clap::Args)]
struct KeepArgs {
    /// Keep only this many of the agent poses the stream appends (a sliding-window
    /// trajectory: the oldest is removed as each new one arrives); default: keep all.
    #[arg(long)]
    keep_poses: Option<usize>,
    /// Keep only this many of the objects the stream adds (the oldest is removed with its
    /// mesh); default: keep all.
    #[arg(long)]
    keep_objects: Option<usize>,
    /// Keep only this many of the mesh points the stream appends to each room's unclaimed
    /// mesh node (the oldest go first); default: keep all.
    #[arg(long)]
    keep_mesh_points: Option<usize>,
}

impl From<KeepArgs> for Keep {
    fn from(a: KeepArgs) -> Self {
        Keep {
            poses: a.keep_poses,
            objects: a.keep_objects,
            mesh_points: a.keep_mesh_points,
        }
    }
}

/// Runs `ygg serve` until a signal or `--seconds`.
///
/// # Errors
/// When an option is out of range, the scene cannot be loaded or built, or publishing
/// fails.
pub fn run(args: &ServeArgs) -> Result<(), Box<dyn std::error::Error>> {
    if !(args.rate.is_finite() && args.rate >= 0.0) {
        return Err("--rate must be a non-negative number".into());
    }
    if args.seconds.is_some_and(|s| !(s.is_finite() && s > 0.0)) {
        return Err("--seconds must be a positive number".into());
    }
    if let Some(recording) = &args.recording {
        return crate::replay::run(&crate::replay::ReplayArgs {
            scene: &args.scene,
            recording,
            speed: args.speed,
            from: args.from,
            looped: args.looped,
            max_readers: args.max_readers,
            seconds: args.seconds,
        });
    }
    let t = Instant::now();
    let graph = match &args.file {
        Some(path) => {
            let file = SnapshotFile::open(path)?;
            crate::export::to_owned_graph(&file.view())
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
        .point_chunk_len(args.point_chunk_len as usize)
        .part_rows(args.part_rows as usize);
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
    let (mut parts_sent, mut chunk_bytes, mut manifest_bytes, mut segments) = (0, 0, 0, 0);
    let mut last_report = start;
    let mut window = Window::new(writer.graph(), args.keep.into());
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
            parts_sent += r.parts_sent;
            chunk_bytes += r.chunk_bytes_sent;
            manifest_bytes += r.manifest_bytes_sent;
            segments = r.segments;
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
            "parts_sent": parts_sent, "chunk_bytes": chunk_bytes, "manifest_bytes": manifest_bytes,
            "segments": segments,
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
