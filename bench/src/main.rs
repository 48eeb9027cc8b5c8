//! `ygg-bench`: the Yggdrasil demo and benchmarks.

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
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    match Cli::parse().command {
        Command::Demo { objects } => demo(objects),
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
