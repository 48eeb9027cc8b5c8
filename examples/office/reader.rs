//! A planner on the live office: for each new snapshot, the room of the newest agent pose,
//! the object nearest to it and the objects within 2 m of it, answered in place by
//! [`ygg_dsg::objects::Objects`], `count` times (a wait that times out counts).
//!
//! Run the office writer first, then
//! `cargo run --release -p ygg-examples --example office_reader [scene] [count]`
//! (scene `office` and 30 snapshots by default).

use std::time::Duration;
use ygg_dsg::layout;
use ygg_dsg::objects::Objects;
use ygg_reader::SceneReader;

/// Radius of the objects-within query, metres.
const RADIUS: f32 = 2.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene = args.next().unwrap_or_else(|| "office".to_owned());
    let count: u64 = args.next().map_or(Ok(30), |c| c.parse())?;
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
        // The newest agent pose and the room it is in (`ygg_dsg::layout`'s whereabouts).
        let pose = layout::newest_pose(&view)
            .ok_or("no agent pose yet")?
            .position;
        let room = layout::room_of(&view, &pose);
        let objects = Objects::new(&view);
        let nearest = objects.nearest_object(pose)?;
        let within = objects.objects_within(pose, RADIUS)?;
        let list: Vec<String> = within.iter().map(|id| id.0.to_string()).collect();
        println!(
            "generation={} pose={:.2},{:.2},{:.2} room={} nearest={} within={} ids={}",
            snapshot.generation(),
            pose[0],
            pose[1],
            pose[2],
            room.map_or("none".to_owned(), |id| id.0.to_string()),
            nearest.map_or("none".to_owned(), |id| id.0.to_string()),
            within.len(),
            if list.is_empty() {
                "none".to_owned()
            } else {
                list.join(",")
            },
        );
    }
    Ok(())
}
