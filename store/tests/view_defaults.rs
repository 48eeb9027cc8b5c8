//! Every provided method of `SceneView` answers, through its default body, what the live
//! graph and the archive answer through their overrides.
//!
//! `RequiredOnly` implements only the required methods (delegating them to a backend),
//! so its provided methods run their default bodies; each test compares one of them
//! with the backend's own answer, on the live graph and on its archived snapshot.

use ygg_store::query::{nearest_in_subtree, nearest_nodes, nodes_within_radius};
use ygg_store::{
    Aabb, EdgeRef, FeatureRef, FeatureValue, LayerId, NodeId, Points, SceneGraph, SceneView, Scope,
};

/// A view that implements the required methods only, each delegated to `V`.
struct RequiredOnly<V>(V);

impl<V: SceneView> SceneView for RequiredOnly<V> {
    type NodeRef<'a>
        = V::NodeRef<'a>
    where
        Self: 'a;

    fn layers(&self) -> impl Iterator<Item = LayerId> + '_ {
        self.0.layers()
    }
    fn layer_name(&self, layer: LayerId) -> Option<&str> {
        self.0.layer_name(layer)
    }
    fn layer_children(&self, layer: LayerId) -> Vec<LayerId> {
        self.0.layer_children(layer)
    }
    fn layer_generation(&self, layer: LayerId) -> Option<u64> {
        self.0.layer_generation(layer)
    }
    fn layer_nodes(&self, layer: LayerId) -> impl Iterator<Item = Self::NodeRef<'_>> + '_ {
        self.0.layer_nodes(layer)
    }
    fn node_id<'a>(&'a self, node: Self::NodeRef<'a>) -> NodeId {
        self.0.node_id(node)
    }
    fn points<'a>(&'a self, node: Self::NodeRef<'a>) -> Points<'a> {
        self.0.points(node)
    }
    fn parent<'a>(&'a self, node: Self::NodeRef<'a>) -> Option<NodeId> {
        self.0.parent(node)
    }
    fn aabb<'a>(&'a self, node: Self::NodeRef<'a>) -> Option<Aabb> {
        self.0.aabb(node)
    }
    fn out_edges<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = EdgeRef<'a>> + 'a {
        self.0.out_edges(node)
    }
    fn labels<'a>(&'a self, node: Self::NodeRef<'a>) -> impl Iterator<Item = &'a str> + 'a {
        self.0.labels(node)
    }
    fn features<'a>(
        &'a self,
        node: Self::NodeRef<'a>,
    ) -> impl Iterator<Item = (&'a str, FeatureRef<'a>)> + 'a {
        self.0.features(node)
    }
}

const LABELS: [&str; 3] = ["chair", "table", "absent"];
const KEYS: [&str; 4] = ["score", "name", "count", "absent"];
/// A layer no graph here has.
const UNKNOWN_LAYER: LayerId = LayerId(999);
/// A node no graph here has.
const UNKNOWN_NODE: NodeId = NodeId(9_999);

/// Rooms over objects over mesh vertices (rooms also hold vertices directly, so a room's
/// children lie in two layers), with labels, features of every type, edges in two
/// layers, bounding boxes, a layer index and node indexes.
fn graph() -> SceneGraph {
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").unwrap();
    let objects = g.add_layer("objects").unwrap();
    let mesh = g.add_layer("mesh").unwrap();
    let empty = g.add_layer("empty").unwrap();
    g.add_layer_edge(rooms, objects).unwrap();
    g.add_layer_edge(objects, mesh).unwrap();
    g.add_layer_edge(rooms, mesh).unwrap();
    g.add_layer_edge(rooms, empty).unwrap();
    for room in [1, 2] {
        g.add_node(NodeId(room), rooms).unwrap();
        g.enable_bounding_box(NodeId(room)).unwrap();
    }
    g.add_edge(NodeId(1), NodeId(2), "door").unwrap();
    g.add_edge(NodeId(2), NodeId(1), "door").unwrap();
    for object in 10..17u64 {
        let id = NodeId(object);
        g.add_node(id, objects).unwrap();
        g.nest(NodeId(1 + object % 2), id).unwrap();
        g.add_label(id, LABELS[(object % 2) as usize]).unwrap();
        if object % 3 == 0 {
            g.add_label(id, "table").unwrap();
        }
        g.set_feature(id, "score", FeatureValue::Float(object as f64 / 4.0))
            .unwrap();
        if object % 2 == 0 {
            g.set_feature(id, "name", FeatureValue::Str(format!("object {object}")))
                .unwrap();
        }
        if object % 3 == 1 {
            g.set_feature(id, "count", FeatureValue::Int(object as i64))
                .unwrap();
        }
        g.enable_bounding_box(id).unwrap();
    }
    for (a, b) in [(10, 11), (12, 11), (13, 11), (11, 10), (16, 15), (14, 10)] {
        g.add_edge(NodeId(a), NodeId(b), "near").unwrap();
    }
    // Object 10 gets many vertices (an index worth publishing), the others a few.
    for vertex in 100..260u64 {
        let id = NodeId(vertex);
        g.add_node(id, mesh).unwrap();
        let object = if vertex < 200 { 10 } else { 10 + vertex % 7 };
        let parent = if vertex % 17 == 0 {
            1 + vertex % 2
        } else {
            object
        };
        g.nest(NodeId(parent), id).unwrap();
        let x = vertex as f32 * 0.25;
        let points = (0..(1 + vertex % 40))
            .map(|k| [x, (k as f32).sin(), k as f32 * 0.1])
            .collect();
        g.set_geometry(id, points).unwrap();
    }
    g.enable_layer_index(mesh).unwrap();
    g.enable_node_index(NodeId(10)).unwrap();
    g.enable_node_index(NodeId(11)).unwrap();
    g.enable_node_index(NodeId(1)).unwrap();
    g
}

