//! The object queries of `ygg_dsg::objects` equal brute force computed straight from
//! the imported Spark-DSG graph (mesh points and `mesh_connections`; an object claiming
//! no vertex present in the file is its position), on every layout, live and
//! saved-and-reopened.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::objects::{ObjectQuery, Objects, cone_view};
use ygg_dsg::{DsgGraph, NodeKind};
use ygg_store::query::within_radius;
use ygg_store::{NodeId, Point, SceneView, SnapshotFile, distance_squared};

fn fixture(name: &str) -> DsgGraph {
    let path = format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"));
    ygg_dsg::read_file(&path).unwrap()
}

/// Brute force over the imported graph.
struct Truth {
    /// Object id (ascending) and its geometry: its claimed points, or its position
    /// when it claims no vertex present in the file.
    objects: Vec<(u64, Vec<Point>)>,
    /// Object id and labels (labelspace name or name, and the decimal semantic label).
    labels: Vec<(u64, Vec<String>)>,
}

impl Truth {
    fn new(d: &DsgGraph) -> Self {
        let mut objects: Vec<(u64, Vec<Point>)> = d
            .nodes
            .iter()
            .filter(|n| n.kind == NodeKind::Object)
            .map(|n| {
                let pts: Vec<Point> = match &d.mesh {
                    Some(m) => n
                        .mesh_connections
                        .iter()
                        .map(|&v| m.points[v as usize])
                        .collect(),
                    None => Vec::new(),
                };
                if pts.is_empty() {
                    (n.id, vec![n.position])
                } else {
                    (n.id, pts)
                }
            })
            .collect();
        objects.sort_by_key(|o| o.0);
        let labels = d
            .nodes
            .iter()
            .filter(|n| n.kind == NodeKind::Object)
            .map(|n| {
                let mut labels = Vec::new();
                labels.extend(n.label.clone());
                labels.extend(n.semantic_label.map(|l| l.to_string()));
                (n.id, labels)
            })
            .collect();
        Truth { objects, labels }
    }

    fn answer(&self, q: &ObjectQuery) -> Vec<NodeId> {
        let mut out: Vec<u64> = match q {
            ObjectQuery::NearestObject { point } => {
                let mut best: Option<(f32, u64)> = None;
                for (id, pts) in &self.objects {
                    for p in pts {
                        let d = distance_squared(p, point).sqrt();
                        if best.is_none_or(|(bd, bid)| d < bd || (d == bd && *id < bid)) {
                            best = Some((d, *id));
                        }
                    }
                }
                best.map(|b| b.1).into_iter().collect()
            }
            ObjectQuery::ObjectsWithin { point, radius } => self
                .objects
                .iter()
                .filter(|(_, pts)| pts.iter().any(|p| within_radius(p, point, *radius)))
                .map(|o| o.0)
                .collect(),
            ObjectQuery::VisibleObjects {
                eye,
                dir,
                half_angle_deg,
                range,
            } => {
                let cone = cone_view(*eye, *dir, *half_angle_deg, *range).unwrap();
                self.objects
                    .iter()
                    .filter(|(_, pts)| pts.iter().any(|p| cone.contains(p).unwrap()))
                    .map(|o| o.0)
                    .collect()
            }
            ObjectQuery::ObjectsWithLabel { label } => self
                .labels
                .iter()
                .filter(|(_, l)| l.contains(label))
                .map(|o| o.0)
                .collect(),
        };
        out.sort_unstable();
        out.into_iter().map(NodeId).collect()
    }
}

