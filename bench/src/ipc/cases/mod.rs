//! The writer side: the benchmark's cases, run in this process against reader processes.
//!
//! One file per case family ([`sizes`], [`readers`], [`office`], [`baseline`] (the
//! socket against shared memory), [`qps`], [`throughput`]); the writer/reader plumbing
//! they share (publishing, collecting what readers saw, timing) is in [`drive`].

mod attach;
mod bare;
mod baseline;
mod drive;
mod office;
mod qps;
mod readers;
mod sizes;
mod throughput;

pub(crate) use drive::{ATTACH_TIMEOUT, EXIT_GRACE, Jitter, writer};

use super::child::{Scene, remove_stale};
use super::report::{self, Meta, Row, fmt_bytes};
use super::scenes;
use super::{IpcArgs, Res, check_interrupted, install_signal_handler};
use std::time::{Duration, Instant};
use ygg_dsg::DsgGraph;
use ygg_dsg::layout::Layout;
use ygg_store::{SceneGraph, SceneView};

/// Groups of cases (`--only`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    /// Segment size sweep, 1 reader.
    Sizes,
    /// Reader count 1, 2, 4, 8 with a small update.
    Readers,
    /// One agent pose vs the whole office.
    Office,
    /// The same ~40 MB graph through shared memory and through a Unix socket.
    Socket,
    /// Reader queries per second while the writer publishes.
    Qps,
    /// Writer updates per second with no reader, 4 idle and 4 busy readers.
    Throughput,
}

const ALL_GROUPS: [Group; 6] = [
    Group::Sizes,
    Group::Readers,
    Group::Office,
    Group::Socket,
    Group::Qps,
    Group::Throughput,
];

/// Size of the socket-vs-shared-memory graph.
const BIG_BYTES: usize = 40_000_000;

/// Sample counts and durations.
struct Plan {
    quick: bool,
    /// (label, bytes, samples)
    sizes: Vec<(&'static str, usize, usize)>,
    small_samples: usize,
    office_samples: usize,
    full_samples: usize,
    attach_samples: usize,
    shm40_samples: usize,
    socket_samples: usize,
    qps_secs: f64,
    throughput_secs: f64,
    throughput_reps: usize,
    /// Pause between publishes (at least; twice the last publish's duration for big ones),
    /// so that readers are back to waiting and every publish is seen.
    gap: Duration,
}

impl Plan {
    fn new(quick: bool) -> Plan {
        if quick {
            Plan {
                quick,
                sizes: vec![
                    ("1KB", 1_000, 100),
                    ("10KB", 10_000, 100),
                    ("100KB", 100_000, 100),
                    ("1MB", 1_000_000, 60),
                    ("10MB", 10_000_000, 20),
                    ("40MB", 40_000_000, 10),
                ],
                small_samples: 150,
                office_samples: 150,
                full_samples: 20,
                attach_samples: 5,
                shm40_samples: 8,
                socket_samples: 6,
                qps_secs: 1.5,
                throughput_secs: 1.0,
                throughput_reps: 2,
                gap: Duration::from_millis(3),
            }
        } else {
            Plan {
                quick,
                sizes: vec![
                    ("1KB", 1_000, 500),
                    ("10KB", 10_000, 500),
                    ("100KB", 100_000, 400),
                    ("1MB", 1_000_000, 200),
                    ("10MB", 10_000_000, 60),
                    ("40MB", 40_000_000, 30),
                    ("100MB", 100_000_000, 15),
                    ("200MB", 200_000_000, 12),
                ],
                small_samples: 600,
                office_samples: 600,
                full_samples: 60,
                attach_samples: 15,
                shm40_samples: 25,
                socket_samples: 15,
                qps_secs: 5.0,
                throughput_secs: 3.0,
                throughput_reps: 3,
                gap: Duration::from_millis(4),
            }
        }
    }
}

/// State shared by the cases of a run.
struct Ctx {
    plan: Plan,
    /// The built-in office (scale 1) and its mint layout, built on first use.
    office: Option<(DsgGraph, SceneGraph)>,
    /// The office split into 103 rooms, mint layout, built on first use.
    office103: Option<SceneGraph>,
    /// The ~40 MB graph (the office in chocolate layout at a larger scale), built on first use.
    big: Option<(SceneGraph, f64)>,
    leftovers: Vec<String>,
}

impl Ctx {
    /// The built-in office and its mint layout.
    fn office(&mut self) -> Res<&(DsgGraph, SceneGraph)> {
        if self.office.is_none() {
            let t = Instant::now();
            let dsg = scenes::office_dsg(1.0);
            let mint = scenes::office(&dsg, Layout::Mint)?;
            eprintln!(
                "office: {} nodes, {} layers, {} archived (mint), built in {:.1?}",
                mint.node_count(),
                mint.layers().count(),
                fmt_bytes(scenes::archived_bytes(&mint) as f64),
                t.elapsed()
            );
            self.office = Some((dsg, mint));
        }
        Ok(self.office.as_ref().expect("just built"))
    }

