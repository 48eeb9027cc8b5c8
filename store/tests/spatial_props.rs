//! Property tests for the spatial indexes and queries: on random graphs under random
//! mutation sequences, every spatial query answers exactly what brute force answers
//! (same set, same order) on the live graph (with live indexes), on its snapshot (with
//! archived indexes), on the segments a publishing writer sends (layer indexes patched
//! since their base tree, and folded), and through indexes a reader builds itself; bad
//! input is an error.

#[path = "common/published.rs"]
mod published;

use proptest::prelude::*;
use published::{Publisher, TREE_CHUNK};
use ygg_store::index::{IndexCache, SpatialIndex, build_layer_index, build_subtree_index};
use ygg_store::query::{
    self, ConeView, SpatialQueryError, nearest_in_index, nearest_in_subtree, nearest_nodes,
    nodes_within_radius, visible, within_index,
};
use ygg_store::snapshot::{SegmentCache, archive, is_tree_chunk_segment_id};
use ygg_store::{LayerId, NodeId, Point, SceneGraph, SceneView, Scope, distance_squared};

#[derive(Clone, Debug)]
enum Op {
    AddLayer(u8),
    RemoveLayer(u8),
    AddNode(u8, u8),
    RemoveNode(u8),
    /// Points on a coarse grid: duplicates and exact ties are common.
    SetGeometry(u8, Vec<[i8; 3]>),
    /// The same point several times.
    SetDuplicates(u8, [i8; 3], u8),
    /// Many points around one (enough to move the node wholesale into an index's
    /// overlay; see `OverlaidTree`).
    SetCluster(u8, [i8; 3], u8),
    /// Every point of the node moved by the same offset (a rigid move).
    Translate(u8, [i8; 3]),
    /// Points appended to the node's geometry (a mesh growing).
    Append(u8, Vec<[i8; 3]>),
    Nest(u8, u8),
    Unnest(u8),
    EnableBox(u8),
    EnableLayerIndex(u8),
    DisableLayerIndex(u8),
    EnableNodeIndex(u8),
    DisableNodeIndex(u8),
}

const NODES: u8 = 40;
const LAYERS: u8 = 5;

fn point() -> impl Strategy<Value = [i8; 3]> {
    [-6i8..6, -6i8..6, -3i8..3]
}

fn op() -> impl Strategy<Value = Op> {
    let n = 0u8..NODES;
    let l = 0u8..LAYERS;
    prop_oneof![
        1 => l.clone().prop_map(Op::AddLayer),
        1 => l.clone().prop_map(Op::RemoveLayer),
        3 => (n.clone(), l.clone()).prop_map(|(a, b)| Op::AddNode(a, b)),
        2 => n.clone().prop_map(Op::RemoveNode),
        10 => (n.clone(), prop::collection::vec(point(), 0..5)).prop_map(|(a, p)| Op::SetGeometry(a, p)),
        1 => (n.clone(), point(), 2u8..40).prop_map(|(a, p, k)| Op::SetDuplicates(a, p, k)),
        2 => (n.clone(), point(), 8u8..60).prop_map(|(a, p, k)| Op::SetCluster(a, p, k)),
        4 => (n.clone(), [-2i8..3, -2i8..3, -1i8..2]).prop_map(|(a, d)| Op::Translate(a, d)),
        3 => (n.clone(), prop::collection::vec(point(), 0..40)).prop_map(|(a, p)| Op::Append(a, p)),
        5 => (n.clone(), n.clone()).prop_map(|(a, b)| Op::Nest(a, b)),
        3 => n.clone().prop_map(Op::Unnest),
        1 => n.clone().prop_map(Op::EnableBox),
        2 => l.clone().prop_map(Op::EnableLayerIndex),
        1 => l.prop_map(Op::DisableLayerIndex),
        2 => n.clone().prop_map(Op::EnableNodeIndex),
        1 => n.prop_map(Op::DisableNodeIndex),
    ]
}

/// A starting graph: a layer DAG (0 → 1 → 2 → 3, 1 → 3, 0 → 4), nodes with points,
/// nestings, and some indexes, described by a few random choices.
#[derive(Clone, Debug)]
struct Start {
    nodes: Vec<(u8, Vec<[i8; 3]>)>,
    nests: Vec<(u8, u8)>,
    layer_indexes: Vec<u8>,
    node_indexes: Vec<u8>,
    boxes: Vec<u8>,
}

fn start() -> impl Strategy<Value = Start> {
    (
        prop::collection::vec(
            (0u8..LAYERS, prop::collection::vec(point(), 0..10)),
            5..NODES as usize,
        ),
        prop::collection::vec((0u8..NODES, 0u8..NODES), 0..60),
        prop::collection::vec(0u8..LAYERS, 0..4),
        prop::collection::vec(0u8..NODES, 0..6),
        prop::collection::vec(0u8..NODES, 0..6),
    )
        .prop_map(|(nodes, nests, layer_indexes, node_indexes, boxes)| Start {
            nodes,
            nests,
            layer_indexes,
            node_indexes,
            boxes,
        })
}

