//! `ygg bridge zmq` against the real peer: a Python process publishing with
//! spark_dsg's own `DsgSender` (pip `spark-dsg==1.1.3 pyzmq`, `tests/python/dsg_sender.py`)
//! sends the office, then a sequence of edits; after each, this process (a reader of
//! the bridge's scene) checks that its snapshot equals the graph sent, that nearest-object
//! answers equal brute force over the sender's data, and that only the layers whose
//! content changed were republished. Malformed and truncated frames are skipped and the
//! last good graph stays served.

use std::process::Command;
use std::time::{Duration, Instant};

mod bridge_common;

use bridge_common::{
    LAYOUT, STEP, bridge_event, check_objects, command, expected, generations, root, snapshot_at,
};
use rustix::process::Signal;
use ygg_reader::SceneReader;
use ygg_testkit::fingerprint::{changed_layers, layer_fingerprints};
use ygg_testkit::{Input, Proc, TestScene, Watchdog, run, text};

const WATCHDOG: Duration = Duration::from_secs(240);

/// Starts the Python sender on the tiny office; returns it and its TCP port.
fn spawn_sender(watchdog: &Watchdog) -> (Proc, u16) {
    let mut command = Command::new("python3");
    command
        .arg(root().join("tests/python/dsg_sender.py"))
        .arg(root().join("dsg/tests/fixtures/office_tiny.json"));
    let sender = Proc::start(command, "sender", Input::Lines).expect("start python3");
    watchdog.register(sender.pid());
    let line = sender.expect_line(STEP, |l| l.starts_with("port="));
    let port = line
        .split_whitespace()
        .next()
        .and_then(|w| w.strip_prefix("port="))
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no port in {line:?}"));
    (sender, port)
}

