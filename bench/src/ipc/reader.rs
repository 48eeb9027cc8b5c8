//! The reader process of the benchmark (`ygg-bench ipc reader`, started by the writer).
//!
//! Protocol: the reader prints `ready <generation>` once it holds its first validated
//! snapshot, then obeys lines on stdin; stdin closing means "exit cleanly".
//!
//! * `latency`: blocks in [`SceneReader::wait_next`]; for each new snapshot records the
//!   generation, the Unix time it held the validated view, (with `--query-layer`) the
//!   time a nearest-node query on it was answered, and the reader thread's CPU time from
//!   the `wait_next` call that returned it to the view (wake-up, receive, validation,
//!   view; not the query). `report` prints the records as `seen <gen> <visible>
//!   <answered> <cpu ns>` lines and `end`.
//! * `attach`: the attach-to-first-answer measurement: from the process's start, opens the
//!   reader, waits for the first snapshot and answers a nearest-node query on it, then
//!   prints `ready <gen> <start ns> <answered ns> <process CPU ns>` and idles until stdin
//!   closes (so the benchmark can count its descriptors).
//! * `bare`: the bare iceoryx2 subscriber of the physical floor ([`super::bare`]).
//! * `qps`: on `start`, loops `latest()` + nearest-node query on the newest snapshot until
//!   `stop`, then prints `qps <queries> <elapsed ns> <median ns> <p99 ns> <snapshots>`.
//! * `q1a`: for the ladder's `after_update_ipc` rows: blocks in [`SceneReader::wait_next`];
//!   on each new snapshot answers the Q1a given by `--layout`, `--room` and `--point`
//!   through the ladder's query code and prints the answer at once as an
//!   [`AnswerLine`] (`q1a <gen> <visible> <answered> <ids> <checksum>`, the checksum of
//!   the `--object`'s mesh taken after the answer).
//! * `socket`: the Hydra-style baseline: reads length-prefixed frames from a Unix socket,
//!   deserializes each into an owned [`PlainGraph`] and prints `sock <seq> <done ns>
//!   <nodes>`.

use super::clock::{thread_cpu_ns, unix_ns};
use super::commands::{Cmd, read_commands};
use super::error::Res;
use super::socket::PlainGraph;
use crate::ladder::answer_line::{AnswerLine, mesh_checksum};
use crate::ladder::harness::Target;
use crate::ladder::workload::Query;
use crate::ladder::ygg::YggTarget;
use std::io::{Read, Write};
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::time::{Duration, Instant};
use ygg_dsg::layout::Layout;
use ygg_reader::{ReceiveError, SceneReader, SceneReceiveError, SceneSnapshot};
use ygg_store::query::nearest_nodes;
use ygg_store::{ArchivedScene, NodeId, Point, SceneView, Scope};
use ygg_testkit::stats::nearest_rank;

/// Options of the hidden `ygg-bench ipc reader`.
#[derive(clap::Args, Debug)]
pub struct ReaderArgs {
    /// Scene name.
    #[arg(long)]
    scene: String,
    /// iceoryx2 file-name prefix.
    #[arg(long)]
    prefix: String,
    /// What to do.
    #[arg(long, value_enum)]
    mode: Mode,
    /// Layer (by name) of the nearest-node query; none: no query.
    #[arg(long)]
    query_layer: Option<String>,
    /// Unix socket to read frames from (socket mode).
    #[arg(long)]
    socket: Option<PathBuf>,
    /// Index among the case's readers (seeds the query points).
    #[arg(long, default_value_t = 0)]
    index: usize,
    /// Layout the scene was built with (q1a mode).
    #[arg(long)]
    layout: Option<Layout>,
    /// Room of the Q1a query (q1a mode).
    #[arg(long)]
    room: Option<u64>,
    /// Point of the Q1a query, `x,y,z` (q1a mode).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    point: Vec<f32>,
    /// The object the writer moves; its mesh checksum goes with each answer (q1a mode).
    #[arg(long)]
    object: Option<u64>,
}

/// Reader behaviours.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Record publish-to-visible times.
    Latency,
    /// Query in a loop.
    Qps,
    /// Answer the ladder's Q1a on every new snapshot.
    Q1a,
    /// Deserialize frames from a Unix socket.
    Socket,
    /// Time attaching to the first answer.
    Attach,
    /// The bare iceoryx2 subscriber.
    Bare,
}

