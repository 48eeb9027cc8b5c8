//! Recording a live scene and going back in time, with real processes: `ygg record`
//! follows an in-process writer and every recorded cut equals the graph the writer
//! published under that generation; `ygg query` on a past cut answers as the saved graph
//! of that moment; `ygg serve --recording` republishes the cuts and a reader receives the
//! same graphs; a recorder SIGKILLed at random points leaves a readable recording; a
//! file-size limit gives a clear error and keeps what was written.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Stdio;
use std::time::Duration;

use rustix::process::Signal;
use ygg_dsg::layout::{self, Layout};
use ygg_reader::SceneReader;
use ygg_store::recording::Recording;
use ygg_store::{NodeId, SceneView};
use ygg_testkit::fingerprint::layer_fingerprints;
use ygg_testkit::{Proc, TestScene, Watchdog, poll_until, text};
use ygg_writer::SceneWriter;

type Fingerprints = BTreeMap<String, String>;

/// Ticks of `ygg record`'s first test.
const TICKS: u64 = 24;

fn small_office() -> ygg_store::SceneGraph {
    let d = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams {
        seed: 3,
        scale: 0.05,
    });
    layout::build(&d, Layout::Vanilla).expect("build")
}

/// The recording's cuts once its last one has generation `generation`.
fn recorded_through(dir: &Path, generation: u64) -> Recording {
    let mut last = None;
    poll_until(Duration::from_secs(20), || {
        last = Recording::open(dir)
            .ok()
            .filter(|r| r.cuts().last().is_some_and(|c| c.generation >= generation));
        last.is_some()
    })
    .unwrap_or_else(|| panic!("the recorder did not record generation {generation}"));
    last.expect("polled")
}

