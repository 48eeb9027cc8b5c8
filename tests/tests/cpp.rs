//! End-to-end tests of the C/C++ API: the C++ example writer (`examples/cpp/writer.cpp`,
//! built by CMake) serves a scene, and a Rust reader process, the `ygg query` CLI and
//! the C++ example reader read it; their answers are checked against what the writer
//! builds. The writer must stop cleanly on SIGTERM and leave nothing in `/dev/shm`.
//!
//! The C++ binaries come from `.ci/cpp`, which builds them and runs these tests with
//! `YGG_CPP_BUILD=<cmake build dir> cargo test -p ygg-tests --test cpp -- --ignored`;
//! without the binaries the tests are ignored.

use std::io::Write;
use std::path::PathBuf;
use std::process::Stdio;
use std::time::Duration;

use rustix::process::Signal;
use ygg_dsg::objects::Objects;
use ygg_reader::SceneReader;
use ygg_store::{NodeId, SceneView};
use ygg_testkit::{Proc, TestScene, Watchdog, example, field, text};

/// Generous bound for any single step (debug builds on a busy 2-core machine).
const STEP: Duration = Duration::from_secs(60);
/// Per-test watchdog.
const WATCHDOG: Duration = Duration::from_secs(240);

/// The C++ example binary `name` of the CMake build named by `YGG_CPP_BUILD`.
fn cpp_binary(name: &str) -> PathBuf {
    let dir = std::env::var_os("YGG_CPP_BUILD")
        .expect("YGG_CPP_BUILD names the CMake build of examples/cpp (run .ci/cpp)");
    let path = PathBuf::from(dir).join(name);
    assert!(path.is_file(), "{} not built (run .ci/cpp)", path.display());
    path
}

/// Starts the C++ writer on `scene` and waits for its `serving` line.
fn start_cpp_writer(scene: &TestScene, dog: &Watchdog) -> Proc {
    let writer = Proc::spawn(
        scene.command_for(&cpp_binary("writer"), &[&scene.name]),
        "cpp writer",
        dog,
    );
    writer.expect_line(STEP, |l| l.starts_with("serving "));
    writer
}

/// SIGTERM, a clean exit with its `stopped` line, and no files left.
fn stop_cpp_writer(mut writer: Proc, scene: &TestScene) {
    writer.signal(Signal::TERM);
    let status = writer.wait_exit(STEP);
    assert!(status.success(), "{}", writer.describe());
    writer.expect_line(STEP, |l| l.starts_with("stopped at generation="));
    scene.assert_no_leftovers(Duration::from_secs(10));
}

/// Runs a reader process to its clean exit and returns its snapshot lines (those with
/// `generation=`).
fn snapshot_lines(command: std::process::Command, label: &str, dog: &Watchdog) -> Vec<String> {
    let mut reader = Proc::spawn(command, label, dog);
    let status = reader.wait_exit(STEP);
    assert!(status.success(), "{}", reader.describe());
    reader
        .stdout()
        .into_iter()
        .filter(|l| field(l, "generation").is_some())
        .collect()
}

/// The room the C++ writer nests a pose at `x` in.
fn room_at(x: f32) -> NodeId {
    NodeId(if x < 10.0 { 1 } else { 2 })
}