fn node(i: u8) -> NodeId {
    // Ids not in insertion order, so handle order and id order differ.
    NodeId(u64::from(i.wrapping_mul(37) % 64) * 10 + 3)
}

fn layer(g: &SceneGraph, i: u8) -> LayerId {
    g.layer_id(&format!("layer{i}")).unwrap_or(LayerId(999))
}

fn grid(p: &[i8; 3]) -> Point {
    p.map(|c| f32::from(c) / 2.0)
}

/// `k` grid points around `p` (a deterministic spiral of offsets; some coincide).
fn cluster(p: &[i8; 3], k: u8) -> Vec<Point> {
    (0..k)
        .map(|i| {
            let i = i as i8;
            grid(&[p[0] + i % 4, p[1] + (i / 4) % 4, p[2] + i % 3])
        })
        .collect()
}

fn build(s: &Start) -> SceneGraph {
    let mut g = SceneGraph::new();
    for i in 0..LAYERS {
        g.add_layer(&format!("layer{i}")).unwrap();
    }
    for (a, b) in [(0, 1), (1, 2), (2, 3), (1, 3), (0, 4)] {
        g.add_layer_edge(layer(&g, a), layer(&g, b)).unwrap();
    }
    for (i, (l, pts)) in s.nodes.iter().enumerate() {
        g.add_node(node(i as u8), layer(&g, *l)).unwrap();
        g.set_geometry(node(i as u8), pts.iter().map(grid).collect())
            .unwrap();
    }
    for (a, b) in &s.nests {
        let _ = g.nest(node(*a), node(*b));
    }
    for b in &s.boxes {
        let _ = g.enable_bounding_box(node(*b));
    }
    for l in &s.layer_indexes {
        g.enable_layer_index(layer(&g, *l)).unwrap();
    }
    for n in &s.node_indexes {
        let _ = g.enable_node_index(node(*n));
    }
    g
}

fn apply(g: &mut SceneGraph, op: &Op) {
    // Refused mutations are fine: they must change nothing (checked by the invariants).
    let _ = match op {
        Op::AddLayer(i) => g.add_layer(&format!("layer{i}")).map(|_| ()),
        Op::RemoveLayer(i) => g.remove_layer(layer(g, *i)),
        Op::AddNode(n, l) => g.add_node(node(*n), layer(g, *l)),
        Op::RemoveNode(n) => g.remove_node(node(*n)),
        Op::SetGeometry(n, pts) => g.set_geometry(node(*n), pts.iter().map(grid).collect()),
        Op::SetDuplicates(n, p, k) => g.set_geometry(node(*n), vec![grid(p); *k as usize]),
        Op::SetCluster(n, p, k) => g.set_geometry(node(*n), cluster(p, *k)),
        Op::Translate(n, d) => match g.node(node(*n)) {
            Some(x) => {
                let moved = g
                    .points(x)
                    .iter()
                    .map(|q| [0, 1, 2].map(|a| q[a] + f32::from(d[a]) / 2.0))
                    .collect();
                g.set_geometry(node(*n), moved)
            }
            None => Ok(()),
        },
        Op::Append(n, pts) => {
            let pts: Vec<Point> = pts.iter().map(grid).collect();
            g.append_points(node(*n), &pts)
        }
        Op::Nest(a, b) => g.nest(node(*a), node(*b)),
        Op::Unnest(n) => g.unnest(node(*n)),
        Op::EnableBox(n) => g.enable_bounding_box(node(*n)),
        Op::EnableLayerIndex(l) => g.enable_layer_index(layer(g, *l)),
        Op::DisableLayerIndex(l) => g.disable_layer_index(layer(g, *l)),
        Op::EnableNodeIndex(n) => g.enable_node_index(node(*n)),
        Op::DisableNodeIndex(n) => g.disable_node_index(node(*n)),
    };
}

// ---- brute force, written from the definitions alone ------------------------------------

fn min_d2<V: SceneView>(v: &V, id: NodeId, c: &Point) -> Option<f32> {
    let n = v.node(id)?;
    v.points(n)
        .iter()
        .map(|p| distance_squared(p, c))
        .min_by(f32::total_cmp)
}

fn scope_nodes<V: SceneView>(v: &V, scope: Scope) -> Vec<NodeId> {
    scope
        .layers(v)
        .into_iter()
        .flat_map(|l| v.layer_nodes(l).map(|n| v.node_id(n)).collect::<Vec<_>>())
        .collect()
}

fn subtree_nodes<V: SceneView>(v: &V, root: NodeId) -> Vec<NodeId> {
    query::subtree(v, root)
}

fn brute_nearest<V: SceneView>(v: &V, nodes: &[NodeId], c: &Point, m: usize) -> Vec<(NodeId, f32)> {
    let mut all: Vec<(f32, NodeId)> = nodes
        .iter()
        .filter_map(|&id| min_d2(v, id, c).map(|d| (d, id)))
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    all.into_iter()
        .take(m)
        .map(|(d, id)| (id, d.sqrt()))
        .collect()
}

