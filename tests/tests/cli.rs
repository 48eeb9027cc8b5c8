//! The command line, run as real processes: `ygg import`, `ygg inspect` and
//! `ygg query` (on `.ygg` files and on a live scene), `ygg watch` and `ygg export` on a live
//! scene, their answers across layouts,
//! malformed query lines, and bad input files. The expected answers are brute force over
//! the imported Spark-DSG file, not the query code the command runs.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

use serde_json::{Value, json};
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::objects::cone_view;
use ygg_dsg::{DsgGraph, NodeKind};
use ygg_store::query::within_radius;
use ygg_store::{Point, distance_squared};
use ygg_testkit::{TestScene, binary, run, text};
use ygg_writer::SceneWriter;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../dsg/tests/fixtures")
        .join(name)
}

/// Asserts a clean failure: non-zero exit, no panic, and `needles` in stderr.
fn assert_fails(out: &Output, needles: &[&str]) {
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "expected failure; stderr: {stderr}");
    assert_ne!(
        out.status.code(),
        Some(101),
        "a panic exit code; stderr: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "stderr: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "stderr lacks {n:?}: {stderr}");
    }
}

fn import(input: &Path, layout: Layout, out: &Path) {
    let o = run(
        "ygg",
        &[&"import", &input, &"--layout", &layout.name(), &"-o", &out],
    );
    assert!(o.status.success(), "import failed: {}", text(&o.stderr));
    let stdout = text(&o.stdout);
    assert!(stdout.starts_with("imported "), "{stdout}");
    assert!(stdout.contains(&format!("as {layout}")), "{stdout}");
}

/// A small deterministic generator (no extra dependency).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[(self.next() % items.len() as u64) as usize]
    }
}

/// Queries over the office: on claimed vertices (exact ties), near them, and anywhere.
fn office_queries(d: &DsgGraph, n: usize) -> Vec<Value> {
    let mesh = d.mesh.as_ref().expect("office has a mesh");
    let claimed: Vec<[f32; 3]> = d
        .nodes_of_kind(NodeKind::Object)
        .flat_map(|o| o.mesh_connections.iter().map(|&v| mesh.points[v as usize]))
        .collect();
    let labels: Vec<String> = d
        .object_label_histogram()
        .into_keys()
        .chain(["absent".to_owned()])
        .collect();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let point = |rng: &mut Rng| -> Vec<f64> {
        match rng.next() % 3 {
            0 => rng.pick(&claimed).iter().map(|&v| f64::from(v)).collect(),
            1 => rng
                .pick(&claimed)
                .iter()
                .map(|&v| f64::from(v) + (rng.unit() - 0.5) * 0.6)
                .collect(),
            _ => vec![
                rng.range(-1.0, 41.0),
                rng.range(-1.0, 26.0),
                rng.range(0.0, 3.0),
            ],
        }
    };
    (0..n)
        .map(|i| match i % 4 {
            0 => json!({"op": "nearest_object", "point": point(&mut rng)}),
            1 => {
                let radius = *rng.pick(&[0.0, 0.25, 0.5, 1.0, 2.0, 4.0]);
                json!({"op": "objects_within", "point": point(&mut rng), "radius": radius})
            }
            2 => {
                let eye = point(&mut rng);
                let dir = [
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-0.3, 0.3),
                ];
                let half = *rng.pick(&[0.0, 15.0, 30.0, 50.0, 70.0, 120.0, 180.0]);
                let range = *rng.pick(&[0.0, 0.3, 1.0, 3.0, 8.0]);
                json!({"op": "visible_objects", "eye": eye, "dir": dir,
                       "half_angle_deg": half, "range": range})
            }
            _ => json!({"op": "objects_with_label", "label": rng.pick(&labels)}),
        })
        .collect()
}

fn write_lines(path: &Path, lines: &[Value]) {
    let mut f = std::fs::File::create(path).expect("create");
    for l in lines {
        writeln!(f, "{l}").expect("write");
    }
}

fn query_file(snapshot: &Path, queries: &Path) -> String {
    let o = run(
        "ygg",
        &[&"query", &snapshot, &"--queries", &queries, &"--timing"],
    );
    assert!(o.status.success(), "query failed: {}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("timing: open"),
        "{}",
        text(&o.stderr)
    );
    text(&o.stdout)
}

