//! End-to-end tests of the scene layer over shared memory with real processes: a
//! `ygg serve` process publishing the office with a live update stream, reader
//! processes and in-process readers querying validated snapshots, corrupted archives
//! refused, and the demo stopped by Ctrl-C leaving nothing behind.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use rustix::process::Signal;
use ygg_dsg::layout;
use ygg_reader::{SceneReader, SceneReceiveError, SceneSnapshot};
use ygg_store::query::{self, nodes_with_label};
use ygg_store::snapshot::{STRUCTURE_SEGMENT_ID, is_chunk_segment_id, part_segment_id};
use ygg_store::{LayerId, NodeId, SceneGraph, SceneView, Scope};
use ygg_testkit::{Proc, TestScene, Watchdog, catches_signal, wait_until};
use ygg_transport::PublisherBuilder;

const STEP: Duration = Duration::from_secs(60);
const WATCHDOG: Duration = Duration::from_secs(180);

fn attach(scene: &TestScene) -> SceneReader {
    SceneReader::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .wait_for_writer(STEP)
        .open()
        .unwrap_or_else(|e| panic!("attach: {e}"))
}

fn snapshot_after(reader: &mut SceneReader, generation: u64) -> SceneSnapshot {
    let until = Instant::now() + STEP;
    loop {
        let next = reader
            .wait_next(Duration::from_millis(200))
            .expect("receive");
        if let Some(s) = next.filter(|s| s.generation() >= generation) {
            return s;
        }
        assert!(
            Instant::now() < until,
            "no snapshot of generation {generation}"
        );
    }
}

fn spawn_serve(scene: &TestScene, watchdog: &Watchdog, extra: &[&str]) -> Proc {
    let mut args = vec!["serve", "--scene", scene.name.as_str(), "--scale", "0.05"];
    args.extend_from_slice(extra);
    Proc::spawn(scene.command("ygg", &args), "writer", watchdog)
}

#[test]
fn served_office_is_validated_once_per_layer_and_answers_like_brute_force() {
    let scene = TestScene::new("serve");
    let watchdog = Watchdog::new(WATCHDOG);
    let mut writer = spawn_serve(&scene, &watchdog, &["--rate", "30", "--seconds", "60"]);
    writer.expect_line(STEP, |l| l.contains("\"ready\""));
    let mut reader = attach(&scene);
    let first = snapshot_after(&mut reader, 1);
    let later = snapshot_after(&mut reader, first.generation() + 5);
    let view = later.view();
    assert!(
        view.node_count() > 100,
        "office too small: {}",
        view.node_count()
    );
    // Agent poses keep arriving.
    let agents = view.layer_by_name("AGENTS").expect("agents layer");
    assert!(view.layer_len(agents) > first.view().layer_len(agents));
    // Unchanged layers are not validated again: far fewer validations than layers seen.
    let layers = view.layers().count() as u64;
    assert!(
        reader.validations() < layers * 4,
        "{} validations for {layers} layers",
        reader.validations()
    );
    // Indexed room-scoped nearest equals a brute-force scan of the same snapshot.
    let mut compared = 0;
    for (mesh, _) in layout::object_mesh_layers(&view) {
        for c in [[5.0f32, 5.0, 1.0], [20.0, 12.0, 0.5], [33.0, 20.0, 2.0]] {
            let indexed =
                query::nearest_nodes(&view, Scope::Layer(mesh), c, 3).expect("valid query");
            let mut brute: Vec<(NodeId, f32)> = view
                .layer_nodes(mesh)
                .filter_map(|n| {
                    let d = view
                        .points(n)
                        .iter()
                        .map(|p| ygg_store::distance_squared(p, &c))
                        .fold(f32::INFINITY, f32::min);
                    d.is_finite().then(|| (view.node_id(n), d.sqrt()))
                })
                .collect();
            brute.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            brute.truncate(3);
            assert_eq!(
                indexed.iter().map(|x| x.0).collect::<Vec<_>>(),
                brute.iter().map(|x| x.0).collect::<Vec<_>>()
            );
            compared += 1;
        }
    }
    assert!(compared > 0);
    assert!(!nodes_with_label(&view, Scope::Graph, "light").is_empty());
    // A reader process (the demo's planner) agrees with brute force on every check.
    let mut planner = Proc::spawn(
        scene.command(
            "ygg",
            &[
                "demo-role",
                "--scene",
                &scene.name,
                "--role",
                "planner",
                "--seconds",
                "3",
                "--check-every",
                "1",
            ],
        ),
        "planner",
        &watchdog,
    );
    let summary = planner.expect_line(STEP, |l| l.contains("\"summary\""));
    assert!(planner.wait_exit(STEP).success());
    let v: serde_json::Value = serde_json::from_str(&summary).expect("summary is JSON");
    assert!(v["checked"].as_u64().unwrap_or(0) > 0, "{summary}");
    assert_eq!(v["checked"], v["matched"], "{summary}");
    drop(later);
    drop(first);
    drop(reader);
    writer.signal(Signal::TERM);
    assert!(writer.wait_exit(STEP).success());
    scene.assert_no_leftovers(Duration::from_secs(5));
}