fn brute_within<V: SceneView>(v: &V, nodes: &[NodeId], c: &Point, r: f32) -> Vec<NodeId> {
    let mut out: Vec<NodeId> = nodes
        .iter()
        .copied()
        .filter(|&id| {
            let n = v.node(id).expect("listed");
            v.points(n)
                .iter()
                .any(|p| distance_squared(p, c).sqrt() <= r)
        })
        .collect();
    out.sort_unstable();
    out
}

fn brute_visible<V: SceneView>(v: &V, root: NodeId, cone: &ConeView) -> Vec<NodeId> {
    let mut out: Vec<NodeId> = subtree_nodes(v, root)
        .into_iter()
        .filter(|&id| {
            let n = v.node(id).expect("listed");
            v.points(n).iter().any(|p| cone.contains(p).unwrap())
        })
        .collect();
    out.sort_unstable();
    out
}

// ---- the checks -------------------------------------------------------------------------

#[derive(Clone, Debug)]
struct Probe {
    c: [i8; 3],
    m: usize,
    r: u8,
    dir: [i8; 3],
    half_angle: u8,
    range: u8,
}

/// Six probes `i` in 0..6 at `centre(i)`, asking for `m[i % 3]` nodes, radius `i + 1`,
/// looking along +x with `half_angle` degrees, range 8.
fn six_probes(centre: impl Fn(i8) -> [i8; 3], m: [usize; 3], half_angle: u8) -> Vec<Probe> {
    (0..6i8)
        .map(|i| Probe {
            c: centre(i),
            m: m[i as usize % 3],
            r: i as u8 + 1,
            dir: [1, 0, 0],
            half_angle,
            range: 8,
        })
        .collect()
}

fn probe() -> impl Strategy<Value = Probe> {
    (
        [-8i8..8, -8i8..8, -8i8..8],
        0usize..30,
        0u8..12,
        [-2i8..3, -2i8..3, -2i8..3],
        0u8..33,
        0u8..16,
    )
        .prop_map(|(c, m, r, dir, half_angle, range)| Probe {
            c,
            m,
            r,
            dir,
            half_angle,
            range,
        })
}

/// Every spatial query on `v` equals brute force on `v`.
fn check_view<V: SceneView>(v: &V, probes: &[Probe]) {
    let layers: Vec<LayerId> = v.layers().collect();
    let all_nodes: Vec<NodeId> = scope_nodes(v, Scope::Graph);
    for p in probes {
        let c = grid(&p.c);
        let r = f32::from(p.r) / 2.0;
        for scope in std::iter::once(Scope::Graph).chain(layers.iter().map(|&l| Scope::Layer(l))) {
            let nodes = scope_nodes(v, scope);
            assert_eq!(
                nearest_nodes(v, scope, c, p.m).unwrap(),
                brute_nearest(v, &nodes, &c, p.m),
                "nearest_nodes {scope:?} {c:?} m={}",
                p.m
            );
            assert_eq!(
                nodes_within_radius(v, scope, c, r).unwrap(),
                brute_within(v, &nodes, &c, r),
                "nodes_within_radius {scope:?} {c:?} r={r}"
            );
        }
        let cone = ConeView {
            eye: c,
            dir: p.dir.map(f32::from),
            half_angle: f32::from(p.half_angle) * std::f32::consts::PI / 32.0,
            range: f32::from(p.range) / 2.0,
        };
        for &root in &all_nodes {
            let members = subtree_nodes(v, root);
            assert_eq!(
                nearest_in_subtree(v, root, c, p.m).unwrap(),
                brute_nearest(v, &members, &c, p.m),
                "nearest_in_subtree {root} {c:?} m={}",
                p.m
            );
            if p.dir == [0, 0, 0] {
                assert!(matches!(
                    visible(v, root, &cone),
                    Err(SpatialQueryError::InvalidDirection(_))
                ));
            } else {
                assert_eq!(
                    visible(v, root, &cone).unwrap(),
                    brute_visible(v, root, &cone),
                    "visible {root} {cone:?}"
                );
            }
        }
    }
}

/// Indexes a reader builds (directly and through the cache) agree with brute force.
fn check_reader_indexes<V: SceneView>(v: &V, probes: &[Probe], cache: &mut IndexCache) {
    for l in v.layers().collect::<Vec<_>>() {
        let nodes = scope_nodes(v, Scope::Layer(l));
        let built = build_layer_index(v, l);
        let cached = cache.layer(v, l);
        assert_eq!(built.len(), cached.len());
        for p in probes {
            let c = grid(&p.c);
            let r = f32::from(p.r) / 2.0;
            assert_eq!(
                nearest_in_index(&built, c, p.m).unwrap(),
                brute_nearest(v, &nodes, &c, p.m)
            );
            assert_eq!(
                nearest_in_index(cached, c, p.m).unwrap(),
                brute_nearest(v, &nodes, &c, p.m)
            );
            assert_eq!(
                within_index(&built, c, r).unwrap(),
                brute_within(v, &nodes, &c, r)
            );
        }
    }
    for root in scope_nodes(v, Scope::Graph) {
        let members = subtree_nodes(v, root);
        let built = build_subtree_index(v, root);
        let cached = cache.subtree(v, root);
        assert_eq!(built.len(), cached.len());
        for p in probes.iter().take(2) {
            let c = grid(&p.c);
            assert_eq!(
                nearest_in_index(&built, c, p.m).unwrap(),
                brute_nearest(v, &members, &c, p.m)
            );
            assert_eq!(
                nearest_in_index(cached, c, p.m).unwrap(),
                brute_nearest(v, &members, &c, p.m)
            );
        }
    }
}