/// What the contract expects for each query, by brute force straight from the imported
/// Spark-DSG graph (as `dsg/tests/objects.rs` computes it): an object's geometry is its
/// claimed mesh vertices, or its position when it claims none; nearest ties go to the
/// smaller id. Independent of `ygg_dsg::objects::Objects`, the code under test.
fn expected(d: &DsgGraph, queries: &[Value]) -> Vec<Value> {
    let objects: Vec<(u64, Vec<Point>)> = d
        .nodes_of_kind(NodeKind::Object)
        .map(|n| {
            let pts: Vec<Point> = d.mesh.as_ref().map_or_else(Vec::new, |m| {
                n.mesh_connections
                    .iter()
                    .map(|&v| m.points[v as usize])
                    .collect()
            });
            if pts.is_empty() {
                (n.id, vec![n.position])
            } else {
                (n.id, pts)
            }
        })
        .collect();
    let labels = |n: &ygg_dsg::DsgNode| -> Vec<String> {
        n.label
            .iter()
            .cloned()
            .chain(n.semantic_label.map(|l| l.to_string()))
            .collect()
    };
    let any_point = |hit: &dyn Fn(&Point) -> bool| -> Vec<u64> {
        objects
            .iter()
            .filter(|(_, pts)| pts.iter().any(hit))
            .map(|o| o.0)
            .collect()
    };
    let f = |v: &Value| v.as_f64().expect("a number") as f32;
    let p = |v: &Value| -> Point { [f(&v[0]), f(&v[1]), f(&v[2])] };
    queries
        .iter()
        .map(|q| {
            let mut ids: Vec<u64> = match q["op"].as_str().expect("op") {
                "nearest_object" => {
                    let point = p(&q["point"]);
                    let mut best: Option<(f32, u64)> = None;
                    for (id, pts) in &objects {
                        for x in pts {
                            let dist = distance_squared(x, &point).sqrt();
                            if best.is_none_or(|(bd, bid)| dist < bd || (dist == bd && *id < bid)) {
                                best = Some((dist, *id));
                            }
                        }
                    }
                    best.map(|b| b.1).into_iter().collect()
                }
                "objects_within" => {
                    let (point, radius) = (p(&q["point"]), f(&q["radius"]));
                    any_point(&|x| within_radius(x, &point, radius))
                }
                "visible_objects" => {
                    let cone = cone_view(
                        p(&q["eye"]),
                        p(&q["dir"]),
                        f(&q["half_angle_deg"]),
                        f(&q["range"]),
                    )
                    .expect("a valid cone");
                    any_point(&|x| cone.contains(x).expect("a finite point"))
                }
                "objects_with_label" => {
                    let label = q["label"].as_str().expect("label").to_owned();
                    d.nodes_of_kind(NodeKind::Object)
                        .filter(|n| labels(n).contains(&label))
                        .map(|n| n.id)
                        .collect()
                }
                op => panic!("unknown op {op}"),
            };
            ids.sort_unstable();
            json!({ "ids": ids })
        })
        .collect()
}

#[test]
fn query_answers_are_identical_for_every_layout() {
    let dir = tempfile::tempdir().expect("tempdir");
    let input = fixture("office_tiny.json");
    let d = ygg_dsg::read_file(&input).expect("fixture");
    let queries = office_queries(&d, 600);
    let qfile = dir.path().join("q.jsonl");
    write_lines(&qfile, &queries);
    let want = expected(&d, &queries);

    let mut outputs = Vec::new();
    for layout in Layout::ALL {
        let ygg = dir.path().join(format!("{layout}.ygg"));
        import(&input, layout, &ygg);
        let out = query_file(&ygg, &qfile);
        let lines: Vec<Value> = out
            .lines()
            .map(|l| serde_json::from_str(l).expect("a JSON line"))
            .collect();
        assert_eq!(
            lines.len(),
            queries.len(),
            "{layout}: one line out per line in"
        );
        for (i, (got, want)) in lines.iter().zip(&want).enumerate() {
            assert_eq!(got, want, "{layout}: line {}: {}", i + 1, queries[i]);
        }
        outputs.push((layout, out));
    }
    for (layout, out) in &outputs[1..] {
        assert_eq!(out, &outputs[0].1, "{layout} differs from {}", outputs[0].0);
    }
    // The answers are not trivially empty, and ids above 2^53 come out exact.
    let non_empty = want.iter().filter(|w| w["ids"] != json!([])).count();
    assert!(non_empty > queries.len() / 2, "{non_empty}");
    let lights: Vec<u64> = d
        .nodes_of_kind(NodeKind::Object)
        .filter(|n| n.label.as_deref() == Some("light"))
        .map(|n| n.id)
        .collect();
    assert!(lights.iter().all(|&id| id > 1 << 53));
    let qlight = dir.path().join("light.jsonl");
    std::fs::write(
        &qlight,
        "{\"op\":\"objects_with_label\",\"label\":\"light\"}\n",
    )
    .expect("write");
    let out = query_file(&dir.path().join("mint.ygg"), &qlight);
    let mut sorted = lights.clone();
    sorted.sort_unstable();
    let ids: Vec<String> = sorted.iter().map(u64::to_string).collect();
    assert_eq!(out.trim(), format!("{{\"ids\":[{}]}}", ids.join(",")));
}

