//! Random mutation sequences shared by the property tests: an operation language over a
//! small id space, so that random operations often hit existing nodes and layers.

use proptest::prelude::*;
use ygg_store::{FeatureValue, LayerId, NodeId, SceneGraph};

/// One random mutation.
#[derive(Clone, Debug)]
#[allow(missing_docs, reason = "a test-only operation language")]
pub enum Op {
    AddLayer(u8),
    RemoveLayer(u8),
    AddLayerEdge(u8, u8),
    RemoveLayerEdge(u8, u8),
    AddNode(u8, u8),
    RemoveNode(u8),
    SetGeometry(u8, Vec<[i8; 3]>),
    AppendPoints(u8, Vec<[i8; 3]>),
    SetFeature(u8, u8, i8),
    RemoveFeature(u8, u8),
    AddLabel(u8, u8),
    RemoveLabel(u8, u8),
    AddEdge(u8, u8, u8),
    RemoveEdge(u8, u8),
    Nest(u8, u8),
    Unnest(u8),
    EnableBox(u8),
    DisableBox(u8),
    NonFinite(u8),
    NonFiniteAppend(u8),
    EnableLayerIndex(u8),
    DisableLayerIndex(u8),
    EnableNodeIndex(u8),
    DisableNodeIndex(u8),
}

/// A random mutation.
pub fn op() -> impl Strategy<Value = Op> {
    let n = 0u8..24;
    let l = 0u8..6;
    prop_oneof![
        2 => l.clone().prop_map(Op::AddLayer),
        1 => l.clone().prop_map(Op::RemoveLayer),
        2 => (l.clone(), l.clone()).prop_map(|(a, b)| Op::AddLayerEdge(a, b)),
        1 => (l.clone(), l.clone()).prop_map(|(a, b)| Op::RemoveLayerEdge(a, b)),
        6 => (n.clone(), l.clone()).prop_map(|(a, b)| Op::AddNode(a, b)),
        1 => n.clone().prop_map(Op::RemoveNode),
        4 => (n.clone(), prop::collection::vec(any::<[i8; 3]>(), 0..4)).prop_map(|(a, p)| Op::SetGeometry(a, p)),
        2 => (n.clone(), prop::collection::vec(any::<[i8; 3]>(), 0..4)).prop_map(|(a, p)| Op::AppendPoints(a, p)),
        2 => (n.clone(), 0u8..3, any::<i8>()).prop_map(|(a, k, v)| Op::SetFeature(a, k, v)),
        1 => (n.clone(), 0u8..3).prop_map(|(a, k)| Op::RemoveFeature(a, k)),
        2 => (n.clone(), 0u8..4).prop_map(|(a, k)| Op::AddLabel(a, k)),
        1 => (n.clone(), 0u8..4).prop_map(|(a, k)| Op::RemoveLabel(a, k)),
        3 => (n.clone(), n.clone(), 0u8..2).prop_map(|(a, b, d)| Op::AddEdge(a, b, d)),
        1 => (n.clone(), n.clone()).prop_map(|(a, b)| Op::RemoveEdge(a, b)),
        4 => (n.clone(), n.clone()).prop_map(|(a, b)| Op::Nest(a, b)),
        1 => n.clone().prop_map(Op::Unnest),
        2 => n.clone().prop_map(Op::EnableBox),
        1 => n.clone().prop_map(Op::DisableBox),
        1 => n.clone().prop_map(Op::NonFinite),
        1 => n.clone().prop_map(Op::NonFiniteAppend),
        1 => l.clone().prop_map(Op::EnableLayerIndex),
        1 => l.prop_map(Op::DisableLayerIndex),
        1 => n.clone().prop_map(Op::EnableNodeIndex),
        1 => n.prop_map(Op::DisableNodeIndex),
    ]
}

/// Labels the operations use.
pub const LABELS: [&str; 4] = ["chair", "light", "desk", "door"];
/// Feature keys the operations use.
pub const KEYS: [&str; 3] = ["name", "weight", "open"];

