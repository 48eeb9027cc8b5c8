//! Spark-DSG 1.1.4's binary format (its `develop` branch: a new `Place2dNodeAttributes`
//! layout behind `header.version`), read from a file spark_dsg 1.1.4 itself wrote
//! (`fixtures/office_tiny_v1_1_4.sparkdsg`, see the fixtures' README) and written back.

use ygg_dsg::{DsgGraph, DsgVersion, parse_binary, parse_binary_body, read_file};

fn fixture(name: &str) -> Vec<u8> {
    let path = format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The graph without what a file's origin changes (its name and version) or the 1.1.4
/// file does not hold (the mesh, and so the objects' claims on it).
fn comparable(mut g: DsgGraph) -> DsgGraph {
    g.source.clear();
    g.version = DsgVersion::V1_1_3;
    g.mesh = None;
    for n in &mut g.nodes {
        n.mesh_connections.clear();
    }
    g
}

#[test]
fn a_file_spark_dsg_1_1_4_wrote_reads_as_the_same_graph_as_its_1_1_3_source() {
    let bytes = fixture("office_tiny_v1_1_4.sparkdsg");
    let g = parse_binary(&bytes, "v1.1.4").expect("1.1.4 file");
    assert_eq!(g.version, DsgVersion::V1_1_4);
    let source = read_file(format!(
        "{}/tests/fixtures/office_tiny.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("1.1.3 source");
    assert_eq!(comparable(g.clone()), comparable(source));
    // 29 mesh places, one with 1.1.4's new fields set.
    assert_eq!(g.nodes_of_kind(ygg_dsg::NodeKind::Place2d).count(), 29);
}

#[test]
fn a_1_1_4_body_reads_only_at_1_1_4() {
    let bytes = fixture("office_tiny_v1_1_4.sparkdsg");
    let file = parse_binary(&bytes, "v1.1.4").expect("1.1.4 file");
    // The header: the identifier, the project name and three version bytes.
    let header = 5 + 9 + 5 + 4 + 3 * 2;
    let body = &bytes[header..];
    let g = parse_binary_body(body, DsgVersion::V1_1_4, "body").expect("a 1.1.4 body");
    assert_eq!(g.nodes, file.nodes);
    // Read with 1.1.3's layout, the mesh places do not decode: the version matters.
    let wrong = parse_binary_body(body, DsgVersion::V1_1_3, "body").expect_err("1.1.3 layout");
    assert!(wrong.to_string().contains("attributes."), "{wrong}");
}

#[test]
fn the_writer_writes_both_versions_and_reads_them_back() {
    let g = parse_binary(&fixture("office_tiny_v1_1_4.sparkdsg"), "v1.1.4").expect("file");
    for version in [DsgVersion::V1_1_3, DsgVersion::V1_1_4] {
        let bytes = ygg_dsg::to_binary_bytes_at(&g, version).expect("writes");
        let back = parse_binary(&bytes, "written").expect("reads");
        assert_eq!(back.version, version);
        assert_eq!(back.nodes, g.nodes);
        let body = ygg_dsg::to_binary_body_at(&g, version).expect("writes");
        assert_eq!(
            parse_binary_body(&body, version, "body")
                .expect("reads")
                .nodes,
            g.nodes
        );
    }
    assert!(ygg_dsg::to_binary_bytes_at(&g, DsgVersion::new(1, 2, 0)).is_err());
}
