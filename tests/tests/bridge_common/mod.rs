//! What the bridge tests share (`bridge.rs`: ZeroMQ, `ros2.rs`: ROS 2): driving a Python
//! peer by commands, the graph a dumped message should build, and the checks of a
//! reader's snapshot against it.

use std::path::Path;
use std::time::{Duration, Instant};

use ygg_dsg::layout::{self, Layout};
use ygg_dsg::{DsgGraph, DsgVersion, NodeKind};
use ygg_reader::{SceneReader, SceneSnapshot};
use ygg_store::{SceneGraph, SceneView, Scope, distance_squared, query};
use ygg_testkit::Proc;

/// Generous bound for one step (debug builds on a busy 2-core machine).
pub const STEP: Duration = Duration::from_secs(60);
/// The layout the bridges build.
pub const LAYOUT: Layout = Layout::Mint;

/// The workspace root.
pub fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// Sends a command to the sender and returns its `ok ...` answer.
pub fn command(sender: &mut Proc, line: &str) -> String {
    let skip = sender.stdout().len();
    sender.send(line).expect("sender reads commands");
    let (_, answer) = sender
        .wait_line_after(skip, STEP, |l| {
            l.starts_with("ok") || l.starts_with("error")
        })
        .unwrap_or_else(|| panic!("sender did not answer {line:?}: {}", sender.describe()));
    assert!(answer.starts_with("ok"), "{line:?}: {answer}");
    answer
}

/// The graph in a dumped message, as the sender's data and as the bridge should build it.
pub fn expected(path: &Path) -> (DsgGraph, SceneGraph) {
    let bytes = std::fs::read(path).expect("dumped message");
    let dsg = ygg_dsg::parse_binary_body(&bytes, DsgVersion::V1_1_3, "dump").expect("decodes");
    let g = layout::build(&dsg, LAYOUT).expect("builds");
    (dsg, g)
}

pub fn snapshot_at(reader: &mut SceneReader, generation: u64) -> SceneSnapshot {
    let until = Instant::now() + STEP;
    loop {
        if let Some(s) = reader
            .wait_next(Duration::from_millis(100))
            .expect("receive")
            .filter(|s| s.generation() >= generation)
        {
            return s;
        }
        // `wait_next` returns only new snapshots; the current one may already be it.
        if let Some(s) = reader
            .latest()
            .expect("receive")
            .filter(|s| s.generation() >= generation)
        {
            return s;
        }
        assert!(
            Instant::now() < until,
            "no snapshot of generation {generation}"
        );
    }
}

/// Layer name -> generation in a snapshot.
pub fn generations(s: &SceneSnapshot) -> std::collections::BTreeMap<String, u64> {
    let v = s.view();
    v.layers()
        .map(|l| {
            (
                v.layer_name(l).unwrap_or("?").to_owned(),
                v.layer_generation(l).unwrap_or(0),
            )
        })
        .collect()
}

/// Nearest objects to a few points: through the snapshot's indexes (object mesh layers,
/// then the object that nests the mesh node) and by brute force over the sender's
/// object positions (the layout locates an object without mesh by its position).
pub fn check_objects(view: &impl SceneView, dsg: &DsgGraph) {
    for c in [
        [5.0f32, 5.0, 1.0],
        [12.0, 20.0, 1.5],
        [30.0, 10.0, 0.5],
        [0.0; 3],
    ] {
        let mut best: Option<(ygg_store::NodeId, f32)> = None;
        for (mesh, _) in layout::object_mesh_layers(view) {
            for (n, d) in query::nearest_nodes(view, Scope::Layer(mesh), c, 1).expect("query") {
                let object = query::parent(view, n).expect("mesh node nested in its object");
                if best.is_none_or(|b| (d, object) < (b.1, b.0)) {
                    best = Some((object, d));
                }
            }
        }
        let brute = dsg
            .nodes
            .iter()
            .filter(|n| n.kind == NodeKind::Object)
            .map(|n| {
                (
                    ygg_store::NodeId(n.id),
                    distance_squared(&n.position, &c).sqrt(),
                )
            })
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        assert_eq!(
            best.map(|b| b.0),
            brute.map(|b| b.0),
            "nearest object to {c:?}"
        );
    }
}

/// The bridge's newest `update` or `bad-frame` line after the first `skip` lines.
pub fn bridge_event(bridge: &Proc, skip: usize, event: &str) -> serde_json::Value {
    let needle = format!("\"event\":\"{event}\"");
    let (_, line) = bridge
        .wait_line_after(skip, STEP, |l| l.contains(&needle))
        .unwrap_or_else(|| panic!("no {event} from the bridge: {}", bridge.describe()));
    serde_json::from_str(&line).expect("JSON line")
}
