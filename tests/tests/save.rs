//! Crash-safe `.ygg` saves: a reader process that maps and queries the file in a loop
//! while this process re-saves it never crashes and always answers on a valid snapshot,
//! and a save that runs out of room fails clearly and leaves the old file intact.

use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use ygg_store::query::nearest_nodes;
use ygg_store::{NodeId, SceneGraph, SceneView, Scope, SnapshotFile};
use ygg_testkit::{Proc, Watchdog, binary};

/// Set in the environment of the reader child: the file it maps in a loop.
const ENV_CHILD_FILE: &str = "YGG_SAVE_TEST_FILE";
/// Re-saves of the file while the reader loops.
const SAVES: usize = 100;
/// Points of the graph ([`graph`]) saved first and after every large one.
const SMALL: u64 = 10;
/// Points of the graph saved between the small ones.
const LARGE: u64 = 50_000;
/// Points of the graph saved last (no earlier save wrote it).
const LAST: u64 = 20;

/// A one-layer graph of `n` points on a line; its nearest node to the origin answers
/// which graph a snapshot holds (`NodeId(n)`).
fn graph(n: u64) -> SceneGraph {
    let mut g = SceneGraph::new();
    let layer = g.add_layer("points").unwrap();
    for i in 0..n {
        let id = NodeId(n + i);
        g.add_node(id, layer).unwrap();
        g.set_geometry(id, vec![[i as f32 * 0.01, 1.0, 0.0]])
            .unwrap();
    }
    g.enable_layer_index(layer).unwrap();
    g
}

/// The answer that tells the small graph from the large one.
fn answer(file: &SnapshotFile) -> Option<NodeId> {
    let view = file.view();
    let layer = view.layer_by_name("points")?;
    let near = nearest_nodes(&view, Scope::Layer(layer), [0.0, 1.0, 0.0], 1).ok()?;
    near.first().map(|&(id, _)| id)
}

/// The reader process: maps the file, validates it and queries it in a loop, keeping
/// the last few mappings alive while the file is replaced, until stdin closes. Prints
/// `answer <id>` whenever the answer changes (so the parent sees which version it read)
/// and `opened N` at the end; any wrong answer or failed open ends it with an error.
#[test]
#[ignore = "the child process of `reader_never_crashes_while_the_file_is_re_saved`"]
fn reader_child() {
    let path = std::env::var_os(ENV_CHILD_FILE).unwrap_or_else(|| {
        panic!(
            "{ENV_CHILD_FILE} unset: run only by reader_never_crashes_while_the_file_is_re_saved"
        )
    });
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = std::sync::Arc::clone(&stop);
    std::thread::spawn(move || {
        for _ in std::io::stdin().lock().lines() {}
        flag.store(true, std::sync::atomic::Ordering::SeqCst);
    });
    let valid = [SMALL, LARGE, LAST].map(|n| Some(NodeId(n)));
    let mut held: Vec<(SnapshotFile, Option<NodeId>)> = Vec::new();
    let mut opened = 0u64;
    let mut last = None;
    println!("ready");
    while !stop.load(std::sync::atomic::Ordering::SeqCst) {
        let file = SnapshotFile::open(&path).unwrap_or_else(|e| panic!("open #{opened}: {e}"));
        let got = answer(&file);
        assert!(valid.contains(&got), "open #{opened}: answer {got:?}");
        if let Some(id) = got.filter(|_| got != last) {
            println!("answer {}", id.0);
            last = got;
        }
        // Mappings opened before the file was replaced still answer as they did.
        for (old, was) in &held {
            assert_eq!(answer(old), *was, "a held mapping changed");
        }
        held.push((file, got));
        if held.len() > 4 {
            held.remove(0);
        }
        opened += 1;
    }
    println!("opened {opened}");
}

#[test]
fn reader_never_crashes_while_the_file_is_re_saved() {
    let watchdog = Watchdog::new(Duration::from_secs(300));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ygg");
    let (small, large) = (graph(SMALL), graph(LARGE));
    small.save(&path).unwrap();
    let mut command = Command::new(std::env::current_exe().unwrap());
    command
        .args([
            "--exact",
            "reader_child",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(ENV_CHILD_FILE, &path);
    let mut reader = Proc::start(command, "reader", ygg_testkit::Input::Lines).unwrap();
    watchdog.register(reader.pid());
    reader.expect_line(Duration::from_secs(60), |l| l.ends_with("ready"));
    for i in 0..SAVES {
        let g = if i % 2 == 0 { &large } else { &small };
        g.save(&path).unwrap();
    }
    // A last version no earlier save wrote: the reader has read it once it answers so.
    graph(LAST).save(&path).unwrap();
    reader.expect_line(Duration::from_secs(60), |l| l == format!("answer {LAST}"));
    reader.close_stdin();
    let status = reader.wait_exit(Duration::from_secs(60));
    assert!(status.success(), "reader failed: {}", reader.describe());
    let opened: u64 = reader
        .expect_line(Duration::from_secs(5), |l| l.starts_with("opened "))
        .trim_start_matches("opened ")
        .parse()
        .unwrap();
    assert!(opened > 0, "the reader never opened the file");
    assert_eq!(temp_files(dir.path()), Vec::<PathBuf>::new());
}

/// Files a save left beside the target (temporary files start with `.`).
fn temp_files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with('.'))
        .collect()
}

#[test]
fn a_save_that_runs_out_of_room_fails_clearly_and_keeps_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("office.ygg");
    graph(SMALL).save(&out).unwrap();
    let before = std::fs::read(&out).unwrap();
    let input =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../dsg/tests/fixtures/office_tiny.json");
    // A file-size limit of 64 KiB (128 blocks of 512 bytes), with SIGXFSZ ignored so that
    // the write fails with EFBIG instead of killing the writer.
    let script = "trap '' XFSZ; ulimit -f 128; exec \"$0\" import \"$1\" --layout mint -o \"$2\"";
    let output = Command::new("sh")
        .args(["-c", script])
        .arg(binary("ygg"))
        .arg(&input)
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "the import succeeded: {stderr}");
    assert!(
        stderr.contains(&out.display().to_string()) && stderr.contains("File too large"),
        "unclear error: {stderr}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), before, "the old file changed");
    assert_eq!(
        answer(&SnapshotFile::open(&out).unwrap()),
        Some(NodeId(SMALL))
    );
    assert_eq!(temp_files(dir.path()), Vec::<PathBuf>::new());
}