#[test]
fn bridge_follows_a_spark_dsg_sender_and_republishes_only_the_layers_touched() {
    let scene = TestScene::new("bridge");
    let watchdog = Watchdog::new(WATCHDOG);
    let dir = tempfile::tempdir().expect("tempdir");
    let (mut sender, port) = spawn_sender(&watchdog);
    let endpoint = format!("tcp://127.0.0.1:{port}");
    let bridge = Proc::spawn(
        scene.command(
            "ygg",
            &[
                "bridge",
                "zmq",
                "--connect",
                &endpoint,
                "--scene",
                &scene.name,
                "--layout",
                LAYOUT.name(),
            ],
        ),
        "bridge",
        &watchdog,
    );
    bridge.expect_line(STEP, |l| l.contains("\"connected\""));
    // PUB drops what it sends before the subscription arrives (and nothing tells the
    // sender when it did): resend until the bridge says it serves the graph.
    let first = dir.path().join("0.bin");
    let until = Instant::now() + STEP;
    loop {
        assert!(
            Instant::now() < until,
            "bridge never ready: {}",
            bridge.describe()
        );
        command(&mut sender, &format!("send {}", first.display()));
        let resend = Duration::from_millis(200);
        if bridge
            .wait_line_after(0, resend, |l| l.contains("\"ready\""))
            .is_some()
        {
            break;
        }
    }
    let mut reader = SceneReader::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .wait_for_writer(STEP)
        .open()
        .expect("attach to the bridge's scene");
    let (dsg, mut want) = expected(&first);
    let mut snap = snapshot_at(&mut reader, 1);
    assert_eq!(
        layer_fingerprints(&snap.view(), true),
        layer_fingerprints(&want, true)
    );
    check_objects(&snap.view(), &dsg);

    let ids = |sender: &mut Proc, layer: u32| -> Vec<u64> {
        command(sender, &format!("ids {layer}"))
            .split_whitespace()
            .skip(1)
            .map(|w| w.parse().expect("id"))
            .collect()
    };
    let objects = ids(&mut sender, 2);
    let places = ids(&mut sender, 3);
    assert!(objects.len() > 3 && places.len() > 3);
    let new_object = objects.iter().max().unwrap() + 100;
    for (k, what) in [
        "object moved",
        "object added",
        "object removed",
        "edge added",
    ]
    .into_iter()
    .enumerate()
    {
        match k {
            0 => {
                command(&mut sender, &format!("move {} 0.75 -0.5 0", objects[0]));
            }
            1 => {
                command(&mut sender, &format!("add {new_object} 2 6.0 7.0 1.0"));
            }
            2 => {
                command(&mut sender, &format!("remove {}", objects[1]));
            }
            _ => {
                // Two places with no edge yet (spark_dsg answers False for an existing one).
                let added = (0..places.len())
                    .flat_map(|a| (0..places.len()).map(move |b| (a, b)))
                    .filter(|(a, b)| a != b)
                    .any(|(a, b)| {
                        command(&mut sender, &format!("edge {} {}", places[a], places[b]))
                            == "ok edge True"
                    });
                assert!(added, "no two places without an edge");
            }
        }
        let path = dir.path().join(format!("{}.bin", k + 1));
        let skip = bridge.stdout().len();
        command(&mut sender, &format!("send {}", path.display()));
        let update = bridge_event(&bridge, skip, "update");
        // Without a mesh sent, an object's geometry is its position, held by a node the
        // layout derives: even its move builds the layout and syncs to it.
        assert_eq!(update["path"], "build", "{what}: {update}");
        assert_eq!(update["mesh_reused"], true, "{what}: {update}");
        let (next_dsg, next_want) = expected(&path);
        let generation = update["generation"].as_u64().expect("generation");
        let before = generations(&snap);
        snap = snapshot_at(&mut reader, generation);
        let view = snap.view();
        assert_eq!(
            layer_fingerprints(&view, true),
            layer_fingerprints(&next_want, true),
            "{what}: the reader's snapshot differs from the graph sent"
        );
        check_objects(&view, &next_dsg);
        // Only the layers whose content changed were republished.
        let after = generations(&snap);
        let republished: Vec<String> = after
            .iter()
            .filter(|(name, g)| before.get(*name) != Some(g))
            .map(|(name, _)| name.clone())
            .collect();
        let touched = changed_layers(&want, &next_want);
        assert_eq!(republished, touched, "{what}: {update}");
        let reported: Vec<String> =
            serde_json::from_value(update["changed_layers"].clone()).expect("names");
        assert_eq!(reported, touched, "{what}");
        assert!(!touched.is_empty(), "{what}: no layer changed");
        assert!(
            touched.len() < after.len() / 4,
            "{what}: {} of {} layers changed: {touched:?}",
            touched.len(),
            after.len()
        );
        want = next_want;
    }

    // Bad frames, alone on the wire: logged and skipped; the last good graph stays.
    for bad in ["garbage 5000", "truncated"] {
        let skip = bridge.stdout().len();
        command(&mut sender, bad);
        let event = bridge_event(&bridge, skip, "bad-frame");
        assert!(
            event["error"].as_str().is_some_and(|e| !e.is_empty()),
            "{event}"
        );
        eprintln!("{bad}: {event}");
    }
    let held = reader.latest().expect("receive").unwrap_or(snap.clone());
    assert_eq!(
        held.generation(),
        snap.generation(),
        "a bad frame was published"
    );
    assert_eq!(
        layer_fingerprints(&held.view(), true),
        layer_fingerprints(&want, true)
    );
    // The same graph again: nothing to publish. Then a move still goes through, patched
    // (a place's geometry is its position).
    let skip = bridge.stdout().len();
    command(&mut sender, "send");
    let update = bridge_event(&bridge, skip, "update");
    assert_eq!(update["changed_layers"], serde_json::json!([]), "{update}");
    assert_eq!(update["path"], "unchanged", "{update}");
    assert_eq!(update["generation"].as_u64(), Some(snap.generation()));
    command(&mut sender, &format!("move {} 0 0 0.25", places[2]));
    let path = dir.path().join("last.bin");
    let skip = bridge.stdout().len();
    command(&mut sender, &format!("send {}", path.display()));
    let update = bridge_event(&bridge, skip, "update");
    assert_eq!(update["path"], "patch", "{update}");
    let last = snapshot_at(&mut reader, update["generation"].as_u64().unwrap());
    let (last_dsg, last_want) = expected(&path);
    assert_eq!(
        layer_fingerprints(&last.view(), true),
        layer_fingerprints(&last_want, true)
    );
    check_objects(&last.view(), &last_dsg);

    // The reader's samples and node go before the bridge's shared memory is checked.
    drop((last, snap, held, reader));
    let mut bridge = bridge;
    bridge.signal(Signal::TERM);
    assert!(bridge.wait_exit(STEP).success(), "{}", bridge.describe());
    let summary = bridge.expect_line(STEP, |l| l.contains("\"summary\""));
    assert!(summary.contains("\"bad_frames\":2"), "{summary}");
    sender.send("quit").ok();
    sender.close_stdin();
    scene.assert_no_leftovers(Duration::from_secs(5));
}

#[test]
fn bridge_refuses_bad_arguments_and_an_unreachable_endpoint_cleanly() {
    let cases: [(&[&str], &str); 4] = [
        (
            &["--connect", "nonsense", "--scene", "s"],
            "cannot subscribe to nonsense",
        ),
        (
            &[
                "--connect",
                "tcp://127.0.0.1:1",
                "--scene",
                "s",
                "--connect-timeout",
                "0.5",
            ],
            "cannot subscribe to tcp://127.0.0.1:1",
        ),
        (
            &["--connect", "tcp://127.0.0.1:1", "--scene", "a/b"],
            "scene",
        ),
        (
            &[
                "--connect",
                "tcp://127.0.0.1:1",
                "--scene",
                "s",
                "--layout",
                "x",
            ],
            "unknown layout",
        ),
    ];
    for (args, needle) in cases {
        let mut all: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"bridge", &"zmq"];
        all.extend(args.iter().map(|a| a as &dyn AsRef<std::ffi::OsStr>));
        let out = run("ygg", &all);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
}
