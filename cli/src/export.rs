//! `ygg export`: writes the current snapshot of a live scene to a `.ygg` file, which
//! `ygg inspect`, `ygg query`, `ygg serve --file` and every binding open.
//!
//! A `.ygg` file is the one format a scene leaves Yggdrasil in: `ygg import` reads
//! Spark-DSG files into it, but the way back to Spark-DSG JSON does not exist yet
//! (`ygg_dsg` writes JSON from its own graph model only, and a built layout does not
//! convert back to it).
//!
//! Prints one line on success: `exported scene <name> generation <n>: <nodes> nodes,
//! <layers> layers -> <file>`.

use std::path::PathBuf;

use clap::Parser;
use ygg_store::{NodeId, SceneGraph, SceneView};

use crate::query::{live_snapshot, seconds};

/// Arguments of `ygg export`.
#[derive(Parser, Debug)]
pub struct ExportArgs {
    /// The live scene to export.
    #[arg(long)]
    scene: String,
    /// The `.ygg` file to write (replaced crash-safely when it exists).
    #[arg(short, long)]
    output: PathBuf,
    /// Seconds to wait for the scene's writer and first snapshot.
    #[arg(long, default_value_t = 5.0)]
    timeout: f64,
}

/// Runs `ygg export`.
///
/// # Errors
/// A message naming the scene (no writer or snapshot in time) or the file that could not
/// be written.
pub fn run(args: &ExportArgs) -> Result<(), String> {
    let snapshot = live_snapshot(&args.scene, seconds(args.timeout, "--timeout")?)?;
    let view = snapshot.view();
    let graph = to_owned_graph(&view);
    graph.save(&args.output).map_err(|e| e.to_string())?;
    println!(
        "exported scene {} generation {}: {} nodes, {} layers -> {}",
        args.scene,
        snapshot.generation(),
        graph.node_count(),
        graph.layers().count(),
        args.output.display()
    );
    Ok(())
}

/// An owned copy of every layer, node, edge and point of `view`.
pub fn to_owned_graph<V: SceneView>(view: &V) -> SceneGraph {
    let all: Vec<NodeId> = view
        .layers()
        .flat_map(|l| {
            view.layer_nodes(l)
                .map(|n| view.node_id(n))
                .collect::<Vec<_>>()
        })
        .collect();
    ygg_store::query::subgraph(view, &all)
}
