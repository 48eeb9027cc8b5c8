//! Bad input to the Spark-DSG importer: precise errors, and no panic under fuzzing.

/// Named `dsg` so that `cargo test -p ygg-store dsg` selects these tests.
mod dsg {
    use std::path::Path;

    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use serde_json::{Value, json};
    use ygg_dsg::{DsgImportError, LayerKey, NodeSymbol};

    const O0: u64 = 0x4F00_0000_0000_0000;
    const O1: u64 = 0x4F00_0000_0000_0001;
    const P0: u64 = 0x7000_0000_0000_0000;
    const R0: u64 = 0x5200_0000_0000_0000;

    /// A small valid v1.1.3 document: two objects under a place under a room, a mesh.
    fn doc() -> Value {
        json!({
            "SPARK_DSG_header": {"project_name": "main", "version": {"major": 1, "minor": 1, "patch": 3}},
            "directed": false,
            "layer_keys": [{"layer": 2, "partition": 0}, {"layer": 3, "partition": 0}, {"layer": 4, "partition": 0}],
            "layer_names": {"OBJECTS": {"layer": 2, "partition": 0}, "PLACES": {"layer": 3, "partition": 0}},
            "nodes": [
                {"id": O0, "layer": 2, "partition": 0, "attributes": {
                    "type": "ObjectNodeAttributes", "position": [1.0, 2.0, 0.5], "name": "desk",
                    "semantic_label": 6, "mesh_connections": [0, 1, 2],
                    "bounding_box": {"type": "AABB", "dimensions": [1.0, 1.0, 1.0],
                                     "world_P_center": [1.0, 2.0, 0.5],
                                     "world_R_center": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0}}}},
                {"id": O1, "layer": 2, "partition": 0, "attributes": {
                    "type": "ObjectNodeAttributes", "position": [3.0, 2.0, 0.5], "name": "chair",
                    "mesh_connections": [2, 3]}},
                {"id": P0, "layer": 3, "partition": 0, "attributes": {
                    "type": "PlaceNodeAttributes", "position": [2.0, 2.0, 1.0]}},
                {"id": R0, "layer": 4, "partition": 0, "attributes": {
                    "type": "RoomNodeAttributes", "position": [2.0, 2.0, 1.5], "name": "R(0)"}}
            ],
            "edges": [
                {"source": O0, "target": P0, "info": {"type": "EdgeAttributes", "weight": 1.0, "weighted": false}},
                {"source": P0, "target": O1},
                {"source": P0, "target": R0},
                {"source": O0, "target": O1, "info": {"weight": 0.5, "weighted": true}}
            ],
            "mesh": {
                "points": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
                "faces": [[0, 1, 2], [1, 3, 2]],
                "labels": [6, 6, 6, 2],
                "has_labels": true
            }
        })
    }

    fn parse(v: &Value) -> Result<ygg_dsg::DsgGraph, DsgImportError> {
        let bytes = serde_json::to_vec(v).expect("serialize");
        ygg_dsg::parse_json(&bytes, "test.json")
    }

    fn err(v: &Value) -> DsgImportError {
        match parse(v) {
            Ok(_) => panic!("expected an error"),
            Err(e) => {
                assert_eq!(e.file(), "test.json");
                assert!(e.to_string().starts_with("test.json: "), "{e}");
                e
            }
        }
    }

    #[test]
    fn small_document_is_valid() {
        let g = parse(&doc()).expect("valid");
        let c = g.counts();
        assert_eq!(
            (c.nodes, c.edges, c.intra_edges, c.parent_edges),
            (4, 4, 1, 3)
        );
        assert_eq!(g.edges[0].weight, Some(0.5));
        let o0 = &g.nodes[0];
        assert_eq!(o0.parent, Some(P0));
        assert_eq!(o0.label.as_deref(), Some("desk"));
        let b = o0.bbox.expect("box");
        assert_eq!((b.min, b.max), ([0.5, 1.5, 0.0], [1.5, 2.5, 1.0]));
        assert_eq!(g.nodes[3].label, None, "R(0) is a symbol, not a label");
        assert_eq!(g.nodes[3].name.as_deref(), Some("R(0)"));
        assert_eq!(
            g.layer_by_name("ROOMS").map(|l| l.key),
            Some(LayerKey::ROOMS)
        );
    }

    #[test]
    fn truncated_json_reports_line_and_column() {
        let text = serde_json::to_string_pretty(&doc()).expect("serialize");
        let cut = &text.as_bytes()[..text.len() / 2];
        let e = ygg_dsg::parse_json(cut, "cut.json").expect_err("truncated");
        assert!(matches!(e, DsgImportError::Syntax { .. }), "{e}");
        let (line, column) = e.line_column().expect("position");
        assert!(line > 10 && column > 0, "{e}");
        assert!(
            e.to_string()
                .starts_with("cut.json: malformed JSON at line"),
            "{e}"
        );
    }

    #[test]
    fn garbage_is_a_syntax_error() {
        for bad in [&b""[..], b"{", b"nul", b"{\"nodes\": [}", b"\xff\xfe"] {
            let e = ygg_dsg::parse_json(bad, "g.json").expect_err("garbage");
            assert!(matches!(e, DsgImportError::Syntax { .. }), "{e}");
        }
        let e = ygg_dsg::parse_json(b"[1,2]", "g.json").expect_err("not an object");
        assert!(matches!(e, DsgImportError::InvalidField { .. }), "{e}");
    }

    #[test]
    fn wrong_type_in_a_node_names_node_and_field() {
        let mut d = doc();
        d["nodes"][1]["attributes"]["position"][1] = json!("two");
        let e = err(&d);
        assert!(matches!(e, DsgImportError::InvalidField { .. }), "{e}");
        assert_eq!(e.node(), Some(O1));
        assert_eq!(e.field(), Some("nodes[1].attributes.position[1]"));
        assert!(e.line_column().is_some());
        assert!(e.to_string().contains("O(1)"), "{e}");

        let mut d = doc();
        d["nodes"][0]["attributes"]["mesh_connections"][2] = json!(-4);
        let e = err(&d);
        assert_eq!(e.node(), Some(O0));
        assert_eq!(e.field(), Some("nodes[0].attributes.mesh_connections[2]"));

        let mut d = doc();
        d["nodes"][0]["attributes"]["bounding_box"]["dimensions"][0] = json!(true);
        let e = err(&d);
        assert_eq!(
            e.field(),
            Some("nodes[0].attributes.bounding_box.dimensions[0]")
        );

        let mut d = doc();
        d["nodes"][2]["id"] = json!("p(0)");
        let e = err(&d);
        assert_eq!(e.node(), None);
        assert_eq!(e.field(), Some("nodes[2].id"));

        let mut d = doc();
        d["nodes"][2]["attributes"]
            .as_object_mut()
            .expect("object")
            .remove("position");
        let e = err(&d);
        assert_eq!(e.node(), Some(P0));
        assert_eq!(e.field(), Some("nodes[2].attributes.position"));
    }

    #[test]
    fn wrong_type_in_edges_and_mesh_names_the_entry() {
        let mut d = doc();
        d["edges"][2]["target"] = json!(1.5);
        let e = err(&d);
        assert_eq!(e.field(), Some("edges[2].target"));

        let mut d = doc();
        d["mesh"]["points"][3] = json!([1.0, 2.0]);
        let e = err(&d);
        assert_eq!(e.field(), Some("mesh.points[3]"), "{e}");

        let mut d = doc();
        d["mesh"]["faces"][1][2] = json!("x");
        let e = err(&d);
        assert_eq!(e.field(), Some("mesh.faces[1]"), "{e}");
    }

    #[test]
    fn ids_above_2_pow_53_are_exact_and_floats_are_rejected() {
        let mut d = doc();
        let big = NodeSymbol::new(b'R', (1 << 53) + 1).id();
        d["nodes"][3]["id"] = json!(big);
        d["edges"][2]["target"] = json!(big);
        let g = parse(&d).expect("valid");
        assert_eq!(g.nodes[3].id, big);
        assert_eq!(g.nodes[2].parent, Some(big));

        let text = serde_json::to_string(&doc())
            .expect("serialize")
            .replace(&R0.to_string(), "5.908722711110091e18");
        let e = ygg_dsg::parse_json(text.as_bytes(), "f.json").expect_err("float id");
        assert!(
            e.field()
                .is_some_and(|f| f.ends_with(".id") || f.ends_with(".target")),
            "{e}"
        );
    }

    #[test]
    fn unknown_layer_is_an_error() {
        let mut d = doc();
        d["nodes"][2]["layer"] = json!(7);
        let e = err(&d);
        assert!(
            matches!(e, DsgImportError::UnknownLayer { node: P0, layer, .. } if layer == LayerKey::new(7, 0)),
            "{e}"
        );
        let mut d = doc();
        d["nodes"][2]["partition"] = json!(5);
        assert!(matches!(err(&d), DsgImportError::UnknownLayer { .. }));
    }

    #[test]
    fn unknown_attribute_type_is_an_error() {
        let mut d = doc();
        d["nodes"][2]["attributes"]["type"] = json!("FrobnicatorAttributes");
        let e = err(&d);
        assert!(
            matches!(&e, DsgImportError::UnknownNodeType { node: P0, type_name, .. } if type_name == "FrobnicatorAttributes"),
            "{e}"
        );
    }

    #[test]
    fn dangling_self_and_duplicate_edges_are_errors() {
        let mut d = doc();
        d["edges"][1]["target"] = json!(O0 + 99);
        let e = err(&d);
        assert!(
            matches!(e, DsgImportError::DanglingEdge { edge: 1, missing, .. } if missing == O0 + 99),
            "{e}"
        );

        let mut d = doc();
        d["edges"][3]["target"] = json!(O0);
        assert!(matches!(
            err(&d),
            DsgImportError::SelfEdge {
                edge: 3,
                node: O0,
                ..
            }
        ));

        let mut d = doc();
        d["edges"][3] = json!({"source": P0, "target": O0});
        assert!(matches!(
            err(&d),
            DsgImportError::DuplicateEdge { edge: 3, .. }
        ));
    }

    #[test]
    fn duplicate_node_ids_are_errors() {
        let mut d = doc();
        d["nodes"][1]["id"] = json!(O0);
        let e = err(&d);
        assert!(
            matches!(
                e,
                DsgImportError::DuplicateNode {
                    node: O0,
                    first: 0,
                    second: 1,
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn non_finite_coordinates_are_errors() {
        let mut d = doc();
        d["nodes"][0]["attributes"]["position"][2] = Value::Null; // nlohmann's NaN
        let e = err(&d);
        assert!(matches!(e, DsgImportError::NonFinite { .. }), "{e}");
        assert_eq!(e.node(), Some(O0));
        assert_eq!(e.field(), Some("attributes.position[2]"));

        let mut d = doc();
        d["mesh"]["points"][1][0] = json!(1e39); // finite f64, infinite f32
        let e = err(&d);
        assert_eq!(e.field(), Some("mesh.points[1][0]"), "{e}");

        let mut d = doc();
        d["edges"][3]["info"]["weight"] = Value::Null;
        let e = err(&d);
        assert_eq!(e.field(), Some("edges[3].info.weight"), "{e}");

        let mut d = doc();
        d["nodes"][0]["attributes"]["bounding_box"]["world_P_center"][0] = Value::Null;
        let e = err(&d);
        assert_eq!(
            e.field(),
            Some("attributes.bounding_box.world_P_center[0]"),
            "{e}"
        );
    }

    #[test]
    fn out_of_range_mesh_indices_are_errors() {
        let mut d = doc();
        d["nodes"][1]["attributes"]["mesh_connections"][1] = json!(4);
        let e = err(&d);
        assert!(
            matches!(
                e,
                DsgImportError::MeshConnectionOutOfRange {
                    node: O1,
                    index: 1,
                    vertex: 4,
                    vertex_count: 4,
                    ..
                }
            ),
            "{e}"
        );

        let mut d = doc();
        d["mesh"]["faces"][0][1] = json!(17);
        assert!(matches!(
            err(&d),
            DsgImportError::FaceOutOfRange {
                face: 0,
                vertex: 17,
                ..
            }
        ));

        let mut d = doc();
        d["mesh"]["labels"] = json!([1, 2]);
        assert!(matches!(
            err(&d),
            DsgImportError::MeshLabelCount { labels: 2, .. }
        ));

        // Without a mesh, mesh_connections are not range checked (real Hydra files).
        let mut d = doc();
        d.as_object_mut().expect("object").remove("mesh");
        d["nodes"][1]["attributes"]["mesh_connections"][1] = json!(4000);
        assert!(parse(&d).is_ok());
    }

    #[test]
    fn version_and_partition_rules() {
        let mut d = doc();
        d["SPARK_DSG_header"]["version"]["major"] = json!(2);
        assert!(matches!(err(&d), DsgImportError::UnsupportedVersion { .. }));

        let mut d = doc();
        d["nodes"][2]
            .as_object_mut()
            .expect("object")
            .remove("partition");
        let e = err(&d);
        assert!(
            matches!(e, DsgImportError::MissingField { node: Some(P0), .. }),
            "{e}"
        );

        let mut d = doc();
        d.as_object_mut().expect("object").remove("layer_keys");
        assert!(matches!(err(&d), DsgImportError::MissingField { .. }));
    }

    #[test]
    fn several_parents_keep_the_first_and_record_the_rest() {
        let mut d = doc();
        let r1 = NodeSymbol::new(b'R', 1).id();
        d["nodes"]
            .as_array_mut()
            .expect("array")
            .push(json!({"id": r1, "layer": 4, "partition": 0,
                     "attributes": {"type": "RoomNodeAttributes", "position": [0, 0, 0]}}));
        d["edges"]
            .as_array_mut()
            .expect("array")
            .push(json!({"source": r1, "target": P0}));
        let g = parse(&d).expect("valid");
        assert_eq!(g.nodes[2].parent, Some(R0));
        assert_eq!(g.extra_parent_edges.len(), 1);
        assert_eq!(g.extra_parent_edges[0].parent, r1);
        assert_eq!(g.extra_parent_edges[0].child, P0);
        assert_eq!(g.counts().edges, 5);
    }

    // ---------------------------------------------------------------- fuzzing

    fn fixture_value(name: &str) -> Value {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(name);
        serde_json::from_slice(&std::fs::read(path).expect("fixture")).expect("json")
    }

    /// A small but complete slice of a fixture: about `n` nodes from every layer (all
    /// rooms and buildings), the edges among them, and (if present) the first vertices
    /// of the mesh, with `mesh_connections` and faces cut to them.
    fn shrink(mut v: Value, n: usize) -> Value {
        let nodes: Vec<Value> = v["nodes"]
            .as_array()
            .map(|a| {
                let step = (a.len() / n).max(1);
                a.iter()
                    .enumerate()
                    .filter(|(i, x)| i % step == 0 || x["layer"].as_u64().is_some_and(|l| l >= 4))
                    .map(|(_, x)| x.clone())
                    .collect()
            })
            .unwrap_or_default();
        let ids: std::collections::HashSet<u64> =
            nodes.iter().filter_map(|n| n["id"].as_u64()).collect();
        let edges: Vec<Value> = v["edges"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter(|e| {
                        e["source"].as_u64().is_some_and(|s| ids.contains(&s))
                            && e["target"].as_u64().is_some_and(|t| ids.contains(&t))
                    })
                    .cloned()
                    .collect()
            })
            .unwrap_or_default();
        let keep_vertices = 64u64;
        let mut nodes = nodes;
        for node in &mut nodes {
            if let Some(mc) = node["attributes"]["mesh_connections"].as_array_mut() {
                mc.retain(|x| x.as_u64().is_some_and(|x| x < keep_vertices));
                mc.truncate(16);
            }
        }
        v["nodes"] = Value::Array(nodes);
        v["edges"] = Value::Array(edges);
        if let Some(mesh) = v.get_mut("mesh").and_then(Value::as_object_mut) {
            for key in ["points", "colors", "labels", "stamps", "first_seen_stamps"] {
                if let Some(a) = mesh.get_mut(key).and_then(Value::as_array_mut) {
                    a.truncate(keep_vertices as usize);
                }
            }
            if let Some(f) = mesh.get_mut("faces").and_then(Value::as_array_mut) {
                f.retain(|t| {
                    t.as_array().is_some_and(|t| {
                        t.iter()
                            .all(|i| i.as_u64().is_some_and(|i| i < keep_vertices))
                    })
                });
            }
        }
        v
    }

    const TOKENS: &[&str] = &[
        "null",
        "true",
        "0",
        "-1",
        "1e999",
        "1e39",
        "18446744073709551616",
        "4294967296",
        "\"x\"",
        "[]",
        "{}",
        "[1,2]",
        "[0,0,0]",
        ",",
        ":",
        "]",
        "}",
        "\"",
        "\\u0000",
        "NaN",
        "-0.0",
        "9007199254740993",
    ];

    fn random_value(rng: &mut ChaCha8Rng) -> Value {
        match rng.gen_range(0..12) {
            0 => Value::Null,
            1 => json!(rng.r#gen::<bool>()),
            2 => json!(rng.r#gen::<u64>()),
            3 => json!(rng.gen_range(-5i64..5)),
            4 => json!(rng.gen_range(-1e40..1e40)),
            5 => json!("ObjectNodeAttributes"),
            6 => json!([]),
            7 => json!({}),
            8 => json!([rng.gen_range(0u32..100), 1, 2]),
            9 => json!(rng.gen_range(0u32..8)),
            10 => json!("INVALID"),
            _ => json!({"layer": rng.gen_range(0..6), "partition": rng.gen_range(0..3)}),
        }
    }

    /// Replaces, deletes or inserts a random field somewhere inside `v`.
    fn mutate_value(v: &mut Value, rng: &mut ChaCha8Rng, depth: usize) {
        let descend = depth < 6 && rng.gen_bool(0.8);
        match v {
            Value::Object(map) if !map.is_empty() => {
                let i = rng.gen_range(0..map.len());
                let key = map.keys().nth(i).cloned().unwrap_or_default();
                if descend {
                    if let Some(child) = map.get_mut(&key) {
                        mutate_value(child, rng, depth + 1);
                    }
                } else {
                    match rng.gen_range(0..3) {
                        0 => {
                            map.remove(&key);
                        }
                        1 => {
                            map.insert(key, random_value(rng));
                        }
                        _ => {
                            map.insert("unexpected".to_owned(), random_value(rng));
                        }
                    }
                }
            }
            Value::Array(a) if !a.is_empty() => {
                let i = rng.gen_range(0..a.len());
                if descend {
                    mutate_value(&mut a[i], rng, depth + 1);
                } else {
                    match rng.gen_range(0..3) {
                        0 => {
                            a.remove(i);
                        }
                        1 => a[i] = random_value(rng),
                        _ => {
                            let dup = a[i].clone();
                            a.push(dup);
                        }
                    }
                }
            }
            _ => *v = random_value(rng),
        }
    }

    fn mutate_bytes(bytes: &mut Vec<u8>, rng: &mut ChaCha8Rng) {
        for _ in 0..rng.gen_range(1..4) {
            if bytes.is_empty() {
                return;
            }
            let at = rng.gen_range(0..bytes.len());
            match rng.gen_range(0..6) {
                0 => bytes[at] = rng.r#gen(),
                1 => {
                    bytes.remove(at);
                }
                2 => bytes.truncate(at),
                3 => {
                    let t = TOKENS[rng.gen_range(0..TOKENS.len())].as_bytes();
                    let end = (at + rng.gen_range(0..8)).min(bytes.len());
                    bytes.splice(at..end, t.iter().copied());
                }
                4 => {
                    // Change one digit: ids, indices and coordinates shift.
                    if let Some(p) = bytes[at..].iter().position(u8::is_ascii_digit) {
                        bytes[at + p] = b'0' + rng.gen_range(0..10);
                    }
                }
                _ => {
                    let len = rng.gen_range(1..64).min(bytes.len() - at);
                    let chunk = bytes[at..at + len].to_vec();
                    let to = rng.gen_range(0..bytes.len());
                    bytes.splice(to..to, chunk);
                }
            }
        }
    }

    fn must_not_panic(bytes: &[u8], what: &str) -> bool {
        let r = std::panic::catch_unwind(|| ygg_dsg::parse_json(bytes, "fuzz.json"));
        match r {
            Ok(Ok(_)) => true,
            Ok(Err(e)) => {
                assert!(e.to_string().starts_with("fuzz.json: "), "{e}");
                false
            }
            Err(_) => panic!(
                "parse_json panicked on {what}: {}",
                String::from_utf8_lossy(&bytes[..bytes.len().min(4000)])
            ),
        }
    }

    #[test]
    fn fuzzed_fixtures_never_panic() {
        let bases = [
            shrink(fixture_value("office_tiny.json"), 24),
            shrink(fixture_value("apartment_dsg.json"), 24),
            doc(),
        ];
        for b in &bases {
            assert!(parse(b).is_ok(), "shrunk fixture must be valid");
        }
        let mut rng = ChaCha8Rng::seed_from_u64(0xD56);
        let iterations = if cfg!(debug_assertions) {
            2_000
        } else {
            20_000
        };
        let (mut ok, mut err) = (0usize, 0usize);
        for it in 0..iterations {
            let base = &bases[it % bases.len()];
            let bytes = if rng.gen_bool(0.5) {
                let mut v = base.clone();
                for _ in 0..rng.gen_range(1..4) {
                    mutate_value(&mut v, &mut rng, 0);
                }
                serde_json::to_vec(&v).expect("serialize")
            } else {
                let mut b = serde_json::to_vec(base).expect("serialize");
                mutate_bytes(&mut b, &mut rng);
                b
            };
            if must_not_panic(&bytes, &format!("iteration {it}")) {
                ok += 1;
            } else {
                err += 1;
            }
        }
        eprintln!("fuzz: {iterations} mutations, {ok} parsed, {err} rejected");
        assert!(
            err > iterations / 4,
            "mutations should mostly produce errors"
        );
    }
}
