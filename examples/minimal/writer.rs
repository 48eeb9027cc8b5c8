//! A minimal mapping-stack writer: owns a scene graph, adds an agent pose every 100 ms
//! and publishes the changed layer, until SIGINT or SIGTERM.
//!
//! Run: `cargo run --release -p ygg-examples --example minimal_writer [scene]`
//! (scene `example` by default).

use std::time::Duration;
use ygg_store::{FeatureValue, NodeId, SceneGraph};
use ygg_writer::{SceneWriter, WriterWaitError};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "example".to_owned());
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("ROOMS")?;
    let objects = g.add_layer("OBJECTS")?;
    let agents = g.add_layer("AGENTS")?;
    g.add_layer_edge(rooms, objects)?;
    g.add_node(NodeId(1), rooms)?;
    g.enable_bounding_box(NodeId(1))?; // kept exact as objects move
    for (i, label) in ["chair", "desk", "light"].iter().enumerate() {
        let id = NodeId(100 + i as u64);
        g.add_node(id, objects)?;
        g.set_geometry(id, vec![[i as f32, 1.0, 0.5], [i as f32 + 0.4, 1.2, 0.9]])?;
        g.add_label(id, label)?;
        g.nest(NodeId(1), id)?;
    }
    g.enable_layer_index(objects)?; // readers query the writer's kd-tree zero-copy

    let mut writer = SceneWriter::builder(&scene).max_readers(8).create(g)?;
    writer.publish()?;
    println!("serving scene={scene}; Ctrl-C to stop");
    for tick in 0u64.. {
        let pose = NodeId(10_000 + tick);
        let graph = writer.graph_mut();
        graph.add_node(pose, agents)?;
        graph.set_geometry(pose, vec![[tick as f32 * 0.01, 0.0, 1.0]])?;
        graph.set_feature(pose, "tick", FeatureValue::Int(tick as i64))?;
        let report = writer.publish()?; // only AGENTS changed: one layer is sent
        if tick % 50 == 0 {
            println!(
                "generation={} bytes_sent={}",
                report.generation, report.bytes_sent
            );
        }
        match writer.publisher().wait(Duration::from_millis(100)) {
            Ok(()) => {}
            Err(WriterWaitError::Interrupt | WriterWaitError::TerminationRequest) => break,
        }
    }
    println!("stopped at generation={}", writer.generation());
    Ok(()) // dropping the writer removes its shared memory
}