#[test]
fn recorded_cuts_are_the_published_graphs_and_replay_republishes_them() {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let watchdog = Watchdog::new(Duration::from_secs(120));
    let scene = TestScene::new("rec-live");
    let replayed = TestScene::new("rec-replay");
    let dir = tempfile::tempdir().expect("tempdir");
    let rec_dir = dir.path().join("run.yggrec");
    let mut writer = SceneWriter::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .create(small_office())
        .expect("writer");
    writer.publish().expect("publish");
    let mut expected: BTreeMap<u64, Fingerprints> = BTreeMap::new();
    expected.insert(
        writer.generation(),
        layer_fingerprints(writer.graph(), true),
    );
    let recorder = Proc::spawn(
        scene.command(
            "ygg",
            &[
                "record",
                "--scene",
                &scene.name,
                "-o",
                rec_dir.to_str().unwrap(),
            ],
        ),
        "recorder",
        &watchdog,
    );
    recorder.expect_line(Duration::from_secs(20), |l| {
        l.contains("\"event\":\"ready\"")
    });
    recorded_through(&rec_dir, writer.generation());

    // Each tick moves a place, adds a labelled object; the recorder is waited
    // for, so every cut is recorded.
    let objects = writer
        .graph()
        .layer_by_name("OBJECTS")
        .expect("objects layer");
    let places = writer
        .graph()
        .layer_by_name("PLACES")
        .expect("places layer");
    let moved: Vec<NodeId> = {
        let g = writer.graph();
        g.layer_nodes(places)
            .take(3)
            .map(|n| g.node_id(n))
            .collect()
    };
    let mut saved = Vec::new();
    for tick in 0..TICKS {
        let g = writer.graph_mut();
        let id = moved[tick as usize % moved.len()];
        g.set_geometry(id, vec![[tick as f32 * 0.5, 1.0, 0.5]])
            .expect("move");
        g.add_node(NodeId(7_000_000 + tick), objects).expect("add");
        g.set_geometry(NodeId(7_000_000 + tick), vec![[1.0, tick as f32, 0.2]])
            .expect("place");
        g.add_label(NodeId(7_000_000 + tick), "recorded")
            .expect("label");
        writer.publish().expect("publish");
        expected.insert(
            writer.generation(),
            layer_fingerprints(writer.graph(), true),
        );
        if tick % 8 == 0 {
            let path = dir.path().join(format!("g{}.ygg", writer.generation()));
            writer.graph().save(&path).expect("save");
            saved.push((writer.generation(), path));
        }
        recorded_through(&rec_dir, writer.generation());
    }
    let last_generation = writer.generation();

    let recording = Recording::open(&rec_dir).expect("open");
    assert!(recording.defects().is_empty(), "{:?}", recording.defects());
    assert_eq!(recording.cuts().len() as u64, TICKS + 1);
    for (i, cut) in recording.cuts().iter().enumerate() {
        let scene = recording.scene(i).expect("cut opens");
        assert_eq!(
            &layer_fingerprints(scene.view(), true),
            &expected[&cut.generation],
            "cut {i} (generation {})",
            cut.generation
        );
    }
    let first = 0;
    let last = recording.cuts().len() - 1;
    let changes = recording.changes(first, last, 0.01).expect("changes");
    let added: Vec<NodeId> = (0..TICKS).map(|t| NodeId(7_000_000 + t)).collect();
    assert_eq!(changes.nodes_added, added);
    let moved_ids: Vec<NodeId> = changes.nodes_moved.iter().map(|m| m.id).collect();
    assert!(
        moved.iter().all(|id| moved_ids.contains(id)),
        "{moved:?} moved; changes: {changes:?}"
    );
    assert!(changes.nodes_removed.is_empty());

    // `ygg query` on a past cut answers as the graph saved at that moment.
    let queries = dir.path().join("q.jsonl");
    std::fs::write(
        &queries,
        "{\"op\":\"objects_with_label\",\"label\":\"recorded\"}\n\
         {\"op\":\"objects_within\",\"point\":[1,2,0.2],\"radius\":3}\n\
         {\"op\":\"nearest_object\",\"point\":[4,1,0.5]}\n",
    )
    .expect("queries");
    let query = |args: &[&str]| {
        let o = scene.command("ygg", args).output().expect("spawn");
        assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
        text(&o.stdout)
    };
    let q = queries.to_str().unwrap();
    for (generation, path) in &saved {
        let past = query(&[
            "query",
            rec_dir.to_str().unwrap(),
            "--at",
            &generation.to_string(),
            "--queries",
            q,
        ]);
        assert_eq!(
            past,
            query(&["query", path.to_str().unwrap(), "--queries", q])
        );
    }
    let timeline = query(&["inspect", rec_dir.to_str().unwrap()]);
    assert!(
        timeline.contains(&format!("{} cuts", TICKS + 1)),
        "{timeline}"
    );
    assert!(timeline.contains("OBJECTS"), "{timeline}");

    // Replayed, a reader receives the recorded graphs under their generations; after the
    // last cut the player keeps serving it until signalled.
    let mut replay = Proc::spawn(
        replayed.command(
            "ygg",
            &[
                "serve",
                "--scene",
                &replayed.name,
                "--recording",
                rec_dir.to_str().unwrap(),
            ],
        ),
        "replay",
        &watchdog,
    );
    let mut reader = SceneReader::builder(&replayed.name)
        .iceoryx_prefix(&replayed.prefix)
        .wait_for_writer(Duration::from_secs(20))
        .open()
        .expect("reader");
    let mut seen = 0;
    let started = std::time::Instant::now();
    loop {
        let snapshot = reader
            .wait_next(Duration::from_secs(20))
            .expect("receive")
            .expect("a replayed cut within 20 s");
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "stuck at generation {} of {last_generation}; player: {:?} {:?}",
            snapshot.generation(),
            replay.stdout(),
            replay.stderr()
        );
        assert_eq!(
            &layer_fingerprints(snapshot.view(), true),
            &expected[&snapshot.generation()],
            "replayed generation {}",
            snapshot.generation()
        );
        seen += 1;
        if snapshot.generation() == last_generation {
            break;
        }
    }
    assert!(seen >= 1);
    replay.expect_line(Duration::from_secs(20), |l| l.contains("\"event\":\"end\""));
    replay.signal(Signal::INT);
    assert!(replay.wait_exit(Duration::from_secs(20)).success());
    assert!(
        replay
            .stdout()
            .iter()
            .any(|l| l.contains("\"event\":\"summary\"")),
        "{:?}",
        replay.stdout()
    );
    drop(reader);

    // Looped at 50x: generations keep growing past the recording's, and every cut a reader
    // receives is one of the recorded graphs.
    let looped = TestScene::new("rec-loop");
    let mut player = Proc::spawn(
        looped.command(
            "ygg",
            &[
                "serve",
                "--scene",
                &looped.name,
                "--recording",
                rec_dir.to_str().unwrap(),
                "--speed",
                "50",
                "--loop",
            ],
        ),
        "looped replay",
        &watchdog,
    );
    let mut reader = SceneReader::builder(&looped.name)
        .iceoryx_prefix(&looped.prefix)
        .wait_for_writer(Duration::from_secs(20))
        .open()
        .expect("reader");
    let recorded: Vec<&Fingerprints> = expected.values().collect();
    let mut previous = 0;
    while previous <= last_generation + 2 {
        let snapshot = reader
            .wait_next(Duration::from_secs(20))
            .expect("receive")
            .expect("a looped cut within 20 s");
        assert!(snapshot.generation() > previous, "generations only grow");
        previous = snapshot.generation();
        assert!(recorded.contains(&&layer_fingerprints(snapshot.view(), true)));
    }
    drop(reader);
    player.signal(Signal::INT);
    assert!(player.wait_exit(Duration::from_secs(20)).success());

    recorder.signal(Signal::TERM);
    let mut recorder = recorder;
    assert!(recorder.wait_exit(Duration::from_secs(20)).success());
    assert!(
        recorder
            .stdout()
            .iter()
            .any(|l| l.contains("\"event\":\"summary\""))
    );
    drop(writer);
    scene.assert_no_leftovers(Duration::from_secs(10));
    replayed.assert_no_leftovers(Duration::from_secs(10));
    looped.assert_no_leftovers(Duration::from_secs(10));
}

