//! A minimal planner-side reader: attaches to the minimal writer's scene, waits for each
//! new snapshot and queries it in place, `count` times (a wait that times out counts).
//!
//! Run the writer first, then
//! `cargo run --release -p ygg-examples --example minimal_reader [scene] [count]`
//! (scene `example` and 50 snapshots by default).

use std::time::Duration;
use ygg_reader::SceneReader;
use ygg_store::query::{nearest_nodes, nodes_with_label};
use ygg_store::{SceneView, Scope};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene = args.next().unwrap_or_else(|| "example".to_owned());
    let count: u64 = args.next().map_or(Ok(50), |c| c.parse())?;
    let mut reader = SceneReader::builder(&scene)
        .wait_for_writer(Duration::from_secs(5))
        .open()?;
    for _ in 0..count {
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
            "generation={} poses={} nearest={} lights={}",
            snapshot.generation(),
            view.layer_len(agents),
            nearest
                .first()
                .map_or("none".to_owned(), |(id, _)| id.0.to_string()),
            ids(lights.iter().map(|id| id.0)),
        );
    }
    Ok(())
}

/// Ids as `a,b,c` (`none` when empty).
fn ids(ids: impl Iterator<Item = u64>) -> String {
    let list: Vec<String> = ids.map(|id| id.to_string()).collect();
    if list.is_empty() {
        "none".to_owned()
    } else {
        list.join(",")
    }
}