#[test]
fn malformed_lines_are_answered_with_errors_and_the_rest_still_answered() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ygg = dir.path().join("tiny.ygg");
    import(&fixture("office_tiny.json"), Layout::Mint, &ygg);
    let good = [
        r#"{"op":"nearest_object","point":[5,5,1]}"#,
        r#"{"op":"objects_within","point":[5,5,1],"radius":3}"#,
        r#"{"op":"visible_objects","eye":[5,5,1],"dir":[1,0,0],"half_angle_deg":60,"range":8}"#,
        r#"{"op":"objects_with_label","label":"light"}"#,
    ];
    // (line, whether it is malformed, a word the error must contain)
    let lines: Vec<(&[u8], Option<&str>)> = vec![
        (good[0].as_bytes(), None),
        (br#"{"op":"nearest_object","point":[1,2]}"#, Some("field \"point\": expected an array of 3 numbers")),
        (b"not json", Some("malformed JSON")),
        (b"", Some("empty line")),
        (br#"{"op":"teleport","point":[0,0,0]}"#, Some("teleport")),
        (good[1].as_bytes(), None),
        (br#"{"op":"objects_within","point":[0,0,0],"radius":-1}"#, Some("radius")),
        (br#"{"op":"objects_within","point":[1e39,0,0],"radius":1}"#, Some("field \"point\": 1e39 is not a finite f32")),
        (br#"{"op":"visible_objects","eye":[0,0,0],"dir":[0,0,0],"half_angle_deg":30,"range":2}"#, Some("direction")),
        (br#"{"op":"visible_objects","eye":[0,0,0],"dir":[1,0,0],"half_angle_deg":200,"range":2}"#, Some("half_angle_deg")),
        (br#"{"op":"objects_with_label","label":"light","extra":1}"#, Some("unknown field \"extra\"")),
        (good[2].as_bytes(), None),
        (b"{\"op\":\"objects_with_label\",\"label\":\"\xff\xfe\"}", Some("UTF-8")),
        (b"[1,2,3]", Some("op")),
        (br#"{"op":"objects_within","point":[0,0,0],"radius":"far"}"#, Some("far")),
        (br#"{"point":[0,0,0]}"#, Some("missing field \"op\"")),
        (br#"{"op":"nearest_object","point":[1,2,3]} {"op":"nearest_object","point":[1,2,3]}"#, Some("trailing")),
        (b"{\"op\":\"nearest_object\",\"point\":[5,5,1]}  \r", None),
        (good[3].as_bytes(), None),
    ];
    let mut bytes = Vec::new();
    for (i, (l, _)) in lines.iter().enumerate() {
        bytes.extend_from_slice(l);
        if i + 1 < lines.len() {
            bytes.push(b'\n'); // the last line has no newline
        }
    }
    let qfile = dir.path().join("mixed.jsonl");
    std::fs::write(&qfile, &bytes).expect("write");
    let gfile = dir.path().join("good.jsonl");
    std::fs::write(&gfile, good.join("\n")).expect("write");
    let good_out: Vec<String> = query_file(&ygg, &gfile)
        .lines()
        .map(str::to_owned)
        .collect();

    let out = query_file(&ygg, &qfile);
    let out: Vec<&str> = out.lines().collect();
    assert_eq!(out.len(), lines.len(), "one line out per line in: {out:#?}");
    let mut next_good = 0;
    for (i, ((line, bad), answer)) in lines.iter().zip(&out).enumerate() {
        let v: Value = serde_json::from_str(answer).expect("JSON answer");
        match bad {
            Some(word) => {
                let e = v["error"]
                    .as_str()
                    .unwrap_or_else(|| panic!("line {}: {answer}", i + 1));
                assert!(e.starts_with(&format!("line {}: ", i + 1)), "{e}");
                assert!(e.contains(word), "line {}: {e:?} lacks {word:?}", i + 1);
            }
            None => {
                assert!(v.get("ids").is_some(), "line {}: {answer}", i + 1);
                if line.starts_with(b"{\"op\":\"nearest_object\",\"point\":[5,5,1]}  ") {
                    assert_eq!(*answer, good_out[0]);
                } else {
                    assert_eq!(*answer, good_out[next_good], "line {}", i + 1);
                    next_good += 1;
                }
            }
        }
    }
    assert_eq!(next_good, good.len());

    // The same through standard input.
    let mut child = Command::new(binary("ygg"))
        .args([Path::new("query"), &ygg])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(&bytes)
        .expect("write stdin");
    let o = child.wait_with_output().expect("wait");
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(text(&o.stdout).lines().collect::<Vec<_>>(), out);
}

/// `inspect FILE` lists the object labels with their counts: integer labels only in real
/// Hydra output (no labelspace), label ids and names in the office.
#[test]
fn inspect_lists_object_labels() {
    let o = run("ygg", &[&"inspect", &fixture("apartment_dsg.json")]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    let rows = |out: &str| -> Vec<Vec<String>> {
        out.lines()
            .skip_while(|l| !l.starts_with("object labels:"))
            .skip(2)
            .take_while(|l| !l.trim().is_empty())
            .map(|l| l.split_whitespace().map(str::to_owned).collect())
            .collect()
    };
    assert!(
        out.contains("object labels: 3 distinct over 7 objects"),
        "{out}"
    );
    assert_eq!(
        rows(&out),
        [["5", "-", "3"], ["11", "-", "2"], ["16", "-", "2"]],
        "{out}"
    );
    let o = run("ygg", &[&"inspect", &fixture("office_tiny.json")]);
    let out = text(&o.stdout);
    let rows = rows(&out);
    assert_eq!(rows.len(), 27, "{out}");
    assert_eq!(rows[0][1..], ["light", "4"], "{out}");
    assert_eq!(
        rows.iter()
            .map(|r| r[2].parse::<usize>().unwrap())
            .sum::<usize>(),
        34
    );
}

#[test]
fn inspect_shows_layers_dag_indexes_and_memory() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ygg = dir.path().join("mint.ygg");
    import(&fixture("office_tiny.json"), Layout::Mint, &ygg);
    let o = run("ygg", &[&"inspect", &ygg, &"--verbose"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    for needle in [
        "layers:",
        "layer DAG (parent -> children):",
        "BUILDINGS -> ROOMS",
        "/claimed-mesh",
        "objects: 34 in 9 object layers, 34 with geometry in 9 mesh layers",
        "layer indexes: 9 layers",
        "node indexes: 34 nodes",
        "O(0) [5692549928996306944]",
        "memory: manifest",
    ] {
        assert!(out.contains(needle), "inspect lacks {needle:?}:\n{out}");
    }

    // The paper's static table from the Spark-DSG file.
    let o = run("ygg", &[&"inspect", &fixture("office_tiny.json")]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    for l in Layout::ALL {
        assert!(
            out.lines().any(|line| line.starts_with(l.name())),
            "table lacks {l}:\n{out}"
        );
    }
    let o = run(
        "ygg",
        &[
            &"inspect",
            &fixture("office_tiny.json"),
            &"--layouts",
            &"mint,saffron",
        ],
    );
    let out = text(&o.stdout);
    assert!(out.lines().any(|l| l.starts_with("saffron")));
    assert!(!out.lines().any(|l| l.starts_with("vanilla")), "{out}");
}

#[test]
fn live_scene_answers_like_the_file() {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let scene = TestScene::new("cli-live");
    let dir = tempfile::tempdir().expect("tempdir");
    let input = fixture("office_tiny.json");
    let d = ygg_dsg::read_file(&input).expect("fixture");
    let queries = office_queries(&d, 200);
    let qfile = dir.path().join("q.jsonl");
    write_lines(&qfile, &queries);
    let ygg = dir.path().join("mint.ygg");
    import(&input, Layout::Mint, &ygg);
    let from_file = query_file(&ygg, &qfile);

    let graph = layout::build(&d, Layout::Mint).expect("build");
    let mut writer = SceneWriter::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .create(graph)
        .expect("writer");
    writer.publish().expect("publish");

    let q = scene
        .command(
            "ygg",
            &[
                "query",
                "--scene",
                &scene.name,
                "--timeout",
                "20",
                "--queries",
            ],
        )
        .arg(&qfile)
        .output()
        .expect("spawn");
    assert!(q.status.success(), "{}", text(&q.stderr));
    assert_eq!(text(&q.stdout), from_file);

    let i = scene
        .command(
            "ygg",
            &["inspect", "--scene", &scene.name, "--timeout", "20"],
        )
        .output()
        .expect("spawn");
    assert!(i.status.success(), "{}", text(&i.stderr));
    let out = text(&i.stdout);
    assert!(
        out.starts_with(&format!("live scene {}", scene.name)),
        "{out}"
    );
    assert!(out.contains("node indexes: 34 nodes"), "{out}");

    // `ygg watch` sees the published snapshot through SceneReader.
    let w = scene
        .command("ygg", &["watch", "--scene", &scene.name, "--count", "1"])
        .stdin(Stdio::null())
        .output()
        .expect("spawn");
    assert!(w.status.success(), "{}", text(&w.stderr));
    let out = text(&w.stdout);
    assert!(
        out.contains(" generation=1 ") && out.contains(" nodes=171"),
        "{out}"
    );
    assert!(out.contains("received 1 snapshots"), "{out}");

    // `ygg export` writes the live snapshot to a file that answers like the original.
    let exported = dir.path().join("exported.ygg");
    let e = scene
        .command(
            "ygg",
            &["export", "--scene", &scene.name, "--timeout", "20", "-o"],
        )
        .arg(&exported)
        .output()
        .expect("spawn");
    assert!(e.status.success(), "{}", text(&e.stderr));
    assert_eq!(query_file(&exported, &qfile), from_file);
    drop(writer);
    scene.assert_no_leftovers(Duration::from_secs(10));

    // No writer: a clear error naming the scene, quickly.
    let gone = TestScene::new("cli-none");
    let o = gone
        .command("ygg", &["query", "--scene", &gone.name, "--timeout", "0.2"])
        .stdin(Stdio::null())
        .output()
        .expect("spawn");
    assert_fails(&o, &[gone.name.as_str()]);
}

/// office_tiny.json as a JSON value, mutated by `f`, written to `dir/name`.
fn mutated(dir: &Path, name: &str, f: impl FnOnce(&mut Value)) -> PathBuf {
    let mut v: Value =
        serde_json::from_slice(&std::fs::read(fixture("office_tiny.json")).expect("read"))
            .expect("parse");
    f(&mut v);
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(&v).expect("serialize")).expect("write");
    path
}

#[test]
fn bad_import_input_is_a_clear_error_naming_file_node_and_field() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let out = d.join("out.ygg");
    let import_fails = |input: &Path, needles: &[&str]| {
        let o = run(
            "ygg",
            &[&"import", &input, &"--layout", &"mint", &"-o", &out],
        );
        let name = input.display().to_string();
        let mut all = vec![name.as_str()];
        all.extend_from_slice(needles);
        assert_fails(&o, &all);
        assert!(!out.exists(), "a failed import left {}", out.display());
    };

    import_fails(&d.join("missing.json"), &["cannot read"]);
    let empty = d.join("empty.json");
    std::fs::write(&empty, b"").expect("write");
    import_fails(&empty, &["malformed JSON"]);
    let truncated = d.join("truncated.json");
    let bytes = std::fs::read(fixture("office_tiny.json")).expect("read");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).expect("write");
    import_fails(&truncated, &["line"]);
    let gz = d.join("broken.json.gz");
    std::fs::write(&gz, [0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3, 1, 2, 3, 4]).expect("write");
    import_fails(&gz, &["gzip"]);

    // O(3) is nodes[3] of the fixture.
    let o3 = "O(3)";
    let path = mutated(d, "wrong_type.json", |v| {
        v["nodes"][3]["attributes"]["position"] = json!([1.0, "x", 3.0]);
    });
    import_fails(&path, &[o3, "position"]);
    let path = mutated(d, "non_finite.json", |v| {
        v["nodes"][3]["attributes"]["position"] = json!([1e39, 0.0, 0.0]);
    });
    import_fails(&path, &[o3, "position"]);
    let path = mutated(d, "out_of_range.json", |v| {
        v["nodes"][3]["attributes"]["mesh_connections"] = json!([0, 99_999_999]);
    });
    import_fails(&path, &[o3, "mesh_connections"]);
    let path = mutated(d, "dangling.json", |v| {
        let id = v["nodes"][3]["id"].clone();
        v["edges"]
            .as_array_mut()
            .expect("edges")
            .push(json!({"source": id, "target": 12345}));
    });
    import_fails(&path, &["12345"]);
    let path = mutated(d, "duplicate.json", |v| {
        let n = v["nodes"][3].clone();
        v["nodes"].as_array_mut().expect("nodes").push(n);
    });
    import_fails(&path, &[o3, "duplicate"]);
    let path = mutated(d, "mesh_nan.json", |v| {
        v["mesh"]["points"][7] = json!([0.0, -1e40, 0.0]);
    });
    import_fails(&path, &["mesh.points[7]"]);

    // Unknown layout: clap's error lists the layouts.
    let o = run(
        "ygg",
        &[
            &"import",
            &fixture("office_tiny.json"),
            &"--layout",
            &"strawberry",
            &"-o",
            &out,
        ],
    );
    assert_fails(&o, &["strawberry", "vanilla, chocolate, mint or saffron"]);
    // An output directory that does not exist.
    let nowhere = d.join("no/such/dir/out.ygg");
    let o = run(
        "ygg",
        &[&"import", &fixture("office_tiny.json"), &"-o", &nowhere],
    );
    assert_fails(&o, &[&nowhere.display().to_string(), "cannot write"]);
}

#[test]
fn bad_snapshot_and_query_files_are_clear_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let ygg = d.join("tiny.ygg");
    import(&fixture("office_tiny.json"), Layout::Chocolate, &ygg);
    let q = d.join("q.jsonl");
    std::fs::write(&q, "{\"op\":\"nearest_object\",\"point\":[1,2,3]}\n").expect("write");
    let bytes = std::fs::read(&ygg).expect("read");
    let truncated = d.join("truncated.ygg");
    std::fs::write(&truncated, &bytes[..bytes.len() / 3]).expect("write");
    let mut flipped = bytes.clone();
    let at = flipped.len() / 2;
    flipped[at] ^= 0x5a;
    let flipped_path = d.join("flipped.ygg");
    std::fs::write(&flipped_path, &flipped).expect("write");
    let empty = d.join("empty.ygg");
    std::fs::write(&empty, b"").expect("write");
    let foreign = d.join("foreign.ygg");
    std::fs::write(&foreign, b"PK\x03\x04 not a snapshot at all").expect("write");
    let missing = d.join("missing.ygg");

    for bad in [&truncated, &empty, &foreign, &missing] {
        let name = bad.display().to_string();
        let o = run("ygg", &[&"query", bad, &"--queries", &q]);
        assert_fails(&o, &[&name]);
        let o = run("ygg", &[&"inspect", bad]);
        assert_fails(&o, &[&name]);
    }
    // A flipped byte may land in padding; it must never crash.
    let o = run("ygg", &[&"query", &flipped_path, &"--queries", &q]);
    assert_ne!(o.status.code(), Some(101), "{}", text(&o.stderr));
    assert!(!text(&o.stderr).contains("panicked"));

    let no_queries = d.join("no_queries.jsonl");
    let o = run("ygg", &[&"query", &ygg, &"--queries", &no_queries]);
    assert_fails(&o, &[&no_queries.display().to_string(), "cannot read"]);

    let bad_json = d.join("bad.json");
    std::fs::write(&bad_json, b"{\"nodes\": [").expect("write");
    let o = run("ygg", &[&"inspect", &bad_json]);
    assert_fails(&o, &[&bad_json.display().to_string()]);
    let o = run("ygg", &[&"inspect", &ygg, &"--layouts", &"mint"]);
    assert_fails(&o, &["--layouts"]);
}

#[test]
fn serve_splits_the_office_into_rooms_or_says_why_not() {
    let scene = TestScene::new("cli-rooms");
    let serve = |extra: &[&str]| {
        let mut args = vec!["serve", "--scene", &scene.name, "--rate", "0"];
        args.extend_from_slice(extra);
        scene
            .command("ygg", &args)
            .stdin(Stdio::null())
            .output()
            .expect("spawn")
    };
    assert_fails(&serve(&["--rooms", "3"]), &["--rooms 3"]);
    let o = serve(&["--rooms", "20", "--seconds", "0.3"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let ready = text(&o.stdout);
    assert!(ready.contains("\"event\":\"ready\""), "{ready}");
    scene.assert_no_leftovers(Duration::from_secs(10));
}
