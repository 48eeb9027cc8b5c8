//! Strict and lenient import of real Hydra output with faults: the apartment file with an
//! edge to an absent node, a duplicated edge and a node of an undeclared layer, in JSON
//! and in binary. Strict refuses, naming the problem and the lenient option; lenient
//! imports the rest and reports each class dropped with its count and first example.

use serde_json::{Value, json};
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::objects::Objects;
use ygg_dsg::{DropClass, DsgGraph, DsgImportError, ImportOptions, NodeSymbol};

fn fixture_path(name: &str) -> String {
    format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// p(99999): no such place in the apartment.
fn absent() -> u64 {
    NodeSymbol::new(b'p', 99_999).id()
}

/// The apartment JSON with three faults appended: an edge to the absent p(99999), a copy
/// of the first edge (reversed: edges are undirected) and an object in layer 9, which the
/// file does not declare.
fn faulty_apartment_json() -> Vec<u8> {
    let text = std::fs::read_to_string(fixture_path("apartment_dsg.json")).unwrap();
    let mut doc: Value = serde_json::from_str(&text).unwrap();
    let edges = doc["edges"].as_array_mut().unwrap();
    let first = edges[0].clone();
    let source = first["source"].as_u64().unwrap();
    edges.push(json!({"source": source, "target": absent(),
        "info": {"type": "EdgeAttributes", "weight": 1.0, "weighted": false}}));
    let mut dup = first.clone();
    dup["source"] = first["target"].clone();
    dup["target"] = first["source"].clone();
    edges.push(dup);
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let mut stray = nodes
        .iter()
        .find(|n| n["attributes"]["type"] == "ObjectNodeAttributes")
        .unwrap()
        .clone();
    stray["id"] = json!(NodeSymbol::new(b'O', 9_999).id());
    stray["layer"] = json!(9);
    nodes.push(stray);
    serde_json::to_vec(&doc).unwrap()
}

/// The same faults in Spark-DSG's binary encoding: the apartment written by
/// `to_binary_bytes` with an isolated object patched into layer 9, an edge to p(99999)
/// and a copy of the last edge inserted after the edge list.
fn faulty_apartment_binary(clean: &DsgGraph) -> Vec<u8> {
    let mut with_stray = clean.clone();
    let mut stray = clean
        .nodes_of_kind(ygg_dsg::NodeKind::Object)
        .next()
        .unwrap()
        .clone();
    stray.id = NodeSymbol::new(b'O', 9_999).id();
    stray.parent = None;
    with_stray.nodes.push(stray.clone());
    let mut fewer = with_stray.clone();
    fewer.edges.pop();
    let full = ygg_dsg::to_binary_bytes(&with_stray).unwrap();
    let short = ygg_dsg::to_binary_bytes(&fewer).unwrap();
    // No mesh: the body ends with the edge list's close (0x01) and has_mesh = false.
    assert_eq!(full[full.len() - 2..], [0x01, 0xc2]);
    // The last edge written (every intra-layer edge encodes to the same length).
    let end = full.len() - 2;
    let edge = full[end - (full.len() - short.len())..end].to_vec();
    // ARR32(3) = dd 03000000, then UINT64 source (cf + 8 bytes), UINT64 target.
    assert_eq!(edge[..6], [0xdd, 3, 0, 0, 0, 0xcf]);
    assert_eq!(edge[14], 0xcf);
    let mut dangling = edge.clone();
    dangling[15..23].copy_from_slice(&absent().to_le_bytes());
    let mut bytes = full;
    bytes.splice(bytes.len() - 2..bytes.len() - 2, [dangling, edge].concat());
    // The stray node: ARR32(4), INT64 layer (d3 + 8 bytes), UINT64 id (cf + 8 bytes).
    let id = [[0xcf].as_slice(), &stray.id.to_le_bytes()].concat();
    let pos = bytes.windows(9).position(|w| w == id.as_slice()).unwrap();
    assert_eq!(bytes[pos - 9], 0xd3);
    bytes[pos - 8..pos].copy_from_slice(&9i64.to_le_bytes());
    bytes
}

fn check_lenient(imported: &ygg_dsg::Imported, clean: &DsgGraph) {
    let r = &imported.report;
    assert_eq!(r.count(DropClass::EdgeToAbsentNode), 1, "{r}");
    assert_eq!(r.count(DropClass::DuplicateEdge), 1, "{r}");
    assert_eq!(r.count(DropClass::NodeOfUnknownLayer), 1, "{r}");
    assert_eq!(r.dropped.len(), 3, "{r}");
    let text = r.to_string();
    assert!(text.contains("dropped 1 edges to absent nodes"), "{text}");
    assert!(text.contains("p(99999)"), "{text}");
    assert!(text.contains("O(9999)"), "{text}");
    assert!(text.contains("layer 9"), "{text}");
    assert!(!text.contains("--lenient"), "{text}");
    let g = &imported.graph;
    assert_eq!(g.nodes, clean.nodes);
    assert_eq!(g.counts(), clean.counts());
    assert_eq!(g.edges, clean.edges);
    // The lenient graph is a whole graph: its layouts build and answer.
    let scene = layout::build(g, Layout::Mint).unwrap();
    assert_eq!(Objects::new(&scene).objects_with_label("5").len(), 3);
}

#[test]
fn strict_refuses_and_names_the_problem_and_the_flag() {
    let bytes = faulty_apartment_json();
    let e = ygg_dsg::parse_json(&bytes, "faulty.json").unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, DsgImportError::UnknownLayer { .. }), "{msg}");
    assert!(msg.contains("unknown layer 9 partition 0"), "{msg}");
    assert!(msg.contains("--lenient"), "{msg}");
    // Without the stray node, the first fault is the edge to the absent place.
    let mut doc: Value = serde_json::from_slice(&bytes).unwrap();
    doc["nodes"].as_array_mut().unwrap().pop();
    let e = ygg_dsg::parse_json(&serde_json::to_vec(&doc).unwrap(), "faulty.json").unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, DsgImportError::DanglingEdge { .. }), "{msg}");
    assert!(msg.contains("node p(99999)"), "{msg}");
    assert!(msg.contains("does not exist"), "{msg}");
    assert!(msg.contains("--lenient"), "{msg}");
}

