//! Property tests of `SceneGraph::sync_to` and `sync_to_owned`: after it the graph equals
//! the target (every accessor, layers matched by name), its invariants and indexes hold
//! (the trees it rebuilt or adopted hold exactly their points), a layer whose content did
//! not differ keeps its generation, and a second sync changes nothing.

mod common;

use common::{Op, apply, op, seeded_graph};
use proptest::prelude::*;
use std::collections::BTreeMap;
use ygg_store::{SceneGraph, SceneView};
use ygg_testkit::fingerprint::layer_fingerprints;

/// Every layer's fingerprint by name, and each node's bounding-box flag (which a view
/// cannot tell for a node whose sub-tree has no point).
fn fingerprints(g: &SceneGraph, with_dag: bool) -> BTreeMap<String, String> {
    let mut out = layer_fingerprints(g, with_dag);
    for l in g.layers() {
        let fp = out.get_mut(g.layer_name(l).unwrap()).unwrap();
        let mut ids: Vec<_> = g.layer_nodes(l).map(|n| g.node_id(n)).collect();
        ids.sort_unstable();
        let flags: Vec<_> = ids.iter().map(|&id| g.bounding_box_enabled(id)).collect();
        *fp += &format!("boxes enabled {flags:?}\n");
    }
    out
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

/// Syncs `g` to `target` (`owned`: by `sync_to_owned`, on a copy) and checks every
/// property.
fn check_sync(mut g: SceneGraph, target: &SceneGraph, owned: bool) -> Result<(), TestCaseError> {
    let before = fingerprints(&g, false);
    let gens = generations(&g);
    let report = if owned {
        g.sync_to_owned(target.clone())
    } else {
        g.sync_to(target)
    }
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
        owned in any::<bool>(),
    ) {
        check_sync(build(a, &ops_a), &build(b, &ops_b), owned)?;
    }

    /// A graph and a few edits of it (the bridge's case: a stream of full states that
    /// differ a little).
    #[test]
    fn sync_to_an_edited_copy(
        a in 0u8..20,
        ops_a in prop::collection::vec(op(), 0..160),
        edits in prop::collection::vec(op(), 0..6),
        owned in any::<bool>(),
    ) {
        let g = build(a, &ops_a);
        let mut target = g.clone();
        for op in &edits {
            let _ = apply(&mut target, op);
        }
        check_sync(g, &target, owned)?;
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
