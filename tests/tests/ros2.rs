//! `ygg bridge ros2` against a real DDS peer: Eclipse Cyclone DDS (pip `cyclonedds`, the
//! DDS of `rmw_cyclonedds`) in a Python process (`tests/python/ros2_peer.py`) publishes
//! hydra_msgs' `DsgUpdate` built with spark_dsg 1.1.3's `to_binary`, under the ROS 2
//! names (`rt/<topic>`, `hydra_msgs::msg::dds_::DsgUpdate_`) and hydra_ros's QoS: the
//! office, then incremental updates (a move, an added object, a removed object, an edge
//! added and one removed). After each, this process (a reader of the bridge's scene) checks
//! that its snapshot equals the sender's whole graph and that nearest-object answers equal
//! brute force on the sender's data. A sequence gap and malformed messages never publish
//! a graph; the next full update recovers.
//!
//! The other direction: `ygg export ros2` publishes the bridge's scene on a second topic;
//! a Cyclone DDS subscriber receives it, spark_dsg decodes every message's body, and the
//! full update then each incremental one applied give back the graph Hydra's side sent.
//!
//! Discovery is by unicast: Cyclone DDS runs with multicast off and the bridge's address as
//! its peer; RustDDS answers a participant it hears from on that participant's unicast
//! locators. RustDDS announces itself on a multicast group too (it has no setting to stop
//! that) and uses non-loopback interfaces only, so the bridge and the peer run in a network
//! namespace the test creates (one end of a veth pair, no multicast route;
//! `ygg_testkit::VethLink`) and removes. They need root and `ip`, as in CI;
//! `YGG_SKIP_NETNS_TESTS=1` skips them where that is impossible.

mod bridge_common;

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use bridge_common::{
    LAYOUT, STEP, bridge_event, check_objects, command, expected, generations, root, snapshot_at,
};
use rustix::process::Signal;
use ygg_dsg::{DsgGraph, DsgVersion};
use ygg_reader::SceneReader;
use ygg_testkit::fingerprint::layer_fingerprints;
use ygg_testkit::{Input, Proc, TestScene, VethLink, Watchdog, binary, run, text};

const WATCHDOG: Duration = Duration::from_secs(300);
/// The ROS 2 topic; each test has its own namespace, so domain and topic may repeat.
const TOPIC: &str = "/hydra/backend/dsg";
const DOMAIN: &str = "42";

/// The namespace (host 0 of a veth pair) and the Cyclone DDS configuration binding the
/// peer to its end, discovering by unicast only.
struct Host {
    link: VethLink,
    _dir: tempfile::TempDir,
    cyclone_uri: String,
}

impl Host {
    fn create() -> Option<Self> {
        let link = VethLink::create_for_test("y2")?;
        let dir = tempfile::tempdir().expect("tempdir");
        let config = dir.path().join("cyclonedds.xml");
        std::fs::write(
            &config,
            link.cyclone_unicast_config(0, &[link.address(0)], "", ""),
        )
        .expect("write the Cyclone DDS configuration");
        Some(Self {
            link,
            cyclone_uri: format!("file://{}", config.display()),
            _dir: dir,
        })
    }

    /// The Cyclone DDS peer (`send` or `listen` mode) in the namespace, once ready.
    fn peer(&self, args: &[&str], watchdog: &Watchdog) -> Proc {
        let script = root().join("tests/python/ros2_peer.py");
        let mut all = vec![script.to_str().expect("UTF-8 path")];
        all.extend(args);
        let mut command: Command = self.link.command(0, "python3".as_ref(), &all);
        command.env("CYCLONEDDS_URI", &self.cyclone_uri);
        let peer = Proc::start(command, "peer", Input::Lines).expect("start python3");
        watchdog.register(peer.pid());
        peer.expect_line(STEP, |l| l.starts_with("ready"));
        peer
    }