/// Applies `op` to `g`.
pub fn apply(g: &mut SceneGraph, op: &Op) -> Result<(), ygg_store::GraphEditError> {
    let node = |i: u8| NodeId(u64::from(i) * 1000 + 7);
    let layer = |g: &SceneGraph, i: u8| g.layer_id(&format!("layer{i}")).unwrap_or(LayerId(999));
    match op {
        Op::AddLayer(i) => g.add_layer(&format!("layer{i}")).map(|_| ()),
        Op::RemoveLayer(i) => g.remove_layer(layer(g, *i)),
        Op::AddLayerEdge(a, b) => g.add_layer_edge(layer(g, *a), layer(g, *b)),
        Op::RemoveLayerEdge(a, b) => g.remove_layer_edge(layer(g, *a), layer(g, *b)),
        Op::AddNode(n, l) => g.add_node(node(*n), layer(g, *l)),
        Op::RemoveNode(n) => g.remove_node(node(*n)),
        Op::SetGeometry(n, pts) => g.set_geometry(
            node(*n),
            pts.iter().map(|p| p.map(|c| f32::from(c) / 8.0)).collect(),
        ),
        Op::AppendPoints(n, pts) => {
            let pts: Vec<[f32; 3]> = pts.iter().map(|p| p.map(|c| f32::from(c) / 8.0)).collect();
            g.append_points(node(*n), &pts)
        }
        Op::SetFeature(n, k, v) => {
            let value = match k {
                0 => FeatureValue::Str(format!("v{}", v % 3)),
                1 => FeatureValue::Float(f64::from(*v) / 4.0),
                _ => FeatureValue::Bool(*v > 0),
            };
            g.set_feature(node(*n), KEYS[*k as usize], value)
        }
        Op::RemoveFeature(n, k) => g.remove_feature(node(*n), KEYS[*k as usize]),
        Op::AddLabel(n, k) => g.add_label(node(*n), LABELS[*k as usize]),
        Op::RemoveLabel(n, k) => g.remove_label(node(*n), LABELS[*k as usize]),
        Op::AddEdge(a, b, d) => g.add_edge(node(*a), node(*b), ["door", "hall"][*d as usize]),
        Op::RemoveEdge(a, b) => g.remove_edge(node(*a), node(*b)),
        Op::Nest(a, b) => g.nest(node(*a), node(*b)),
        Op::Unnest(n) => g.unnest(node(*n)),
        Op::EnableBox(n) => g.enable_bounding_box(node(*n)),
        Op::DisableBox(n) => g.disable_bounding_box(node(*n)),
        Op::NonFinite(n) => g.set_geometry(node(*n), vec![[0.0, f32::NAN, 1.0]]),
        Op::NonFiniteAppend(n) => {
            g.append_points(node(*n), &[[1.0, 2.0, 3.0], [f32::INFINITY, 0.0, 0.0]])
        }
        Op::EnableLayerIndex(l) => g.enable_layer_index(layer(g, *l)),
        Op::DisableLayerIndex(l) => g.disable_layer_index(layer(g, *l)),
        Op::EnableNodeIndex(n) => g.enable_node_index(node(*n)),
        Op::DisableNodeIndex(n) => g.disable_node_index(node(*n)),
    }
}

/// A graph with four layers in a DAG (0 -> 1 -> 2 -> 3, 0 -> 2) and the first `nodes`
/// nodes spread over them, so that random nestings and edges often succeed.
pub fn seeded_graph(nodes: u8) -> SceneGraph {
    let mut g = SceneGraph::new();
    for i in 0..4 {
        apply(&mut g, &Op::AddLayer(i)).unwrap();
    }
    for (a, b) in [(0, 1), (1, 2), (0, 2), (2, 3)] {
        apply(&mut g, &Op::AddLayerEdge(a, b)).unwrap();
    }
    for n in 0..nodes {
        apply(&mut g, &Op::AddNode(n, n % 4)).unwrap();
    }
    g
}
