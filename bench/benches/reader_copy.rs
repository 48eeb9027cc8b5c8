//! What the reader's copy-then-validate mode costs (`SceneReaderBuilder::copy_segments`):
//! one object of the built-in office (mint) moved, published, and the new snapshot
//! received, validated and queried, zero-copy against copy mode, in one process. Also the
//! first snapshot of a newly attached reader (every layer received and validated). Paired:
//! both modes do the same work in every iteration, in alternating order, and each benchmark
//! times one of them.
#![expect(clippy::unwrap_used, reason = "acceptable in benchmarks")]
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::{Duration, Instant};
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::office::{OfficeParams, generate};
use ygg_reader::{SceneReader, SceneSnapshot};
use ygg_store::query::nearest_nodes;
use ygg_store::{NodeId, SceneView, Scope};
use ygg_writer::SceneWriter;

const MODES: [(&str, bool); 2] = [("zero_copy", false), ("copy", true)];

fn open(scene: &str, prefix: &str, copy: bool) -> SceneReader {
    SceneReader::builder(scene)
        .iceoryx_prefix(prefix)
        .wait_for_writer(Duration::from_secs(10))
        .copy_segments(copy)
        .open()
        .unwrap()
}

/// Blocks until `reader` holds snapshot `generation` or newer.
fn receive(reader: &mut SceneReader, generation: u64) -> SceneSnapshot {
    loop {
        if let Some(s) = reader.wait_next(Duration::from_secs(5)).unwrap()
            && s.generation() >= generation
        {
            return s;
        }
    }
}

fn reader_copy(c: &mut Criterion) {
    let prefix = format!("yggbench{}_", std::process::id());
    let scene = "reader-copy";
    let graph = layout::build(
        &generate(OfficeParams {
            seed: 7,
            scale: 1.0,
        }),
        Layout::Mint,
    )
    .unwrap();
    let (mesh, _) = layout::object_mesh_layers(&graph)[0];
    let node = graph
        .layer_nodes(mesh)
        .find(|&n| !graph.points(n).is_empty())
        .unwrap();
    let mesh_node: NodeId = graph.node_id(node);
    let points = graph.points(node).to_vec();
    let mut writer = SceneWriter::builder(scene)
        .iceoryx_prefix(&prefix)
        .create(graph)
        .unwrap();
    writer.publish().unwrap();

    // Both readers are attached and receive every update; each benchmark times one of
    // them. The two benchmarks do the same work, and which reader receives first alternates,
    // so neither run order nor the host's drift favours a mode.
    let mut readers = MODES.map(|(_, copy)| open(scene, &prefix, copy));
    for reader in &mut readers {
        receive(reader, writer.generation());
    }
    let mut group = c.benchmark_group("reader_copy");
    group.measurement_time(Duration::from_secs(5));
    let mut step = 0u32;
    for (timed, (tag, _)) in MODES.iter().enumerate() {
        group.bench_function(format!("object_moved/{tag}"), |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                for _ in 0..iters {
                    step += 1;
                    let dx = (step % 2) as f32 * 0.25;
                    let moved = points.iter().map(|p| [p[0] + dx, p[1], p[2]]).collect();
                    writer.graph_mut().set_geometry(mesh_node, moved).unwrap();
                    let generation = writer.publish().unwrap().generation;
                    for turn in 0..MODES.len() {
                        let which = (turn + step as usize) % MODES.len();
                        let start = Instant::now();
                        let snapshot = receive(&mut readers[which], generation);
                        let view = snapshot.view();
                        black_box(nearest_nodes(&view, Scope::Layer(mesh), points[0], 1).unwrap());
                        if which == timed {
                            spent += start.elapsed();
                        }
                    }
                }
                spent
            })
        });
    }
    drop(readers);
    let mut attach = 0usize;
    for (timed, (tag, _)) in MODES.iter().enumerate() {
        group.bench_function(format!("first_snapshot/{tag}"), |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                for _ in 0..iters {
                    attach += 1;
                    for turn in 0..MODES.len() {
                        let which = (turn + attach) % MODES.len();
                        let start = Instant::now();
                        let mut fresh = open(scene, &prefix, MODES[which].1);
                        black_box(receive(&mut fresh, writer.generation()).view().node_count());
                        if which == timed {
                            spent += start.elapsed();
                        }
                    }
                }
                spent
            })
        });
    }
    group.finish();
    drop(writer);
    // The per-prefix counter iceoryx2 keeps by design.
    for entry in std::fs::read_dir("/dev/shm")
        .into_iter()
        .flatten()
        .flatten()
    {
        if entry.file_name().to_string_lossy().starts_with(&prefix) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

criterion_group!(benches, reader_copy);
criterion_main!(benches);
