//! A minimal planner-side reader: attaches to the example scene, waits for each new
//! snapshot and queries it in place. Run the writer first, then
//! `cargo run --release -p ygg-examples --example reader`.

use std::time::Duration;
use ygg_reader::SceneReader;
use ygg_store::query::{nearest_nodes, nodes_with_label};
use ygg_store::{SceneView, Scope};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut reader = SceneReader::builder("example")
        .wait_for_writer(Duration::from_secs(10))
        .open()?;
    for _ in 0..50 {
        // Blocks on the writer's event (no polling); None after the timeout.
        let Some(snapshot) = reader.wait_next(Duration::from_secs(2))? else {
            println!("no new snapshot ({:?})", reader.writer_status());
            continue;
        };
        let view = snapshot.view(); // validated archived bytes, queried zero-copy
        let objects = view.layer_by_name("OBJECTS").ok_or("no OBJECTS layer")?;
        let agents = view.layer_by_name("AGENTS").ok_or("no AGENTS layer")?;
        let here = [1.0, 1.0, 0.5];
        let nearest = nearest_nodes(&view, Scope::Layer(objects), here, 1)?;
        let lights = nodes_with_label(&view, Scope::Graph, "light");
        println!(
            "generation {}: {} poses, nearest object {:?}, lights {:?}",
            snapshot.generation(),
            view.layer_len(agents),
            nearest.first(),
            lights
        );
    }
    Ok(())
}
