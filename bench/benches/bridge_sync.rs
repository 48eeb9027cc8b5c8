//! The bridge's work on a full-office message after decoding (`ygg bridge zmq`, the
//! build path): the message's graph built in the mint layout, then the live graph brought
//! to equal it with `SceneGraph::sync_to` (the target borrowed: indexes it changes much are
//! rebuilt) or `sync_to_owned` (the target taken: its trees are adopted, as the bridge
//! does). Two messages: the whole office translated by a centimetre (every node and mesh
//! vertex moved, the layers kept), and the office arriving after a small office (most
//! layers new). Each benchmark times one step; the copies of the live graph (and of the
//! target, when taken) are made outside the timing in every iteration.
#![expect(clippy::unwrap_used, reason = "acceptable in benchmarks")]
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use ygg_dsg::DsgGraph;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::office::{OfficeParams, generate};
use ygg_store::SceneGraph;

/// `g` translated by `dx` metres along x: every node, box and mesh vertex.
fn shifted(g: &DsgGraph, dx: f32) -> DsgGraph {
    let mut g = g.clone();
    for n in &mut g.nodes {
        n.position[0] += dx;
        if let Some(b) = n.bbox.as_mut() {
            b.min[0] += dx;
            b.max[0] += dx;
        }
    }
    if let Some(m) = g.mesh.as_mut() {
        for p in &mut m.points {
            p[0] += dx;
        }
    }
    g
}

fn bridge_sync(c: &mut Criterion) {
    let office = generate(OfficeParams {
        seed: 7,
        scale: 1.0,
    });
    let moved = shifted(&office, 0.01);
    // A small office (a room or two): the full office's layers are then mostly new.
    let small = generate(OfficeParams {
        seed: 7,
        scale: 0.01,
    });
    let live_office = layout::build(&office, Layout::Mint).unwrap();
    let live_small = layout::build(&small, Layout::Mint).unwrap();

    let mut group = c.benchmark_group("bridge_sync");
    group.sample_size(10);
    group.bench_function("office_moved/build", |b| {
        b.iter(|| black_box(layout::build(&moved, Layout::Mint).unwrap()));
    });
    let target_moved = layout::build(&moved, Layout::Mint).unwrap();
    group.bench_function("office_moved/sync_to", |b| {
        b.iter_batched(
            || live_office.clone(),
            |mut live: SceneGraph| {
                black_box(live.sync_to(&target_moved).unwrap());
                live
            },
            BatchSize::LargeInput,
        );
    });
    let target_office = live_office.clone();
    group.bench_function("office_new/sync_to", |b| {
        b.iter_batched(
            || live_small.clone(),
            |mut live: SceneGraph| {
                black_box(live.sync_to(&target_office).unwrap());
                live
            },
            BatchSize::LargeInput,
        );
    });
    group.bench_function("office_moved/sync_to_owned", |b| {
        b.iter_batched(
            || (live_office.clone(), target_moved.clone()),
            |(mut live, target): (SceneGraph, SceneGraph)| {
                black_box(live.sync_to_owned(target).unwrap());
                live
            },
            BatchSize::LargeInput,
        );
    });
    group.bench_function("office_new/sync_to_owned", |b| {
        b.iter_batched(
            || (live_small.clone(), target_office.clone()),
            |(mut live, target): (SceneGraph, SceneGraph)| {
                black_box(live.sync_to_owned(target).unwrap());
                live
            },
            BatchSize::LargeInput,
        );
    });
    group.finish();
}

criterion_group!(benches, bridge_sync);
criterion_main!(benches);
