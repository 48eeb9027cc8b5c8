//! `ygg-relay` across two real network stacks: two network namespaces joined by a veth
//! pair, the writer and `ygg-relay export` in one, `ygg-relay import` and the readers in the
//! other, Zenoh with explicit endpoints on the pair's addresses and scouting off, every link
//! mutual TLS with certificates `ygg-relay certs` makes (hosts `robot` and `base`, plus an
//! `intruder` of the same CA and a `robot` and a `base` of another CA for the attacks).
//!
//! Each side has its own iceoryx2 prefix (its own "host"), so the remote readers can only
//! see what crossed the link. The tests create the namespaces and tear them down
//! themselves (also on failure). They need root and `ip` (iproute2), as in CI: without
//! them they fail, saying why, unless `YGG_SKIP_NETNS_TESTS=1`
//! ([`ygg_testkit::ENV_SKIP_NETNS_TESTS`]) says this machine cannot run them (they then
//! skip with a message).

use std::collections::BTreeMap;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::time::{Duration, Instant};

use rustix::process::Signal;
use ygg_testkit::{Proc, TestScene, VethLink, Watchdog, binary, field};
use ygg_transport::{ReceiveError, Snapshot, SubscriberBuilder};

/// Generous bound for one step (debug builds on a busy 2-core machine).
const STEP: Duration = Duration::from_secs(60);
/// Per-test watchdog.
const WATCHDOG: Duration = Duration::from_secs(240);
/// Zenoh port the exporter listens on.
const PORT: u16 = 7447;
/// Zenoh port the importer listens on (for peers that put on its key).
const IMPORT_PORT: u16 = 7448;

/// The test's two hosts (0: the robot, 1: the remote host).
struct Link(VethLink);

impl Link {
    /// Creates them; `None` (after printing why) where that is impossible and
    /// `YGG_SKIP_NETNS_TESTS=1`; fails the test where it is impossible otherwise.
    fn create() -> Option<Self> {
        VethLink::create_for_test("yr").map(Self)
    }

    /// `program args` run inside host `side`, with `scene`'s iceoryx2 prefix.
    fn command(&self, side: usize, scene: &TestScene, program: &Path, args: &[&str]) -> Command {
        let mut command = self.0.command(side, program, args);
        scene.configure(&mut command);
        command
    }

    /// `tls/<address of side>:<port>`.
    fn endpoint(&self, side: usize, port: u16) -> String {
        format!("tls/{}:{port}", self.0.address(side))
    }

    /// `tcp/<address of side>:<port>` (plain TCP, for the attacks).
    fn tcp_endpoint(&self, side: usize, port: u16) -> String {
        self.0.endpoint(side, port)
    }

    /// Takes the robot's end of the link down or up.
    fn set_up(&self, up: bool) {
        self.0.set_up(up).unwrap_or_else(|e| panic!("{e}"));
    }
}

/// The robot side's scene and the remote side's, each with its own prefix, and the
/// certificates.
struct Hosts {
    link: Link,
    robot: TestScene,
    remote: TestScene,
    key: String,
    /// `fleet/`: the CA of `robot` (host 0), `base` (host 1) and `intruder`; `foreign/`:
    /// another CA's `robot` and `base`.
    pki: tempfile::TempDir,
}

/// The fleet's CA (the one the relays trust).
const FLEET: &str = "fleet";
/// Another CA, with certificates of the same names.
const FOREIGN: &str = "foreign";

