//! Property tests: random mutation sequences keep every invariant, refused mutations
//! leave the graph unchanged, and every query answers the same on the live graph, on its
//! saved-and-reopened snapshot, and on the parts a publishing writer sends.

mod common;
#[path = "common/fingerprint.rs"]
mod fingerprint;
#[path = "common/published.rs"]
mod published;

use common::{LABELS, apply, op, seeded_graph};
use fingerprint::fingerprint;
use proptest::prelude::*;
use std::collections::BTreeMap;
use ygg_store::query::{self, Direction};
use ygg_store::snapshot::{SegmentCache, archive};
use ygg_store::{FeatureRef, NodeId, SceneGraph, SceneView, Scope};
use ygg_testkit::fingerprint::{manifest_fingerprint, segment_fingerprint, structure_fingerprint};

/// Answers of every non-spatial query on a view, for comparing backends.
fn query_answers<V: SceneView>(v: &V) -> String {
    let mut out = String::new();
    let mut scopes = vec![Scope::Graph];
    scopes.extend(v.layers().map(Scope::Layer));
    for scope in scopes {
        for label in LABELS.iter().chain(&["absent"]) {
            out += &format!(
                "{scope:?} label {label} {:?}\n",
                query::nodes_with_label(v, scope, label)
            );
        }
        out += &format!(
            "{scope:?} having {:?}\n",
            query::nodes_having(v, scope, &["name"])
        );
        out += &format!(
            "{scope:?} having2 {:?}\n",
            query::nodes_having(v, scope, &["name", "open"])
        );
        out += &format!(
            "{scope:?} matching {:?}\n",
            query::nodes_matching(v, scope, &[("name", FeatureRef::Str("v1"))])
        );
        out += &format!(
            "{scope:?} matching-bool {:?}\n",
            query::nodes_matching(v, scope, &[("open", FeatureRef::Bool(true))])
        );
        out += &format!(
            "{scope:?} doors {:?}\n",
            query::edges_matching(v, scope, "door")
        );
    }
    for i in 0..24u64 {
        let id = NodeId(i * 1000 + 7);
        out += &format!(
            "{id}: from {:?} to {:?} parent {:?} children {:?} subtree {:?} bfs {:?} dfs {:?} bfs-u {:?} path {:?}\n",
            query::edges_from(v, id),
            query::edges_to(v, id),
            query::parent(v, id),
            query::children(v, id),
            query::subtree(v, id),
            query::bfs(v, id, Direction::Outgoing),
            query::dfs(v, id, Direction::Outgoing),
            query::bfs(v, id, Direction::Undirected),
            query::shortest_path(
                v,
                id,
                NodeId(((i + 5) % 24) * 1000 + 7),
                Direction::Undirected
            ),
        );
    }
    let half: Vec<NodeId> = (0..24u64)
        .step_by(2)
        .map(|i| NodeId(i * 1000 + 7))
        .collect();
    out += &fingerprint(&query::subgraph(v, &half));
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn random_mutations_keep_invariants_and_refused_ones_change_nothing(seed in 0u8..20, ops in prop::collection::vec(op(), 1..160)) {
        let mut g = seeded_graph(seed);
        for op in &ops {
            let before = fingerprint(&g);
            let result = apply(&mut g, op);
            if let Err(e) = g.check_invariants() {
                panic!("after {op:?} ({result:?}): {e}");
            }
            if result.is_err() {
                prop_assert_eq!(&before, &fingerprint(&g), "refused {:?} changed the graph", op);
            }
        }
    }

    #[test]
    fn queries_agree_on_live_graph_and_reopened_snapshot(seed in 0u8..20, ops in prop::collection::vec(op(), 1..160)) {
        let mut g = seeded_graph(seed);
        for op in &ops {
            let _ = apply(&mut g, op);
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.ygg");
        g.save(&path).unwrap();
        let file = ygg_store::SnapshotFile::open(&path).unwrap();
        let view = file.view();
        prop_assert_eq!(fingerprint(&g), fingerprint(&view));
        prop_assert_eq!(query_answers(&g), query_answers(&view));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Layers split into parts of a few rows (appends, edits, removals and nesting
    /// moving rows between parts, parts sealed, merged, split and dropped), published
    /// incrementally to a reader that keeps unchanged parts: every cut answers every
    /// query as the live graph does.
    #[test]
    fn queries_agree_on_live_graph_and_published_parts(
        seed in 0u8..20,
        ops in prop::collection::vec(op(), 1..200),
        publish_every in 1usize..6,
    ) {
        let mut g = seeded_graph(seed);
        // In parts of a few rows, and (as a writer without parts sends them) in one piece.
        let mut publishers = [published::Publisher::new(), published::Publisher::one_piece()];
        for (i, op) in ops.iter().enumerate() {
            let _ = apply(&mut g, op);
            if i % publish_every == 0 || i + 1 == ops.len() {
                for publisher in &mut publishers {
                    let (manifest, structure, ids) = publisher.publish(&mut g);
                    let segments = publisher.validated(&manifest, &structure, &ids);
                    let view = segments.join().map_err(|e| TestCaseError::fail(format!("after op {i} ({op:?}): {e}")))?;
                    prop_assert_eq!(fingerprint(&g), fingerprint(&view), "after op {} ({:?})", i, op);
                    prop_assert_eq!(query_answers(&g), query_answers(&view), "after op {} ({:?})", i, op);
                }
            }
        }
    }

    /// The writer's incremental segments hold the same rows, indexes and postings as
    /// fresh ones, and its cached manifest (and the archived length it keeps) equals a
    /// fresh one, whatever the mutations between two publishes.
    #[test]
    fn cached_layer_segments_equal_fresh_ones(
        seed in 0u8..20,
        ops in prop::collection::vec(op(), 1..200),
        publish_every in 1usize..8,
    ) {
        let mut g = seeded_graph(seed);
        let mut cache = SegmentCache::new();
        let mut mark = g.touch_mark();
        let mut generations: BTreeMap<_, _> =
            g.layers().map(|l| (l, g.layer_generation(l))).collect();
        for (i, op) in ops.iter().enumerate() {
            let _ = apply(&mut g, op);
            if i % publish_every == 0 {
                // The touch log names every layer whose generation changed (or that is new).
                let touched = g.layers_touched_since(mark).expect("the graph's own mark");
                for l in g.layers() {
                    let generation = g.layer_generation(l);
                    if generations.get(&l) != Some(&generation) {
                        prop_assert!(touched.contains(&l), "layer {} changed, not listed", l);
                    }
                    generations.insert(l, generation);
                }
                mark = g.touch_mark();
                for l in g.layers().collect::<Vec<_>>() {
                    let fresh = segment_fingerprint(&g.layer_segment(l));
                    let cached = segment_fingerprint(cache.layer_segment(&mut g, l));
                    prop_assert_eq!(cached, fresh, "layer {} after op {} ({:?})", l, i, op);
                }
                // Only the touched layers' entries are refreshed when the structure held,
                // and the kept bytes are patched: they equal the manifest archived anew.
                let cut = cache.manifest_bytes(&g, i as u64, Some(&touched));
                let bytes = cut.manifest.to_vec();
                prop_assert_eq!(structure_fingerprint(cut.structure), structure_fingerprint(&g.structure(0)));
                prop_assert_eq!(cut.structure_bytes, &archive(cut.structure)[..]);
                let fresh = g.manifest(i as u64, cut.structure.generation);
                let cached = cache.manifest(&g, i as u64);
                prop_assert_eq!(manifest_fingerprint(cached), manifest_fingerprint(&fresh));
                prop_assert_eq!(&bytes[..], &archive(cached)[..]);
                prop_assert_eq!(bytes.len(), fresh.archived_len());
            }
        }
    }
}

#[test]
fn cycle_in_layer_dag_is_refused() {
    let mut g = SceneGraph::new();
    let a = g.add_layer("a").unwrap();
    let b = g.add_layer("b").unwrap();
    let c = g.add_layer("c").unwrap();
    g.add_layer_edge(a, b).unwrap();
    g.add_layer_edge(b, c).unwrap();
    assert_eq!(
        g.add_layer_edge(c, a),
        Err(ygg_store::GraphEditError::WouldCreateCycle {
            parent: c,
            child: a
        })
    );
    assert!(g.add_layer_edge(a, a).is_err());
}

#[test]
fn bounding_box_shrinks_when_the_extreme_point_moves_inward() {
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").unwrap();
    let objects = g.add_layer("objects").unwrap();
    g.add_layer_edge(rooms, objects).unwrap();
    g.add_node(NodeId(1), rooms).unwrap();
    g.enable_bounding_box(NodeId(1)).unwrap();
    for (id, x) in [(2, 0.0), (3, 5.0)] {
        g.add_node(NodeId(id), objects).unwrap();
        g.set_geometry(NodeId(id), vec![[x, 0.0, 0.0]]).unwrap();
        g.nest(NodeId(1), NodeId(id)).unwrap();
    }
    let b = |g: &SceneGraph| g.node(NodeId(1)).and_then(|n| g.aabb(n));
    assert_eq!(b(&g).unwrap().max[0], 5.0);
    g.set_geometry(NodeId(3), vec![[1.0, 0.0, 0.0]]).unwrap();
    assert_eq!(b(&g).unwrap().max[0], 1.0);
    g.remove_node(NodeId(3)).unwrap();
    assert_eq!(b(&g).unwrap().max[0], 0.0);
    g.unnest(NodeId(2)).unwrap();
    assert_eq!(b(&g), None);
    g.check_invariants().unwrap();
}

/// Nesting lives on the child's side: nesting and unnesting change the child's layer
/// only, and a node's children, spread over two layers below, come merged and ascending
/// from the snapshot as from the live graph.
#[test]
fn nesting_changes_only_the_child_layer() {
    let mut g = SceneGraph::new();
    let places = g.add_layer("places").unwrap();
    let poses = g.add_layer("poses").unwrap();
    let objects = g.add_layer("objects").unwrap();
    g.add_layer_edge(places, poses).unwrap();
    g.add_layer_edge(places, objects).unwrap();
    g.add_node(NodeId(1), places).unwrap();
    g.add_node(NodeId(2), places).unwrap();
    for (id, layer) in [
        (10, poses),
        (11, poses),
        (12, poses),
        (5, objects),
        (20, objects),
    ] {
        g.add_node(NodeId(id), layer).unwrap();
    }
    let (places_before, poses_before) = (
        g.layer_generation(places).unwrap(),
        g.layer_generation(poses).unwrap(),
    );
    for (parent, child) in [(1, 11), (1, 20), (2, 12), (1, 5), (1, 10)] {
        g.nest(NodeId(parent), NodeId(child)).unwrap();
    }
    assert_eq!(g.layer_generation(places).unwrap(), places_before);
    assert!(g.layer_generation(poses).unwrap() > poses_before);
    let ids = |v: Vec<NodeId>| v.into_iter().map(|n| n.0).collect::<Vec<_>>();
    let snapshot = g.to_snapshot();
    let view = snapshot.view();
    for (parent, want) in [(1, vec![5, 10, 11, 20]), (2, vec![12]), (10, vec![])] {
        assert_eq!(ids(query::children(&g, NodeId(parent))), want);
        assert_eq!(ids(query::children(&view, NodeId(parent))), want);
    }
    let places_before = g.layer_generation(places).unwrap();
    g.unnest(NodeId(10)).unwrap();
    g.remove_node(NodeId(20)).unwrap();
    assert_eq!(g.layer_generation(places).unwrap(), places_before);
    let snapshot = g.to_snapshot();
    assert_eq!(ids(query::children(&snapshot.view(), NodeId(1))), [5, 11]);
    assert_eq!(
        query::subtree(&snapshot.view(), NodeId(1)),
        query::subtree(&g, NodeId(1))
    );
}

/// Appending points equals setting the concatenation (points, boxes, layer and node
/// index answers); a non-finite appended point is refused with its index in the node's
/// list, changing nothing.
#[test]
fn appending_points_equals_setting_the_longer_list() {
    let build = || {
        let mut g = SceneGraph::new();
        let rooms = g.add_layer("rooms").unwrap();
        let mesh = g.add_layer("mesh").unwrap();
        g.add_layer_edge(rooms, mesh).unwrap();
        g.add_node(NodeId(1), rooms).unwrap();
        g.enable_bounding_box(NodeId(1)).unwrap();
        g.add_node(NodeId(2), mesh).unwrap();
        g.nest(NodeId(1), NodeId(2)).unwrap();
        g.enable_layer_index(mesh).unwrap();
        g.enable_node_index(NodeId(1)).unwrap();
        g
    };
    let grid = |k: usize| -> Vec<[f32; 3]> {
        (0..k)
            .map(|i| [(i % 7) as f32, (i % 5) as f32 * 0.5, (i / 35) as f32])
            .collect()
    };
    let (mut appended, mut set) = (build(), build());
    let mut all: Vec<[f32; 3]> = Vec::new();
    for (step, k) in [3, 40, 1, 200].into_iter().enumerate() {
        let tail: Vec<[f32; 3]> = grid(k)
            .into_iter()
            .map(|p| [p[0] + step as f32, p[1], p[2] - step as f32])
            .collect();
        appended.append_points(NodeId(2), &tail).unwrap();
        all.extend_from_slice(&tail);
        set.set_geometry(NodeId(2), all.clone()).unwrap();
        appended.check_invariants().unwrap();
        assert_eq!(
            fingerprint(&appended),
            fingerprint(&set),
            "after step {step}"
        );
        for c in [[0.0, 0.0, 0.0], [3.5, 1.0, -2.0], [9.0, 9.0, 9.0]] {
            assert_eq!(
                query::nearest_nodes(&appended, Scope::Graph, c, 3),
                query::nearest_nodes(&set, Scope::Graph, c, 3)
            );
            assert_eq!(
                query::nearest_in_subtree(&appended, NodeId(1), c, 3),
                query::nearest_in_subtree(&set, NodeId(1), c, 3)
            );
        }
    }
    let before = fingerprint(&appended);
    let had = all.len();
    assert_eq!(
        appended.append_points(NodeId(2), &[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0]]),
        Err(ygg_store::GraphEditError::NonFinitePoint {
            node: NodeId(2),
            index: had + 1
        })
    );
    assert_eq!(fingerprint(&appended), before);
}