/// Random queries over the scene's extent, biased to hit objects: points on and near
/// claimed vertices (exact ties on shared vertices), and zero / huge radii and ranges.
fn random_queries(d: &DsgGraph, truth: &Truth, n: usize, seed: u64) -> Vec<ObjectQuery> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let claimed: Vec<Point> = truth
        .objects
        .iter()
        .flat_map(|o| o.1.iter().copied())
        .collect();
    let (lo, hi) = extent(d);
    let mut labels: Vec<String> = truth.labels.iter().flat_map(|l| l.1.clone()).collect();
    labels.extend(["absent".to_owned(), String::new(), "room".to_owned()]);
    let point = |rng: &mut ChaCha8Rng| -> Point {
        match rng.gen_range(0..4) {
            0 if !claimed.is_empty() => claimed[rng.gen_range(0..claimed.len())],
            1 if !claimed.is_empty() => {
                let p = claimed[rng.gen_range(0..claimed.len())];
                p.map(|v| v + rng.gen_range(-0.3..0.3))
            }
            _ => [0, 1, 2].map(|a| rng.gen_range(lo[a] - 2.0..hi[a] + 2.0)),
        }
    };
    (0..n)
        .map(|i| match i % 4 {
            0 => ObjectQuery::NearestObject {
                point: point(&mut rng),
            },
            1 => ObjectQuery::ObjectsWithin {
                point: point(&mut rng),
                radius: *[0.0, 0.05, 0.25, 0.5, 1.0, 2.0, 4.0, 100.0]
                    .get(rng.gen_range(0..8))
                    .unwrap_or(&1.0),
            },
            2 => {
                let dir: Point = if rng.gen_bool(0.2) {
                    [1.0, 0.0, 0.0]
                } else {
                    [0, 1, 2].map(|_| rng.gen_range(-1.0..1.0))
                };
                ObjectQuery::VisibleObjects {
                    eye: point(&mut rng),
                    dir: if dir.iter().all(|v| *v == 0.0) {
                        [0.0, 0.0, 1.0]
                    } else {
                        dir
                    },
                    half_angle_deg: *[0.0, 10.0, 30.0, 45.0, 70.0, 90.0, 135.0, 180.0]
                        .get(rng.gen_range(0..8))
                        .unwrap_or(&30.0),
                    range: *[0.0, 0.3, 1.0, 3.0, 8.0, 50.0]
                        .get(rng.gen_range(0..6))
                        .unwrap_or(&3.0),
                }
            }
            _ => ObjectQuery::ObjectsWithLabel {
                label: labels[rng.gen_range(0..labels.len())].clone(),
            },
        })
        .collect()
}

fn extent(d: &DsgGraph) -> (Point, Point) {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    let pts = d
        .mesh
        .iter()
        .flat_map(|m| m.points.iter())
        .chain(d.nodes.iter().map(|n| &n.position));
    for p in pts {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi)
}

fn answers<V: SceneView>(view: &V, queries: &[ObjectQuery]) -> Vec<Vec<NodeId>> {
    let objects = Objects::new(view);
    queries.iter().map(|q| objects.answer(q).unwrap()).collect()
}

fn check_against_brute_force(d: &DsgGraph, n: usize, seed: u64) {
    let truth = Truth::new(d);
    let queries = random_queries(d, &truth, n, seed);
    let want: Vec<Vec<NodeId>> = queries.iter().map(|q| truth.answer(q)).collect();
    let non_empty = want.iter().filter(|a| !a.is_empty()).count();
    let dir = tempfile::tempdir().unwrap();
    for layout in Layout::ALL {
        let g = layout::build(d, layout).unwrap();
        let live = answers(&g, &queries);
        let path = dir.path().join(format!("{layout}.ygg"));
        g.save(&path).unwrap();
        let file = SnapshotFile::open(&path).unwrap();
        let archived = answers(&file.view(), &queries);
        for (i, q) in queries.iter().enumerate() {
            assert_eq!(live[i], want[i], "{layout} live, query {i}: {q:?}");
            assert_eq!(archived[i], want[i], "{layout} archived, query {i}: {q:?}");
        }
    }
    check_rooms(d, &truth, &queries);
    eprintln!(
        "{}: {n} queries, {non_empty} with non-empty answers",
        d.source
    );
    assert!(non_empty > n / 2, "the queries hit too few objects");
}