#[test]
fn corrupted_archive_bytes_are_refused_by_the_reader() {
    let scene = TestScene::new("corrupt");
    let mut publisher = raw_publisher(&scene);
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").expect("layer");
    g.add_node(NodeId(1), rooms).expect("node");
    let segment = g.layer_segment(rooms);
    let len = segment.archived_len();
    // A layer whose archive is damaged after the transport header (which stays valid).
    publisher
        .publish_layer(
            part_segment_id(rooms, 0).expect("fits"),
            g.layer_generation(rooms).expect("gen"),
            len,
            |buf| {
                segment.archive_into(buf).expect("fits");
                for b in &mut buf[len / 3..] {
                    *b ^= 0x5a;
                }
            },
        )
        .expect("publish layer");
    publish_cut(&mut publisher, &g, 1, |_| ());
    let mut reader = attach(&scene);
    let err = refused(&mut reader, 1);
    assert!(matches!(err, SceneReceiveError::Invalid { .. }), "{err}");
    assert!(
        err.to_string().contains(&scene.name),
        "error names the scene: {err}"
    );
    drop(reader);
    drop(publisher);
    scene.assert_no_leftovers(Duration::from_secs(5));
}

/// A bare segment publisher for `scene`, to publish segments and manifests by hand.
fn raw_publisher(scene: &TestScene) -> ygg_transport::SegmentPublisher {
    PublisherBuilder::new(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .create()
        .expect("writer")
}

/// The error `reader` reports for the cut of `generation`, which it must refuse.
fn refused(reader: &mut SceneReader, generation: u64) -> SceneReceiveError {
    let until = Instant::now() + STEP;
    loop {
        match reader.wait_next(Duration::from_millis(200)) {
            Err(e) => return e,
            Ok(Some(s)) if s.generation() >= generation => {
                panic!("cut {} was accepted", s.generation())
            }
            Ok(_) => assert!(Instant::now() < until, "no cut {generation} arrived"),
        }
    }
}

/// Publishes `layer`'s segment of `g` as it is now.
fn publish_segment(
    publisher: &mut ygg_transport::SegmentPublisher,
    g: &SceneGraph,
    layer: LayerId,
) {
    let segment = g.layer_segment(layer);
    let generation = g.layer_generation(layer).expect("layer generation");
    publisher
        .publish_layer(
            part_segment_id(layer, 0).expect("fits"),
            generation,
            segment.archived_len(),
            |buf| {
                segment.archive_into(buf).expect("fits");
            },
        )
        .expect("publish layer");
}

/// Publishes `g`'s structure (generation 1) and its manifest at `generation`, changed by
/// `tamper` first.
fn publish_cut(
    publisher: &mut ygg_transport::SegmentPublisher,
    g: &SceneGraph,
    generation: u64,
    tamper: impl FnOnce(&mut ygg_store::snapshot::Manifest),
) {
    let structure = g.structure(1);
    if publisher.layer_generation(STRUCTURE_SEGMENT_ID) != Some(1) {
        publisher
            .publish_layer(STRUCTURE_SEGMENT_ID, 1, structure.archived_len(), |buf| {
                structure.archive_into(buf).expect("fits");
            })
            .expect("publish structure");
    }
    let mut manifest = g.manifest(generation, 1);
    tamper(&mut manifest);
    let mut entries: Vec<_> = manifest
        .layers
        .iter()
        .map(|e| ygg_transport::ManifestEntry {
            layer_id: part_segment_id(LayerId(e.id), 0).expect("fits"),
            generation: e.generation,
        })
        .collect();
    entries.push(ygg_transport::ManifestEntry {
        layer_id: STRUCTURE_SEGMENT_ID,
        generation: 1,
    });
    publisher
        .publish_manifest(generation, &entries, manifest.archived_len(), |buf| {
            manifest.archive_into(buf).expect("fits");
        })
        .expect("publish manifest");
}

#[test]
fn a_cut_that_lies_about_an_unchanged_layer_is_refused_and_the_last_one_kept() {
    // A reader checks in full only what changed since its last cut; a manifest that
    // changes an unchanged layer's node count (its bytes the same as before) must not
    // slip through as "known".
    let scene = TestScene::new("lying-cut");
    let mut publisher = raw_publisher(&scene);
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").expect("layer");
    let objects = g.add_layer("objects").expect("layer");
    g.add_layer_edge(rooms, objects).expect("edge");
    g.add_node(NodeId(1), rooms).expect("node");
    g.add_node(NodeId(10), objects).expect("node");
    publish_segment(&mut publisher, &g, rooms);
    publish_segment(&mut publisher, &g, objects);
    publish_cut(&mut publisher, &g, 1, |_| ());
    let mut reader = attach(&scene);
    assert_eq!(snapshot_after(&mut reader, 1).generation(), 1);

    // An honest cut: only the objects layer changed.
    g.add_node(NodeId(11), objects).expect("node");
    publish_segment(&mut publisher, &g, objects);
    publish_cut(&mut publisher, &g, 2, |_| ());
    let second = snapshot_after(&mut reader, 2);
    assert_eq!(second.view().layer_nodes(objects).count(), 2);

    // The rooms layer unchanged, its manifest entry claiming another node count.
    publish_cut(&mut publisher, &g, 3, |m| m.layers[0].node_count = 2);
    let err = refused(&mut reader, 3);
    assert!(
        matches!(err, SceneReceiveError::Invalid { generation: 3, .. })
            && err.to_string().contains("counts 2 nodes, its parts hold 1"),
        "{err}"
    );
    assert_eq!(
        second.view().layer_nodes(objects).count(),
        2,
        "cut 2 still answers"
    );
    // Reported once: while the refused cut is the newest, asking again gives the last
    // accepted snapshot (the refused cut is not checked again).
    for _ in 0..2 {
        let latest = reader.latest().expect("the refusal is reported once");
        assert_eq!(latest.map(|s| s.generation()), Some(2));
    }

    // The next honest cut is accepted again.
    publish_cut(&mut publisher, &g, 4, |_| ());
    let fourth = snapshot_after(&mut reader, 4);
    assert_eq!(fourth.view().layer_nodes(rooms).count(), 1);
    assert_eq!(fourth.view().layer_nodes(objects).count(), 2);
    drop((second, fourth, reader, publisher));
    scene.assert_no_leftovers(Duration::from_secs(5));
}

#[test]
fn demo_stopped_by_ctrl_c_exits_cleanly_and_leaves_no_shared_memory() {
    let scene = TestScene::new("demo");
    let watchdog = Watchdog::new(WATCHDOG);
    let mut demo = Proc::spawn(
        scene.command(
            "ygg",
            &[
                "demo",
                "--seconds",
                "60",
                "--scale",
                "0.05",
                "--readers",
                "2",
            ],
        ),
        "demo",
        &watchdog,
    );
    demo.expect_line(STEP, |l| l.starts_with("Yggdrasil demo"));
    // Press Ctrl-C once the writer and both readers run and handle it (a process that
    // does not handle SIGINT yet would die of the demo passing it on, not stop).
    wait_until(
        STEP,
        "the demo's writer and 2 readers handle SIGINT",
        || {
            let children = demo.children();
            children.len() == 3 && children.iter().all(|&pid| catches_signal(pid, Signal::INT))
        },
    );
    demo.signal(Signal::INT);
    let status = demo.wait_exit(STEP);
    let out = demo.stdout().join("\n");
    assert!(
        status.success(),
        "demo failed after Ctrl-C:\n{out}\n{}",
        demo.stderr().join("\n")
    );
    assert!(out.contains("interrupted"), "{out}");
    assert!(out.contains("nothing left in /dev/shm"), "{out}");
    scene.assert_no_leftovers(Duration::from_secs(5));
}

#[test]
fn a_scene_growing_past_its_writers_layer_bound_is_refused_and_kept() {
    let scene = TestScene::new("bound");
    let _watchdog = Watchdog::new(WATCHDOG);
    let mut graph = SceneGraph::new();
    graph.add_layer("rooms").expect("layer");
    let mut writer = ygg_writer::SceneWriter::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .create(graph)
        .expect("writer");
    assert_eq!(writer.max_layers(), ygg_writer::default_max_layers(1));
    writer.publish().expect("publish");
    let mut reader = attach(&scene);
    let first = snapshot_after(&mut reader, 1);

    for i in 1..=writer.max_layers() {
        writer
            .graph_mut()
            .add_layer(&format!("room{i}"))
            .expect("layer");
    }
    let err = writer.publish().expect_err("one layer past the bound");
    assert!(err.to_string().contains("max_layers"), "{err}");
    // Nothing is lost: the graph keeps its layers, the reader its snapshot, and a publish
    // within the bound goes through.
    assert_eq!(writer.graph().layers().count(), writer.max_layers() + 1);
    assert_eq!(first.view().layers().count(), 1);
    let last = writer
        .graph()
        .layer_by_name(&format!("room{}", writer.max_layers()))
        .expect("the last room");
    writer.graph_mut().remove_layer(last).expect("remove");
    let report = writer.publish().expect("publish within the bound");
    let fresh = snapshot_after(&mut reader, report.generation);
    assert_eq!(fresh.view().layers().count(), writer.max_layers());
    drop((first, fresh, reader, writer));
    scene.assert_no_leftovers(STEP);
}

#[test]
fn a_growing_mesh_resends_only_its_changed_chunks_and_readers_validate_only_those() {
    let scene = TestScene::new("chunks");
    let watchdog = Watchdog::new(WATCHDOG);
    // Chunks of 64 points: the office at this scale has meshes of a few hundred points.
    let mut writer = spawn_serve(
        &scene,
        &watchdog,
        &["--rate", "60", "--seconds", "60", "--point-chunk-len", "64"],
    );
    writer.expect_line(STEP, |l| l.contains("\"ready\""));
    let mut reader = attach(&scene);
    let mut previous = snapshot_after(&mut reader, 1);
    let segment_generations = |s: &SceneSnapshot| -> BTreeMap<u64, u64> {
        s.raw()
            .layers()
            .map(|(e, _)| (e.layer_id, e.generation))
            .collect()
    };
    let (mut grown, mut chunks_held, mut chunks_resent) = (0, 0, 0);
    let until = Instant::now() + STEP;
    while grown < 3 {
        assert!(Instant::now() < until, "no mesh grew ({grown} seen)");
        let validated = reader.validations();
        let next = snapshot_after(&mut reader, previous.generation() + 1);
        let (before, after) = (segment_generations(&previous), segment_generations(&next));
        let new: Vec<u64> = after
            .iter()
            .filter(|(id, g)| before.get(id) != Some(g))
            .map(|(id, _)| *id)
            .collect();
        // Exactly the segments the cut changed are validated; the rest are kept.
        assert_eq!(reader.validations() - validated, new.len() as u64);
        let chunks = after.keys().filter(|id| is_chunk_segment_id(**id)).count();
        chunks_held += chunks;
        chunks_resent += new.iter().filter(|id| is_chunk_segment_id(**id)).count();
        // A grown mesh node keeps its old points and gains a tail, read across chunks.
        let (old, now) = (previous.view(), next.view());
        for layer in now.layers() {
            if !now
                .layer_name(layer)
                .is_some_and(|n| n.ends_with("unclaimed-mesh"))
            {
                continue;
            }
            for n in now.layer_nodes(layer) {
                let id = now.node_id(n);
                let points = now.points(n).to_vec();
                let Some(before) = old.node(id).map(|o| old.points(o).to_vec()) else {
                    continue;
                };
                if points.len() > before.len() {
                    assert_eq!(points[..before.len()], before[..], "node {id}");
                    assert!(now.points(n).runs().count() > 1, "node {id} is chunked");
                    grown += 1;
                }
            }
        }
        previous = next;
    }
    assert!(chunks_held > 0, "no layer was chunked");
    assert!(
        chunks_resent * 4 < chunks_held,
        "{chunks_resent} of {chunks_held} chunks resent"
    );
    drop(previous);
    drop(reader);
    writer.signal(Signal::TERM);
    assert!(writer.wait_exit(STEP).success());
    scene.assert_no_leftovers(Duration::from_secs(5));
}
