//! Incremental updates: on random edit sequences of the office, the update between two
//! graphs ([`ygg_dsg::update_between`]), applied to the first
//! ([`ygg_dsg::DsgGraph::apply_update`]) after a trip through Spark-DSG's binary encoding
//! (as `DsgUpdate.layer_contents` carries it), gives the second.

use proptest::prelude::*;
use ygg_dsg::office::{OfficeParams, generate};
use ygg_dsg::{
    DsgEdge, DsgGraph, DsgVersion, NodeKind, parse_binary_body, to_binary_body, update_between,
};

#[derive(Clone, Debug)]
enum Edit {
    Move(usize, f32),
    Rename(usize, usize),
    Copy(usize),
    Remove(usize),
    Connect(usize, usize),
    Disconnect(usize),
    Orphan(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => (any::<usize>(), -1.0f32..1.0).prop_map(|(i, d)| Edit::Move(i, d)),
        1 => (any::<usize>(), 0..12usize).prop_map(|(i, n)| Edit::Rename(i, n)),
        2 => any::<usize>().prop_map(Edit::Copy),
        2 => any::<usize>().prop_map(Edit::Remove),
        2 => (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::Connect(a, b)),
        1 => any::<usize>().prop_map(Edit::Disconnect),
        1 => any::<usize>().prop_map(Edit::Orphan),
    ]
}

fn change(g: &mut DsgGraph, e: &Edit) {
    let n = g.nodes.len();
    match *e {
        Edit::Move(i, d) => g.nodes[i % n].position[1] += d,
        // Agent poses have no name in Spark-DSG's binary encoding.
        Edit::Rename(i, len) if g.nodes[i % n].kind != NodeKind::Agent => {
            g.nodes[i % n].name = (len > 0).then(|| "n".repeat(len));
        }
        Edit::Rename(..) => {}
        Edit::Copy(i) => {
            let mut copy = g.nodes[i % n].clone();
            copy.id = g.nodes.iter().map(|x| x.id).max().unwrap_or(0) + 1;
            g.nodes.push(copy);
        }
        Edit::Remove(i) if n > 2 => {
            let id = g.nodes.remove(i % n).id;
            g.edges.retain(|x| x.source != id && x.target != id);
            g.sibling_edges.retain(|x| x.source != id && x.target != id);
            g.extra_parent_edges
                .retain(|x| x.parent != id && x.child != id);
            for node in &mut g.nodes {
                if node.parent == Some(id) {
                    node.parent = None;
                }
            }
        }
        Edit::Remove(_) => {}
        Edit::Connect(a, b) => {
            let places: Vec<u64> = g.nodes_of_kind(NodeKind::Place).map(|x| x.id).collect();
            if places.len() < 2 {
                return;
            }
            let (s, t) = (places[a % places.len()], places[b % places.len()]);
            let exists = g
                .edges
                .iter()
                .any(|x| (x.source, x.target) == (s, t) || (x.source, x.target) == (t, s));
            if s != t && !exists {
                g.edges.push(DsgEdge {
                    source: s,
                    target: t,
                    weight: None,
                });
            }
        }
        Edit::Disconnect(i) if !g.edges.is_empty() => {
            let k = i % g.edges.len();
            g.edges.remove(k);
        }
        Edit::Disconnect(_) => {}
        Edit::Orphan(i) => g.nodes[i % n].parent = None,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn the_update_between_two_graphs_applied_to_the_first_gives_the_second(
        steps in proptest::collection::vec(proptest::collection::vec(edit(), 1..4), 1..6)
    ) {
        let mut sent = generate(OfficeParams { seed: 3, scale: 0.02 });
        sent.mesh = None;
        let mut held = sent.clone();
        for edits in &steps {
            let mut next = sent.clone();
            for e in edits {
                change(&mut next, e);
            }
            let update = update_between(&sent, &next);
            let body = to_binary_body(&update.part).expect("encodes");
            let part = parse_binary_body(&body, DsgVersion::V1_1_3, "part").expect("decodes on its own");
            held.apply_update(part, &update.deleted_nodes, &update.deleted_edges).expect("applies");
            // Labels are derived on import (from the labelspaces or the name): not sent.
            let sans_labels = |g: &DsgGraph| {
                g.nodes.iter().map(|n| ygg_dsg::DsgNode { label: None, ..n.clone() }).collect::<Vec<_>>()
            };
            let (h, n) = (sans_labels(&held), sans_labels(&next));
            prop_assert_eq!(h.len(), n.len());
            for (a, b) in h.iter().zip(&n) {
                prop_assert_eq!(a, b);
            }
            let pairs = |g: &DsgGraph| {
                let mut p: Vec<(u64, u64)> = g.edges.iter().map(|e| (e.source.min(e.target), e.source.max(e.target))).collect();
                p.sort_unstable();
                p
            };
            prop_assert_eq!(pairs(&held), pairs(&next));
            sent = next;
        }
    }
}

#[test]
fn an_update_that_does_not_fit_leaves_the_graph_as_it_was() {
    let mut g = generate(OfficeParams {
        seed: 3,
        scale: 0.02,
    });
    g.mesh = None;
    let before = g.clone();
    let mut part = DsgGraph {
        layers: g.layers.clone(),
        ..DsgGraph::default()
    };
    let mut moved = g.nodes[0].clone();
    moved.layer = ygg_dsg::LayerKey::new(9, 0);
    part.nodes.push(moved);
    assert!(g.apply_update(part, &[g.nodes[1].id], &[]).is_err());
    assert_eq!(g, before);
    assert!(
        g.apply_update(DsgGraph::default(), &[], &[1, 2, 3])
            .is_err()
    );
    assert_eq!(g, before);
}
