//! `ygg-bench remote`: a robot writer → `ygg-relay export` → Zenoh over a veth pair →
//! `ygg-relay import` → a remote reader, against spark_dsg's ZMQ full-graph stream
//! (`DsgSender` → `DsgReceiver`, the Hydra way) over the same link, in one run.
//!
//! The bench creates two network namespaces joined by a veth pair (a private /30), runs
//! the exporter in the robot's and the importer in the remote one, each side with its own
//! iceoryx2 prefix (its own "host"); the writer and the remote [`SceneReader`] live in this
//! process, so one clock times publish → remote visible (validated). Bytes on the wire are
//! the veth's rx + tx byte counters (`/proc/<pid>/net/dev` of a process in the robot's
//! namespace): everything both ways, TCP/IP headers and acknowledgements included.
//!
//! Cases (JSON rows `case`, `median_us`, `p99_us`, `bytes`):
//! * `pose_update`: a tick of the demo's SLAM stream that only appends an agent pose;
//!   publish → visible in the remote reader; bytes per update.
//! * `object_move`: one object's mesh moved by a few centimetres (what the stream does
//!   every second); same measures.
//! * `resync_full_office`: the link taken down until the remote reader reports the writer
//!   gone, one update published meanwhile, the link brought up: link up → the remote
//!   reader holds the new snapshot; bytes of the resync.
//! * `stream_bytes_ygg`: the demo's SLAM stream at 30 Hz (20 s, 3 s with `--quick`); latency of every
//!   tick and bytes per tick.
//! * `stream_bytes_spark_dsg_zmq`: the same number of ticks as full-graph messages of the
//!   same office (with mesh) through spark_dsg's sender and receiver, each after the
//!   tick's pose edit; send → received and decoded (`update_from_binary`), bytes per
//!   message.
//!
//! The four relay cases run twice in the one run: over mutual TLS (the relay's default:
//! certificates from `ygg-relay certs`, access control by identity; rows `link: "tls"`) and
//! then over plain TCP (`--insecure`; rows `link: "tcp"`), each with a fresh writer of the
//! same office and the same seeded edits. The spark_dsg row is `link: "zmq"`.
//!
//! With `--breakdown`, a reader of the robot's own scene (a thread here) records when each
//! generation is visible on the robot, and the timed rows also give the writer's update +
//! publish() call, that first hop, and the relay path from there to the remote reader.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError, mpsc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use clap::Parser;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::office::{OfficeParams, generate};
use ygg_dsg::replay::SlamReplay;
use ygg_reader::{SceneReader, SceneReceiveError};
use ygg_store::query::children;
use ygg_store::{NodeId, Point, SceneView};
use ygg_testkit::stats::median_p99;
use ygg_testkit::{Input, Proc, TestScene, VethLink};
use ygg_transport::{ReceiveError, WriterStatus};
use ygg_writer::SceneWriter;

/// Arguments of `ygg-bench remote`.
#[derive(Parser, Debug)]
pub struct RemoteArgs {
    /// Fewer repetitions and a shorter stream (a smoke run).
    #[arg(long)]
    pub quick: bool,
    /// Write the JSON rows to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also write the markdown report to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Office scale (1.0: the full office).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// The Python interpreter with spark_dsg 1.1.3 and pyzmq installed.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Also time each update's first hop: a reader of the robot's own scene (a thread
    /// of this process, one more consumer on the robot) records when each generation is
    /// visible there; rows then carry the writer's update + publish() call and that
    /// local time beside the remote one.
    #[arg(long)]
    pub breakdown: bool,
}

/// Bound on any single wait.
const STEP: Duration = Duration::from_secs(60);
/// Zenoh port of the exporter over TLS (plain TCP: the next one).
const PORT: u16 = 7447;
/// ZMQ port of spark_dsg's sender.
const ZMQ_PORT: u16 = 7450;
/// The demo's tick rate.
const TICK: Duration = Duration::from_millis(33);