/// Checks every query on the segments a publishing writer sends for `g` now, as a
/// reader that kept the unchanged parts and chunks sees them.
fn check_published(g: &mut SceneGraph, publisher: &mut Publisher, probes: &[Probe]) {
    let (manifest, structure, ids) = publisher.publish(g);
    let segments = publisher.validated(&manifest, &structure, &ids);
    let view = segments.join().unwrap();
    check_view(&view, probes);
    for l in g.layers() {
        assert_eq!(
            g.layer_index(l).map(|i| i.len()),
            view.layer_index(l).map(|i| i.len())
        );
        assert_eq!(g.layer_len(l), view.layer_len(l));
        for n in view.layer_nodes(l) {
            let id = view.node_id(n);
            let live = g.node(id).unwrap();
            assert_eq!(g.points(live), view.points(n));
            // A publish withholds node index trees smaller than a tree chunk: the
            // reader walks those sub-trees (`check_view` compared the answers).
            assert_eq!(g.node_index(id).is_some(), view.has_node_index(id));
            match (
                g.node_index(id).map(|i| i.len()),
                view.node_index(id).map(|i| i.len()),
            ) {
                (Some(live), None) => assert!(
                    live < TREE_CHUNK,
                    "node index of {id:?}: a tree of {live} points was withheld"
                ),
                (live, published) => assert_eq!(live, published, "node index of {id:?}"),
            }
        }
    }
}

