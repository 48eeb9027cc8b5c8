//! Recordings (`store/src/recording`): every recorded cut answers as the graph did when it
//! was published, `changes` equals a comparison of the whole graphs, a torn or damaged
//! file is read up to its last complete cut without a panic, bounds drop whole files.

mod common;
#[path = "common/fingerprint.rs"]
mod fingerprint;
#[path = "common/published.rs"]
#[allow(
    dead_code,
    reason = "the recording tests publish; they do not join by hand"
)]
mod published;

use common::{apply, op, seeded_graph};
use fingerprint::fingerprint;
use proptest::prelude::*;
use std::collections::BTreeSet;
use ygg_store::recording::{
    CutToRecord, RecordedSegment, Recording, RecordingOptions, RecordingWriter, SceneChanges,
};
use ygg_store::snapshot::STRUCTURE_SEGMENT_ID;
use ygg_store::{NodeId, SceneGraph, SceneView};

/// Publishes `g` with `p` and appends the cut (generation `generation`) to `w`.
fn record(
    p: &mut published::Publisher,
    g: &mut SceneGraph,
    w: &mut RecordingWriter,
    generation: u64,
) {
    let (manifest, structure, ids) = p.publish(g);
    let structure_generation = p.segments.structure().expect("published").0.generation;
    let mut segments: Vec<RecordedSegment<'_>> = ids
        .iter()
        .map(|id| RecordedSegment {
            id: *id,
            generation: p.held[id].0,
            bytes: &p.held[id].1,
        })
        .collect();
    segments.push(RecordedSegment {
        id: STRUCTURE_SEGMENT_ID,
        generation: structure_generation,
        bytes: &structure,
    });
    segments.sort_by_key(|s| s.id);
    let cut = CutToRecord {
        generation,
        session: 7,
        writer_unix_ns: 1_000 * generation,
        manifest: &manifest,
        segments,
    };
    w.append_cut(&cut).expect("appended");
}

/// What changed from `a` to `b`, by comparing every node of both graphs.
fn brute_force_changes<V: SceneView>(a: &V, b: &V, tolerance: f32) -> SceneChanges {
    let ids = |v: &V| -> BTreeSet<NodeId> {
        v.layers()
            .flat_map(|l| v.layer_nodes(l).map(|n| v.node_id(n)).collect::<Vec<_>>())
            .collect()
    };
    let (ia, ib) = (ids(a), ids(b));
    let mut c = SceneChanges::default();
    for id in ia.union(&ib) {
        let edges = |v: &V| -> BTreeSet<(NodeId, NodeId)> {
            v.node(*id).map_or_else(BTreeSet::new, |n| {
                v.out_edges(n).map(|e| (e.source, e.target)).collect()
            })
        };
        let (ea, eb) = (edges(a), edges(b));
        c.edges_added.extend(eb.difference(&ea));
        c.edges_removed.extend(ea.difference(&eb));
        match (a.node(*id), b.node(*id)) {
            (None, Some(_)) => c.nodes_added.push(*id),
            (Some(_), None) => c.nodes_removed.push(*id),
            (Some(_), Some(_)) => {
                let pos = |v: &V| {
                    let n = v.node(*id).unwrap();
                    v.points(n)
                        .aabb()
                        .or_else(|| v.aabb(n))
                        .map(|b| std::array::from_fn::<f32, 3, _>(|i| (b.min[i] + b.max[i]) / 2.0))
                };
                if let (Some(p), Some(q)) = (pos(a), pos(b))
                    && ygg_store::distance_squared(&p, &q) > tolerance * tolerance
                {
                    c.nodes_moved.push(ygg_store::recording::NodeMove {
                        id: *id,
                        from: p,
                        to: q,
                    });
                }
                let labels = |v: &V| {
                    let mut l: Vec<String> =
                        v.labels(v.node(*id).unwrap()).map(str::to_owned).collect();
                    l.sort_unstable();
                    l
                };
                if labels(a) != labels(b) {
                    c.nodes_relabelled.push(ygg_store::recording::Relabel {
                        id: *id,
                        from: labels(a),
                        to: labels(b),
                    });
                }
            }
            (None, None) => unreachable!("listed by one of the graphs"),
        }
    }
    c
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Every cut recorded answers as the graph did, and `changes` between any two cuts
    /// equals the comparison of the two whole graphs; small files force a file per few
    /// cuts (each file self-contained).
    #[test]
    fn recorded_cuts_answer_as_the_graph_did(
        steps in prop::collection::vec(prop::collection::vec(op(), 0..6), 1..12),
        small_files in any::<bool>(),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let options = RecordingOptions {
            file_bytes: if small_files { 4096 } else { 64 << 20 },
            ..RecordingOptions::default()
        };
        let mut w = RecordingWriter::create(dir.path(), options).unwrap();
        let mut g = seeded_graph(12);
        let mut p = published::Publisher::new();
        let mut graphs = Vec::new();
        for (i, ops) in steps.iter().enumerate() {
            for op in ops {
                let _ = apply(&mut g, op);
            }
            record(&mut p, &mut g, &mut w, i as u64 + 1);
            graphs.push(g.to_snapshot());
        }
        drop(w);
        let rec = Recording::open(dir.path()).unwrap();
        prop_assert_eq!(rec.cuts().len(), steps.len());
        prop_assert!(rec.defects().is_empty());
        for (i, file) in graphs.iter().enumerate() {
            let scene = rec.scene(i).unwrap();
            prop_assert_eq!(fingerprint(scene.view()), fingerprint(&file.view()), "cut {}", i);
            prop_assert_eq!(rec.cut_at_generation(i as u64 + 1), Some(i));
            prop_assert_eq!(rec.cut_at_time(1_000 * (i as u64 + 1) + 999), Some(i));
        }
        let last = graphs.len() - 1;
        for (a, b) in [(0, last), (last / 2, last), (last, 0)] {
            let got = rec.changes(a, b, 0.25).unwrap();
            let mut want = brute_force_changes(&graphs[a].view(), &graphs[b].view(), 0.25);
            want.segments_compared = got.segments_compared;
            prop_assert_eq!(got, want, "changes {} -> {}", a, b);
        }
    }
}

