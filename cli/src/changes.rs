//! `ygg changes`: what changed in a recorded scene between two moments (nodes added,
//! removed, moved, relabelled; edges added and removed), as one JSON object.

use std::path::PathBuf;
use std::time::Instant;

use clap::Parser;

use crate::moment::{TimeSpec, open_recording};

/// Arguments of `ygg changes`.
#[derive(Parser, Debug)]
pub struct ChangesArgs {
    /// The recording (a folder written by `ygg record`).
    recording: PathBuf,
    /// The first moment (see `ygg query --time`); default: the first cut.
    #[arg(long, allow_hyphen_values = true)]
    from: Option<TimeSpec>,
    /// The second moment; default: the last cut.
    #[arg(long, allow_hyphen_values = true)]
    to: Option<TimeSpec>,
    /// A node moved when its position changed by more than this many meters.
    #[arg(long, default_value_t = 0.05)]
    tolerance: f32,
    /// Print only the counts, not the ids.
    #[arg(long)]
    counts: bool,
}

/// Runs `ygg changes`.
///
/// # Errors
/// A message naming the recording, a moment without a cut, or a cut that fails
/// validation.
pub fn run(args: &ChangesArgs) -> Result<(), String> {
    if !(args.tolerance.is_finite() && args.tolerance >= 0.0) {
        return Err("--tolerance must be a non-negative number of meters".into());
    }
    let recording = open_recording(&args.recording)?;
    let from = match args.from {
        Some(t) => t.cut(&recording)?,
        None => 0,
    };
    let to = match args.to {
        Some(t) => t.cut(&recording)?,
        None => recording.cuts().len() - 1,
    };
    let start = Instant::now();
    let c = recording
        .changes(from, to, args.tolerance)
        .map_err(|e| e.to_string())?;
    let elapsed_ms = start.elapsed().as_secs_f64() * 1e3;
    let ids = |v: &[ygg_store::NodeId]| v.iter().map(|n| n.0).collect::<Vec<_>>();
    let edges = |v: &[(ygg_store::NodeId, ygg_store::NodeId)]| {
        v.iter().map(|(a, b)| [a.0, b.0]).collect::<Vec<_>>()
    };
    let cut = |i: usize| {
        let s = recording.cuts()[i];
        serde_json::json!({"cut": i, "generation": s.generation, "time": s.writer_unix_ns as f64 / 1e9})
    };
    let mut out = serde_json::json!({
        "from": cut(from), "to": cut(to), "segments_compared": c.segments_compared,
        "elapsed_ms": elapsed_ms,
        "counts": {"nodes_added": c.nodes_added.len(), "nodes_removed": c.nodes_removed.len(),
            "nodes_moved": c.nodes_moved.len(), "nodes_relabelled": c.nodes_relabelled.len(),
            "edges_added": c.edges_added.len(), "edges_removed": c.edges_removed.len()},
    });
    if !args.counts {
        out["nodes_added"] = ids(&c.nodes_added).into();
        out["nodes_removed"] = ids(&c.nodes_removed).into();
        out["nodes_moved"] = c
            .nodes_moved
            .iter()
            .map(|m| serde_json::json!({"id": m.id.0, "from": m.from, "to": m.to}))
            .collect::<Vec<_>>()
            .into();
        out["nodes_relabelled"] = c
            .nodes_relabelled
            .iter()
            .map(|r| serde_json::json!({"id": r.id.0, "from": r.from, "to": r.to}))
            .collect::<Vec<_>>()
            .into();
        out["edges_added"] = edges(&c.edges_added).into();
        out["edges_removed"] = edges(&c.edges_removed).into();
    }
    println!("{out}");
    Ok(())
}
