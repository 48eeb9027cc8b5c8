//! `ygg import` of real Hydra output with faults, as a real process: the
//! apartment file with an edge to an absent node, a duplicated edge and a node of an
//! undeclared layer. Strict (the default) refuses, naming the problem and `--lenient`;
//! `--lenient` imports the rest and prints each class dropped with its count and first
//! example; the snapshot answers object queries.

use std::path::Path;

use serde_json::{Value, json};
use ygg_dsg::NodeSymbol;
use ygg_dsg::objects::Objects;
use ygg_store::SnapshotFile;
use ygg_testkit::{run, text};

/// apartment_dsg.json plus an edge to the absent p(99999), a reversed copy of its first
/// edge and an object in layer 9.
fn write_faulty_apartment(path: &Path) {
    let fixture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../dsg/tests/fixtures/apartment_dsg.json");
    let mut doc: Value = serde_json::from_slice(&std::fs::read(fixture).unwrap()).unwrap();
    let edges = doc["edges"].as_array_mut().unwrap();
    let first = edges[0].clone();
    edges.push(json!({"source": first["source"], "target": NodeSymbol::new(b'p', 99_999).id()}));
    edges
        .push(json!({"source": first["target"], "target": first["source"], "info": first["info"]}));
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let mut stray = nodes
        .iter()
        .find(|n| n["attributes"]["type"] == "ObjectNodeAttributes")
        .unwrap()
        .clone();
    stray["id"] = json!(NodeSymbol::new(b'O', 9_999).id());
    stray["layer"] = json!(9);
    nodes.push(stray);
    std::fs::write(path, serde_json::to_vec(&doc).unwrap()).unwrap();
}

#[test]
fn import_is_strict_by_default_and_lenient_on_request() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("faulty_apartment.json");
    write_faulty_apartment(&input);
    let out = dir.path().join("apartment.ygg");

    let strict = run("ygg", &[&"import", &input, &"-o", &out, &"-q"]);
    let stderr = text(&strict.stderr);
    assert!(
        !strict.status.success(),
        "strict import succeeded: {stderr}"
    );
    assert_ne!(strict.status.code(), Some(101), "panic: {stderr}");
    for needle in [
        "faulty_apartment.json",
        "unknown layer 9 partition 0",
        "O(9999)",
        "--lenient",
    ] {
        assert!(stderr.contains(needle), "stderr lacks {needle:?}: {stderr}");
    }
    assert!(!out.exists(), "a refused import left a snapshot");

    let lenient = run(
        "ygg",
        &[
            &"import",
            &input,
            &"-o",
            &out,
            &"-q",
            &"--lenient",
            &"--layout",
            &"chocolate",
        ],
    );
    let stdout = text(&lenient.stdout);
    assert!(lenient.status.success(), "{}", text(&lenient.stderr));
    assert!(
        stdout.contains("(296 nodes, 742 edges, 0 mesh vertices)"),
        "{stdout}"
    );
    let report: Vec<&str> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("lenient import: "))
        .collect();
    assert_eq!(report.len(), 3, "{stdout}");
    assert!(
        report[0].starts_with("dropped 1 nodes of undeclared layers (first: "),
        "{stdout}"
    );
    assert!(report[0].contains("O(9999)"), "{stdout}");
    assert!(
        report[1].starts_with("dropped 1 edges to absent nodes (first: "),
        "{stdout}"
    );
    assert!(report[1].contains("p(99999)"), "{stdout}");
    assert!(
        report[2].starts_with("dropped 1 duplicate edges"),
        "{stdout}"
    );

    // The snapshot holds the apartment's seven objects, located by their positions.
    let file = SnapshotFile::open(&out).unwrap();
    let view = file.view();
    let objects = Objects::new(&view);
    assert_eq!(objects.objects().len(), 7);
    assert_eq!(objects.objects_within([0.0; 3], 1000.0).unwrap().len(), 7);

    // A clean file leniently: nothing dropped.
    let clean =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../dsg/tests/fixtures/apartment_dsg.sparkdsg");
    let o = run(
        "ygg",
        &[&"import", &clean, &"-o", &out, &"-q", &"--lenient"],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("lenient import: nothing dropped"),
        "{}",
        text(&o.stdout)
    );
}
