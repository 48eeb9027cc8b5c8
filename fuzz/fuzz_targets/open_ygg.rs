//! A `.ygg` file's bytes: opening validates every segment; whatever opens must then answer
//! every accessor and query without panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;
use ygg_store::query::{nearest_nodes, nodes_with_label};
use ygg_store::{SceneView, Scope, SnapshotFile};

fuzz_target!(|data: &[u8]| {
    let Ok(file) = SnapshotFile::from_bytes(data, "fuzz.ygg") else {
        return;
    };
    let view = file.view();
    for layer in view.layers() {
        let _ = view.layer_name(layer);
        for node in view.layer_nodes(layer) {
            let _ = (view.points(node).len(), view.parent(node), view.aabb(node));
            let _ = view.children(node).len();
            let _ = view.labels(node).count();
            let _ = view.out_edges(node).count();
        }
        let _ = nearest_nodes(&view, Scope::Layer(layer), [1.0, 2.0, 0.5], 3);
    }
    let _ = nodes_with_label(&view, Scope::Graph, "light");
});