/// Runs `check(default_view, backend)` on the live graph and on its archived snapshot.
macro_rules! on_both_backends {
    (|$defaults:ident, $backend:ident| $body:block) => {{
        fn check<V: SceneView>($backend: &V) {
            let $defaults = RequiredOnly($backend);
            $body
        }
        let g = graph();
        check(&g);
        let snapshot = g.to_snapshot();
        check(&snapshot.view());
    }};
}

/// Every layer of a view and one it does not have.
fn layers_and_unknown<V: SceneView>(v: &V) -> Vec<LayerId> {
    v.layers().chain([UNKNOWN_LAYER]).collect()
}

/// Every node id of a view.
fn node_ids<V: SceneView>(v: &V) -> Vec<NodeId> {
    let mut ids: Vec<NodeId> = v
        .layers()
        .flat_map(|l| v.layer_nodes(l).map(|n| v.node_id(n)).collect::<Vec<_>>())
        .collect();
    ids.sort_unstable();
    ids
}

/// The ids of some nodes, sorted.
fn sorted_ids(nodes: impl Iterator<Item = NodeId>) -> Vec<NodeId> {
    let mut ids: Vec<NodeId> = nodes.collect();
    ids.sort_unstable();
    ids
}

#[test]
fn the_fixture_has_what_the_defaults_must_find() {
    let g = graph();
    assert_eq!(node_ids(&g).len(), 2 + 7 + 160);
    assert!(g.layer_index(LayerId(2)).is_some());
    assert!(g.has_node_index(NodeId(10)));
    let snapshot = g.to_snapshot();
    let view = snapshot.view();
    assert!(view.layer_index(LayerId(2)).is_some());
    assert!(view.node_index(NodeId(10)).is_some());
    // A `.ygg` file keeps every tree inline, small ones included.
    assert!(view.node_index(NodeId(11)).is_some());
}

#[test]
fn layer_by_name_default_finds_what_the_backends_find() {
    on_both_backends!(|d, v| {
        let mut names: Vec<String> = v
            .layers()
            .map(|l| v.layer_name(l).unwrap().to_owned())
            .collect();
        names.push("no such layer".into());
        for name in &names {
            assert_eq!(d.layer_by_name(name), v.layer_by_name(name), "{name}");
        }
    });
}

#[test]
fn layer_parents_default_finds_what_the_backends_find() {
    on_both_backends!(|d, v| {
        for l in layers_and_unknown(v) {
            assert_eq!(d.layer_parents(l), v.layer_parents(l), "{l}");
        }
    });
}

#[test]
fn layer_len_default_counts_what_the_backends_count() {
    on_both_backends!(|d, v| {
        for l in layers_and_unknown(v) {
            assert_eq!(d.layer_len(l), v.layer_len(l), "{l}");
        }
    });
}

#[test]
fn node_count_default_counts_what_the_backends_count() {
    on_both_backends!(|d, v| {
        assert_eq!(d.node_count(), v.node_count());
        assert_eq!(d.node_count(), 169);
    });
}

#[test]
fn node_default_finds_what_the_backends_find() {
    on_both_backends!(|d, v| {
        for id in node_ids(v).into_iter().chain([UNKNOWN_NODE]) {
            assert_eq!(
                d.node(id).map(|n| d.node_id(n)),
                v.node(id).map(|n| v.node_id(n))
            );
        }
    });
}

#[test]
fn node_layer_default_finds_what_the_backends_find() {
    on_both_backends!(|d, v| {
        for id in node_ids(v) {
            let (dn, vn) = (d.node(id).unwrap(), v.node(id).unwrap());
            assert_eq!(d.node_layer(dn), v.node_layer(vn), "{id}");
        }
    });
}

#[test]
fn children_default_lists_what_the_backends_list() {
    on_both_backends!(|d, v| {
        let mut nested = 0;
        for id in node_ids(v) {
            let (dn, vn) = (d.node(id).unwrap(), v.node(id).unwrap());
            let want: Vec<NodeId> = v.children(vn).collect();
            assert_eq!(d.children(dn).collect::<Vec<_>>(), want, "{id}");
            assert_eq!(d.children(dn).len(), want.len());
            assert_eq!(d.children(dn).rev().collect::<Vec<_>>().len(), want.len());
            nested += want.len();
        }
        assert_eq!(nested, 7 + 160, "every object and vertex has a parent");
    });
}