#[test]
#[ignore = "needs the C++ examples built by .ci/cpp (YGG_CPP_BUILD)"]
fn cpp_writer_is_read_by_a_rust_reader_and_the_ygg_reader_cli() {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let scene = TestScene::new("cpp-writer");
    let dog = Watchdog::new(WATCHDOG);
    let writer = start_cpp_writer(&scene, &dog);

    // A Rust reader in this process (the writer is another process).
    let mut reader = SceneReader::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .wait_for_writer(STEP)
        .open()
        .expect("reader attaches to the C++ writer");
    let mut generations = Vec::new();
    while generations.len() < 5 {
        let Some(snapshot) = reader.wait_next(STEP).expect("receive") else {
            panic!("no snapshot from the C++ writer within {STEP:?}");
        };
        generations.push(snapshot.generation());
        let view = snapshot.view();
        for layer in ["ROOMS", "OBJECTS", "MESH", "AGENTS"] {
            assert!(view.layer_by_name(layer).is_some(), "no {layer} layer");
        }
        let objects = Objects::new(&view);
        // Objects 1002 (plant, x=10) and 1003 (lamp, x=14) never move.
        assert_eq!(
            objects.nearest_object([10.0, 2.0, 0.5]).expect("query"),
            Some(NodeId(1002))
        );
        assert_eq!(objects.objects_with_label("plant"), vec![NodeId(1002)]);
        assert_eq!(
            objects
                .objects_within([14.0, 2.0, 0.5], 0.5)
                .expect("query"),
            vec![NodeId(1003)]
        );
        // The newest pose lies on the corridor and is nested in its room.
        let agents = view.layer_by_name("AGENTS").expect("AGENTS");
        let pose = view
            .layer_nodes(agents)
            .max_by_key(|&n| view.node_id(n))
            .expect("a pose");
        let p = *view.points(pose).first().expect("a pose has a point");
        assert_eq!((p[1], p[2]), (4.0, 1.0), "pose off the corridor");
        assert_eq!(view.parent(pose), Some(room_at(p[0])));
    }
    assert!(
        generations.windows(2).all(|w| w[0] < w[1]),
        "{generations:?}"
    );

    // The ygg CLI on the live scene: the object contract's answers.
    let mut query = scene
        .command("ygg", &["query", "--scene", &scene.name, "--timeout", "20"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn ygg query");
    let lines = [
        r#"{"op":"nearest_object","point":[10,2,0.5]}"#,
        r#"{"op":"objects_with_label","label":"plant"}"#,
        r#"{"op":"objects_within","point":[14,2,0.5],"radius":0.5}"#,
        r#"{"op":"objects_with_label","label":"unicorn"}"#,
        r#"{"op":"visible_objects","eye":[6,2,0.5],"dir":[1,0,0],"half_angle_deg":5,"range":20}"#,
    ];
    query
        .stdin
        .take()
        .expect("stdin")
        .write_all(lines.join("\n").as_bytes())
        .expect("write queries");
    let out = query.wait_with_output().expect("ygg query");
    assert!(out.status.success(), "{}", text(&out.stderr));
    let answers: Vec<String> = text(&out.stdout).lines().map(str::to_owned).collect();
    assert_eq!(
        answers,
        [
            r#"{"ids":[1002]}"#,
            r#"{"ids":[1002]}"#,
            r#"{"ids":[1003]}"#,
            r#"{"ids":[]}"#,
            r#"{"ids":[1002,1003]}"#,
        ]
    );

    // A Rust reader process: the office_reader example prints the newest pose and the
    // object nearest to it.
    let seen = snapshot_lines(
        scene.command_for(&example("office_reader"), &[&scene.name, "3"]),
        "rust reader",
        &dog,
    );
    assert_eq!(seen.len(), 3, "{seen:?}");
    for line in &seen {
        let nearest: u64 = field(line, "nearest")
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no nearest object in {line:?}"));
        assert!((1000..1054).contains(&nearest), "{line}");
        assert!(
            field(line, "pose").is_some_and(|p| p.ends_with(",4.00,1.00")),
            "{line}"
        );
    }

    drop(reader);
    stop_cpp_writer(writer, &scene);
}

#[test]
#[ignore = "needs the C++ examples built by .ci/cpp (YGG_CPP_BUILD)"]
fn cpp_reader_prints_what_the_cpp_writer_publishes() {
    let scene = TestScene::new("cpp-pair");
    let dog = Watchdog::new(WATCHDOG);
    let writer = start_cpp_writer(&scene, &dog);
    let lines = snapshot_lines(
        scene.command_for(&cpp_binary("reader"), &[&scene.name, "5"]),
        "cpp reader",
        &dog,
    );
    assert_eq!(lines.len(), 5, "{lines:?}");
    for line in &lines {
        let at = field(line, "at").unwrap_or_else(|| panic!("no position in {line:?}"));
        let x: f32 = at
            .split(',')
            .next()
            .and_then(|x| x.parse().ok())
            .expect("x");
        assert!(at.ends_with(",4.00,1.00"), "{line}");
        let room = field(line, "room").and_then(|r| r.parse::<u64>().ok());
        // Rounded to 2 decimals: a pose within 1 cm of the room border may go either way.
        if (x - 10.0).abs() > 0.01 {
            assert_eq!(room, Some(room_at(x).0), "{line}");
        }
        let nearest: u64 = field(line, "nearest")
            .and_then(|v| v.parse().ok())
            .expect("nearest");
        assert!((1000..1054).contains(&nearest), "{line}");
    }
    stop_cpp_writer(writer, &scene);
}