    /// `ygg args` in the namespace, with `scene`'s iceoryx2 prefix.
    fn ygg(&self, scene: &TestScene, args: &[&str], label: &str, watchdog: &Watchdog) -> Proc {
        let mut command = self.link.command(0, &binary("ygg"), args);
        scene.configure(&mut command);
        Proc::spawn(command, label, watchdog)
    }
}

#[test]
fn bridge_follows_cyclone_dds_full_and_incremental_updates_in_sequence() {
    let Some(host) = Host::create() else {
        return;
    };
    binary("ygg");
    let scene = TestScene::new("ros2");
    let watchdog = Watchdog::new(WATCHDOG);
    let dir = tempfile::tempdir().expect("tempdir");
    let fixture = root().join("dsg/tests/fixtures/office_tiny.json");
    let mut peer = host.peer(
        &["send", DOMAIN, TOPIC, fixture.to_str().expect("UTF-8")],
        &watchdog,
    );
    let bridge = host.ygg(
        &scene,
        &[
            "bridge",
            "ros2",
            "--topic",
            TOPIC,
            "--domain-id",
            DOMAIN,
            "--scene",
            &scene.name,
            "--layout",
            LAYOUT.name(),
        ],
        "bridge",
        &watchdog,
    );
    bridge.expect_line(STEP, |l| l.contains("\"subscribed\""));
    // Reliable and transient-local: once matched, the update is delivered.
    command(&mut peer, "matched 1");
    let first = dir.path().join("0.bin");
    command(&mut peer, &format!("send {}", first.display()));
    let ready = bridge.expect_line(STEP, |l| l.contains("\"ready\""));
    assert!(ready.contains("\"sequence_number\":0"), "{ready}");
    let mut reader = SceneReader::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .wait_for_writer(STEP)
        .open()
        .expect("attach to the bridge's scene");
    let (dsg, want) = expected(&first);
    let mut snap = snapshot_at(&mut reader, 1);
    assert_eq!(
        layer_fingerprints(&snap.view(), true),
        layer_fingerprints(&want, true)
    );
    check_objects(&snap.view(), &dsg);

    let ids = |peer: &mut Proc, layer: u32| -> Vec<u64> {
        command(peer, &format!("ids {layer}"))
            .split_whitespace()
            .skip(1)
            .map(|w| w.parse().expect("id"))
            .collect()
    };
    let objects = ids(&mut peer, 2);
    let places = ids(&mut peer, 3);
    assert!(objects.len() > 3 && places.len() > 3);
    let new_object = objects.iter().max().unwrap() + 100;
    // Two places with no edge yet (spark_dsg answers False for an existing one): added
    // here, sent with the next delta, removed by the one after.
    let edge = (0..places.len())
        .flat_map(|a| (0..places.len()).map(move |b| (a, b)))
        .filter(|(a, b)| a != b)
        .map(|(a, b)| (places[a], places[b]))
        .find(|(a, b)| command(&mut peer, &format!("edge {a} {b}")) == "ok edge True")
        .expect("two places without an edge");
    command(&mut peer, &format!("unedge {} {}", edge.0, edge.1));
    let edits: [(&str, Vec<String>); 5] = [
        (
            "object moved",
            vec![format!("move {} 0.75 -0.5 0", objects[0])],
        ),
        (
            "object added",
            vec![format!("add {new_object} 2 6.0 7.0 1.0")],
        ),
        ("object removed", vec![format!("remove {}", objects[1])]),
        ("edge added", vec![format!("edge {} {}", edge.0, edge.1)]),
        (
            "edge removed",
            vec![format!("unedge {} {}", edge.0, edge.1)],
        ),
    ];
    let mut sequence = 0;
    for (k, (what, lines)) in edits.iter().enumerate() {
        for line in lines {
            let answer = command(&mut peer, line);
            assert!(!answer.ends_with("False"), "{what}: {answer}");
        }
        let path = dir.path().join(format!("{}.bin", k + 1));
        let skip = bridge.stdout().len();
        command(&mut peer, &format!("delta {}", path.display()));
        sequence += 1;
        let update = bridge_event(&bridge, skip, "update");
        assert_eq!(update["full_update"], false, "{what}: {update}");
        assert_eq!(update["sequence_number"], sequence, "{what}: {update}");
        let (next_dsg, next_want) = expected(&path);
        snap = snapshot_at(
            &mut reader,
            update["generation"].as_u64().expect("generation"),
        );
        let view = snap.view();
        assert_eq!(
            layer_fingerprints(&view, true),
            layer_fingerprints(&next_want, true),
            "{what}: the reader's snapshot differs from the sender's graph"
        );
        check_objects(&view, &next_dsg);
    }

    // A gap: the update after a missing one is not applied, nor any until a full one.
    let served = snap.generation();
    let before = generations(&snap);
    command(&mut peer, "skip");
    command(&mut peer, &format!("move {} 1.5 0 0", objects[2]));
    let skip = bridge.stdout().len();
    command(&mut peer, "delta");
    let skipped = bridge_event(&bridge, skip, "skipped");
    assert_eq!(skipped["reason"], "gap", "{skipped}");
    assert_eq!(skipped["expected"], sequence + 1, "{skipped}");
    command(&mut peer, &format!("move {} 0 1.5 0", objects[2]));
    let skip = bridge.stdout().len();
    command(&mut peer, "delta");
    let skipped = bridge_event(&bridge, skip, "skipped");
    assert_eq!(skipped["reason"], "waiting-for-full-update", "{skipped}");
    // Malformed: a full update that is no graph, and a sample that is no DsgUpdate CDR
    // (a full update's layer_contents cut short is the same to the decoder).
    let skip = bridge.stdout().len();
    command(&mut peer, "garbage 300");
    let bad = bridge_event(&bridge, skip, "bad-frame");
    assert!(
        bad["error"]
            .as_str()
            .is_some_and(|e| e.contains("DsgUpdate.layer_contents")),
        "{bad}"
    );
    let held = reader.latest().expect("receive").unwrap_or(snap.clone());
    assert_eq!(held.generation(), served, "a skipped update was published");
    assert_eq!(generations(&held), before);
    // The next full update brings the whole graph, both moves included.
    let path = dir.path().join("full.bin");
    let skip = bridge.stdout().len();
    command(&mut peer, &format!("send {}", path.display()));
    let update = bridge_event(&bridge, skip, "update");
    assert_eq!(update["full_update"], true, "{update}");
    let (full_dsg, full_want) = expected(&path);
    let last = snapshot_at(
        &mut reader,
        update["generation"].as_u64().expect("generation"),
    );
    assert_eq!(
        layer_fingerprints(&last.view(), true),
        layer_fingerprints(&full_want, true)
    );
    check_objects(&last.view(), &full_dsg);
    // And incremental updates apply again after it.
    command(&mut peer, &format!("move {} 0 0 0.25", places[2]));
    let path = dir.path().join("after.bin");
    let skip = bridge.stdout().len();
    command(&mut peer, &format!("delta {}", path.display()));
    let update = bridge_event(&bridge, skip, "update");
    assert_eq!(update["path"], "patch", "{update}");
    let after = snapshot_at(
        &mut reader,
        update["generation"].as_u64().expect("generation"),
    );
    assert_eq!(
        layer_fingerprints(&after.view(), true),
        layer_fingerprints(&expected(&path).1, true)
    );

    drop((after, last, held, snap, reader));
    let mut bridge = bridge;
    bridge.signal(Signal::TERM);
    assert!(bridge.wait_exit(STEP).success(), "{}", bridge.describe());
    let summary = bridge.expect_line(STEP, |l| l.contains("\"summary\""));
    assert!(summary.contains("\"bad_frames\":1"), "{summary}");
    assert!(summary.contains("\"out_of_sequence\":2"), "{summary}");
    peer.send("quit").ok();
    peer.close_stdin();
    scene.assert_no_leftovers(Duration::from_secs(5));
}