/// Bytes in the files of a folder.
fn folder_bytes(dir: &Path) -> u64 {
    std::fs::read_dir(dir).map_or(0, |d| {
        d.filter_map(|e| e.ok()?.metadata().ok())
            .map(|m| m.len())
            .sum()
    })
}

#[test]
fn a_recorder_killed_at_any_point_leaves_a_readable_recording() {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let watchdog = Watchdog::new(Duration::from_secs(120));
    let scene = TestScene::new("rec-kill");
    let dir = tempfile::tempdir().expect("tempdir");
    let mut writer = Proc::spawn(
        scene.command(
            "ygg",
            &[
                "serve",
                "--scene",
                &scene.name,
                "--scale",
                "0.05",
                "--rate",
                "100",
            ],
        ),
        "writer",
        &watchdog,
    );
    writer.expect_line(Duration::from_secs(20), |l| {
        l.contains("\"event\":\"ready\"")
    });
    // Kill points: after the recorder wrote this many bytes (the first cut is ~100 KB,
    // each tick a few KB), spread over the first cut and the ticks after it.
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    for round in 0..12 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let threshold = state % 400_000;
        let rec_dir = dir.path().join(format!("run{round}.yggrec"));
        let mut recorder = Proc::spawn(
            scene.command(
                "ygg",
                &[
                    "record",
                    "--scene",
                    &scene.name,
                    "-o",
                    rec_dir.to_str().unwrap(),
                ],
            ),
            "recorder",
            &watchdog,
        );
        poll_until(Duration::from_secs(20), || {
            folder_bytes(&rec_dir) >= threshold
        })
        .expect("the recorder writes");
        recorder.signal(Signal::KILL);
        recorder.wait_exit(Duration::from_secs(10));
        match Recording::open(&rec_dir) {
            Ok(recording) => {
                assert!(recording.defects().is_empty(), "{:?}", recording.defects());
                for i in 0..recording.cuts().len() {
                    let s = recording.scene(i).expect("every complete cut opens");
                    assert!(s.view().node_count() > 0);
                }
            }
            Err(e) => assert!(
                e.to_string().contains("no complete cut"),
                "round {round} (killed after {threshold} bytes): {e}"
            ),
        }
    }
    writer.signal(Signal::TERM);
    assert!(writer.wait_exit(Duration::from_secs(20)).success());
    scene.assert_no_leftovers(Duration::from_secs(10));
}