fn check_all(
    g: &mut SceneGraph,
    probes: &[Probe],
    cache: &mut IndexCache,
    segments: &mut Publisher,
) {
    g.check_invariants().unwrap();
    check_view(&*g, probes);
    check_published(g, segments, probes);
    let g = &*g;
    let snapshot = g.to_snapshot();
    let archived = snapshot.view();
    check_view(&archived, probes);
    check_reader_indexes(&archived, probes, cache);
    // The archive carries exactly the indexes the live graph keeps (a node index over
    // no point reads as none: its sub-tree is walked, finding nothing).
    for l in g.layers() {
        assert_eq!(
            g.layer_index(l).map(|i| i.len()),
            archived.layer_index(l).map(|i| i.len())
        );
    }
    for id in scope_nodes(g, Scope::Graph) {
        assert_eq!(
            g.node_index(id).map(|i| i.len()).filter(|&n| n > 0),
            archived.node_index(id).map(|i| i.len())
        );
        assert_eq!(g.node_index(id).is_some(), archived.has_node_index(id));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn indexed_queries_equal_brute_force_under_random_mutations(
        start in start(),
        ops in prop::collection::vec(op(), 0..60),
        probes in prop::collection::vec(probe(), 1..4),
    ) {
        let mut g = build(&start);
        let mut cache = IndexCache::new();
        let mut segments = Publisher::new();
        check_all(&mut g, &probes, &mut cache, &mut segments);
        for (i, op) in ops.iter().enumerate() {
            apply(&mut g, op);
            if i % 5 == 4 {
                check_published(&mut g, &mut segments, &probes);
            }
            if i % 20 == 19 {
                check_all(&mut g, &probes, &mut cache, &mut segments);
            }
        }
        check_all(&mut g, &probes, &mut cache, &mut segments);
    }
}

#[test]
fn invalid_inputs_are_errors_on_every_backend() {
    let mut g = SceneGraph::new();
    let l = g.add_layer("l").unwrap();
    g.add_node(NodeId(1), l).unwrap();
    g.set_geometry(NodeId(1), vec![[0.0; 3]]).unwrap();
    g.enable_layer_index(l).unwrap();
    g.enable_node_index(NodeId(1)).unwrap();
    let snapshot = g.to_snapshot();
    let archived = snapshot.view();
    let cone = |dir: Point, half_angle: f32, range: f32| ConeView {
        eye: [0.0; 3],
        dir,
        half_angle,
        range,
    };
    fn check<V: SceneView>(v: &V, cone: &dyn Fn(Point, f32, f32) -> ConeView) {
        use SpatialQueryError as E;
        let nan = [f32::NAN, 0.0, 0.0];
        let inf = [0.0, f32::INFINITY, 0.0];
        for s in [Scope::Graph, Scope::Layer(LayerId(0))] {
            assert!(matches!(
                nearest_nodes(v, s, nan, 1),
                Err(E::NonFinitePoint(_))
            ));
            assert!(matches!(
                nearest_nodes(v, s, inf, 0),
                Err(E::NonFinitePoint(_))
            ));
            assert!(matches!(
                nodes_within_radius(v, s, inf, 1.0),
                Err(E::NonFinitePoint(_))
            ));
            for r in [-1.0, -f32::MIN_POSITIVE, f32::NAN, f32::INFINITY] {
                assert!(matches!(
                    nodes_within_radius(v, s, [0.0; 3], r),
                    Err(E::InvalidRadius(_))
                ));
            }
        }
        assert!(matches!(
            nearest_in_subtree(v, NodeId(1), nan, 1),
            Err(E::NonFinitePoint(_))
        ));
        let x = [1.0, 0.0, 0.0];
        assert!(matches!(
            visible(v, NodeId(1), &cone([0.0; 3], 0.5, 1.0)),
            Err(E::InvalidDirection(_))
        ));
        assert!(matches!(
            visible(v, NodeId(1), &cone(nan, 0.5, 1.0)),
            Err(E::InvalidDirection(_))
        ));
        assert!(matches!(
            visible(v, NodeId(1), &cone(x, f32::NAN, 1.0)),
            Err(E::InvalidHalfAngle(_))
        ));
        assert!(matches!(
            visible(v, NodeId(1), &cone(x, -0.1, 1.0)),
            Err(E::InvalidHalfAngle(_))
        ));
        assert!(matches!(
            visible(v, NodeId(1), &cone(x, 4.0, 1.0)),
            Err(E::InvalidHalfAngle(_))
        ));
        assert!(matches!(
            visible(v, NodeId(1), &cone(x, 0.5, -1.0)),
            Err(E::InvalidRange(_))
        ));
        assert!(matches!(
            visible(v, NodeId(1), &cone(x, 0.5, f32::INFINITY)),
            Err(E::InvalidRange(_))
        ));
        let eye_nan = ConeView {
            eye: nan,
            ..cone(x, 0.5, 1.0)
        };
        assert!(matches!(
            visible(v, NodeId(1), &eye_nan),
            Err(E::NonFinitePoint(_))
        ));
        // Valid edge cases answer: zero radius, zero range, empty scopes, unknown roots.
        assert_eq!(
            nodes_within_radius(v, Scope::Graph, [0.0; 3], 0.0).unwrap(),
            vec![NodeId(1)]
        );
        assert_eq!(
            visible(v, NodeId(1), &cone(x, 0.0, 0.0)).unwrap(),
            vec![NodeId(1)]
        );
        assert!(
            nearest_nodes(v, Scope::Layer(LayerId(77)), [0.0; 3], 3)
                .unwrap()
                .is_empty()
        );
        assert!(
            nearest_in_subtree(v, NodeId(99), [0.0; 3], 3)
                .unwrap()
                .is_empty()
        );
        assert!(
            visible(v, NodeId(99), &cone(x, 0.5, 1.0))
                .unwrap()
                .is_empty()
        );
    }
    check(&g, &cone);
    check(&archived, &cone);
}

#[test]
fn extreme_coordinates_match_brute_force() {
    let mut g = SceneGraph::new();
    let l = g.add_layer("l").unwrap();
    let points = [
        [f32::MAX, 0.0, 0.0],
        [-f32::MAX, 1.0, 0.0],
        [1e30, -1e30, 1e-30],
        [0.0, 0.0, 0.0],
        [-0.0, 0.0, 0.0],
        [f32::MIN_POSITIVE, 0.0, 0.0],
        [3e19, 0.0, 0.0],
    ];
    for (i, p) in points.iter().enumerate() {
        g.add_node(NodeId(i as u64), l).unwrap();
        g.set_geometry(NodeId(i as u64), vec![*p]).unwrap();
    }
    g.enable_layer_index(l).unwrap();
    let snapshot = g.to_snapshot();
    let nodes = scope_nodes(&g, Scope::Graph);
    for c in [
        [0.0; 3],
        [1e30, 0.0, 0.0],
        [-3e38, 0.0, 0.0],
        [1.0, 1.0, 1.0],
    ] {
        for m in [1, 3, 10] {
            let want = brute_nearest(&g, &nodes, &c, m);
            assert_eq!(
                nearest_nodes(&g, Scope::Graph, c, m).unwrap(),
                want,
                "{c:?} {m}"
            );
            assert_eq!(
                nearest_nodes(&snapshot.view(), Scope::Graph, c, m).unwrap(),
                want,
                "{c:?} {m}"
            );
        }
        for r in [0.0, 1.0, 1e20, f32::MAX] {
            let want = brute_within(&g, &nodes, &c, r);
            assert_eq!(
                nodes_within_radius(&g, Scope::Graph, c, r).unwrap(),
                want,
                "{c:?} {r}"
            );
            assert_eq!(
                nodes_within_radius(&snapshot.view(), Scope::Graph, c, r).unwrap(),
                want,
                "{c:?} {r}"
            );
        }
    }
}

/// A scene large enough for multi-leaf kd-trees (splits, chains of duplicates, scapegoat
/// rebuilds, leaf removals), mutated thousands of times, checked against brute force.
#[test]
fn large_scene_under_many_mutations_matches_brute_force() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(42);
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").unwrap();
    let objects = g.add_layer("objects").unwrap();
    let mesh = g.add_layer("mesh").unwrap();
    g.add_layer_edge(rooms, objects).unwrap();
    g.add_layer_edge(objects, mesh).unwrap();
    let cell = |rng: &mut rand_chacha::ChaCha8Rng| {
        [0, 1, 2].map(|a| rng.gen_range(-40..40) as f32 * if a == 2 { 0.05 } else { 0.25 })
    };
    for r in 0..4u64 {
        g.add_node(NodeId(r), rooms).unwrap();
    }
    for o in 0..40u64 {
        g.add_node(NodeId(100 + o), objects).unwrap();
        g.set_geometry(NodeId(100 + o), vec![cell(&mut rng)])
            .unwrap();
        g.nest(NodeId(o % 4), NodeId(100 + o)).unwrap();
    }
    let mut next = 1000u64;
    for _ in 0..1500 {
        g.add_node(NodeId(next), mesh).unwrap();
        let k = rng.gen_range(1..4);
        g.set_geometry(NodeId(next), (0..k).map(|_| cell(&mut rng)).collect())
            .unwrap();
        g.nest(NodeId(100 + next % 40), NodeId(next)).unwrap();
        next += 1;
    }
    g.enable_layer_index(mesh).unwrap();
    g.enable_layer_index(objects).unwrap();
    g.enable_node_index(NodeId(0)).unwrap();
    g.enable_node_index(NodeId(1)).unwrap();
    g.enable_node_index(NodeId(105)).unwrap();
    g.enable_bounding_box(NodeId(2)).unwrap();
    let probes: Vec<Probe> = (0..6)
        .map(|i| Probe {
            c: [
                rng.gen_range(-8..8),
                rng.gen_range(-8..8),
                rng.gen_range(-2..2),
            ],
            m: [1, 10, 3, 50, 1, 2][i],
            r: rng.gen_range(0..8),
            dir: [rng.gen_range(-2..3), rng.gen_range(-2..3), 0],
            half_angle: rng.gen_range(1..32),
            range: rng.gen_range(0..16),
        })
        .collect();
    let mut segments = Publisher::new();
    for step in 0..4000 {
        let mesh_nodes: Vec<NodeId> = g.layer_nodes(mesh).map(|n| g.node_id(n)).collect();
        let pick = mesh_nodes[rng.gen_range(0..mesh_nodes.len())];
        match rng.gen_range(0..10) {
            0..=4 => {
                let k = rng.gen_range(0..4);
                g.set_geometry(pick, (0..k).map(|_| cell(&mut rng)).collect())
                    .unwrap();
            }
            5 => {
                let p = cell(&mut rng);
                g.set_geometry(pick, vec![p; rng.gen_range(1..50)]).unwrap();
            }
            6 => g.remove_node(pick).unwrap(),
            7 => {
                g.add_node(NodeId(next), mesh).unwrap();
                g.set_geometry(NodeId(next), vec![cell(&mut rng)]).unwrap();
                g.nest(NodeId(100 + rng.gen_range(0..40)), NodeId(next))
                    .unwrap();
                next += 1;
            }
            8 => {
                let _ = g.unnest(pick);
                g.nest(NodeId(100 + rng.gen_range(0..40)), pick).unwrap();
            }
            _ => {
                let o = NodeId(100 + rng.gen_range(0..40));
                let _ = g.unnest(o);
                g.nest(NodeId(rng.gen_range(0..4)), o).unwrap();
            }
        }
        // A writer publishes every few steps: its layer indexes are patched, and folded
        // past their budget.
        if step % 4 == 3 {
            segments.publish(&mut g);
        }
        if step % 250 == 249 {
            check_published(&mut g, &mut segments, &probes);
        }
        if step % 1000 == 999 {
            g.check_invariants().unwrap();
            check_view(&g, &probes);
            check_view(&g.to_snapshot().view(), &probes);
        }
    }
}

