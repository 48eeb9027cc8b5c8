//! The writer side: the benchmark's cases, run in this process against reader processes.
//!
//! One file per case family ([`sizes`], [`readers`], [`office`], [`baseline`] (the
//! socket against shared memory), [`qps`], [`throughput`]); the writer/reader plumbing
//! they share (publishing, collecting what readers saw, timing) is in [`drive`], the
//! state they share (the scenes built once, the files scenes left) in [`context`], and
//! the sample counts of a quick or full run in [`plan`].

mod attach;
mod bare;
mod baseline;
mod context;
mod drive;
mod office;
mod plan;
mod qps;
mod readers;
mod sizes;
mod throughput;

pub(crate) use attach::spawn_attacher;
pub(crate) use drive::{
    ATTACH_TIMEOUT, EXIT_GRACE, Jitter, Publish, Seen, collect_seen, observe, reader_args, writer,
};

use super::args::{ALL_GROUPS, Group, IpcArgs};
use super::child::remove_stale;
use super::error::Res;
use super::interrupt::{check_interrupted, install_signal_handler};
use super::report::{self, Meta, Row, fmt_bytes};
use super::scenes;
use context::Ctx;
use plan::Plan;
use std::time::{Duration, Instant};
use ygg_store::SceneView;

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