/// Runs the reader process.
pub fn main(args: &ReaderArgs) -> Res<()> {
    let started = unix_ns();
    // Die with the benchmark: SIGTERM (handled, so the reader still cleans up) when the
    // parent goes away, even if it was SIGKILLed.
    ygg_testkit::die_with_parent().map_err(|e| format!("cannot die with the benchmark: {e}"))?;
    let _ = ygg_transport::limits::raise_open_file_limit();
    let commands = read_commands();
    match args.mode {
        Mode::Latency => latency(args, &commands),
        Mode::Qps => qps(args, &commands),
        Mode::Q1a => q1a(args, &commands),
        Mode::Socket => socket(args),
        Mode::Attach => attach_timed(args, started, &commands),
        Mode::Bare => super::bare::subscriber_main(&args.scene, &args.prefix, &commands),
    }
}

/// Attaches, answers one query, reports the times and idles until told to exit.
fn attach_timed(args: &ReaderArgs, started: u64, commands: &Receiver<Cmd>) -> Res<()> {
    let layer = args
        .query_layer
        .as_deref()
        .ok_or("attach mode needs --query-layer")?;
    let (_reader, first) = attach(args)?;
    std::hint::black_box(query(first.view(), layer, &mut Points(1))?);
    let answered = unix_ns();
    let cpu = rustix::time::clock_gettime(rustix::time::ClockId::ProcessCPUTime);
    let cpu_ns = u64::try_from(cpu.tv_sec).unwrap_or(0) * 1_000_000_000
        + u64::try_from(cpu.tv_nsec).unwrap_or(0);
    println!("ready {} {started} {answered} {cpu_ns}", first.generation());
    loop {
        match commands.recv() {
            Ok(Cmd::Exit) | Err(_) => return Ok(()),
            Ok(_) => {}
        }
    }
}

fn attach(args: &ReaderArgs) -> Res<(SceneReader, SceneSnapshot)> {
    let mut reader = SceneReader::builder(&args.scene)
        .iceoryx_prefix(&args.prefix)
        .handle_termination_signals(true)
        .open()?;
    let deadline = Instant::now() + Duration::from_secs(30);
    while Instant::now() < deadline {
        if let Some(snapshot) = reader.wait_next(Duration::from_millis(100))? {
            return Ok((reader, snapshot));
        }
    }
    Err(format!("no snapshot of scene {} within 30 s", args.scene).into())
}

/// A deterministic stream of query points around the office.
struct Points(u64);

impl Points {
    fn next(&mut self) -> Point {
        let mut c = || {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((self.0 >> 40) as f32) / ((1u64 << 24) as f32)
        };
        [c() * 50.0 - 5.0, c() * 40.0 - 5.0, c() * 3.0]
    }
}

/// Answers a nearest-node query on `layer` (by name); the answer's node id, or 0.
fn query(view: &ArchivedScene<'_>, layer: &str, points: &mut Points) -> Res<u64> {
    let l = view
        .layer_by_name(layer)
        .ok_or_else(|| format!("the snapshot has no layer {layer:?}"))?;
    let found = nearest_nodes(view, Scope::Layer(l), points.next(), 1)?;
    Ok(found.first().map_or(0, |(id, _)| id.0))
}

fn latency(args: &ReaderArgs, commands: &Receiver<Cmd>) -> Res<()> {
    let (mut reader, first) = attach(args)?;
    println!("ready {}", first.generation());
    drop(first);
    let mut points = Points(args.index as u64 + 1);
    // (generation, visible, answered, thread CPU ns of the wait that returned it)
    let mut records: Vec<[u64; 4]> = Vec::with_capacity(4096);
    loop {
        match commands.try_recv() {
            Ok(Cmd::Report) => {
                let mut out = std::io::stdout().lock();
                for [g, v, a, cpu] in records.drain(..) {
                    writeln!(out, "seen {g} {v} {a} {cpu}")?;
                }
                writeln!(out, "end")?;
                out.flush()?;
            }
            Ok(Cmd::Exit) | Err(TryRecvError::Disconnected) => return Ok(()),
            Ok(Cmd::Start | Cmd::Stop) | Err(TryRecvError::Empty) => {}
        }
        let cpu_before = thread_cpu_ns();
        match reader.wait_next(Duration::from_millis(20)) {
            Ok(Some(snapshot)) => {
                let view = snapshot.view();
                let visible = unix_ns();
                let cpu = thread_cpu_ns() - cpu_before;
                let generation = view.generation();
                let answered = match &args.query_layer {
                    Some(layer) => {
                        std::hint::black_box(query(view, layer, &mut points)?);
                        unix_ns()
                    }
                    None => visible,
                };
                records.push([generation, visible, answered, cpu]);
            }
            Ok(None) => {}
            Err(SceneReceiveError::Receive(ReceiveError::Terminated)) => return Ok(()),
            Err(e) => return Err(e.into()),
        }
    }
}