/// spark_dsg's `DsgSender` bound to the robot's address, driven by stdin: `send ID DX`
/// moves node ID by DX metres and sends the whole graph as `DsgSender.send` does; prints
/// the CLOCK_MONOTONIC ns just before the socket's send.
const SPARK_SENDER: &str = r#"
import sys, time
import numpy as np
import spark_dsg as dsg
from spark_dsg.zmq import DsgSender
graph = dsg.DynamicSceneGraph.load(sys.argv[1])
sender = DsgSender(sys.argv[2])
print("ready", flush=True)
for line in sys.stdin:
    words = line.split()
    if not words:
        continue
    if words[0] == "send":
        node = graph.get_node(int(words[1]))
        node.attributes.position = node.attributes.position + np.array([float(words[2]), 0.0, 0.0])
        data = graph.to_binary(include_mesh=True)
        t = time.monotonic_ns()
        sender._socket.send(data)
        print(f"sent bytes={len(data)} t_ns={t}", flush=True)
"#;

/// spark_dsg's `DsgReceiver` on the remote host: prints the CLOCK_MONOTONIC ns once each
/// message is decoded into its graph (what `DsgReceiver.recv` does).
const SPARK_RECEIVER: &str = r#"
import sys, time
from spark_dsg.zmq import DsgReceiver
from spark_dsg import DynamicSceneGraph
r = DsgReceiver(sys.argv[1])
print("ready", flush=True)
while True:
    if not r._socket.poll(100):
        continue
    buf = r._socket.recv()
    if r._graph is None:
        r._graph = DynamicSceneGraph.from_binary(buf)
    else:
        r._graph.update_from_binary(buf)
    print(f"received t_ns={time.monotonic_ns()} nodes={r._graph.num_nodes()}", flush=True)
"#;

/// The `ygg-relay` binary beside the testkit's binaries; built once for this profile
/// when run by cargo (`cargo run -p ygg-bench -- remote`).
fn relay_binary() -> Result<PathBuf, String> {
    let ygg = ygg_testkit::binary("ygg");
    let dir = ygg.parent().ok_or("no binary directory")?;
    let relay = dir.join("ygg-relay");
    if let Some(cargo) = std::env::var_os("CARGO") {
        let mut build = Command::new(cargo);
        build.args(["build", "-p", "ygg-relay", "--bins"]);
        if dir.file_name().is_some_and(|n| n == "release") {
            build.arg("--release");
        }
        if let Some(target) = dir.parent() {
            build.env("CARGO_TARGET_DIR", target);
        }
        let built = build
            .output()
            .map_err(|e| format!("cargo build -p ygg-relay: {e}"))?;
        if !built.status.success() {
            return Err(format!(
                "cargo build -p ygg-relay failed:\n{}",
                String::from_utf8_lossy(&built.stderr)
            ));
        }
    }
    if relay.is_file() {
        Ok(relay)
    } else {
        Err(format!(
            "{} not found: cargo build --release -p ygg-relay",
            relay.display()
        ))
    }
}

/// How the relays' link is secured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LinkKind {
    /// Mutual TLS with access control (the default).
    Tls,
    /// Plain TCP (`--insecure`).
    Tcp,
}

impl LinkKind {
    fn name(self) -> &'static str {
        match self {
            Self::Tls => "tls",
            Self::Tcp => "tcp",
        }
    }
}

/// One JSON row.
struct Row {
    case: &'static str,
    /// `tls`, `tcp` or `zmq` (spark_dsg).
    link: &'static str,
    median_us: f64,
    p99_us: f64,
    bytes: f64,
    samples: usize,
    /// With `--breakdown`: the per-hop medians.
    hops: Option<Hops>,
}

/// Where an update's time goes (medians, µs, each over the samples that have it).
#[derive(Clone, Copy)]
struct Hops {
    /// Update start → the writer's publish() call returned.
    publish_call_us: f64,
    /// Update start → visible in a reader on the robot (first shared-memory hop).
    local_us: f64,
    /// Visible on the robot → visible remotely (exporter, Zenoh, importer, remote hop).
    relay_us: f64,
}