/// Objects scoped to one room ([`Objects::in_subtree`]) answer what brute force answers
/// over that room's objects, on every per-room layout, live and archived.
fn check_rooms(d: &DsgGraph, truth: &Truth, queries: &[ObjectQuery]) {
    let index = d.node_index();
    let room_nodes: Vec<&ygg_dsg::DsgNode> = d.nodes_of_kind(NodeKind::Room).collect();
    // An object's room: its ancestor room; without one (Hydra links only some places to
    // rooms), the first room whose box holds it in x and y, else the nearest in x and y.
    let room_of = |id: u64| {
        let object = &d.nodes[index[&id]];
        let mut cur = object.parent;
        while let Some(p) = cur {
            let n = &d.nodes[index[&p]];
            if n.kind == NodeKind::Room {
                return Some(p);
            }
            cur = n.parent;
        }
        let p = object.position;
        let xy =
            |r: &ygg_dsg::DsgNode| (r.position[0] - p[0]).powi(2) + (r.position[1] - p[1]).powi(2);
        room_nodes
            .iter()
            .find(|r| {
                r.bbox
                    .is_some_and(|b| (0..2).all(|a| b.min[a] <= p[a] && p[a] <= b.max[a]))
            })
            .or_else(|| {
                room_nodes
                    .iter()
                    .min_by(|a, b| xy(a).total_cmp(&xy(b)).then(a.id.cmp(&b.id)))
            })
            .map(|r| r.id)
    };
    let rooms: Vec<u64> = room_nodes.iter().map(|n| n.id).collect();
    for layout in [Layout::Chocolate, Layout::Mint, Layout::Saffron] {
        let g = layout::build(d, layout).unwrap();
        let snapshot = g.to_snapshot();
        let archived = snapshot.view();
        for &room in &rooms {
            let live = Objects::in_subtree(&g, NodeId(room));
            let arch = Objects::in_subtree(&archived, NodeId(room));
            for (i, q) in queries.iter().enumerate() {
                let want: Vec<NodeId> = match q {
                    // The nearest among the room's objects is not the nearest overall.
                    ObjectQuery::NearestObject { point } => {
                        let here = Truth {
                            objects: truth
                                .objects
                                .iter()
                                .filter(|o| room_of(o.0) == Some(room))
                                .cloned()
                                .collect(),
                            labels: Vec::new(),
                        };
                        here.answer(&ObjectQuery::NearestObject { point: *point })
                    }
                    _ => truth
                        .answer(q)
                        .into_iter()
                        .filter(|o| room_of(o.0) == Some(room))
                        .collect(),
                };
                assert_eq!(
                    live.answer(q).unwrap(),
                    want,
                    "{layout} room {room}, query {i}: {q:?}"
                );
                assert_eq!(
                    arch.answer(q).unwrap(),
                    want,
                    "{layout} archived room {room}, query {i}"
                );
            }
        }
    }
}

#[test]
fn office_tiny_answers_equal_brute_force_on_every_layout() {
    check_against_brute_force(&fixture("office_tiny.json"), 2000, 11);
}

#[test]
fn generated_office_answers_equal_brute_force_on_every_layout() {
    let d = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams {
        seed: 3,
        scale: 0.05,
    });
    check_against_brute_force(&d, 600, 5);
}

/// Real Hydra output saves no mesh: every object is located by its position, labelled
/// by its decimal semantic label, and keeps its stored box as features; the same from
/// the JSON file and from its binary twin.
#[test]
fn apartment_objects_are_located_by_position() {
    for file in ["apartment_dsg.json", "apartment_dsg.sparkdsg"] {
        let d = fixture(file);
        assert!(d.mesh.is_none());
        check_against_brute_force(&d, 400, 2);
        let truth = Truth::new(&d);
        for layout in Layout::ALL {
            let g = layout::build(&d, layout).unwrap();
            let o = Objects::new(&g);
            assert_eq!(o.objects().len(), 7, "{layout}");
            assert_eq!(o.objects_with_geometry().count(), 7, "{layout}");
            // From exactly an object's position, that object is the nearest.
            for (id, pts) in &truth.objects {
                assert_eq!(o.nearest_object(pts[0]).unwrap(), Some(NodeId(*id)));
                assert!(
                    o.objects_within(pts[0], 0.0)
                        .unwrap()
                        .contains(&NodeId(*id))
                );
            }
            // Integer labels only (no labelspace; names are symbols): 5 x3, 11 x2, 16 x2.
            for (label, n) in [("5", 3), ("11", 2), ("16", 2), ("O(0)", 0), ("4", 0)] {
                assert_eq!(o.objects_with_label(label).len(), n, "{layout} {label}");
            }
            // The stored box is reachable as features.
            let o0 = d.nodes_of_kind(NodeKind::Object).next().unwrap();
            let bb = o0.bbox.unwrap();
            let n = g.node(NodeId(o0.id)).unwrap();
            for (k, v) in layout::STORED_BOX_FEATURES
                .iter()
                .zip(bb.min.iter().chain(&bb.max))
            {
                assert_eq!(
                    g.feature(n, k),
                    Some(ygg_store::FeatureRef::Float(f64::from(*v))),
                    "{layout} {k}"
                );
            }
        }
    }
}

