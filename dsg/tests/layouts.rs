//! Every layout of the fixtures holds the same objects with the same labels and the same
//! claimed geometry.

use std::collections::BTreeMap;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::{DsgGraph, NodeKind};
use ygg_store::query::{children, nodes_with_label};
use ygg_store::{NodeId, SceneGraph, SceneView, Scope};

fn fixture(name: &str) -> DsgGraph {
    let path = format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"));
    ygg_dsg::read_file(&path).unwrap()
}

/// Object id -> sorted claimed points (as bit patterns; its position when it claims none),
/// read through the layout.
fn object_geometry<V: SceneView>(v: &V, objects: &[u64]) -> BTreeMap<u64, Vec<[u32; 3]>> {
    objects
        .iter()
        .map(|&o| {
            let mut pts: Vec<[u32; 3]> = children(v, NodeId(o))
                .into_iter()
                .flat_map(|c| v.points(v.node(c).unwrap()).to_vec())
                .map(|p| p.map(f32::to_bits))
                .collect();
            pts.sort_unstable();
            (o, pts)
        })
        .collect()
}

fn expected_geometry(d: &DsgGraph) -> BTreeMap<u64, Vec<[u32; 3]>> {
    let mesh = d.mesh.as_ref();
    d.nodes
        .iter()
        .filter(|n| n.kind == NodeKind::Object)
        .map(|n| {
            let mut v = n.mesh_connections.clone();
            v.sort_unstable();
            v.dedup();
            let mut pts: Vec<[u32; 3]> = v
                .iter()
                .filter_map(|&i| mesh.map(|m| m.points[i as usize].map(f32::to_bits)))
                .collect();
            if pts.is_empty() {
                // No claimed vertex in the file: the object is located by its position.
                pts.push(n.position.map(f32::to_bits));
            }
            pts.sort_unstable();
            (n.id, pts)
        })
        .collect()
}

fn check(d: &DsgGraph, layouts: &[Layout]) {
    let objects: Vec<u64> = d
        .nodes
        .iter()
        .filter(|n| n.kind == NodeKind::Object)
        .map(|n| n.id)
        .collect();
    let want = expected_geometry(d);
    let labels: Vec<String> = d.object_label_histogram().into_keys().collect();
    for &l in layouts {
        let g: SceneGraph = layout::build(d, l).unwrap();
        g.check_invariants().unwrap();
        assert_eq!(
            object_geometry(&g, &objects),
            want,
            "{l}: object geometry differs"
        );
        let snap = g.to_snapshot();
        assert_eq!(
            object_geometry(&snap.view(), &objects),
            want,
            "{l}: archived geometry differs"
        );
        for label in &labels {
            let found = nodes_with_label(&g, Scope::Graph, label);
            let expect: Vec<NodeId> = {
                let mut v: Vec<NodeId> = d
                    .nodes
                    .iter()
                    .filter(|n| n.label.as_deref() == Some(label.as_str()))
                    .map(|n| NodeId(n.id))
                    .collect();
                v.sort_unstable();
                v
            };
            assert_eq!(found, expect, "{l}: label {label}");
        }
        let mesh_layers = layout::object_mesh_layers(&g);
        assert!(
            !mesh_layers.is_empty() || d.mesh.is_none(),
            "{l}: no mesh layers found"
        );
    }
}

#[test]
fn office_tiny_layouts_agree_on_objects() {
    check(&fixture("office_tiny.json"), &Layout::ALL);
}

#[test]
fn apartment_layouts_agree_on_objects() {
    check(&fixture("apartment_dsg.json"), &Layout::ALL);
}

#[test]
fn layout_names_parse() {
    for l in Layout::ALL {
        assert_eq!(l.name().parse::<Layout>().unwrap(), l);
    }
    assert!(
        "strawberry"
            .parse::<Layout>()
            .unwrap_err()
            .contains("strawberry")
    );
}