/// One update's times from its start, seconds.
#[derive(Clone, Copy)]
struct Timing {
    /// Visible in the remote reader.
    remote: f64,
    /// The writer's publish() call returned.
    publish_call: f64,
    /// Visible in the robot's own reader (with `--breakdown`).
    local: Option<f64>,
}

impl Row {
    fn new(case: &'static str, link: &'static str, latency_s: &[f64], bytes: f64) -> Self {
        let us: Vec<f64> = latency_s.iter().map(|s| s * 1e6).collect();
        let (median_us, p99_us) = median_p99(&us).unwrap_or((f64::NAN, f64::NAN));
        Self {
            case,
            link,
            median_us,
            p99_us,
            bytes,
            samples: latency_s.len(),
            hops: None,
        }
    }

    /// A row of updates timed by [`Relay::publish_and_wait`]; with per-hop medians when
    /// the local times were recorded.
    fn timed(case: &'static str, link: LinkKind, timings: &[Timing], bytes: f64) -> Self {
        let remote: Vec<f64> = timings.iter().map(|t| t.remote).collect();
        let locals: Vec<(f64, f64)> = timings
            .iter()
            .filter_map(|t| t.local.map(|l| (l, t.remote - l)))
            .collect();
        let us = |v: Vec<f64>| median(&v) * 1e6;
        let hops = (!locals.is_empty()).then(|| Hops {
            publish_call_us: us(timings.iter().map(|t| t.publish_call).collect()),
            local_us: us(locals.iter().map(|l| l.0).collect()),
            relay_us: us(locals.iter().map(|l| l.1).collect()),
        });
        Self {
            hops,
            ..Self::new(case, link.name(), &remote, bytes)
        }
    }

    fn json(&self) -> serde_json::Value {
        let mut row = serde_json::json!({"case": self.case, "link": self.link, "median_us": self.median_us,
            "p99_us": self.p99_us, "bytes": self.bytes, "samples": self.samples});
        if let Some(h) = self.hops {
            row["publish_call_us"] = h.publish_call_us.into();
            row["local_visible_us"] = h.local_us.into();
            row["relay_us"] = h.relay_us.into();
        }
        row
    }
}

