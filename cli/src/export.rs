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
//!
//! `ygg export ros2` ([`ros2`]) publishes a live scene to ROS 2 instead, as Hydra's
//! `DsgUpdate` messages.

mod ros2;

use std::path::PathBuf;

use clap::Parser;
use ygg_store::{NodeId, SceneGraph, SceneView};

use crate::query::{live_snapshot, seconds};

/// Arguments of `ygg export`.
#[derive(Parser, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct ExportArgs {
    /// Publish the scene elsewhere instead of writing a file.
    #[command(subcommand)]
    to: Option<ExportTo>,
    /// The live scene to export.
    #[arg(long, required = true)]
    scene: Option<String>,
    /// The `.ygg` file to write (replaced crash-safely when it exists).
    #[arg(short, long, required = true)]
    output: Option<PathBuf>,
    /// Seconds to wait for the scene's writer and first snapshot.
    #[arg(long, default_value_t = 5.0)]
    timeout: f64,
}

/// Where else `ygg export` publishes a scene.
#[derive(clap::Subcommand, Debug)]
pub enum ExportTo {
    /// Publish a live scene on a ROS 2 topic as hydra_msgs/msg/DsgUpdate (full updates
    /// every --full-every seconds, incremental ones between), with hydra_ros's QoS,
    /// without ROS installed. Prints `{"event":"advertised",...}`, one
    /// `{"event":"sent",...}` line per message and a final `{"event":"summary",...}`.
    Ros2(ros2::Ros2ExportArgs),
}

/// Runs `ygg export`.
///
/// # Errors
/// A message naming the scene (no writer or snapshot in time) or the file that could not
/// be written; for `ygg export ros2`, what [`ros2::run`] reports.
pub fn run(args: &ExportArgs) -> Result<(), Box<dyn std::error::Error>> {
    match &args.to {
        Some(ExportTo::Ros2(ros2)) => ros2::run(ros2),
        None => to_file(args).map_err(Into::into),
    }
}

/// `ygg export --scene S --output F`.
fn to_file(args: &ExportArgs) -> Result<(), String> {
    let (Some(scene), Some(output)) = (&args.scene, &args.output) else {
        return Err("--scene and --output are required".to_owned());
    };
    let snapshot = live_snapshot(scene, seconds(args.timeout, "--timeout")?)?;
    let view = snapshot.view();
    let graph = to_owned_graph(&view);
    graph.save(output).map_err(|e| e.to_string())?;
    println!(
        "exported scene {} generation {}: {} nodes, {} layers -> {}",
        scene,
        snapshot.generation(),
        graph.node_count(),
        graph.layers().count(),
        output.display()
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
