//! The built-in office (uHumans2 counts, generated from a fixed seed) in the `mint`
//! layout, published live: at 30 Hz an agent pose is appended and one object moves,
//! and each tick publishes only the layers that changed. Runs until SIGINT or SIGTERM.
//!
//! Run: `cargo run --release -p ygg-examples --example office_writer [scene] [scale]`
//! (scene `office`, scale 1 by default).

use std::time::{Duration, Instant};
use ygg_dsg::NodeSymbol;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::objects::Objects;
use ygg_dsg::office::{self, OfficeParams};
use ygg_store::query::children;
use ygg_store::{Aabb, FeatureValue, NodeId, Point, SceneView};
use ygg_writer::{SceneWriter, WriterWaitError};

/// Time between ticks (30 Hz).
const PERIOD: Duration = Duration::from_nanos(33_333_333);

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene = args.next().unwrap_or_else(|| "office".to_owned());
    let scale: f64 = args.next().map_or(Ok(1.0), |s| s.parse())?;
    let dsg = office::generate(OfficeParams { seed: 7, scale });
    let graph = layout::build(&dsg, Layout::Mint)?;
    let agents = graph.layer_by_name("AGENTS").ok_or("no AGENTS layer")?;
    // The agent walks a circle inside the office's rooms.
    let rooms = graph.layer_by_name("ROOMS").ok_or("no ROOMS layer")?;
    let bounds = graph
        .layer_nodes(rooms)
        .filter_map(|n| graph.aabb(n))
        .reduce(|a, b| a.union(&b))
        .unwrap_or(Aabb::from_point([0.0; 3]));
    let centre = [0, 1].map(|a| (bounds.min[a] + bounds.max[a]) / 2.0);
    let radius = (0..2)
        .map(|a| (bounds.max[a] - bounds.min[a]) / 4.0)
        .fold(f32::INFINITY, f32::min);
    // The object that moves: the first with geometry, and its mesh as generated.
    let object = Objects::new(&graph)
        .objects_with_geometry()
        .next()
        .ok_or("the office has no objects")?;
    let mesh: Vec<(NodeId, Vec<Point>)> = children(&graph, object)
        .into_iter()
        .filter_map(|m| Some((m, graph.points(graph.node(m)?).to_vec())))
        .collect();

    let mut writer = SceneWriter::builder(&scene).max_readers(8).create(graph)?;
    writer.publish()?;
    println!(
        "serving scene={scene} nodes={} moving={}; Ctrl-C to stop",
        writer.graph().node_count(),
        object.0
    );
    let mut next = Instant::now();
    for tick in 0u64.. {
        let graph = writer.graph_mut();
        // A new agent pose (ids of Spark-DSG symbol 'a').
        let angle = tick as f32 * 0.01;
        let pose = NodeId(NodeSymbol::new(b'a', 1_000_000 + tick).0);
        graph.add_node(pose, agents)?;
        graph.set_geometry(
            pose,
            vec![[
                centre[0] + radius * angle.cos(),
                centre[1] + radius * angle.sin(),
                1.0,
            ]],
        )?;
        graph.set_feature(pose, "tick", FeatureValue::Int(tick as i64))?;
        // The object sways along x by up to 10 cm (its box follows).
        let dx = 0.1 * (tick as f32 * 0.1).sin();
        for (m, points) in &mesh {
            graph.set_geometry(*m, points.iter().map(|p| [p[0] + dx, p[1], p[2]]).collect())?;
        }
        let report = writer.publish()?; // AGENTS and the object's layers only
        if tick % 30 == 0 {
            println!(
                "generation={} layers_sent={} bytes_sent={}",
                report.generation, report.layers_sent, report.bytes_sent
            );
        }
        next += PERIOD;
        let wait = next.saturating_duration_since(Instant::now());
        match writer.publisher().wait(wait) {
            Ok(()) => {}
            Err(WriterWaitError::Interrupt | WriterWaitError::TerminationRequest) => break,
        }
    }
    println!("stopped at generation={}", writer.generation());
    Ok(()) // dropping the writer removes its shared memory
}