/// With `--breakdown`: a reader of the robot's own scene in a thread, recording when each
/// generation became visible on the robot.
struct LocalWatch {
    seen: Arc<Mutex<HashMap<u64, Instant>>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl LocalWatch {
    /// Opens the reader (in its thread: a reader stays on the thread that opened it).
    fn start(scene: &str, prefix: &str) -> Result<Self, Box<dyn std::error::Error>> {
        let seen: Arc<Mutex<HashMap<u64, Instant>>> = Arc::default();
        let stop = Arc::new(AtomicBool::new(false));
        let (opened, open_result) = mpsc::channel();
        let (scene, prefix) = (scene.to_owned(), prefix.to_owned());
        let (record, stopped) = (Arc::clone(&seen), Arc::clone(&stop));
        let thread = std::thread::spawn(move || {
            let reader = SceneReader::builder(&scene)
                .iceoryx_prefix(&prefix)
                .wait_for_writer(STEP)
                .open();
            let mut reader = match reader {
                Ok(r) => {
                    let _ = opened.send(Ok(()));
                    r
                }
                Err(e) => {
                    let _ = opened.send(Err(e.to_string()));
                    return;
                }
            };
            while !stopped.load(Ordering::Relaxed) {
                if let Ok(Some(s)) = reader.wait_next(Duration::from_millis(50)) {
                    let at = Instant::now();
                    record
                        .lock()
                        .unwrap_or_else(PoisonError::into_inner)
                        .insert(s.generation(), at);
                }
            }
        });
        open_result.recv()??;
        Ok(Self {
            seen,
            stop,
            thread: Some(thread),
        })
    }

    /// When `generation` became visible on the robot; waits up to a second for it.
    fn visible(&self, generation: u64) -> Option<Instant> {
        let until = Instant::now() + Duration::from_secs(1);
        loop {
            let seen = self.seen.lock().unwrap_or_else(PoisonError::into_inner);
            if let Some(&at) = seen.get(&generation) {
                return Some(at);
            }
            drop(seen);
            if Instant::now() > until {
                return None;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

impl Drop for LocalWatch {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The robot writer, the relay pair and the remote reader.
struct Relay<'a> {
    link: &'a VethLink,
    writer: SceneWriter,
    reader: SceneReader,
    exporter: Proc,
    importer: Proc,
    /// With `--breakdown`.
    local: Option<LocalWatch>,
}

impl Relay<'_> {
    /// Stops the relays with SIGTERM (so the importer removes its shared memory), then the
    /// reader and the writer.
    fn stop(self) {
        let Self {
            writer,
            reader,
            mut exporter,
            mut importer,
            local,
            ..
        } = self;
        drop(local);
        for proc in [&mut importer, &mut exporter] {
            proc.signal(rustix::process::Signal::TERM);
            if proc.wait_timeout(Duration::from_secs(10)).is_none() {
                eprintln!(
                    "warning: {} did not stop: {}",
                    proc.label(),
                    proc.describe()
                );
            }
        }
        drop(reader);
        drop(writer);
    }

    /// Publishes what changed; waits until the remote reader holds that generation.
    /// Returns the update's times from `t0` (its start) and the wire bytes.
    fn publish_and_wait(
        &mut self,
        t0: Instant,
    ) -> Result<(Timing, u64), Box<dyn std::error::Error>> {
        let bytes0 = self.link.wire_bytes(self.exporter.pid())?;
        let generation = self.writer.publish()?.generation;
        let publish_call = t0.elapsed().as_secs_f64();
        let remote = self.wait_for(generation, t0)?;
        let local = self
            .local
            .as_ref()
            .and_then(|w| w.visible(generation))
            .map(|at| at.saturating_duration_since(t0).as_secs_f64());
        // Let the acknowledgements of the update cross too.
        std::thread::sleep(TICK / 2);
        let bytes = self.link.wire_bytes(self.exporter.pid())? - bytes0;
        let timing = Timing {
            remote,
            publish_call,
            local,
        };
        Ok((timing, bytes))
    }

    /// Waits until the remote reader holds `generation` or newer; seconds since `t0`.
    fn wait_for(
        &mut self,
        generation: u64,
        t0: Instant,
    ) -> Result<f64, Box<dyn std::error::Error>> {
        let until = Instant::now() + STEP;
        loop {
            match self.reader.wait_next(Duration::from_millis(100)) {
                Ok(Some(s)) if s.generation() >= generation => {
                    return Ok(t0.elapsed().as_secs_f64());
                }
                Ok(_) | Err(SceneReceiveError::Receive(ReceiveError::WriterGone { .. })) => {}
                Err(e) => return Err(e.into()),
            }
            if Instant::now() > until {
                return Err(
                    format!("generation {generation} never reached the remote reader").into(),
                );
            }
        }
    }
}

/// Moves every point of `object`'s children by `d` (how the SLAM stream moves an object).
fn move_object(
    g: &mut ygg_store::SceneGraph,
    object: NodeId,
    d: Point,
) -> Result<(), Box<dyn std::error::Error>> {
    for child in children(&*g, object) {
        let moved: Vec<Point> = g
            .node(child)
            .map(|n| {
                g.points(n)
                    .iter()
                    .map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
                    .collect()
            })
            .unwrap_or_default();
        g.set_geometry(child, moved)?;
    }
    Ok(())
}

/// Runs `ygg-bench remote`.
///
/// # Errors
/// Not root, `ip` or a process that does not start, a reader that never sees an update.
pub fn run(args: &RemoteArgs) -> Result<(), Box<dyn std::error::Error>> {
    let load_before = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let (updates, resyncs, stream_s) = if args.quick {
        (30, 2, 3.0)
    } else {
        (200, 7, 20.0)
    };
    let relay_bin = relay_binary()?;
    let link = VethLink::create("yb")
        .map_err(|e| format!("ygg-bench remote cannot create its two hosts: {e}"))?;

    let dsg = generate(OfficeParams {
        seed: 7,
        scale: args.scale,
    });
    let dir = tempfile::tempdir()?;
    let office_file = dir.path().join("office.sparkdsg");
    ygg_dsg::write_binary(&dsg, &office_file)?;
    let spark_object = dsg
        .nodes
        .iter()
        .find(|n| n.kind == ygg_dsg::NodeKind::Object)
        .ok_or("the office has no object")?
        .id;
    let graph = layout::build(&dsg, Layout::Mint)?;
    drop(dsg);
    let pki = dir.path().join("pki");
    make_certs(&relay_bin, &pki, &link)?;

    let cases = Cases {
        updates,
        resyncs,
        ticks: (stream_s / TICK.as_secs_f64()) as usize,
        breakdown: args.breakdown,
    };
    let mut rows = Vec::new();
    for kind in [LinkKind::Tls, LinkKind::Tcp] {
        let security = match kind {
            LinkKind::Tls => Security::Tls(&pki),
            LinkKind::Tcp => Security::Insecure,
        };
        rows.extend(relay_cases(
            &link,
            &relay_bin,
            kind,
            security,
            graph.clone(),
            &cases,
        )?);
    }
    drop(graph);
    let ticks = cases.ticks;

    // spark_dsg's full-graph stream over the same link, for the same number of edits.
    let zmq_endpoint = format!("tcp://{}:{ZMQ_PORT}", link.address(0));
    let python = Path::new(&args.python);
    let mut sender_cmd = link.command(0, python, &["-c", SPARK_SENDER]);
    sender_cmd.arg(&office_file).arg(&zmq_endpoint);
    let mut sender = Proc::start(sender_cmd, "spark_dsg sender", Input::Lines)?;
    sender
        .wait_line_after(0, STEP, |l| l == "ready")
        .ok_or_else(|| format!("sender: {}", sender.describe()))?;
    let mut receiver_cmd = link.command(1, python, &["-c", SPARK_RECEIVER]);
    receiver_cmd.arg(&zmq_endpoint);
    let receiver = Proc::start(receiver_cmd, "spark_dsg receiver", Input::Null)?;
    receiver
        .wait_line_after(0, STEP, |l| l == "ready")
        .ok_or_else(|| format!("receiver: {}", receiver.describe()))?;
    // ZMQ's slow joiner: send until the receiver gets one.
    let until = Instant::now() + STEP;
    while receiver.count_lines(|l| l.starts_with("received")) == 0 {
        sender.send(&format!("send {spark_object} 0.0"))?;
        std::thread::sleep(Duration::from_millis(500));
        if Instant::now() > until {
            return Err(format!("spark_dsg receiver got nothing: {}", receiver.describe()).into());
        }
    }
    std::thread::sleep(Duration::from_millis(500));
    let spark_ticks = if args.quick {
        ticks.min(20)
    } else {
        ticks.min(100)
    };
    let (mut lat, mut total, mut message_bytes) = (Vec::new(), 0u64, 0u64);
    for k in 0..spark_ticks {
        let dx = if k % 2 == 0 { 0.03 } else { -0.03 };
        let seen_s = sender.stdout().len();
        let seen_r = receiver.stdout().len();
        let bytes0 = link.wire_bytes(sender.pid())?;
        sender.send(&format!("send {spark_object} {dx}"))?;
        let (_, sent) = sender
            .wait_line_after(seen_s, STEP, |l| l.starts_with("sent"))
            .ok_or("sender did not send")?;
        let (_, got) = receiver
            .wait_line_after(seen_r, STEP, |l| l.starts_with("received"))
            .ok_or("receiver got nothing")?;
        std::thread::sleep(TICK / 2);
        total += link.wire_bytes(sender.pid())? - bytes0;
        let field = |line: &str, k: &str| -> Result<u64, Box<dyn std::error::Error>> {
            Ok(ygg_testkit::field(line, k)
                .ok_or("missing field")?
                .parse()?)
        };
        message_bytes = field(&sent, "bytes")?;
        lat.push(field(&got, "t_ns")?.saturating_sub(field(&sent, "t_ns")?) as f64 / 1e9);
    }
    drop(receiver);
    drop(sender);
    rows.push(Row::new(
        "stream_bytes_spark_dsg_zmq",
        "zmq",
        &lat,
        total as f64 / spark_ticks as f64,
    ));

    let load_after = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let report = report(&rows, message_bytes, &load_before, &load_after, args);
    print!("{report}");
    if let Some(path) = &args.out {
        std::fs::write(path, &report)?;
    }
    let json: Vec<serde_json::Value> = rows.iter().map(Row::json).collect();
    let json = serde_json::to_string_pretty(&json)?;
    if let Some(path) = &args.json {
        std::fs::write(path, &json)?;
    } else {
        println!("{json}");
    }
    Ok(())
}

/// How many samples each relay case takes.
struct Cases {
    updates: usize,
    resyncs: usize,
    /// Ticks of the 30 Hz stream.
    ticks: usize,
    breakdown: bool,
}

/// How the relays are secured: certificates from this folder, or `--insecure`.
#[derive(Clone, Copy)]
enum Security<'a> {
    /// Mutual TLS with the certificates `ygg-relay certs` made in this folder.
    Tls(&'a Path),
    /// Plain TCP.
    Insecure,
}

impl Security<'_> {
    /// The relay options of host `me`, exchanging the scene with `peer`.
    fn args(self, me: &str, peer: &str) -> Vec<String> {
        match self {
            Self::Tls(dir) => {
                let file = |name: String| dir.join(name).display().to_string();
                vec![
                    "--ca".into(),
                    file("ca.pem".into()),
                    "--cert".into(),
                    file(format!("{me}.pem")),
                    "--private-key".into(),
                    file(format!("{me}.key")),
                    "--allow".into(),
                    peer.into(),
                ]
            }
            Self::Insecure => vec!["--insecure".into()],
        }
    }
}

/// `ygg-relay certs` for `robot` (host 0) and `base` (host 1) in `dir`.
fn make_certs(relay_bin: &Path, dir: &Path, link: &VethLink) -> Result<(), String> {
    let (robot, base) = (
        format!("robot={}", link.address(0)),
        format!("base={}", link.address(1)),
    );
    let dir_arg = dir.to_str().ok_or("non-UTF-8 temp dir")?;
    let out = Command::new(relay_bin)
        .args(["certs", "--dir", dir_arg, "--host", &robot, "--host", &base])
        .output()
        .map_err(|e| format!("ygg-relay certs: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ygg-relay certs: {}",
            String::from_utf8_lossy(&out.stderr)
        ))
    }
}

/// The relay cases over one kind of link: a writer of `graph` on the robot, the relay
/// pair, the remote reader; one-pose updates, object moves, resyncs, the 30 Hz stream.
fn relay_cases(
    link: &VethLink,
    relay_bin: &Path,
    kind: LinkKind,
    security: Security<'_>,
    graph: ygg_store::SceneGraph,
    cases: &Cases,
) -> Result<Vec<Row>, Box<dyn std::error::Error>> {
    let robot = TestScene::for_run("remote-robot");
    let remote = TestScene::for_run("remote-host");
    let key = format!("bench/{}", robot.name);

    let writer = SceneWriter::builder(&robot.name)
        .iceoryx_prefix(&robot.prefix)
        .create(graph)?;

    // Each kind its own port: the other run's connections may linger in TIME_WAIT.
    let endpoint = match security {
        Security::Tls(_) => format!("tls/{}:{PORT}", link.address(0)),
        Security::Insecure => link.endpoint(0, PORT + 1),
    };
    let mut export_args = vec![
        "export",
        "--scene",
        &robot.name,
        "--key",
        &key,
        "--listen",
        &endpoint,
    ];
    let robot_security = security.args("robot", "base");
    export_args.extend(robot_security.iter().map(String::as_str));
    let mut exporter_cmd = link.command(0, relay_bin, &export_args);
    robot.configure(&mut exporter_cmd);
    let exporter = Proc::start(exporter_cmd, "exporter", Input::Null)?;
    let mut import_args = vec![
        "import",
        "--key",
        &key,
        "--scene",
        &remote.name,
        "--connect",
        &endpoint,
    ];
    let base_security = security.args("base", "robot");
    import_args.extend(base_security.iter().map(String::as_str));
    let mut importer_cmd = link.command(1, relay_bin, &import_args);
    remote.configure(&mut importer_cmd);
    let importer = Proc::start(importer_cmd, "importer", Input::Null)?;
    let mut writer = writer;
    let t0 = Instant::now();
    let first = writer.publish()?.generation;
    let reader = SceneReader::builder(&remote.name)
        .iceoryx_prefix(&remote.prefix)
        .wait_for_writer(STEP)
        .open()?;
    let local = if cases.breakdown {
        Some(LocalWatch::start(&robot.name, &robot.prefix)?)
    } else {
        None
    };
    let mut relay = Relay {
        link,
        writer,
        reader,
        exporter,
        importer,
        local,
    };
    relay.wait_for(first, t0)?;
    eprintln!(
        "{}: office across in {:.0} ms",
        kind.name(),
        t0.elapsed().as_secs_f64() * 1e3
    );

    let mut rows = Vec::new();
    // One-pose updates: the stream's ticks that only append a pose.
    let mut replay = SlamReplay::new(relay.writer.graph(), 7);
    let (mut lat, mut bytes) = (Vec::new(), Vec::new());
    while lat.len() < cases.updates {
        let t0 = Instant::now();
        let report = replay.step(relay.writer.graph_mut())?;
        let (l, b) = relay.publish_and_wait(t0)?;
        if report.objects_moved == 0 && report.objects_added == 0 && report.mesh_points == 0 {
            lat.push(l);
            bytes.push(b as f64);
        }
        std::thread::sleep(TICK);
    }
    rows.push(Row::timed("pose_update", kind, &lat, median(&bytes)));
    eprintln!("{}: pose_update done", kind.name());

    // One-object moves.
    let g = relay.writer.graph();
    let object = layout::object_mesh_layers(g)
        .into_iter()
        .find_map(|(l, _)| g.layer_nodes(l).find_map(|m| g.parent(m)))
        .ok_or("no object with a mesh")?;
    let (mut lat, mut bytes) = (Vec::new(), Vec::new());
    for k in 0..cases.updates {
        let dx = if k % 2 == 0 { 0.03 } else { -0.03 };
        let t0 = Instant::now();
        move_object(relay.writer.graph_mut(), object, [dx, 0.0, 0.0])?;
        let (l, b) = relay.publish_and_wait(t0)?;
        lat.push(l);
        bytes.push(b as f64);
        std::thread::sleep(TICK);
    }
    rows.push(Row::timed("object_move", kind, &lat, median(&bytes)));
    eprintln!("{}: object_move done", kind.name());

    // Resync after the link comes back.
    let (mut lat, mut bytes) = (Vec::new(), Vec::new());
    for _ in 0..cases.resyncs {
        link.set_up(false)?;
        let until = Instant::now() + STEP;
        while relay.reader.writer_status() != WriterStatus::Gone {
            let _ = relay.reader.wait_next(Duration::from_millis(50));
            if Instant::now() > until {
                return Err("the remote reader never reported the writer gone".into());
            }
        }
        replay.step(relay.writer.graph_mut())?;
        let generation = relay.writer.publish()?.generation;
        let bytes0 = link.wire_bytes(relay.exporter.pid())?;
        let t0 = Instant::now();
        link.set_up(true)?;
        lat.push(relay.wait_for(generation, t0)?);
        std::thread::sleep(Duration::from_millis(200));
        bytes.push((link.wire_bytes(relay.exporter.pid())? - bytes0) as f64);
    }
    rows.push(Row::new(
        "resync_full_office",
        kind.name(),
        &lat,
        median(&bytes),
    ));
    eprintln!("{}: resync done", kind.name());

    // The demo's SLAM stream at 30 Hz.
    let ticks = cases.ticks;
    let (mut lat, mut total) = (Vec::new(), 0u64);
    for _ in 0..ticks {
        let t0 = Instant::now();
        replay.step(relay.writer.graph_mut())?;
        let (l, b) = relay.publish_and_wait(t0)?;
        lat.push(l);
        total += b;
        std::thread::sleep(TICK.saturating_sub(t0.elapsed()));
    }
    rows.push(Row::timed(
        "stream_bytes_ygg",
        kind,
        &lat,
        total as f64 / ticks as f64,
    ));
    eprintln!("{}: stream_bytes_ygg done", kind.name());
    relay.stop();
    for scene in [&robot, &remote] {
        if let Some(left) = scene.clean_up() {
            eprintln!("warning: left in /dev/shm: {left}");
        }
    }
    Ok(rows)
}

fn median(v: &[f64]) -> f64 {
    ygg_testkit::stats::median(v).unwrap_or(f64::NAN)
}

/// The markdown report: table, targets met or missed.
fn report(
    rows: &[Row],
    message_bytes: u64,
    load_before: &str,
    load_after: &str,
    args: &RemoteArgs,
) -> String {
    let find = |case: &str, link: &str| rows.iter().find(|r| r.case == case && r.link == link);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# ygg-bench remote{} (office scale {})\n\nload average before: {}; after: {}\n",
        if args.quick { " --quick" } else { "" },
        args.scale,
        load_before.trim(),
        load_after.trim()
    );
    let _ = writeln!(
        out,
        "| case | link | samples | median µs | p99 µs | bytes on the wire |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|");
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.0} | {:.0} | {:.0} |",
            r.case, r.link, r.samples, r.median_us, r.p99_us, r.bytes
        );
    }
    let _ = writeln!(
        out,
        "\nspark_dsg message (to_binary with mesh): {message_bytes} bytes\n"
    );
    if rows.iter().any(|r| r.hops.is_some()) {
        let _ = writeln!(
            out,
            "Per hop (`--breakdown`, medians µs from the update's start): the writer's update + \
             publish() call; visible in a reader on the robot (the first shared-memory hop); \
             from there to the remote reader (exporter, Zenoh over the veth, importer's \
             validation and republish, the remote shared-memory hop).\n"
        );
        let _ = writeln!(
            out,
            "| case | link | update + publish() | → robot's reader | → remote (relay path) | remote |"
        );
        let _ = writeln!(out, "|---|---|---|---|---|---|");
        for r in rows {
            if let Some(h) = r.hops {
                let _ = writeln!(
                    out,
                    "| {} | {} | {:.0} | {:.0} | {:.0} | {:.0} |",
                    r.case, r.link, h.publish_call_us, h.local_us, h.relay_us, r.median_us
                );
            }
        }
        let _ = writeln!(out);
    }
    if let (Some(tls), Some(tcp)) = (find("pose_update", "tls"), find("pose_update", "tcp")) {
        let ratio = tls.median_us / tcp.median_us;
        let _ = writeln!(
            out,
            "- one-pose update visible remotely over TLS ≤ 1.2× plain TCP and ≤ 2 ms p50: \
             {:.2} ms against {:.2} ms, {ratio:.2}× — {}",
            tls.median_us / 1e3,
            tcp.median_us / 1e3,
            if ratio <= 1.2 && tls.median_us <= 2000.0 {
                "met"
            } else {
                "missed"
            }
        );
    }
    if let (Some(y), Some(s)) = (
        find("stream_bytes_ygg", "tls"),
        find("stream_bytes_spark_dsg_zmq", "zmq"),
    ) {
        let ratio = y.bytes / s.bytes * 100.0;
        let _ = writeln!(
            out,
            "- SLAM stream bytes ≤ 2% of spark_dsg's ZMQ full-graph messages: {ratio:.3}% — {}",
            if ratio <= 2.0 { "met" } else { "missed" }
        );
    }
    if let Some(r) = find("resync_full_office", "tls") {
        let _ = writeln!(
            out,
            "- full-office resync over TLS ≤ 1 s after the link comes back: {:.0} ms median, {:.0} ms p99 — {}",
            r.median_us / 1e3,
            r.p99_us / 1e3,
            if r.median_us <= 1e6 { "met" } else { "missed" }
        );
    }
    out
}
