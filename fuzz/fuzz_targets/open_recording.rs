//! A recording file's bytes (one file of a recording folder): opening scans its records
//! (CRCs, cut lists), and every cut that opens validates and joins its segments; whatever
//! opens must then answer accessors, a query and `changes` without panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;
use ygg_store::query::nearest_nodes;
use ygg_store::recording::Recording;
use ygg_store::{SceneView, Scope};

fuzz_target!(|data: &[u8]| {
    let Ok(dir) = tempfile::tempdir() else { return };
    if std::fs::write(dir.path().join("00000001.ygr"), data).is_err() {
        return;
    }
    let Ok(recording) = Recording::open(dir.path()) else {
        return;
    };
    let cuts = recording.cuts().len();
    for cut in 0..cuts {
        let _ = recording.raw_cut(cut);
        let Ok(scene) = recording.scene(cut) else { continue };
        let view = scene.view();
        for layer in view.layers() {
            for node in view.layer_nodes(layer) {
                let _ = (view.points(node).len(), view.parent(node), view.labels(node).count());
            }
            let _ = nearest_nodes(view, Scope::Layer(layer), [1.0, 2.0, 0.5], 2);
        }
    }
    if let Some(last) = cuts.checked_sub(1) {
        let _ = recording.changes(0, last, 0.1);
    }
});