/// Indexes large enough that updates locate their tree paths first (more than 2^17
/// entries together): moves, multi-point edits and removals keep them exact.
#[test]
fn updates_of_large_indexes_stay_exact() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").unwrap();
    let mesh = g.add_layer("mesh").unwrap();
    g.add_layer_edge(rooms, mesh).unwrap();
    g.add_node(NodeId(1), rooms).unwrap();
    let n = 70_000u64;
    let point = |rng: &mut rand_chacha::ChaCha8Rng| {
        [0, 1, 2].map(|a| rng.gen_range(0..400) as f32 * if a == 2 { 0.01 } else { 0.25 })
    };
    for i in 0..n {
        g.add_node(NodeId(100 + i), mesh).unwrap();
        g.set_geometry(NodeId(100 + i), vec![point(&mut rng)])
            .unwrap();
        g.nest(NodeId(1), NodeId(100 + i)).unwrap();
    }
    g.enable_layer_index(mesh).unwrap();
    g.enable_node_index(NodeId(1)).unwrap();
    for _ in 0..3000 {
        let id = NodeId(100 + rng.gen_range(0..n));
        let k = [0, 1, 1, 1, 2, 5][rng.gen_range(0..6)];
        g.set_geometry(id, (0..k).map(|_| point(&mut rng)).collect())
            .unwrap();
    }
    g.check_invariants().unwrap();
    let probes: Vec<Probe> = (0..3)
        .map(|i| Probe {
            c: [rng.gen_range(0..50), rng.gen_range(0..50), 0],
            m: [1, 10, 3][i],
            r: rng.gen_range(0..3),
            dir: [1, rng.gen_range(-2..3), 0],
            half_angle: rng.gen_range(1..32),
            range: rng.gen_range(0..6),
        })
        .collect();
    check_view(&g, &probes);
}