/// A recording of `cuts` cuts of a growing graph (one file with the default options).
fn growing_recording(cuts: u64, options: RecordingOptions) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let mut w = RecordingWriter::create(dir.path(), options).unwrap();
    let mut g = seeded_graph(8);
    let mut p = published::Publisher::new();
    let layer = g.layers().next().unwrap();
    for i in 0..cuts {
        g.add_node(NodeId(90_000 + i), layer).unwrap();
        g.set_geometry(NodeId(90_000 + i), vec![[i as f32, 0.0, 1.0]])
            .unwrap();
        record(&mut p, &mut g, &mut w, i + 1);
    }
    dir
}

fn only_file(dir: &std::path::Path) -> std::path::PathBuf {
    let files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    files[0].clone()
}

#[test]
fn a_torn_tail_is_ignored_at_every_length() {
    let dir = growing_recording(6, RecordingOptions::default());
    let path = only_file(dir.path());
    let whole = std::fs::read(&path).unwrap();
    let full = Recording::open(dir.path()).unwrap();
    let ends: Vec<u64> = full
        .cuts()
        .iter()
        .scan(0, |_, c| Some(c.bytes_added))
        .collect();
    assert_eq!(ends.len(), 6);
    let mut last_count = 0;
    for len in (0..=whole.len()).step_by(7).chain([whole.len()]) {
        std::fs::write(&path, &whole[..len]).unwrap();
        match Recording::open(dir.path()) {
            Ok(rec) => {
                assert!(
                    rec.defects().is_empty(),
                    "a torn tail is not damage: {:?}",
                    rec.defects()
                );
                assert!(
                    rec.cuts().len() >= last_count,
                    "cuts never disappear as the file grows"
                );
                last_count = rec.cuts().len();
                for i in 0..rec.cuts().len() {
                    // Cut i holds the seeded nodes and i + 1 added ones.
                    assert_eq!(rec.scene(i).unwrap().view().node_count(), 8 + i + 1);
                }
            }
            Err(e) => assert!(
                last_count == 0,
                "a longer file lost every cut after {last_count} were readable: {e}"
            ),
        }
    }
    assert_eq!(last_count, 6);
}

#[test]
fn damaged_bytes_give_errors_or_fewer_cuts_never_a_wrong_scene() {
    let dir = growing_recording(5, RecordingOptions::default());
    let path = only_file(dir.path());
    let whole = std::fs::read(&path).unwrap();
    for at in (0..whole.len()).step_by(13) {
        let mut bad = whole.clone();
        bad[at] ^= 0x5a;
        std::fs::write(&path, &bad).unwrap();
        let Ok(rec) = Recording::open(dir.path()) else {
            continue;
        };
        for i in 0..rec.cuts().len() {
            if let Ok(scene) = rec.scene(i) {
                // Every byte of a record is under its CRC: a cut that opens is the one
                // recorded.
                assert_eq!(scene.view().node_count(), 8 + i + 1, "byte {at} flipped");
            }
        }
    }
}

#[test]
fn bounds_drop_whole_old_files_and_what_stays_opens() {
    let options = RecordingOptions {
        file_bytes: 4096,
        max_bytes: Some(1),
        max_age: None,
    };
    // A bound of one byte keeps only the file being written.
    assert_only_the_newest_file_is_left(&growing_recording(40, options), 40);
}

/// Asserts that the recording in `dir` of `cuts` cuts of [`growing_recording`] holds one
/// file, whose last cut opens with every node.
fn assert_only_the_newest_file_is_left(dir: &tempfile::TempDir, cuts: u64) {
    let rec = Recording::open(dir.path()).unwrap();
    assert_eq!(rec.files().count(), 1);
    let last = rec.cuts().len() - 1;
    assert_eq!(rec.cuts()[last].generation, cuts);
    assert_eq!(
        rec.scene(last).unwrap().view().node_count(),
        8 + cuts as usize
    );
}

#[test]
fn a_folder_that_is_not_a_recording_is_refused_with_its_name() {
    let dir = tempfile::tempdir().unwrap();
    let err = Recording::open(dir.path()).unwrap_err().to_string();
    assert!(err.contains("no complete cut"), "{err}");
    std::fs::write(dir.path().join("notes.txt"), b"hello").unwrap();
    let err = Recording::open(dir.path()).unwrap_err().to_string();
    assert!(err.contains("notes.txt"), "{err}");
    let missing = dir.path().join("absent");
    let err = Recording::open(&missing).unwrap_err().to_string();
    assert!(err.contains("absent"), "{err}");
}

#[test]
fn an_age_bound_drops_files_whose_newest_cut_is_older() {
    let options = RecordingOptions {
        file_bytes: 4096,
        max_bytes: None,
        max_age: Some(std::time::Duration::from_nanos(1)),
    };
    // Every closed file is older than a nanosecond: only the one being written is left.
    assert_only_the_newest_file_is_left(&growing_recording(20, options), 20);
}