#[test]
fn a_full_file_system_gives_a_clear_error_and_keeps_what_was_recorded() {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    // A full disk is a 600 KB tmpfs mounted in a mount namespace of the recorder's own
    // (root only, as CI runs; the namespace and its mount vanish with the recorder).
    if !rustix::process::geteuid().is_root() {
        assert_eq!(
            std::env::var(ygg_testkit::ENV_SKIP_NETNS_TESTS).as_deref(),
            Ok("1"),
            "this test mounts a tmpfs in a mount namespace: run as root (CI does), or set \
             {}=1 to skip on this machine",
            ygg_testkit::ENV_SKIP_NETNS_TESTS
        );
        eprintln!("skipped: not root");
        return;
    }
    let watchdog = Watchdog::new(Duration::from_secs(120));
    let scene = TestScene::new("rec-full");
    let dir = tempfile::tempdir().expect("tempdir");
    let mount = dir.path().join("small-disk");
    let kept = dir.path().join("kept.yggrec");
    std::fs::create_dir(&mount).expect("mount point");
    let mut writer = Proc::spawn(
        scene.command(
            "ygg",
            &[
                "serve",
                "--scene",
                &scene.name,
                "--scale",
                "0.05",
                "--rate",
                "200",
            ],
        ),
        "writer",
        &watchdog,
    );
    writer.expect_line(Duration::from_secs(20), |l| {
        l.contains("\"event\":\"ready\"")
    });
    let ygg = ygg_testkit::binary("ygg");
    let mut command = std::process::Command::new("unshare");
    command.args([
        "--mount",
        "--propagation",
        "private",
        "sh",
        "-c",
        // The recording is copied out before the namespace (and the tmpfs) goes.
        "mount -t tmpfs -o size=600k tmpfs \"$1\" || exit 9; \
         \"$0\" record --scene \"$2\" -o \"$1/run.yggrec\" --seconds 60; rc=$?; \
         cp -r \"$1/run.yggrec\" \"$3\"; exit $rc",
        ygg.to_str().unwrap(),
        mount.to_str().unwrap(),
        &scene.name,
        kept.to_str().unwrap(),
    ]);
    scene.configure(&mut command).stdin(Stdio::null());
    let mut recorder = Proc::spawn(command, "recorder", &watchdog);
    let status = recorder.wait_exit(Duration::from_secs(60));
    let stderr = recorder.stderr().join("\n");
    assert_eq!(
        status.code(),
        Some(1),
        "the recorder fails at the limit: {stderr}"
    );
    assert!(
        stderr.contains("00000001.ygr") && stderr.contains("No space left on device"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let recording = Recording::open(&kept).expect("what was recorded opens");
    assert!(
        recording.cuts().len() > 1,
        "ticks were recorded before the disk was full"
    );
    assert!(recording.defects().is_empty(), "{:?}", recording.defects());
    for i in 0..recording.cuts().len() {
        assert!(
            recording
                .scene(i)
                .expect("every cut opens")
                .view()
                .node_count()
                > 0
        );
    }
    writer.signal(Signal::TERM);
    assert!(writer.wait_exit(Duration::from_secs(20)).success());
    scene.assert_no_leftovers(Duration::from_secs(10));
}

#[test]
fn bad_recording_arguments_are_refused_with_clear_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let empty = dir.path().to_str().unwrap();
    let scene = TestScene::new("rec-args");
    let run = |args: &[&str]| {
        scene
            .command("ygg", args)
            .stdin(Stdio::null())
            .output()
            .expect("spawn")
    };
    let cases: [(&[&str], &str); 5] = [
        (&["query", empty, "--at", "3"], "no complete cut"),
        (&["changes", empty], "no complete cut"),
        (
            &["record", "--scene", "x", "-o", empty, "--max-size", "12T"],
            "K, M or G",
        ),
        (
            &["record", "--scene", "x", "-o", empty, "--max-age", "0"],
            "--max-age",
        ),
        (
            &[
                "serve",
                "--scene",
                "x",
                "--recording",
                empty,
                "--speed",
                "0",
            ],
            "--speed",
        ),
    ];
    for (args, needle) in cases {
        let o = run(args);
        let stderr = text(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}