/// Flipped bits anywhere in a snapshot with indexes give an error at open, or a
/// snapshot whose spatial queries answer without panicking.
#[test]
fn corrupted_indexed_snapshots_are_refused_or_answer_without_panic() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").unwrap();
    let mesh = g.add_layer("mesh").unwrap();
    g.add_layer_edge(rooms, mesh).unwrap();
    g.add_node(NodeId(1), rooms).unwrap();
    for i in 0..300u64 {
        g.add_node(NodeId(10 + i), mesh).unwrap();
        let p = [
            rng.gen_range(-5.0..5.0),
            rng.gen_range(-5.0..5.0),
            rng.gen_range(0.0..3.0),
        ];
        g.set_geometry(NodeId(10 + i), vec![p, [p[0], p[1], p[2] + 0.1]])
            .unwrap();
        g.nest(NodeId(1), NodeId(10 + i)).unwrap();
    }
    g.enable_layer_index(mesh).unwrap();
    g.enable_node_index(NodeId(1)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ygg");
    g.save(&path).unwrap();
    let clean = std::fs::read(&path).unwrap();
    let cone = ConeView {
        eye: [0.0; 3],
        dir: [1.0, 0.0, 0.0],
        half_angle: 0.7,
        range: 4.0,
    };
    let (mut refused, mut answered) = (0, 0);
    for _ in 0..3000 {
        let mut bytes = clean.clone();
        for _ in 0..rng.gen_range(1..4) {
            let at = rng.gen_range(0..bytes.len());
            bytes[at] ^= 1 << rng.gen_range(0..8);
        }
        let Ok(file) = ygg_store::SnapshotFile::from_bytes(&bytes, "corrupted") else {
            refused += 1;
            continue;
        };
        answered += 1;
        let v = file.view();
        for c in [[0.0, 0.0, 1.0], [4.0, -3.0, 0.5]] {
            let _ = nearest_nodes(&v, Scope::Graph, c, 5).unwrap();
            let _ = nodes_within_radius(&v, Scope::Layer(mesh), c, 1.5).unwrap();
            let _ = nearest_in_subtree(&v, NodeId(1), c, 3).unwrap();
        }
        let _ = visible(&v, NodeId(1), &cone).unwrap();
    }
    assert!(
        refused > 0 && answered > 0,
        "{refused} refused, {answered} answered"
    );
}

/// A fold that keeps the layer index's point count (every node moved, none added) builds
/// a new base tree of the same size: its tree chunk must go out again, or a reader that
/// kept the old one answers from the old positions.
#[test]
fn a_fold_that_keeps_the_point_count_resends_the_tree_chunk() {
    let mut g = SceneGraph::new();
    let mesh = g.add_layer("mesh").unwrap();
    for i in 0..100u64 {
        g.add_node(NodeId(i), mesh).unwrap();
        let p = [(i % 10) as i8 - 5, (i / 10) as i8 - 5, 0];
        g.set_geometry(NodeId(i), cluster(&p, 50)).unwrap();
    }
    g.enable_layer_index(mesh).unwrap();
    let probes = six_probes(|i| [i - 3, 2 - i, i % 3], [1, 10, 60], 20);
    let mut publisher = Publisher::one_piece();
    let mut resent = 0;
    let mut last = None;
    for i in 0..40u64 {
        // Moved far off: 50 points each, as many as before.
        let p = [(i % 10) as i8 - 5, (i / 10) as i8 + 2, 3];
        g.set_geometry(NodeId(i), cluster(&p, 50)).unwrap();
        check_published(&mut g, &mut publisher, &probes);
        let tree = publisher
            .held
            .iter()
            .find(|(id, _)| is_tree_chunk_segment_id(**id))
            .map(|(_, (generation, _))| *generation);
        assert!(tree.is_some(), "the 5,000-point tree travels as a chunk");
        resent += usize::from(last.is_some() && tree != last);
        last = tree;
    }
    // The patch folds past 1,024 live points: once in 40 moves of 50 points.
    assert_eq!(
        resent, 1,
        "the tree chunk is resent at the fold, and only then"
    );
}