#[test]
fn in_edges_default_lists_what_the_backends_list() {
    on_both_backends!(|d, v| {
        let mut edges = 0;
        for id in node_ids(v) {
            let (dn, vn) = (d.node(id).unwrap(), v.node(id).unwrap());
            let want: Vec<EdgeRef> = v.in_edges(vn).collect();
            assert_eq!(d.in_edges(dn).collect::<Vec<_>>(), want, "{id}");
            edges += want.len();
        }
        assert_eq!(edges, 8);
    });
}

#[test]
fn feature_default_finds_what_the_backends_find() {
    on_both_backends!(|d, v| {
        for id in node_ids(v) {
            let (dn, vn) = (d.node(id).unwrap(), v.node(id).unwrap());
            for key in KEYS {
                assert_eq!(d.feature(dn, key), v.feature(vn, key), "{id} {key}");
            }
        }
    });
}

#[test]
fn has_label_default_finds_what_the_backends_find() {
    on_both_backends!(|d, v| {
        for id in node_ids(v) {
            let (dn, vn) = (d.node(id).unwrap(), v.node(id).unwrap());
            for label in LABELS {
                assert_eq!(
                    d.has_label(dn, label),
                    v.has_label(vn, label),
                    "{id} {label}"
                );
            }
        }
    });
}

#[test]
fn nodes_with_label_default_finds_what_the_inverted_indexes_find() {
    on_both_backends!(|d, v| {
        for l in layers_and_unknown(v) {
            for label in LABELS {
                let want = sorted_ids(v.nodes_with_label(l, label).map(|n| v.node_id(n)));
                let got = sorted_ids(d.nodes_with_label(l, label).map(|n| d.node_id(n)));
                assert_eq!(got, want, "{l} {label}");
            }
        }
        assert_eq!(d.nodes_with_label(LayerId(1), "table").count(), 4);
    });
}

#[test]
fn nodes_with_key_default_finds_what_the_inverted_indexes_find() {
    on_both_backends!(|d, v| {
        for l in layers_and_unknown(v) {
            for key in KEYS {
                let want = sorted_ids(v.nodes_with_key(l, key).map(|n| v.node_id(n)));
                let got = sorted_ids(d.nodes_with_key(l, key).map(|n| d.node_id(n)));
                assert_eq!(got, want, "{l} {key}");
            }
        }
        assert_eq!(d.nodes_with_key(LayerId(1), "count").count(), 3);
    });
}

#[test]
fn layers_with_label_default_finds_what_the_inverted_indexes_find() {
    on_both_backends!(|d, v| {
        for label in LABELS {
            let mut want: Vec<LayerId> = v.layers_with_label(label).collect();
            want.sort_unstable();
            assert_eq!(
                d.layers_with_label(label).collect::<Vec<_>>(),
                want,
                "{label}"
            );
        }
    });
}

#[test]
fn layers_with_key_default_finds_what_the_inverted_indexes_find() {
    on_both_backends!(|d, v| {
        for key in KEYS {
            let mut want: Vec<LayerId> = v.layers_with_key(key).collect();
            want.sort_unstable();
            assert_eq!(d.layers_with_key(key).collect::<Vec<_>>(), want, "{key}");
        }
    });
}

/// Query points around and inside the mesh.
const PROBES: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [30.0, 0.5, 1.0],
    [52.0, -1.0, 2.0],
    [70.0, 0.0, 0.0],
];

#[test]
fn layer_index_default_is_none_and_scans_answer_what_the_index_answers() {
    on_both_backends!(|d, v| {
        for l in layers_and_unknown(v) {
            assert!(d.layer_index(l).is_none());
        }
        for scope in [Scope::Graph, Scope::Layer(LayerId(2))] {
            for c in PROBES {
                for m in [1, 5] {
                    assert_eq!(
                        nearest_nodes(&d, scope, c, m).unwrap(),
                        nearest_nodes(v, scope, c, m).unwrap()
                    );
                }
                assert_eq!(
                    nodes_within_radius(&d, scope, c, 3.0).unwrap(),
                    nodes_within_radius(v, scope, c, 3.0).unwrap()
                );
            }
        }
    });
}

#[test]
fn node_index_default_is_none_and_walks_answer_what_the_index_answers() {
    on_both_backends!(|d, v| {
        for root in [NodeId(1), NodeId(2), NodeId(10), NodeId(11)] {
            assert!(d.node_index(root).is_none());
            for c in PROBES {
                for m in [1, 4] {
                    assert_eq!(
                        nearest_in_subtree(&d, root, c, m).unwrap(),
                        nearest_in_subtree(v, root, c, m).unwrap(),
                        "{root}"
                    );
                }
            }
        }
    });
}

#[test]
fn has_node_index_default_follows_node_index() {
    on_both_backends!(|d, v| {
        for id in node_ids(v) {
            assert!(!d.has_node_index(id), "{id}");
        }
        assert!(v.has_node_index(NodeId(10)) && v.has_node_index(NodeId(1)));
        assert!(!v.has_node_index(NodeId(12)));
    });
}