impl Hosts {
    fn new(tag: &str) -> Option<Self> {
        let link = Link::create()?;
        // Built (or found) before a test starts its watchdog: a cold build of the relay and
        // its Zenoh dependencies takes minutes on a fresh 2-core machine, and a watchdog that
        // fired during it killed the test's writer (seen in a clean-clone CI run).
        binary("ygg-relay");
        binary("ygg");
        let robot = TestScene::new(tag);
        let remote = TestScene::new(tag);
        let key = format!("test/{}", robot.name);
        let pki = tempfile::tempdir().expect("temp dir");
        let (robot_host, base_host) = (
            format!("robot={}", link.0.address(0)),
            format!("base={}", link.0.address(1)),
        );
        for (ca, hosts) in [
            (FLEET, vec![&robot_host, &base_host, &"intruder".to_owned()]),
            (FOREIGN, vec![&robot_host, &base_host]),
        ] {
            let dir = pki.path().join(ca);
            let mut args = vec!["certs", "--dir", dir.to_str().expect("utf-8")];
            for host in hosts {
                args.extend(["--host", host.as_str()]);
            }
            let out = Command::new(binary("ygg-relay"))
                .args(&args)
                .output()
                .expect("run ygg-relay certs");
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        Some(Self {
            link,
            robot,
            remote,
            key,
            pki,
        })
    }

    /// `--ca --cert --private-key` of `host` from `ca`'s folder.
    fn tls(&self, ca: &str, host: &str) -> Vec<String> {
        let file = |name: &str| {
            let path = self.pki.path().join(ca).join(name);
            path.to_str().expect("utf-8").to_owned()
        };
        vec![
            "--ca".into(),
            file("ca.pem"),
            "--cert".into(),
            file(&format!("{host}.pem")),
            "--private-key".into(),
            file(&format!("{host}.key")),
        ]
    }

    /// `ygg serve` of a small office on the robot at `rate` updates per second, its
    /// growing layers in parts of a few rows (many part segments cross the relay).
    fn writer(&self, rate: &str, watchdog: &Watchdog) -> Proc {
        let args = [
            "serve",
            "--scene",
            &self.robot.name,
            "--scale",
            "0.05",
            "--rate",
            rate,
            "--part-rows",
            "8",
        ];
        let command = self.link.command(0, &self.robot, &binary("ygg"), &args);
        let writer = Proc::spawn(command, "writer", watchdog);
        writer.expect_line(STEP, |l| l.contains("\"ready\""));
        writer
    }

    /// `ygg-relay export` on the robot, listening on the robot's address.
    fn exporter(&self, watchdog: &Watchdog) -> Proc {
        let listen = self.link.endpoint(0, PORT);
        let tls = self.tls(FLEET, "robot");
        let mut args = vec![
            "export",
            "--scene",
            &self.robot.name,
            "--key",
            &self.key,
            "--listen",
            &listen,
            "--allow",
            "base",
        ];
        args.extend(tls.iter().map(String::as_str));
        let command = self
            .link
            .command(0, &self.robot, &binary("ygg-relay"), &args);
        Proc::spawn(command, "exporter", watchdog)
    }

    /// `ygg-relay import` on the remote host into `scene` as `base`, trusting `robot`,
    /// connecting to the exporter and listening on the remote address.
    fn importer(&self, scene: &TestScene, watchdog: &Watchdog) -> Proc {
        let listen = self.link.endpoint(1, IMPORT_PORT);
        let mut security = self.tls(FLEET, "base");
        security.extend(["--listen".into(), listen]);
        self.importer_as(scene, &security, "importer", watchdog)
    }

    /// `ygg-relay import` on the remote host into `scene`, trusting `robot` (unless
    /// `--insecure`) and connecting to the exporter, with `security` (certificate options,
    /// or an attacker's).
    fn importer_as(
        &self,
        scene: &TestScene,
        security: &[String],
        label: &str,
        watchdog: &Watchdog,
    ) -> Proc {
        let insecure = security.iter().any(|a| a == "--insecure");
        let connect = if insecure {
            self.link.tcp_endpoint(0, PORT)
        } else {
            self.link.endpoint(0, PORT)
        };
        let mut args = vec![
            "import",
            "--key",
            &self.key,
            "--scene",
            &scene.name,
            "--connect",
            &connect,
        ];
        // Plain TCP carries no identity to allow: such an importer takes from anyone.
        if !insecure {
            args.extend(["--allow", "robot"]);
        }
        args.extend(security.iter().map(String::as_str));
        let command = self.link.command(1, scene, &binary("ygg-relay"), &args);
        Proc::spawn(command, label, watchdog)
    }

    /// `ygg-relay put` of `bytes` on `key` from the robot's host to the importer, with
    /// `security`; returns its `peers=` (how many peers it had a link to when it put).
    fn put(&self, key: &str, bytes: &[u8], connect: &str, security: &[String]) -> usize {
        let file = std::env::temp_dir().join(format!("{}-put", self.robot.name));
        std::fs::write(&file, bytes).expect("write the payload");
        let mut args = vec![
            "put",
            "--key",
            key,
            "--file",
            file.to_str().expect("utf-8"),
            "--connect",
            connect,
            "--settle-ms",
            "500",
        ];
        args.extend(security.iter().map(String::as_str));
        let out = self
            .link
            .command(0, &self.robot, &binary("ygg-relay"), &args)
            .output()
            .expect("run ygg-relay put");
        let _ = std::fs::remove_file(&file);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        stdout
            .lines()
            .find_map(|l| field(l, "peers"))
            .and_then(|p| p.parse().ok())
            .unwrap_or_else(|| panic!("no peers= in {stdout}"))
    }

    /// `ygg <args>` on the remote host, on `scene`.
    fn remote_reader(&self, scene: &TestScene, args: &[&str], watchdog: &Watchdog) -> Proc {
        let command = self.link.command(1, scene, &binary("ygg"), args);
        Proc::spawn(command, "remote reader", watchdog)
    }
}

/// Stops a relay or writer with SIGTERM and asserts a clean exit.
fn terminate(proc: &mut Proc) {
    proc.signal(Signal::TERM);
    let status = proc.wait_exit(STEP);
    assert!(status.success(), "{}", proc.describe());
}

/// A digest of everything a snapshot carries: entries, every segment's bytes, the
/// manifest bytes.
fn digest(snapshot: &Snapshot) -> u64 {
    let mut h = DefaultHasher::new();
    for (entry, bytes) in snapshot.layers() {
        (entry.layer_id, entry.generation, bytes).hash(&mut h);
    }
    snapshot.manifest_bytes().hash(&mut h);
    h.finish()
}

/// Digests by generation, and the condition variable notified on each new one.
type Digests = Arc<(Mutex<BTreeMap<u64, u64>>, Condvar)>;

/// Follows a scene in a thread, recording the digest of every snapshot by generation.
struct Recorder {
    digests: Digests,
    gone: Arc<AtomicU32>,
    stop: Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Recorder {
    fn start(scene: &TestScene) -> Self {
        let mut reader = SubscriberBuilder::new(&scene.name)
            .iceoryx_prefix(&scene.prefix)
            .wait_for_writer(STEP)
            .open()
            .unwrap_or_else(|e| panic!("attach to {}: {e}", scene.name));
        let digests: Digests = Arc::default();
        let gone = Arc::new(AtomicU32::new(0));
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (d, g, s) = (Arc::clone(&digests), Arc::clone(&gone), Arc::clone(&stop));
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                match reader.wait_next(Duration::from_millis(50)) {
                    Ok(Some(snapshot)) => {
                        let digest = digest(&snapshot);
                        let (lock, received) = &*d;
                        lock.lock()
                            .unwrap_or_else(PoisonError::into_inner)
                            .insert(snapshot.generation(), digest);
                        received.notify_all();
                    }
                    Ok(None) => {}
                    Err(ReceiveError::WriterGone { .. }) => {
                        g.fetch_add(1, Ordering::Relaxed);
                    }
                    Err(e) => panic!("receive: {e}"),
                }
            }
        });
        Self {
            digests,
            gone,
            stop,
            thread: Some(thread),
        }
    }

    fn digests(&self) -> BTreeMap<u64, u64> {
        self.digests
            .0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// Waits until a generation above `after` was received; returns the newest.
    fn wait_beyond(&self, after: u64) -> u64 {
        let (lock, received) = &*self.digests;
        let newest = |d: &BTreeMap<u64, u64>| d.last_key_value().map(|(&g, _)| g);
        let digests = lock.lock().unwrap_or_else(PoisonError::into_inner);
        let (digests, _) = received
            .wait_timeout_while(digests, STEP, |d| newest(d).is_none_or(|g| g <= after))
            .unwrap_or_else(PoisonError::into_inner);
        newest(&digests)
            .filter(|&g| g > after)
            .unwrap_or_else(|| panic!("no generation beyond {after} within {STEP:?}"))
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// Asserts that every generation both recorders saw has the same digest, and that they
/// share at least `min` generations.
fn assert_same_snapshots(local: &Recorder, remote: &Recorder, min: usize) {
    let (local, remote) = (local.digests(), remote.digests());
    let mut common = 0;
    for (generation, digest) in &remote {
        if let Some(expected) = local.get(generation) {
            assert_eq!(digest, expected, "generation {generation} differs remotely");
            common += 1;
        }
    }
    assert!(
        common >= min,
        "only {common} common generations (local {}, remote {})",
        local.len(),
        remote.len()
    );
}

/// Query lines for `ygg query`.
const QUERIES: &str = r#"{"op":"nearest_object","point":[1.0,2.0,0.5]}
{"op":"objects_within","point":[3.0,3.0,1.0],"radius":2.0}
{"op":"visible_objects","eye":[0.0,0.0,1.0],"dir":[1.0,0.0,0.0],"half_angle_deg":50,"range":8}
{"op":"objects_with_label","label":"light"}
"#;

#[test]
fn a_late_importer_resyncs_by_query_and_remote_answers_equal_local_ones() {
    let Some(hosts) = Hosts::new("relay-static") else {
        return;
    };
    let watchdog = Watchdog::new(WATCHDOG);
    // A scene that does not change: the importer, started after the snapshot was put,
    // can only get it by querying.
    let mut writer = hosts.writer("0", &watchdog);
    let mut exporter = hosts.exporter(&watchdog);
    exporter.expect_line(STEP, |l| l.starts_with("sent generation=1 "));
    let started = Instant::now();
    let mut importer = hosts.importer(&hosts.remote, &watchdog);
    importer.expect_line(STEP, |l| l.starts_with("published generation=1 "));
    eprintln!("late importer consistent after {:?}", started.elapsed());
    exporter.expect_line(STEP, |l| l.starts_with("answered query"));

    let queries = std::env::temp_dir().join(format!("{}.jsonl", hosts.robot.name));
    std::fs::write(&queries, QUERIES).expect("write queries");
    let q = queries.to_str().expect("utf-8 path");
    let answers = |side: usize, scene: &TestScene| {
        let args = ["query", "--scene", &scene.name, "--queries", q];
        let out = hosts
            .link
            .command(side, scene, &binary("ygg"), &args)
            .output()
            .expect("run ygg query");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let local = answers(0, &hosts.robot);
    let remote = answers(1, &hosts.remote);
    let _ = std::fs::remove_file(&queries);
    assert_eq!(local.lines().count(), 4, "{local}");
    assert!(
        !local.contains("error") && local.lines().any(|l| !l.contains("\"ids\":[]")),
        "{local}"
    );
    assert_eq!(remote, local, "the remote reader answers differently");

    // The remote `inspect` works unchanged too.
    let inspect = hosts
        .link
        .command(
            1,
            &hosts.remote,
            &binary("ygg"),
            &["inspect", "--scene", &hosts.remote.name],
        )
        .output()
        .expect("run ygg inspect");
    assert!(
        inspect.status.success(),
        "{}",
        String::from_utf8_lossy(&inspect.stderr)
    );

    terminate(&mut importer);
    terminate(&mut exporter);
    terminate(&mut writer);
    hosts.remote.assert_no_leftovers(Duration::from_secs(5));
    hosts.robot.assert_no_leftovers(Duration::from_secs(5));
}

/// Garbage on the key: a segment, a manifest and a foreign key, as (key, bytes).
fn garbage(base: &str) -> [(String, Vec<u8>); 3] {
    let session = "0123456789abcdef";
    [
        (format!("{base}/{session}/0/999999"), vec![0xAB; 4096]),
        (format!("{base}/{session}/manifest/999999"), vec![0xCD; 512]),
        (format!("{base}/not/a/segment"), b"hello".to_vec()),
    ]
}

#[test]
fn live_updates_cross_byte_for_byte_and_garbage_on_the_key_is_dropped() {
    let Some(hosts) = Hosts::new("relay-live") else {
        return;
    };
    let watchdog = Watchdog::new(WATCHDOG);
    let mut writer = hosts.writer("20", &watchdog);
    let mut exporter = hosts.exporter(&watchdog);
    let mut importer = hosts.importer(&hosts.remote, &watchdog);
    importer.expect_line(STEP, |l| l.starts_with("published generation="));
    let local = Recorder::start(&hosts.robot);
    let remote = Recorder::start(&hosts.remote);
    let first = remote.wait_beyond(0);
    remote.wait_beyond(first + 20);

    // Garbage from another peer on the key: a segment, a manifest and a foreign key.
    // Put from the trusted identity: access control lets it in, validation drops it.
    let trusted = hosts.tls(FLEET, "robot");
    let connect = hosts.link.endpoint(1, IMPORT_PORT);
    for (key, bytes) in garbage(&hosts.key) {
        let peers = hosts.put(&key, &bytes, &connect, &trusted);
        assert_eq!(peers, 1, "the trusted put did not connect");
        importer.expect_line(STEP, |l| {
            field(l, "key") == Some(key.as_str()) && l.starts_with("dropped")
        });
    }
    let after_garbage = remote.digests().last_key_value().map_or(0, |(g, _)| *g);
    remote.wait_beyond(after_garbage + 10);
    assert_eq!(
        remote.gone.load(Ordering::Relaxed),
        0,
        "garbage made the remote writer go"
    );
    assert_same_snapshots(&local, &remote, 20);

    drop(remote);
    drop(local);
    terminate(&mut importer);
    terminate(&mut exporter);
    terminate(&mut writer);
    hosts.remote.assert_no_leftovers(Duration::from_secs(5));
    hosts.robot.assert_no_leftovers(Duration::from_secs(5));
}

/// The newest `peers=N` a relay printed.
fn peers(relay: &Proc) -> Option<usize> {
    relay
        .stdout()
        .iter()
        .rev()
        .find_map(|l| field(l, "peers").and_then(|p| p.parse().ok()))
}

/// Asserts that an attacking importer got nothing: it never saw the exporter nor published
/// a cut, and no byte of the scene is in its shared memory.
fn assert_got_nothing(attacker: &Proc, scene: &TestScene) {
    let lines = attacker.stdout();
    assert!(
        !lines
            .iter()
            .any(|l| l.starts_with("published") || l.starts_with("exporter alive")),
        "{}",
        attacker.describe()
    );
    assert!(scene.files().is_empty(), "{:?}", scene.files());
}

#[test]
fn peers_without_the_fleet_s_certificate_or_identity_get_nothing_in_or_out() {
    let Some(hosts) = Hosts::new("relay-attacks") else {
        return;
    };
    let watchdog = Watchdog::new(WATCHDOG);
    let mut writer = hosts.writer("20", &watchdog);
    let mut exporter = hosts.exporter(&watchdog);
    let mut importer = hosts.importer(&hosts.remote, &watchdog);
    importer.expect_line(STEP, |l| l.starts_with("published generation="));
    exporter.expect_line(STEP, |l| l == "peers=1");
    let local = Recorder::start(&hosts.robot);
    let remote = Recorder::start(&hosts.remote);
    let first = remote.wait_beyond(0);

    // Puts on the importer's key: garbage, which the importer would log as dropped had it
    // reached it (the trusted put of `live_updates_...` is).
    let tls = hosts.link.endpoint(1, IMPORT_PORT);
    let tcp = hosts.link.tcp_endpoint(1, IMPORT_PORT);
    let no_client_cert = hosts.pki.path().join("no-client-cert.json5");
    let fleet_ca = hosts.pki.path().join(FLEET).join("ca.pem");
    std::fs::write(
        &no_client_cert,
        format!(
            "{{transport: {{link: {{tls: {{root_ca_certificate: {:?}}}}}}}}}",
            fleet_ca.to_str().expect("utf-8")
        ),
    )
    .expect("write the zenoh config");
    let insecure = vec!["--insecure".to_owned()];
    let tls_without_cert = vec![
        "--insecure".to_owned(),
        "--zenoh-config".to_owned(),
        no_client_cert.to_str().expect("utf-8").to_owned(),
    ];
    let attacks = [
        ("plain TCP", &tcp, insecure.clone(), 0),
        (
            "TLS without a client certificate",
            &tls,
            tls_without_cert.clone(),
            0,
        ),
        (
            "`robot` of another CA",
            &tls,
            hosts.tls(FOREIGN, "robot"),
            0,
        ),
        (
            "`intruder` of the fleet's CA",
            &tls,
            hosts.tls(FLEET, "intruder"),
            1,
        ),
    ];
    for (attack, connect, security, linked) in &attacks {
        for (key, bytes) in garbage(&hosts.key) {
            let peers = hosts.put(&key, &bytes, connect, security);
            assert_eq!(peers, *linked, "{attack}: links when putting");
        }
        eprintln!("put attack done: {attack}");
    }
    let after_puts = remote.wait_beyond(first);
    remote.wait_beyond(after_puts + 10);
    assert!(
        !importer.stdout().iter().any(|l| l.starts_with("dropped")),
        "an unauthorised put reached the importer: {}",
        importer.describe()
    );

    // Reads of the exporter's scene: importers that trust `robot` but are not `base` of
    // the fleet's CA.
    let mut scenes = Vec::new();
    let mut attackers = Vec::new();
    for (label, security) in [
        ("plain TCP importer", insecure),
        ("importer without a client certificate", tls_without_cert),
        ("`base` of another CA", hosts.tls(FOREIGN, "base")),
    ] {
        let scene = TestScene::new("relay-stolen");
        attackers.push(hosts.importer_as(&scene, &security, label, &watchdog));
        scenes.push(scene);
    }
    for attacker in &attackers {
        attacker.expect_line(STEP, |l| l.starts_with("importing"));
    }
    let newest = remote.wait_beyond(0);
    remote.wait_beyond(newest + 10);
    assert_eq!(peers(&exporter), Some(1), "{}", exporter.describe());
    // The fleet's `intruder`: its link opens, and nothing crosses it.
    let seen = exporter.count_lines(|_| true);
    let scene = TestScene::new("relay-stolen");
    let intruder = hosts.importer_as(&scene, &hosts.tls(FLEET, "intruder"), "intruder", &watchdog);
    exporter
        .wait_line_after(seen, STEP, |l| l == "peers=2")
        .unwrap_or_else(|| panic!("the intruder never linked: {}", exporter.describe()));
    intruder.expect_line(STEP, |l| l == "peers=1");
    attackers.push(intruder);
    scenes.push(scene);
    let newest = remote.wait_beyond(0);
    remote.wait_beyond(newest + 10);
    for (attacker, scene) in attackers.iter().zip(&scenes) {
        assert_got_nothing(attacker, scene);
    }

    // The legitimate link worked throughout, byte for byte.
    assert_eq!(
        remote.gone.load(Ordering::Relaxed),
        0,
        "the remote writer went"
    );
    assert_same_snapshots(&local, &remote, 40);

    for attacker in &mut attackers {
        terminate(attacker);
    }
    drop(remote);
    drop(local);
    terminate(&mut importer);
    terminate(&mut exporter);
    terminate(&mut writer);
    for scene in &scenes {
        scene.assert_no_leftovers(Duration::from_secs(5));
    }
    hosts.remote.assert_no_leftovers(Duration::from_secs(5));
    hosts.robot.assert_no_leftovers(Duration::from_secs(5));
}

#[test]
fn link_down_up_and_a_killed_exporter_leave_remote_readers_stale_then_resync() {
    let Some(hosts) = Hosts::new("relay-faults") else {
        return;
    };
    let watchdog = Watchdog::new(WATCHDOG);
    let mut writer = hosts.writer("10", &watchdog);
    let mut exporter = hosts.exporter(&watchdog);
    let mut importer = hosts.importer(&hosts.remote, &watchdog);
    importer.expect_line(STEP, |l| l.starts_with("published generation="));
    let local = Recorder::start(&hosts.robot);
    let mut watch = hosts.remote_reader(
        &hosts.remote,
        &["watch", "--scene", &hosts.remote.name],
        &watchdog,
    );
    watch.expect_line(STEP, |l| l.starts_with("snapshot "));

    // Link down: the remote reader keeps its snapshot and reports the writer gone.
    hosts.link.set_up(false);
    let stale = watch.expect_line(STEP, |l| l.starts_with("writer gone; keeping generation="));
    let kept: u64 = field(&stale, "generation")
        .and_then(|g| g.parse().ok())
        .expect("generation");
    // Link up: a newer snapshot arrives, equal to the local one of that generation.
    let seen = watch.count_lines(|_| true);
    let up = Instant::now();
    hosts.link.set_up(true);
    let (_, line) = watch
        .wait_line_after(seen, STEP, |l| {
            l.starts_with("snapshot ")
                && field(l, "generation").and_then(|g| g.parse::<u64>().ok()) > Some(kept)
        })
        .unwrap_or_else(|| {
            panic!(
                "no resync after link up: {}\n{}\n{}",
                watch.describe(),
                importer.describe(),
                exporter.describe()
            )
        });
    eprintln!("resynced after link up in {:?}: {line}", up.elapsed());

    // Exporter killed: the remote reader reports the writer gone; a restarted exporter
    // is picked up.
    let seen = watch.count_lines(|_| true);
    exporter.kill();
    watch
        .wait_line_after(seen, STEP, |l| l.starts_with("writer gone"))
        .unwrap_or_else(|| {
            panic!(
                "no writer gone after the exporter died: {}",
                watch.describe()
            )
        });
    let seen = watch.count_lines(|_| true);
    let mut exporter = hosts.exporter(&watchdog);
    watch
        .wait_line_after(seen, STEP, |l| l.starts_with("snapshot "))
        .unwrap_or_else(|| {
            panic!(
                "no snapshot from the restarted exporter: {}",
                watch.describe()
            )
        });

    // What the remote side holds now is what the robot published.
    let remote = Recorder::start(&hosts.remote);
    let newest = remote.wait_beyond(0);
    remote.wait_beyond(newest + 5);
    assert_same_snapshots(&local, &remote, 5);

    drop(remote);
    drop(local);
    terminate(&mut watch);
    terminate(&mut importer);
    terminate(&mut exporter);
    terminate(&mut writer);
    hosts.remote.assert_no_leftovers(Duration::from_secs(5));
    hosts.robot.assert_no_leftovers(Duration::from_secs(5));
}

#[test]
fn bad_arguments_are_refused_with_a_clear_error() {
    let relay = binary("ygg-relay");
    let pki = tempfile::tempdir().expect("temp dir");
    let dir = pki.path().to_str().expect("utf-8").to_owned();
    let out = Command::new(&relay)
        .args(["certs", "--dir", &dir, "--host", "robot"])
        .output()
        .expect("run ygg-relay certs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let file = |name: &str| format!("{dir}/{name}");
    let (ca, cert, key) = (file("ca.pem"), file("robot.pem"), file("robot.key"));
    // Plain TCP only when asked for, and then with a warning (a put to nobody on loopback).
    let insecure = Command::new(&relay)
        .args(["put", "--key", "a/b", "--file", &ca, "--settle-ms", "0"])
        .args(["--connect", "tcp/127.0.0.1:9", "--insecure"])
        .output()
        .expect("run ygg-relay put --insecure");
    let stderr = String::from_utf8_lossy(&insecure.stderr);
    assert!(insecure.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: --insecure: plain TCP"),
        "{stderr}"
    );
    for (args, says) in [
        (
            vec!["export", "--scene", "s", "--key", "a/b"],
            "--connect or --listen",
        ),
        (
            vec![
                "export",
                "--scene",
                "s",
                "--key",
                "a/*",
                "--listen",
                "tcp/127.0.0.1:0",
            ],
            "--key",
        ),
        (
            vec![
                "import",
                "--scene",
                "bad/name",
                "--key",
                "a/b",
                "--connect",
                "tcp/127.0.0.1:9",
            ],
            "--scene",
        ),
        (
            vec![
                "import",
                "--scene",
                "s",
                "--key",
                "a/b",
                "--connect",
                "nonsense",
            ],
            "--connect",
        ),
        (vec!["import", "--key", "a/b"], "--scene"),
        (
            vec![
                "export",
                "--scene",
                "s",
                "--key",
                "a/b",
                "--listen",
                "tls/127.0.0.1:0",
            ],
            "--ca, --cert and --private-key",
        ),
        (
            vec![
                "export",
                "--scene",
                "s",
                "--key",
                "a/b",
                "--listen",
                "tcp/127.0.0.1:0",
                "--ca",
                &ca,
                "--cert",
                &cert,
                "--private-key",
                &key,
            ],
            "--listen tcp/127.0.0.1:0: links are mutual TLS by default",
        ),
        (
            vec![
                "export",
                "--scene",
                "s",
                "--key",
                "a/b",
                "--listen",
                "tls/127.0.0.1:0",
                "--ca",
                &ca,
                "--cert",
                &cert,
                "--private-key",
                &key,
            ],
            "give --allow NAME",
        ),
        (
            vec![
                "export",
                "--scene",
                "s",
                "--key",
                "a/b",
                "--listen",
                "tls/127.0.0.1:0",
                "--ca",
                &ca,
                "--cert",
                &key,
                "--private-key",
                &key,
                "--allow",
                "base",
            ],
            "--cert",
        ),
        (
            vec![
                "import",
                "--scene",
                "s",
                "--key",
                "a/b",
                "--connect",
                "tcp/127.0.0.1:9",
                "--insecure",
                "--allow",
                "robot",
            ],
            "--allow needs mutual TLS",
        ),
        (
            vec!["certs", "--dir", &dir, "--host", "robot=not an address"],
            "neither an IP address nor a DNS name",
        ),
    ] {
        let out = Command::new(&relay)
            .args(&args)
            .output()
            .expect("run ygg-relay");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}
