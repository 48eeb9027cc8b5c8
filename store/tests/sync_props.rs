//! Property tests of `SceneGraph::sync_to`: after it the graph equals the target (every
//! accessor, layers matched by name), its invariants and indexes hold, a layer whose
//! content did not differ keeps its generation, and a second sync changes nothing.

mod common;

use common::{Op, apply, op, seeded_graph};
use proptest::prelude::*;
use std::collections::BTreeMap;
use ygg_store::query;
use ygg_store::{LayerId, SceneGraph, SceneView};

/// The content of one layer, by name: what its archived segment holds, with the layer
/// names of every node a row refers to (a row that names a node which moved layers is
/// rebuilt, so that counts as a change). `with_dag` adds the layer's DAG neighbours.
fn layer_fingerprint(g: &SceneGraph, l: LayerId, with_dag: bool) -> String {
    let name = |l: LayerId| g.layer_name(l).unwrap_or("?").to_owned();
    let layer_of = |id| g.node(id).map(|n| name(g.node_layer(n)));
    let mut out = format!("layer {:?} index {}\n", name(l), g.layer_index(l).is_some());
    if with_dag {
        let mut parents: Vec<_> = g.layer_parents(l).into_iter().map(name).collect();
        let mut children: Vec<_> = g.layer_children(l).into_iter().map(name).collect();
        parents.sort_unstable();
        children.sort_unstable();
        out += &format!("  dag {parents:?} {children:?}\n");
    }
    let mut nodes: Vec<_> = g.layer_nodes(l).map(|n| g.node_id(n)).collect();
    nodes.sort_unstable();
    for id in nodes {
        let n = g.node(id).expect("listed");
        let mut labels: Vec<_> = g.labels(n).collect();
        labels.sort_unstable();
        let mut features: Vec<_> = g.features(n).map(|(k, f)| format!("{k}={f:?}")).collect();
        features.sort_unstable();
        let out_edges: Vec<_> = g.out_edges(n).collect();
        let in_edges: Vec<_> = g.in_edges(n).collect();
        let children: Vec<_> = g.children(n).iter().map(|&c| (c, layer_of(c))).collect();
        let index = g.node_index(id).is_some().then(|| {
            query::subtree(&g, id)
                .into_iter()
                .map(|m| (m, layer_of(m), g.node(m).map(|m| g.points(m).to_vec())))
                .collect::<Vec<_>>()
        });
        out += &format!(
            "  {id} pts {:?} parent {:?} children {children:?} box {:?} {:?} labels {labels:?} \
             features {features:?} out {out_edges:?} in {in_edges:?} index {index:?}\n",
            g.points(n),
            g.parent(n).map(|p| (p, layer_of(p))),
            g.bounding_box_enabled(id),
            g.aabb(n),
        );
    }
    out
}

/// Every layer's fingerprint, by layer name.
fn fingerprints(g: &SceneGraph, with_dag: bool) -> BTreeMap<String, String> {
    g.layers()
        .map(|l| {
            (
                g.layer_name(l).unwrap().to_owned(),
                layer_fingerprint(g, l, with_dag),
            )
        })
        .collect()
}

fn generations(g: &SceneGraph) -> BTreeMap<String, u64> {
    g.layers()
        .map(|l| {
            (
                g.layer_name(l).unwrap().to_owned(),
                g.layer_generation(l).unwrap(),
            )
        })
        .collect()
}

fn build(seed: u8, ops: &[Op]) -> SceneGraph {
    let mut g = seeded_graph(seed);
    for op in ops {
        let _ = apply(&mut g, op);
    }
    g
}

/// Syncs `g` to `target` and checks every property; returns the report.
fn check_sync(mut g: SceneGraph, target: &SceneGraph) -> Result<(), TestCaseError> {
    let before = fingerprints(&g, false);
    let gens = generations(&g);
    let report = g
        .sync_to(target)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    if let Err(e) = g.check_invariants() {
        return Err(TestCaseError::fail(format!("invariants after sync: {e}")));
    }
    prop_assert_eq!(fingerprints(&g, true), fingerprints(target, true));
    let after = fingerprints(&g, false);
    let new_gens = generations(&g);
    for (name, fp) in &after {
        let unchanged = before.get(name) == Some(fp);
        let same_generation = gens.get(name) == new_gens.get(name);
        prop_assert_eq!(
            unchanged,
            same_generation,
            "layer {} unchanged {} but generation {:?} -> {:?}",
            name,
            unchanged,
            gens.get(name),
            new_gens.get(name)
        );
        prop_assert_eq!(!same_generation, report.changed_layers.contains(name));
    }
    // Idempotent: a second sync finds nothing to do.
    let again = g
        .sync_to(target)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    prop_assert!(again.is_empty(), "second sync changed {:?}", again);
    prop_assert_eq!(generations(&g), new_gens);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// Two unrelated random graphs.
    #[test]
    fn sync_to_an_unrelated_graph(
        a in 0u8..20,
        ops_a in prop::collection::vec(op(), 0..120),
        b in 0u8..20,
        ops_b in prop::collection::vec(op(), 0..120),
    ) {
        check_sync(build(a, &ops_a), &build(b, &ops_b))?;
    }

    /// A graph and a few edits of it (the bridge's case: a stream of full states that
    /// differ a little).
    #[test]
    fn sync_to_an_edited_copy(
        a in 0u8..20,
        ops_a in prop::collection::vec(op(), 0..160),
        edits in prop::collection::vec(op(), 0..6),
    ) {
        let g = build(a, &ops_a);
        let mut target = g.clone();
        for op in &edits {
            let _ = apply(&mut target, op);
        }
        check_sync(g, &target)?;
    }
}

#[test]
fn sync_of_equal_graphs_touches_nothing() {
    let g = build(12, &[]);
    let mut copy = g.clone();
    let report = copy.sync_to(&g).unwrap();
    assert!(report.is_empty(), "{report:?}");
    let mut empty = SceneGraph::new();
    let report = empty.sync_to(&g).unwrap();
    assert_eq!(report.layers_added, 4);
    assert_eq!(report.nodes_added, 12);
    assert_eq!(report.changed_layers.len(), 4);
}