/// The office files carry a labelspace: objects are found under its names and under
/// their decimal ids.
#[test]
fn office_objects_are_found_by_name_and_by_id() {
    let d = fixture("office_tiny.json");
    let light = d
        .nodes_of_kind(NodeKind::Object)
        .find(|n| n.label.as_deref() == Some("light"))
        .unwrap();
    let id = light.semantic_label.unwrap().to_string();
    for layout in Layout::ALL {
        let g = layout::build(&d, layout).unwrap();
        let o = Objects::new(&g);
        let by_name = o.objects_with_label("light");
        assert_eq!(by_name.len(), 4, "{layout}");
        assert_eq!(o.objects_with_label(&id), by_name, "{layout}");
    }
}

#[test]
fn objects_are_found_in_every_layout() {
    let d = fixture("office_tiny.json");
    let want: Vec<NodeId> = Truth::new(&d).objects.iter().map(|o| NodeId(o.0)).collect();
    for layout in Layout::ALL {
        let g = layout::build(&d, layout).unwrap();
        let o = Objects::new(&g);
        assert_eq!(o.objects(), want, "{layout}");
        assert_eq!(
            o.objects_with_geometry().collect::<Vec<_>>(),
            want,
            "{layout}"
        );
        assert!(!o.mesh_layers().is_empty(), "{layout}");
    }
}

#[test]
fn shared_vertices_tie_to_the_smaller_id() {
    let d = fixture("office_tiny.json");
    let truth = Truth::new(&d);
    // A vertex claimed by two or more objects: nearest from exactly there is the
    // smallest claimant, and a zero radius finds every claimant.
    let mut claims: std::collections::BTreeMap<[u32; 3], Vec<u64>> = Default::default();
    for (id, pts) in &truth.objects {
        for p in pts {
            claims.entry(p.map(f32::to_bits)).or_default().push(*id);
        }
    }
    let shared: Vec<(Point, Vec<u64>)> = claims
        .into_iter()
        .filter_map(|(k, mut ids)| {
            ids.sort_unstable();
            ids.dedup();
            (ids.len() > 1).then(|| (k.map(f32::from_bits), ids))
        })
        .take(50)
        .collect();
    assert!(!shared.is_empty());
    for layout in Layout::ALL {
        let g = layout::build(&d, layout).unwrap();
        let o = Objects::new(&g);
        for (p, ids) in &shared {
            assert_eq!(o.nearest_object(*p).unwrap(), Some(NodeId(ids[0])));
            let within = o.objects_within(*p, 0.0).unwrap();
            for id in ids {
                assert!(within.contains(&NodeId(*id)), "{layout}");
            }
        }
    }
}

#[test]
fn bad_inputs_are_errors_on_every_layout() {
    let d = fixture("office_tiny.json");
    let bad = [
        ObjectQuery::NearestObject {
            point: [f32::NAN, 0.0, 0.0],
        },
        ObjectQuery::ObjectsWithin {
            point: [0.0; 3],
            radius: -1.0,
        },
        ObjectQuery::ObjectsWithin {
            point: [f32::INFINITY, 0.0, 0.0],
            radius: 1.0,
        },
        ObjectQuery::VisibleObjects {
            eye: [0.0; 3],
            dir: [0.0; 3],
            half_angle_deg: 30.0,
            range: 1.0,
        },
        ObjectQuery::VisibleObjects {
            eye: [0.0; 3],
            dir: [1.0, 0.0, 0.0],
            half_angle_deg: 181.0,
            range: 1.0,
        },
        ObjectQuery::VisibleObjects {
            eye: [0.0; 3],
            dir: [1.0, 0.0, 0.0],
            half_angle_deg: 30.0,
            range: f32::NAN,
        },
    ];
    for layout in Layout::ALL {
        let g = layout::build(&d, layout).unwrap();
        let o = Objects::new(&g);
        for q in &bad {
            assert!(o.answer(q).is_err(), "{layout}: {q:?}");
        }
    }
}