fn qps(args: &ReaderArgs, commands: &Receiver<Cmd>) -> Res<()> {
    let layer = args
        .query_layer
        .as_deref()
        .ok_or("qps mode needs --query-layer")?;
    let (mut reader, first) = attach(args)?;
    println!("ready {}", first.generation());
    drop(first);
    let mut points = Points(args.index as u64 + 1);
    let mut latencies: Vec<u32> = Vec::new();
    loop {
        match commands.recv_timeout(Duration::from_millis(100)) {
            Ok(Cmd::Start) => {}
            Ok(Cmd::Exit) | Err(RecvTimeoutError::Disconnected) => return Ok(()),
            Ok(Cmd::Report | Cmd::Stop) | Err(RecvTimeoutError::Timeout) => {
                if reader.termination_requested() {
                    return Ok(());
                }
                continue;
            }
        }
        latencies.clear();
        let mut snapshots = 0u64;
        let mut last = 0u64;
        let start = Instant::now();
        let mut exit = false;
        for i in 0u64.. {
            if i.is_multiple_of(64) {
                match commands.try_recv() {
                    Ok(Cmd::Stop) => break,
                    Ok(Cmd::Exit) | Err(TryRecvError::Disconnected) => {
                        exit = true;
                        break;
                    }
                    _ => {}
                }
                if i.is_multiple_of(4096) && reader.termination_requested() {
                    return Ok(());
                }
            }
            let t = Instant::now();
            let snapshot = reader.latest()?.ok_or("the reader lost its snapshot")?;
            if snapshot.generation() != last {
                last = snapshot.generation();
                snapshots += 1;
            }
            std::hint::black_box(query(snapshot.view(), layer, &mut points)?);
            latencies.push(u32::try_from(t.elapsed().as_nanos()).unwrap_or(u32::MAX));
        }
        let elapsed = start.elapsed().as_nanos();
        latencies.sort_unstable();
        let at = |q: f64| nearest_rank(&latencies, q).unwrap_or(0);
        println!(
            "qps {} {elapsed} {} {} {snapshots}",
            latencies.len(),
            at(0.5),
            at(0.99)
        );
        if exit {
            return Ok(());
        }
    }
}

fn q1a(args: &ReaderArgs, commands: &Receiver<Cmd>) -> Res<()> {
    let layout = args.layout.ok_or("q1a mode needs --layout")?;
    let room = args.room.ok_or("q1a mode needs --room")?;
    let object = NodeId(args.object.ok_or("q1a mode needs --object")?);
    let point: Point = args.point[..]
        .try_into()
        .map_err(|_| format!("--point needs x,y,z, got {:?}", args.point))?;
    let query = Query::Nearest { room, point };
    let (mut reader, first) = attach(args)?;
    println!("ready {}", first.generation());
    drop(first);
    loop {
        match commands.try_recv() {
            Ok(Cmd::Exit) | Err(TryRecvError::Disconnected) => return Ok(()),
            Ok(_) | Err(TryRecvError::Empty) => {}
        }
        match reader.wait_next(Duration::from_millis(20)) {
            Ok(Some(snapshot)) => {
                let view = snapshot.view();
                let visible_ns = unix_ns();
                let ids = YggTarget::new(String::new(), layout, &view).answer(&query);
                let answered_ns = unix_ns();
                let line = AnswerLine {
                    generation: view.generation(),
                    visible_ns,
                    answered_ns,
                    ids,
                    mesh_checksum: mesh_checksum(&view, object),
                };
                println!("{line}");
            }
            Ok(None) => {}
            Err(SceneReceiveError::Receive(ReceiveError::Terminated)) => return Ok(()),
            Err(e) => return Err(e.into()),
        }
    }
}

fn socket(args: &ReaderArgs) -> Res<()> {
    let path = args.socket.as_ref().ok_or("socket mode needs --socket")?;
    let mut stream = std::os::unix::net::UnixStream::connect(path)
        .map_err(|e| format!("cannot connect to {}: {e}", path.display()))?;
    println!("ready 0");
    let mut buf = Vec::new();
    loop {
        let mut header = [0u8; 16];
        match stream.read_exact(&mut header) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(format!("socket read: {e}").into()),
        }
        let len = u64::from_le_bytes(header[..8].try_into()?);
        let seq = u64::from_le_bytes(header[8..].try_into()?);
        let len = usize::try_from(len)?;
        buf.resize(len, 0);
        stream
            .read_exact(&mut buf)
            .map_err(|e| format!("socket read of frame {seq}: {e}"))?;
        let graph: PlainGraph = postcard::from_bytes(&buf)
            .map_err(|e| format!("frame {seq} does not deserialize: {e}"))?;
        let done = unix_ns();
        println!("sock {seq} {done} {}", graph.node_count());
        drop(graph);
    }
}