#[test]
fn lenient_json_drops_each_fault_and_reports_it() {
    let clean = ygg_dsg::read_file(fixture_path("apartment_dsg.json")).unwrap();
    let bytes = faulty_apartment_json();
    let imported = ygg_dsg::parse_json_with(&bytes, "faulty.json", ImportOptions::LENIENT)
        .unwrap_or_else(|e| panic!("{e}"));
    check_lenient(
        &imported,
        &DsgGraph {
            source: "faulty.json".to_owned(),
            ..clean.clone()
        },
    );
    // Through a file, the same.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("faulty.json");
    std::fs::write(&path, &bytes).unwrap();
    let from_file = ygg_dsg::read_file_with(&path, ImportOptions::LENIENT).unwrap();
    for d in &imported.report.dropped {
        assert_eq!(from_file.report.count(d.class), d.count);
    }
    assert!(ygg_dsg::read_file_with(&path, ImportOptions::default()).is_err());
    // A clean file leniently: nothing dropped.
    let ok = ygg_dsg::read_file_with(fixture_path("apartment_dsg.json"), ImportOptions::LENIENT)
        .unwrap();
    assert!(ok.report.is_empty());
    assert_eq!(ok.report.to_string(), "nothing dropped");
    assert_eq!(ok.graph, clean);
}

#[test]
fn lenient_binary_drops_each_fault_and_reports_it() {
    let clean = ygg_dsg::read_file(fixture_path("apartment_dsg.sparkdsg")).unwrap();
    let bytes = faulty_apartment_binary(&clean);
    let e = ygg_dsg::parse_binary(&bytes, "faulty.sparkdsg").unwrap_err();
    assert!(e.to_string().contains("--lenient"), "{e}");
    let imported = ygg_dsg::parse_binary_with(&bytes, "faulty.sparkdsg", ImportOptions::LENIENT)
        .unwrap_or_else(|e| panic!("{e}"));
    check_lenient(
        &imported,
        &DsgGraph {
            source: "faulty.sparkdsg".to_owned(),
            ..clean
        },
    );
}

#[test]
fn edges_to_dropped_nodes_are_their_own_class() {
    let mut doc: Value = serde_json::from_slice(&faulty_apartment_json()).unwrap();
    let first_place = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["attributes"]["type"] == "PlaceNodeAttributes")
        .unwrap()["id"]
        .clone();
    // An edge to the stray layer-9 node, and a node of an unknown attribute type.
    doc["edges"].as_array_mut().unwrap().push(json!({
        "source": NodeSymbol::new(b'O', 9_999).id(), "target": first_place}));
    let mut odd = doc["nodes"][0].clone();
    odd["id"] = json!(NodeSymbol::new(b'K', 1).id());
    odd["attributes"]["type"] = json!("KhronosObjectAttributes");
    doc["nodes"].as_array_mut().unwrap().push(odd);
    let bytes = serde_json::to_vec(&doc).unwrap();
    let r = ygg_dsg::parse_json_with(&bytes, "faulty.json", ImportOptions::LENIENT)
        .unwrap()
        .report;
    assert_eq!(r.count(DropClass::EdgeToDroppedNode), 1, "{r}");
    assert_eq!(r.count(DropClass::NodeOfUnknownType), 1, "{r}");
    assert!(r.to_string().contains("KhronosObjectAttributes"), "{r}");
    assert!(r.to_string().contains("was dropped"), "{r}");
}