/// A graph as `to_dsg` gives it back from a Vanilla scene: every node's id, layer, kind,
/// position, name, semantic label and parent, and every edge as an unordered pair (the
/// mesh, its claims and edge weights are not sent: `ygg_dsg::layout::to_dsg`).
fn sent_form(g: &DsgGraph) -> (Vec<String>, Vec<(u64, u64)>) {
    let mut nodes: Vec<String> = g
        .nodes
        .iter()
        .map(|n| {
            format!(
                "{} {} {:?} {:?} {:?} {:?} {:?}",
                n.id, n.layer, n.kind, n.position, n.name, n.semantic_label, n.parent
            )
        })
        .collect();
    nodes.sort_unstable();
    let mut edges: Vec<(u64, u64)> = g
        .edges
        .iter()
        .chain(&g.sibling_edges)
        .map(|e| (e.source.min(e.target), e.source.max(e.target)))
        .collect();
    edges.sort_unstable();
    (nodes, edges)
}

fn decode(path: &Path) -> DsgGraph {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    ygg_dsg::parse_binary_body(&bytes, DsgVersion::V1_1_3, "received").expect("decodes")
}

#[test]
fn export_ros2_sends_a_live_scene_that_cyclone_dds_and_spark_dsg_receive() {
    let Some(host) = Host::create() else {
        return;
    };
    binary("ygg");
    let scene = TestScene::new("ros2x");
    let watchdog = Watchdog::new(WATCHDOG);
    let dir = tempfile::tempdir().expect("tempdir");
    let (sent_dir, received) = (dir.path().join("sent"), dir.path().join("received"));
    std::fs::create_dir_all(&sent_dir).expect("mkdir");
    std::fs::create_dir_all(&received).expect("mkdir");
    let fixture = root().join("dsg/tests/fixtures/office_tiny.json");
    // Hydra (Cyclone DDS) -> `ygg bridge ros2` -> the scene -> `ygg export ros2` -> a
    // ROS 2 subscriber (Cyclone DDS), on two topics.
    let mut peer = host.peer(
        &["send", DOMAIN, TOPIC, fixture.to_str().expect("UTF-8")],
        &watchdog,
    );
    let listener = host.peer(
        &[
            "listen",
            DOMAIN,
            "/ygg/dsg",
            received.to_str().expect("UTF-8"),
        ],
        &watchdog,
    );
    let bridge = host.ygg(
        &scene,
        &[
            "bridge",
            "ros2",
            "--topic",
            TOPIC,
            "--domain-id",
            DOMAIN,
            "--scene",
            &scene.name,
            "--layout",
            "vanilla",
        ],
        "bridge",
        &watchdog,
    );
    bridge.expect_line(STEP, |l| l.contains("\"subscribed\""));
    command(&mut peer, "matched 1");
    let first = sent_dir.join("0.bin");
    command(&mut peer, &format!("send {}", first.display()));
    bridge.expect_line(STEP, |l| l.contains("\"ready\""));
    let export = host.ygg(
        &scene,
        &[
            "export",
            "ros2",
            "--scene",
            &scene.name,
            "--topic",
            "/ygg/dsg",
            "--domain-id",
            DOMAIN,
            "--full-every",
            "3600",
        ],
        "export",
        &watchdog,
    );
    export.expect_line(STEP, |l| l.contains("\"advertised\""));
    // The first message is full: spark_dsg decodes it, to the graph Hydra sent.
    let got = listener
        .wait_line_after(0, STEP, |l| l.starts_with("got seq=0 "))
        .map(|(_, l)| l)
        .unwrap_or_else(|| panic!("nothing received: {}", export.describe()));
    assert!(got.contains(" full=1 "), "{got}");
    let spark = decode(&first);
    assert!(
        got.contains(&format!(" nodes={} ", spark.nodes.len())),
        "{got}: spark_dsg decoded another node count"
    );
    let mut held = decode(&received.join("0.bin"));
    assert_eq!(sent_form(&held), sent_form(&spark));

    let objects: Vec<u64> = command(&mut peer, "ids 2")
        .split_whitespace()
        .skip(1)
        .map(|w| w.parse().expect("id"))
        .collect();
    let new_object = objects.iter().max().unwrap() + 7;
    for (k, line) in [
        format!("move {} 0.5 0.25 0", objects[0]),
        format!("add {new_object} 2 6.0 7.0 1.0"),
        format!("remove {}", objects[1]),
    ]
    .iter()
    .enumerate()
    {
        command(&mut peer, line);
        let path = sent_dir.join(format!("{}.bin", k + 1));
        let skip = bridge.stdout().len();
        command(&mut peer, &format!("delta {}", path.display()));
        bridge_event(&bridge, skip, "update");
        // The exporter's next message: incremental, a Spark-DSG body of its own.
        let seq = k + 1;
        let got = listener.expect_line(STEP, |l| l.starts_with(&format!("got seq={seq} ")));
        assert!(got.contains(" full=0 "), "{line}: {got}");
        assert!(
            !got.contains("nodes=error"),
            "{line}: spark_dsg refused the part: {got}"
        );
        let meta: serde_json::Value = serde_json::from_slice(
            &std::fs::read(received.join(format!("{seq}.json"))).expect("message"),
        )
        .expect("JSON");
        let ids =
            |key: &str| -> Vec<u64> { serde_json::from_value(meta[key].clone()).expect("ids") };
        held.apply_update(
            decode(&received.join(format!("{seq}.bin"))),
            &ids("deleted_nodes"),
            &ids("deleted_edges"),
        )
        .unwrap_or_else(|e| panic!("{line}: {e}"));
        assert_eq!(sent_form(&held), sent_form(&decode(&path)), "{line}");
    }

    for mut p in [export, bridge] {
        p.signal(Signal::TERM);
        assert!(p.wait_exit(STEP).success(), "{}", p.describe());
    }
    peer.send("quit").ok();
    peer.close_stdin();
    drop(listener);
    scene.assert_no_leftovers(Duration::from_secs(5));
}

