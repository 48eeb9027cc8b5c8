//! The reader's copy-then-validate mode (`SceneReaderBuilder::copy_segments`): same answers
//! as zero-copy, unchanged layers keep their copy, and a process that rewrites the shared
//! segments after validation cannot reach what the reader queries.

use std::os::unix::fs::FileExt;
use std::path::Path;
use std::time::{Duration, Instant};

use ygg_dsg::layout::{self, Layout};
use ygg_dsg::office::{OfficeParams, generate};
use ygg_reader::{SceneReader, SceneSnapshot};
use ygg_store::query::{nearest_nodes, nodes_with_label};
use ygg_store::{SceneGraph, SceneView, Scope};
use ygg_testkit::{TestScene, Watchdog};
use ygg_writer::SceneWriter;

const STEP: Duration = Duration::from_secs(30);

fn office() -> SceneGraph {
    layout::build(
        &generate(OfficeParams {
            seed: 7,
            scale: 0.05,
        }),
        Layout::Mint,
    )
    .expect("office")
}

/// A writer serving the small office in `scene`, its first snapshot published.
fn publish_office(scene: &TestScene) -> SceneWriter {
    let mut writer = SceneWriter::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .create(office())
        .expect("writer");
    writer.publish().expect("publish");
    writer
}

fn reader(scene: &TestScene, copy: bool) -> SceneReader {
    SceneReader::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .wait_for_writer(STEP)
        .copy_segments(copy)
        .open()
        .expect("reader")
}

fn snapshot_at(reader: &mut SceneReader, generation: u64) -> SceneSnapshot {
    let until = Instant::now() + STEP;
    loop {
        if let Some(s) = reader.latest().expect("receive")
            && s.generation() >= generation
        {
            return s;
        }
        assert!(Instant::now() < until, "no snapshot {generation}");
        let _ = reader
            .wait_next(Duration::from_millis(200))
            .expect("receive");
    }
}

/// What the snapshot answers: every layer's nearest nodes from a few points and the
/// label postings, as text.
fn answers(snapshot: &SceneSnapshot) -> String {
    let view = snapshot.view();
    let mut out = format!("{} nodes\n", view.node_count());
    for layer in view.layers() {
        for c in [[5.0f32, 5.0, 1.0], [20.0, 12.0, 0.5]] {
            let near = nearest_nodes(&view, Scope::Layer(layer), c, 3).expect("query");
            out.push_str(&format!("{layer} {c:?} {near:?}\n"));
        }
    }
    for label in ["light", "chair", "desk"] {
        out.push_str(&format!(
            "{label} {:?}\n",
            nodes_with_label(&view, Scope::Graph, label)
        ));
    }
    out
}

#[test]
fn copy_mode_answers_like_zero_copy_and_copies_only_changed_layers() {
    let scene = TestScene::new("copy");
    let _watchdog = Watchdog::new(Duration::from_secs(120));
    let mut writer = publish_office(&scene);
    let mut shared = reader(&scene, false);
    let mut copied = reader(&scene, true);
    let a = snapshot_at(&mut shared, 1);
    let b = snapshot_at(&mut copied, 1);
    assert_eq!(answers(&a), answers(&b));
    // Every segment (layers, point and tree chunks) validated once.
    let segments = b.raw().layer_count() as u64;
    assert_eq!(copied.validations(), segments);

    // One object moved: one more snapshot, only the changed segments copied and validated.
    let (mesh_node, moved) = {
        let g = writer.graph();
        let (mesh, _) = layout::object_mesh_layers(g)[0];
        let node = g
            .layer_nodes(mesh)
            .find(|&n| !g.points(n).is_empty())
            .expect("a mesh node with points");
        let moved: Vec<[f32; 3]> = g
            .points(node)
            .iter()
            .map(|p| [p[0] + 0.5, p[1], p[2]])
            .collect();
        (g.node_id(node), moved)
    };
    writer
        .graph_mut()
        .set_geometry(mesh_node, moved)
        .expect("move");
    let report = writer.publish().expect("publish");
    let a2 = snapshot_at(&mut shared, report.generation);
    let b2 = snapshot_at(&mut copied, report.generation);
    assert_eq!(answers(&a2), answers(&b2));
    assert_ne!(answers(&b), answers(&b2), "the move changed no answer");
    assert_eq!(
        copied.validations(),
        segments + (report.layers_sent + report.chunks_sent) as u64
    );
    drop((a, b, a2, b2, shared, copied, writer));
    scene.assert_no_leftovers(STEP);
}

#[test]
fn copy_mode_is_not_reached_by_rewrites_of_the_shared_segments() {
    let scene = TestScene::new("rewrite");
    let _watchdog = Watchdog::new(Duration::from_secs(120));
    let writer = publish_office(&scene);
    let mut copied = reader(&scene, true);
    let snapshot = snapshot_at(&mut copied, 1);
    let before = answers(&snapshot);

    // Another process of the same user may open the payload segments read-write: rewrite
    // every byte of every one of this scene's data segments after validation.
    let mut rewritten = 0;
    for entry in std::fs::read_dir("/dev/shm").expect("/dev/shm") {
        let path = entry.expect("entry").path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with(&scene.prefix) && name.ends_with("__0.data") {
            rewrite(&path);
            rewritten += 1;
        }
    }
    assert!(
        rewritten > 0,
        "found no data segment of the scene to rewrite"
    );
    assert_eq!(answers(&snapshot), before);
    drop((snapshot, copied, writer));
    scene.remove_all();
}

/// Overwrites the whole file with 0xA5 through a read-write descriptor.
fn rewrite(path: &Path) {
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .expect("open the segment read-write");
    let len = file.metadata().expect("metadata").len() as usize;
    file.write_all_at(&vec![0xA5; len], 0).expect("rewrite");
}