/// A graph of an `objects` layer over a `mesh` layer, and the objects layer: each
/// object `(id, parts)` nests one mesh node per part `(id, points)` and has a node index.
fn indexed_objects(
    objects: impl IntoIterator<Item = (u64, Vec<(u64, Vec<Point>)>)>,
) -> (SceneGraph, LayerId) {
    let mut g = SceneGraph::new();
    let object_layer = g.add_layer("objects").unwrap();
    let mesh = g.add_layer("mesh").unwrap();
    g.add_layer_edge(object_layer, mesh).unwrap();
    for (object, parts) in objects {
        g.add_node(NodeId(object), object_layer).unwrap();
        for (part, points) in parts {
            g.add_node(NodeId(part), mesh).unwrap();
            g.set_geometry(NodeId(part), points).unwrap();
            g.nest(NodeId(object), NodeId(part)).unwrap();
        }
        g.enable_node_index(NodeId(object)).unwrap();
    }
    (g, object_layer)
}

/// A publishing writer withholds node index trees smaller than a tree chunk: moving a
/// small object resends neither its tree nor the large object's tree chunk, answers stay
/// those of brute force (the sub-tree is walked), and the same cache asked for the layer
/// inline builds every tree it had left unbuilt.
#[test]
fn small_node_index_trees_are_withheld_from_a_publish_and_built_for_an_inline_segment() {
    // Objects 0..6 hold 5 points each (below `TREE_CHUNK`); object 6 holds 40.
    let (mut g, objects) = indexed_objects((0..7u64).map(|i| {
        let k = if i == 6 { 40 } else { 5 };
        (i, vec![(100 + i, cluster(&[2 * i as i8 - 6, 0, 0], k))])
    }));
    let probes = six_probes(|i| [2 * i - 6, 1, i % 2], [1, 3, 8], 30);
    let mut publisher = Publisher::one_piece();
    check_published(&mut g, &mut publisher, &probes);
    let big_tree = |publisher: &Publisher| {
        let trees: Vec<(u64, u64)> = publisher
            .held
            .iter()
            .filter(|(id, _)| is_tree_chunk_segment_id(**id))
            .map(|(id, (generation, _))| (*id, *generation))
            .collect();
        assert_eq!(trees.len(), 1, "only the 40-point tree travels: {trees:?}");
        trees[0]
    };
    let first = big_tree(&publisher);
    let inline_len = archive(&g.layer_segment(objects)).len();
    for step in 0..6u64 {
        let p = [2 * step as i8 - 6, 3, 1];
        g.set_geometry(NodeId(100 + step), cluster(&p, 5)).unwrap();
        let published = publisher.segments.published_layer(&mut g, objects);
        let published_len = archive(published.parts()[0].segment).len();
        assert!(
            published_len < inline_len,
            "the published objects layer ({published_len} bytes) carries no small tree (inline: {inline_len} bytes)"
        );
        check_published(&mut g, &mut publisher, &probes);
        assert_eq!(
            big_tree(&publisher),
            first,
            "moving a small object resent the large tree"
        );
    }
    // Inline, the cache's segment has every tree again, as a fresh build does.
    let fresh = g.layer_segment(objects);
    let cached = publisher.segments.layer_segment(&mut g, objects);
    let shape = |s: &ygg_store::snapshot::LayerSegment| -> Vec<(u64, Vec<u64>, usize)> {
        s.node_indexes
            .iter()
            .map(|i| (i.root, i.ids.clone(), i.tree.size()))
            .collect()
    };
    assert_eq!(shape(cached), shape(&fresh));
    assert_eq!(shape(&fresh)[0].2, 5);
}

/// With the default bounds, a publish withholds the tree of an object of two mesh nodes
/// (100 points) but not that of an object of one node per vertex (100 nodes, 100 points),
/// which a walk would visit node by node; moving the latter builds its tree again.
#[test]
fn a_small_tree_over_many_nodes_is_not_withheld() {
    let two_nodes = (0..2u64).map(|k| (100 + k, cluster(&[k as i8, 0, 0], 50)));
    let one_per_point = (0..100u64).map(|k| (200 + k, vec![grid(&[k as i8 % 10, 5, 0])]));
    let (mut g, objects) =
        indexed_objects([(1, two_nodes.collect()), (2, one_per_point.collect())]);
    let mut cache = SegmentCache::new();
    let tree_sizes = |cache: &mut SegmentCache, g: &mut SceneGraph| -> Vec<(u64, usize)> {
        let published = cache.published_layer(g, objects);
        published.parts()[0]
            .segment
            .node_indexes
            .iter()
            .map(|i| (i.root, i.tree.size()))
            .collect()
    };
    assert_eq!(tree_sizes(&mut cache, &mut g), vec![(1, 0), (2, 100)]);
    for k in 0..100u64 {
        g.set_geometry(NodeId(200 + k), vec![grid(&[k as i8 % 10, 6, 0])])
            .unwrap();
    }
    g.set_geometry(NodeId(100), cluster(&[3, 3, 0], 50))
        .unwrap();
    assert_eq!(tree_sizes(&mut cache, &mut g), vec![(1, 0), (2, 100)]);
}