/// The README's ROS 2 commands are ones `ygg` takes (each checked up to `--help`, which
/// clap answers only after accepting every argument before it).
#[test]
fn readme_ros2_commands_are_accepted() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let section = readme
        .split("## ROS 2 (Hydra)")
        .nth(1)
        .and_then(|s| s.split("```sh").nth(1))
        .and_then(|s| s.split("```").next())
        .expect("a sh block in the README's ROS 2 section");
    let commands: Vec<Vec<&str>> = section
        .lines()
        .filter_map(|l| l.split('#').next()?.trim().strip_prefix("ygg "))
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(commands.len(), 2, "{section}");
    for args in commands {
        let mut all: Vec<&dyn AsRef<std::ffi::OsStr>> = args
            .iter()
            .map(|a| a as &dyn AsRef<std::ffi::OsStr>)
            .collect();
        all.push(&"--help");
        let out = run("ygg", &all);
        assert!(out.status.success(), "ygg {args:?}: {}", text(&out.stderr));
    }
}

#[test]
fn bridge_ros2_refuses_bad_arguments_cleanly() {
    let cases: [(&[&str], &str); 3] = [
        (
            &["--topic", "hydra//dsg", "--scene", "s"],
            "not a ROS 2 topic name",
        ),
        (&["--scene", "s", "--domain-id", "300"], "domain id 300"),
        (&["--scene", "a/b"], "scene"),
    ];
    for (args, needle) in cases {
        let mut all: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"bridge", &"ros2"];
        all.extend(args.iter().map(|a| a as &dyn AsRef<std::ffi::OsStr>));
        let out = run("ygg", &all);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
}
