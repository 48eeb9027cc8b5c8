//! Store benchmarks (issue: data model and archived snapshot): update latency with and
//! without bounding boxes, label query latency (frequent, rare, absent) on the live
//! graph and the archive, and validated open of a ~40 MB snapshot.
#![expect(clippy::unwrap_used, reason = "acceptable in benchmarks")]
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use ygg_store::query::nodes_with_label;
use ygg_store::{NodeId, SceneGraph, SceneView, Scope, SnapshotFile};

/// Rooms (with boxes when `boxes`) nesting `n` objects of one point each; labels
/// "common" on every 2nd object, "rare" on one.
fn scene(n: u64, boxes: bool) -> SceneGraph {
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").unwrap();
    let objects = g.add_layer("objects").unwrap();
    g.add_layer_edge(rooms, objects).unwrap();
    for r in 0..9 {
        g.add_node(NodeId(r), rooms).unwrap();
        if boxes {
            g.enable_bounding_box(NodeId(r)).unwrap();
        }
    }
    for i in 0..n {
        let id = NodeId(100 + i);
        g.add_node(id, objects).unwrap();
        g.set_geometry(id, vec![point(i)]).unwrap();
        g.nest(NodeId(i % 9), id).unwrap();
        if i % 2 == 0 {
            g.add_label(id, "common").unwrap();
        }
    }
    g.add_label(NodeId(100 + n / 2), "rare").unwrap();
    g
}

fn point(i: u64) -> [f32; 3] {
    let h = i.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    [
        (h % 4000) as f32 / 100.0,
        (h >> 20) as f32 % 25.0,
        (h >> 40) as f32 % 3.0,
    ]
}

fn updates(c: &mut Criterion) {
    let mut group = c.benchmark_group("update");
    for boxes in [false, true] {
        let tag = if boxes { "with_boxes" } else { "no_boxes" };
        let mut g = scene(100_000, boxes);
        let objects = g.layer_id("objects").unwrap();
        let mut next = 10_000_000u64;
        group.bench_function(format!("add_node/{tag}"), |b| {
            b.iter(|| {
                next += 1;
                g.add_node(black_box(NodeId(next)), objects).unwrap();
            })
        });
        let mut i = 0u64;
        group.bench_function(format!("move_node/{tag}"), |b| {
            b.iter(|| {
                i += 1;
                let id = NodeId(100 + i % 100_000);
                g.set_geometry(id, vec![point(i + 7)]).unwrap();
            })
        });
        let mut k = 0u64;
        group.bench_function(format!("add_edge/{tag}"), |b| {
            b.iter(|| {
                k += 1;
                let (s, t) = (
                    NodeId(100 + k % 100_000),
                    NodeId(100 + (k * 7919 + 1) % 100_000),
                );
                let _ = g.add_edge(s, t, "near");
            })
        });
    }
    group.finish();
}

fn labels(c: &mut Criterion) {
    let g = scene(100_000, false);
    let snapshot = g.to_snapshot();
    let view = snapshot.view();
    let mut group = c.benchmark_group("label_query");
    for label in ["common", "rare", "absent"] {
        group.bench_function(format!("live/{label}"), |b| {
            b.iter(|| nodes_with_label(&g, Scope::Graph, black_box(label)))
        });
        group.bench_function(format!("archived/{label}"), |b| {
            b.iter(|| nodes_with_label(&view, Scope::Graph, black_box(label)))
        });
    }
    group.finish();
}