    /// A copy of the office in mint layout.
    fn office_mint(&mut self) -> Res<SceneGraph> {
        Ok(self.office()?.1.clone())
    }

    /// A copy of the office split into [`scenes::MANY_ROOMS`] rooms, in mint layout.
    fn office_many_rooms(&mut self) -> Res<SceneGraph> {
        if self.office103.is_none() {
            let t = Instant::now();
            let dsg = ygg_dsg::office::split_rooms(&self.office()?.0, scenes::MANY_ROOMS)?;
            let mint = scenes::office(&dsg, Layout::Mint)?;
            eprintln!(
                "office with {} rooms: {} nodes, {} layers, {} archived (mint), built in {:.1?}",
                scenes::MANY_ROOMS,
                mint.node_count(),
                mint.layers().count(),
                fmt_bytes(scenes::archived_bytes(&mint) as f64),
                t.elapsed()
            );
            self.office103 = Some(mint);
        }
        Ok(self.office103.clone().expect("just built"))
    }
}

/// Runs the benchmark and writes its reports.
pub fn run(args: &IpcArgs) -> Res<()> {
    install_signal_handler();
    let _ = ygg_transport::limits::raise_open_file_limit();
    let stale = remove_stale();
    if stale > 0 {
        eprintln!("removed {stale} files left by earlier, killed runs");
    }
    let started = Instant::now();
    let machine = crate::ladder::report::machine();
    let mut plan = Plan::new(args.quick);
    if let Some(ms) = args.gap_ms {
        if !(ms.is_finite() && ms >= 0.0) {
            return Err("--gap-ms must be a non-negative number".into());
        }
        plan.gap = Duration::from_secs_f64(ms / 1e3);
    }
    let rounds = args.rounds.unwrap_or(if args.quick { 1 } else { 3 }).max(1);
    let groups: Vec<Group> = if args.only.is_empty() {
        ALL_GROUPS.to_vec()
    } else {
        args.only.clone()
    };
    let mut ctx = Ctx {
        plan,
        office: None,
        office103: None,
        big: None,
        leftovers: Vec::new(),
    };
    let mut all = Vec::new();
    for round in 0..rounds {
        if rounds > 1 {
            eprintln!("round {} of {rounds}", round + 1);
        }
        all.push(run_round(&mut ctx, &groups)?);
    }
    let rows = report::aggregate(&all);
    let targets = report::targets(&rows);
    let meta = Meta {
        machine: machine.clone(),
        machine_end: crate::ladder::report::machine(),
        quick: args.quick,
        rounds,
        duration_s: started.elapsed().as_secs_f64(),
        leftovers: ctx.leftovers.clone(),
        notes: method_notes(&ctx, &machine),
        hand_written: args
            .out_dir
            .as_ref()
            .and_then(|dir| std::fs::read_to_string(dir.join("ipc.md")).ok())
            .and_then(|md| report::hand_written(&md)),
        command: std::iter::once("ygg-bench".to_owned())
            .chain(std::env::args().skip(1))
            .collect::<Vec<_>>()
            .join(" "),
    };
    let json = serde_json::to_string_pretty(&report::to_json(&meta, &rows, &targets))?;
    let md = report::to_markdown(&meta, &rows, &targets);
    if let Some(path) = &args.json {
        std::fs::write(path, &json).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(dir) = &args.out_dir {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        for (name, text) in [("ipc.md", &md), ("ipc.json", &json)] {
            let path = dir.join(name);
            std::fs::write(&path, text)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        eprintln!("wrote {}/ipc.md and ipc.json", dir.display());
    }
    println!("{md}");
    Ok(())
}

fn run_round(ctx: &mut Ctx, groups: &[Group]) -> Res<Vec<Row>> {
    let mut rows = Vec::new();
    let mut add = |row: Row| {
        eprintln!(
            "  {:<34} p50 {:>10}  p99 {:>10}{}  ({} samples)",
            row.case,
            report::fmt_us(row.median_us),
            report::fmt_us(row.p99_us),
            row.value
                .map(|v| format!("  {v:.0} {}", row.unit.unwrap_or("")))
                .unwrap_or_default(),
            row.samples
        );
        rows.push(row);
    };
    for group in ALL_GROUPS.iter().filter(|g| groups.contains(g)) {
        check_interrupted()?;
        match group {
            Group::Sizes => {
                let sizes = ctx.plan.sizes.clone();
                for (label, bytes, samples) in sizes {
                    add(sizes::case_size(ctx, label, bytes, samples)?);
                }
            }
            Group::Readers => {
                for n in [1, 2, 4, 8] {
                    add(readers::case_readers(ctx, n)?);
                }
            }
            Group::Office => {
                for row in office::case_office(ctx)? {
                    add(row);
                }
            }
            Group::Socket => {
                for row in baseline::case_socket(ctx)? {
                    add(row);
                }
            }
            Group::Qps => {
                for row in qps::case_qps(ctx)? {
                    add(row);
                }
            }
            Group::Throughput => {
                for row in throughput::case_throughput(ctx)? {
                    add(row);
                }
            }
        }
    }
    Ok(rows)
}

/// Runs `f` in a fresh scene; afterwards (every process of the scene has exited) records
/// files the scene left behind and removes them.
fn in_scene<T>(ctx: &mut Ctx, tag: &str, f: impl FnOnce(&mut Ctx, &Scene) -> Res<T>) -> Res<T> {
    let scene = Scene::new(&format!("ipcb-{tag}"));
    let result = f(ctx, &scene);
    if let Some(left) = scene.clean_up()
        && result.is_ok()
    {
        ctx.leftovers.push(left);
    }
    result
}

/// How the cases were measured; the numbers in them are the run's own (cores, layer
/// sizes, graph scale).
fn method_notes(ctx: &Ctx, machine: &serde_json::Value) -> Vec<String> {
    let cores = machine["cores"]
        .as_u64()
        .map_or("the".to_owned(), |c| c.to_string());
    let query_layer = ctx
        .office
        .as_ref()
        .and_then(|(_, g)| Some(g.layer_len(g.layer_by_name(drive::QUERY_LAYER)?)))
        .map_or(String::new(), |n| format!(", {n} nodes"));
    let mut notes = vec![
        "Readers are separate processes: this executable re-executed as `ygg-bench ipc reader`; each case uses a fresh scene name and iceoryx2 prefix (pid-based) and checks that nothing is left in /dev/shm afterwards.".to_owned(),
        format!("Publish-to-visible: Unix ns taken in the writer just before `SceneWriter::publish()` (so archiving the changed layers counts), to Unix ns taken in the reader once `SceneReader::wait_next` returned the validated snapshot and its view was built (same host clock). The readers block on the iceoryx2 event (no polling). For the office cases the time runs to the first nearest-node query (layer {}{query_layer}) answered on the new snapshot.", drive::QUERY_LAYER),
        "The writer pauses between publishes (a few ms, ±25 % jitter, at least twice the last publish call) so readers are back to waiting; readers keep their timings in memory and report them after the case, so no pipe traffic disturbs the measurement. A publish a slow reader skipped (it found a newer one when it woke) is timed to that newer snapshot, which is when the change became visible to it; `skipped_by_slow_reader` counts those.".to_owned(),
        format!("`readers_N`: per publish, the time until the slowest of the N readers holds the snapshot; N readers share {cores} cores with the writer."),
        "Socket baseline: the same graph copied into a plain owned struct (layers → nodes with points, labels, features, edges; the shape of a Spark-DSG consumer's copy), serialized with serde + postcard (compact binary, bincode-like), written to a Unix stream socket with a length prefix; the reader process reads the frame and deserializes it into the owned struct. Latency: serialize start → deserialized. No spatial index is rebuilt on the socket side, which favours the baseline.".to_owned(),
        "`shm_40MB` republishes every layer (one node added to or removed from each) so the whole graph is re-archived into shared memory on every sample.".to_owned(),
        format!("Writer throughput: an agent pose moved and published back to back for a fixed time; runs with no reader, 4 idle readers (attached, not reading) and 4 busy readers alternate (ABC CBA ...) to cancel drift. With 4 busy readers the writer shares {cores} cores with them (and with other load on the host), so updates per wall-clock second fall whatever the transport does; updates per second of the writer thread's own CPU time show whether readers make an update more expensive."),
        "Rows of several rounds give the median over rounds of each round's median and p99; p99 of a small sample is its maximum.".to_owned(),
    ];
    if let Some((g, scale)) = &ctx.big {
        notes.push(format!(
            "The 40 MB graph: the built-in office at scale {scale} in chocolate layout ({} nodes, {} archived).",
            g.node_count(),
            fmt_bytes(scenes::archived_bytes(g) as f64)
        ));
    }
    if ctx.plan.quick {
        notes.push("Quick mode: fewer samples, segments up to 40 MB.".to_owned());
    }
    notes
}
