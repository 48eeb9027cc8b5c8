//! `ygg-bench`: the Yggdrasil demo and benchmarks.

mod ipc;
mod ladder;

use clap::{Parser, Subcommand};
use std::time::Instant;
use ygg_store::query::{self, Direction};
use ygg_store::{NodeId, SceneGraph, SceneView, Scope, SnapshotFile};

#[derive(Parser)]
#[command(version, about = "Yggdrasil demo and benchmarks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Builds a scene, saves it as a snapshot, reopens it and queries both.
    Demo {
        /// Number of object nodes to generate.
        #[arg(long, default_value_t = 20_000)]
        objects: u64,
    },
    /// Archive size and bytes per node for feature-less graphs of 10k, 100k and 1M nodes.
    ArchiveSizes,
    /// The paper's ablation ladder on the office workload.
    Ladder(ladder::LadderArgs),
    /// Multi-process publish-to-visible latency: shared memory vs a Unix socket.
    Ipc(ipc::IpcArgs),
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    match Cli::parse().command {
        Command::Demo { objects } => demo(objects),
        Command::ArchiveSizes => archive_sizes(),
        Command::Ladder(args) => ladder::run(&args),
        Command::Ipc(args) => ipc::run(&args),
    }
}

fn demo(objects: u64) -> Result<(), Box<dyn std::error::Error>> {
    let t = Instant::now();
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms")?;
    let objs = g.add_layer("objects")?;
    g.add_layer_edge(rooms, objs)?;
    for r in 0..9u64 {
        g.add_node(NodeId(r), rooms)?;
        g.enable_bounding_box(NodeId(r))?;
    }
    let labels = ["light", "chair", "desk", "shelf", "bulletin"];
    for i in 0..objects {
        let id = NodeId(1_000 + i);
        g.add_node(id, objs)?;
        let x = (i % 97) as f32 * 0.4;
        let y = (i / 97 % 61) as f32 * 0.4;
        g.set_geometry(id, vec![[x, y, 1.0], [x + 0.1, y, 1.2]])?;
        g.add_label(id, labels[(i % labels.len() as u64) as usize])?;
        g.nest(NodeId(i % 9), id)?;
        if i > 0 {
            g.add_edge(NodeId(1_000 + i - 1), id, "next")?;
        }
    }
    println!("built {} nodes in {:.1?}", g.node_count(), t.elapsed());
    let dir = std::env::temp_dir().join(format!("ygg-demo-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("scene.ygg");
    let t = Instant::now();
    g.save(&path)?;
    let size = std::fs::metadata(&path)?.len();
    println!(
        "saved {} ({} bytes) in {:.1?}",
        path.display(),
        size,
        t.elapsed()
    );
    let t = Instant::now();
    let file = SnapshotFile::open(&path)?;
    println!("opened and validated in {:.1?}", t.elapsed());
    let view = file.view();
    for label in ["bulletin", "unicorn"] {
        let live = query::nodes_with_label(&g, Scope::Graph, label);
        let archived = query::nodes_with_label(&view, Scope::Graph, label);
        assert_eq!(live, archived);
        println!("label {label:>9}: {} nodes (live == archived)", live.len());
    }
    let room = NodeId(4);
    println!(
        "room {room}: {} nodes in sub-tree, box {:?}",
        query::subtree(&view, room).len(),
        view.node(room).and_then(|n| view.aabb(n))
    );
    let path_len = query::shortest_path(&view, NodeId(1_000), NodeId(1_010), Direction::Outgoing)
        .map(|p| p.len());
    println!("shortest path 1000 -> 1010: {path_len:?} nodes");
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

/// Prints a markdown table: archive bytes per feature-less node (one point each, nested
/// under one of 9 rooms), and the same nodes without geometry.
fn archive_sizes() -> Result<(), Box<dyn std::error::Error>> {
    println!(
        "| nodes | points per node | archive bytes | bytes per node | bytes per node minus 12 per point |"
    );
    println!("|---|---|---|---|---|");
    for n in [10_000u64, 100_000, 1_000_000] {
        for points in [0usize, 1] {
            let mut g = SceneGraph::new();
            let layer = g.add_layer("points")?;
            for i in 0..n {
                g.add_node(NodeId(i), layer)?;
                if points > 0 {
                    g.set_geometry(NodeId(i), vec![[i as f32, 0.0, 1.0]])?;
                }
            }
            let (manifest, layers) = g.to_segments();
            let bytes = manifest.len() + layers.iter().map(|l| l.len()).sum::<usize>();
            let per_node = bytes as f64 / n as f64;
            println!(
                "| {n} | {points} | {bytes} | {per_node:.1} | {:.1} |",
                per_node - 12.0 * points as f64
            );
        }
    }
    Ok(())
}