fn open(c: &mut Criterion) {
    // ~40 MB: 200k nodes of 16 points each (the shape of an object mesh layer).
    let mut g = SceneGraph::new();
    let mesh = g.add_layer("mesh").unwrap();
    for i in 0..200_000u64 {
        g.add_node(NodeId(i), mesh).unwrap();
        g.set_geometry(NodeId(i), (0..16).map(|k| point(i * 16 + k)).collect())
            .unwrap();
    }
    let dir = tempfile_dir();
    let path = dir.join("open.ygg");
    g.save(&path).unwrap();
    let bytes = std::fs::metadata(&path).unwrap().len();
    let mut group = c.benchmark_group("open_validate");
    group.throughput(Throughput::Bytes(bytes));
    group.bench_function(format!("{:.1}MB", bytes as f64 / 1e6), |b| {
        b.iter_batched(
            || (),
            |_| SnapshotFile::open(&path).unwrap(),
            BatchSize::SmallInput,
        )
    });
    group.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

fn tempfile_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("ygg-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The writer's per-layer publish work and the reader's per-layer validation, on the
/// office's places layer (1,130 nodes with edges and nesting).
fn segments(c: &mut Criterion) {
    let dsg = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams {
        seed: 7,
        scale: 1.0,
    });
    let g = ygg_dsg::layout::build(&dsg, ygg_dsg::layout::Layout::Mint).unwrap();
    let mut group = c.benchmark_group("segment");
    for name in ["PLACES", "AGENTS"] {
        let layer = g.layer_id(name).unwrap();
        let segment = g.layer_segment(layer);
        let len = segment.archived_len();
        let mut buf = ygg_store::snapshot::SegmentBytes::with_capacity(len);
        buf.resize(len, 0);
        group.bench_function(format!("build/{name}"), |b| {
            b.iter(|| g.layer_segment(layer))
        });
        group.bench_function(format!("archived_len/{name}"), |b| {
            b.iter(|| segment.archived_len())
        });
        group.bench_function(format!("archive_into/{name}"), |b| {
            b.iter(|| segment.archive_into(&mut buf).unwrap())
        });
        // The writer's path: one node of the layer moved, then its segment rebuilt
        // from the previous one (only the changed rows).
        let mut live = g.clone();
        let moved = NodeId(segment.ids[segment.ids.len() / 2]);
        let at = live.points(live.node(moved).unwrap()).to_vec();
        let mut step = 0u32;
        let mut cache = ygg_store::snapshot::SegmentCache::new();
        group.bench_function(format!("cached_after_move/{name}"), |b| {
            b.iter(|| {
                step += 1;
                let dx = if step.is_multiple_of(2) { 0.0 } else { 0.01 };
                let points = at.iter().map(|p| [p[0] + dx, p[1], p[2]]).collect();
                live.set_geometry(moved, points).unwrap();
                cache.layer_segment(&mut live, layer).ids.len()
            })
        });
        segment.archive_into(&mut buf).unwrap();
        group.bench_function(format!("validate/{name}"), |b| {
            b.iter(|| {
                ygg_store::snapshot::validate_layer(&buf, name)
                    .unwrap()
                    .ids
                    .len()
            })
        });
    }
    group.finish();
}

/// The writer's publish work when SLAM appends 64 vertices to the office's largest
/// unclaimed mesh node (and takes them off again, alternately): the layer brought up to
/// date and everything that changed archived, with the layer's point column in chunks
/// of 32,768 points (only the last chunk changes) and in one piece (the whole layer).
fn mesh_append(c: &mut Criterion) {
    use ygg_store::snapshot::{MAX_POINT_CHUNK_LEN, POINT_CHUNK_LEN, SegmentBytes, SegmentCache};
    let dsg = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams {
        seed: 7,
        scale: 1.0,
    });
    let g = ygg_dsg::layout::build(&dsg, ygg_dsg::layout::Layout::Mint).unwrap();
    let (layer, node) = g
        .layers()
        .filter(|&l| {
            g.layer_name(l)
                .is_some_and(|n| n.ends_with("unclaimed-mesh"))
        })
        .flat_map(|l| g.layer_nodes(l).map(move |n| (l, n)))
        .max_by_key(|&(_, n)| g.points(n).len())
        .map(|(l, n)| (l, g.node_id(n)))
        .unwrap();
    let base = g.points(g.node(node).unwrap()).to_vec();
    let mut group = c.benchmark_group("mesh_append");
    for (name, chunk_len) in [
        ("chunked", POINT_CHUNK_LEN),
        ("one_piece", MAX_POINT_CHUNK_LEN),
    ] {
        let mut live = g.clone();
        let mut cache = SegmentCache::with_point_chunk_len(chunk_len);
        let mut buf = SegmentBytes::with_capacity(1 << 20);
        let mut sent = std::collections::HashMap::new();
        let mut step = 0u64;
        group.bench_function(name, |b| {
            b.iter(|| {
                step += 1;
                let mut points = base.clone();
                if step.is_multiple_of(2) {
                    points.extend_from_slice(&base[..64]);
                }
                live.set_geometry(node, points).unwrap();
                let published = cache.published_layer(&mut live, layer);
                // One part: the cache keeps the layer in one piece.
                let published = &published.parts()[0];
                let mut bytes = published.segment.archived_len();
                buf.resize(bytes, 0);
                published.segment.archive_into(&mut buf).unwrap();
                for (i, (id, generation)) in published.chunks().enumerate() {
                    if sent.insert(id, generation) != Some(generation) {
                        let chunk = published.chunk(i);
                        let len = chunk.archived_len();
                        buf.resize(len, 0);
                        bytes += chunk.archive_into(&mut buf).unwrap();
                    }
                }
                bytes
            })
        });
    }
    group.finish();
}

criterion_group!(benches, updates, labels, open, segments, mesh_append);
criterion_main!(benches);
