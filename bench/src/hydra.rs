//! `ygg-bench hydra`: Spark-DSG's ZMQ stream consumed through `ygg bridge zmq` and
//! Yggdrasil readers, against the same number of spark_dsg `DsgReceiver`s, in one run.
//!
//! A Python process publishes with spark_dsg's own `DsgSender` socket
//! (`tests/python/dsg_sender.py`; it loads the office written by `write_binary` and
//! sends `to_binary(include_mesh=True)`, stamping CLOCK_MONOTONIC just before the
//! socket's send). Two cases, each sent `--messages` times:
//! * **full office**: the office after a graph of one room (every consumer gets all of
//!   it anew);
//! * **full office, every node moved**: the whole office translated by a centimetre
//!   (every layer resent, none created);
//! * **one-object edit**: one object moved by a few centimetres.
//!
//! For 1 and 4 consumers, two phases on the same sender (one after the other, so the two
//! sides do not share the 2 cores): the bridge with N reader processes (`ygg-bench
//! hydra-reader`: a new validated snapshot is visible), then N Python processes each
//! with a `DsgReceiver`'s socket doing exactly what `DsgReceiver.recv` does
//! (`update_from_binary` of every message). Measured per message: send → visible in the
//! first and in the last consumer; CPU seconds of all consumers together (from each
//! thread's `/proc/PID/task/TID/schedstat`; on our side the bridge counts as a
//! consumer); spark_dsg's `update_from_binary` time. Also the binary file import against spark_dsg's `load`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use clap::Parser;
use serde_json::Value;
use ygg_dsg::office::{OfficeParams, generate};
use ygg_reader::SceneReader;
use ygg_testkit::stats::median;
use ygg_testkit::{Input, Proc, TestScene};

/// Arguments of `ygg-bench hydra`.
#[derive(Parser, Debug)]
pub struct HydraArgs {
    /// Full-office messages per consumer count (medians are reported).
    #[arg(long, default_value_t = 5)]
    pub messages: usize,
    /// One-object edits per consumer count (medians are reported).
    #[arg(long, default_value_t = 20)]
    pub edits: usize,
    /// Office scale (1.0: the full office).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Consumer counts to measure.
    #[arg(long, value_delimiter = ',', default_value = "1,4")]
    pub consumers: Vec<usize>,
    /// Layout the bridge builds.
    #[arg(long, default_value = "mint")]
    pub layout: ygg_dsg::layout::Layout,
    /// The Python interpreter with spark_dsg and pyzmq installed.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Timed binary file imports per tool.
    #[arg(long, default_value_t = 5)]
    pub import_runs: usize,
    /// Also write the markdown report to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Arguments of `ygg-bench hydra-reader` (a consumer process of the benchmark).
#[derive(Parser, Debug)]
pub struct HydraReaderArgs {
    /// Scene name.
    #[arg(long)]
    pub scene: String,
}

/// A DsgReceiver's work, timed: what `spark_dsg.zmq.DsgReceiver.recv` does per message.
const SPARK_RECEIVER: &str = r#"
import sys, time, json
import zmq
from spark_dsg.zmq import DsgReceiver
from spark_dsg import DynamicSceneGraph
r = DsgReceiver(sys.argv[1])
print("ready", flush=True)
while True:
    if not r._socket.poll(100):
        continue
    buf = r._socket.recv()
    t0 = time.monotonic_ns()
    if r._graph is None:
        r._graph = DynamicSceneGraph.from_binary(buf)
    else:
        r._graph.update_from_binary(buf)
    t1 = time.monotonic_ns()
    print(json.dumps({"t_ns": t1, "update_s": (t1 - t0) / 1e9, "nodes": r._graph.num_nodes()}), flush=True)
"#;

pub(crate) const STEP: Duration = Duration::from_secs(120);

const NEW: &str = "full office with mesh, all layers new (after a one-room graph)";
const MOVED: &str = "full office with mesh, every node moved 1 cm (layers kept)";
const EDIT: &str = "one-object edit";

pub(crate) fn now_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::Monotonic);
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

/// CPU seconds of process `pid` so far: the time its threads spent on a CPU, in
/// nanoseconds from each thread's `/proc/PID/task/TID/schedstat` (`/proc/PID/stat`
/// counts 10 ms ticks, too coarse for a one-object edit). Every consumer here keeps its
/// threads for its whole life, so no exited thread's time is missed.
pub(crate) fn cpu_seconds(pid: u32) -> f64 {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return 0.0;
    };
    let on_cpu_ns = |task: std::fs::DirEntry| {
        let stat = std::fs::read_to_string(task.path().join("schedstat")).ok()?;
        stat.split_whitespace().next()?.parse::<u64>().ok()
    };
    let ns: u64 = tasks.flatten().filter_map(on_cpu_ns).sum();
    ns as f64 / 1e9
}

/// `ygg-bench hydra-reader`: prints `{"t_ns":..,"generation":..,"nodes":..}` each time a
/// new validated snapshot is visible, until SIGTERM.
pub fn run_reader(args: &HydraReaderArgs) -> Result<(), Box<dyn std::error::Error>> {
    let mut reader = SceneReader::builder(&args.scene)
        .handle_termination_signals(true)
        .wait_for_writer(STEP)
        .open()?;
    println!("ready");
    while !reader.termination_requested() {
        // A long wait: SIGTERM ends it at once, and every wake-up costs CPU counted here.
        if let Some(s) = reader.wait_next(Duration::from_secs(1))? {
            let nodes = ygg_store::SceneView::node_count(&s.view());
            println!(
                "{}",
                serde_json::json!({"t_ns": now_ns(), "generation": s.generation(), "nodes": nodes})
            );
        }
    }
    Ok(())
}

/// The Python sender.
pub(crate) struct Sender {
    proc: Proc,
    pub(crate) port: u16,
}

impl Sender {
    pub(crate) fn start(
        python: &str,
        graph: &Path,
        mesh: bool,
    ) -> Result<Self, Box<dyn std::error::Error>> {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/python/dsg_sender.py");
        let mut command = Command::new(python);
        command.arg(script).arg(graph);
        if mesh {
            command.arg("--mesh");
        }
        let proc = Proc::start(command, "sender", Input::Lines)?;
        let (_, line) = proc
            .wait_line_after(0, STEP, |l| l.starts_with("port="))
            .ok_or_else(|| format!("sender did not start: {}", proc.describe()))?;
        let port = line
            .split_whitespace()
            .next()
            .and_then(|w| w.strip_prefix("port="))
            .and_then(|p| p.parse().ok())
            .ok_or("no port")?;
        Ok(Sender { proc, port })
    }

    /// Sends a command; returns the answer (`ok ...`).
    pub(crate) fn command(&mut self, line: &str) -> Result<String, Box<dyn std::error::Error>> {
        let skip = self.proc.stdout().len();
        self.proc.send(line)?;
        let (_, answer) = self
            .proc
            .wait_line_after(skip, STEP, |l| {
                l.starts_with("ok") || l.starts_with("error")
            })
            .ok_or_else(|| format!("sender did not answer {line:?}"))?;
        if !answer.starts_with("ok") {
            return Err(format!("sender: {line:?}: {answer}").into());
        }
        Ok(answer)
    }

    /// Sends the graph (or a one-room graph); returns the send's CLOCK_MONOTONIC ns.
    pub(crate) fn send(&mut self, minimal: bool) -> Result<u64, Box<dyn std::error::Error>> {
        let answer = self.command(if minimal { "send-minimal" } else { "send" })?;
        answer
            .split_whitespace()
            .find_map(|w| w.strip_prefix("t_ns="))
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| format!("no t_ns in {answer:?}").into())
    }
}

/// A consumer process printing one JSON line (with `t_ns`) per graph made visible.
pub(crate) struct Consumer {
    pub(crate) proc: Proc,
}

impl Consumer {
    /// Waits for the next line after `skip` lines; returns it.
    pub(crate) fn line_after(&self, skip: usize) -> Result<Value, Box<dyn std::error::Error>> {
        let (_, line) = self
            .proc
            .wait_line_after(skip, STEP, |l| l.starts_with('{'))
            .ok_or_else(|| format!("{}: no graph: {}", self.proc.label(), self.proc.describe()))?;
        Ok(serde_json::from_str(&line)?)
    }

    /// Stdout lines so far (of any kind), for [`Consumer::line_after`].
    pub(crate) fn lines(&self) -> usize {
        self.proc.stdout().len()
    }

    /// Whether it printed a graph line yet.
    fn has_graph(&self) -> bool {
        self.proc.stdout().iter().any(|l| l.starts_with('{'))
    }
}

/// One measured case for one side and consumer count.
#[derive(Default, Clone)]
struct Measured {
    /// Send → visible in the first consumer, seconds, per message.
    first: Vec<f64>,
    /// Send → visible in the last consumer, seconds, per message.
    last: Vec<f64>,
    /// CPU seconds of all consumers per message.
    cpu: Vec<f64>,
    /// spark_dsg's `update_from_binary` seconds (one per receiver and message).
    update: Vec<f64>,
    /// CPU seconds of all consumers over the whole batch, per message (a mean; for the
    /// full office it includes the one-room graphs between).
    cpu_mean: f64,
    /// [`Measured::cpu_mean`] split by process, in the order of the pids measured.
    cpu_mean_per_process: Vec<f64>,
}

/// What changes between two measured messages.
#[derive(Clone, Copy, PartialEq)]
enum Case {
    /// The office after a one-room graph: every layer new (created, then retired again).
    New,
    /// The whole office translated by a centimetre: every node and vertex moved, every
    /// layer resent, the layers themselves kept.
    Moved,
    /// One object moved by a few centimetres.
    Edit,
}

/// Sends `messages` messages of a case and measures every consumer.
fn measure(
    sender: &mut Sender,
    consumers: &[Consumer],
    cpu_pids: &[u32],
    messages: usize,
    case: Case,
    object: u64,
) -> Result<Measured, Box<dyn std::error::Error>> {
    let mut m = Measured::default();
    let batch0: Vec<f64> = cpu_pids.iter().map(|&p| cpu_seconds(p)).collect();
    for k in 0..messages {
        let dx = if k % 2 == 0 { 0.05 } else { -0.05 };
        if case == Case::New {
            // A one-room graph first (not measured), so the office is all new.
            let seen: Vec<usize> = consumers.iter().map(Consumer::lines).collect();
            sender.send(true)?;
            for (c, &s) in consumers.iter().zip(&seen) {
                c.line_after(s)?;
            }
        } else if case == Case::Moved {
            sender.command(&format!("shift {} 0 0", dx / 5.0))?;
        } else {
            sender.command(&format!("move {object} {dx} 0.03 0"))?;
        }
        std::thread::sleep(Duration::from_millis(300));
        let seen: Vec<usize> = consumers.iter().map(Consumer::lines).collect();
        let cpu0: f64 = cpu_pids.iter().map(|&p| cpu_seconds(p)).sum();
        let t_send = sender.send(false)?;
        let mut visible = Vec::new();
        for (c, &s) in consumers.iter().zip(&seen) {
            let v = c.line_after(s)?;
            let t = v["t_ns"].as_u64().ok_or("no t_ns")?;
            visible.push(t.saturating_sub(t_send) as f64 / 1e9);
            if let Some(u) = v["update_s"].as_f64() {
                m.update.push(u);
            }
        }
        // Let every process finish its work on the message (the bridge publishes before
        // readers see it; receivers print after their update).
        std::thread::sleep(Duration::from_millis(200));
        let cpu1: f64 = cpu_pids.iter().map(|&p| cpu_seconds(p)).sum();
        visible.sort_by(f64::total_cmp);
        m.first.push(visible[0]);
        m.last.push(*visible.last().expect("consumers"));
        m.cpu.push(cpu1 - cpu0);
    }
    let per_message =
        |(&p, before): (&u32, &f64)| (cpu_seconds(p) - before) / messages.max(1) as f64;
    m.cpu_mean_per_process = cpu_pids.iter().zip(&batch0).map(per_message).collect();
    m.cpu_mean = m.cpu_mean_per_process.iter().sum();
    Ok(m)
}

/// Medians (seconds) of the bridge's decode, sync and publish times in its `update`
/// lines, and how many updates took each path (`patch 20`, `build 5`, ...).
type Phases = ([f64; 3], String);

/// The bridge's [`Phases`] in its output `lines`; `full`: only the updates that added
/// the office (not the one-room graphs).
fn phases(lines: &[String], full: bool) -> Phases {
    let updates: Vec<Value> = lines
        .iter()
        .filter(|l| l.contains("\"update\""))
        .filter_map(|l| serde_json::from_str(l).ok())
        .filter(|v: &Value| !full || v["nodes_added"].as_u64().unwrap_or(0) > 100)
        .collect();
    let field = |k: &str| {
        let v: Vec<f64> = updates
            .iter()
            .filter_map(|u| u[k].as_f64())
            .map(|us| us / 1e6)
            .collect();
        med(&v)
    };
    let mut paths = std::collections::BTreeMap::new();
    for u in &updates {
        *paths.entry(u["path"].as_str().unwrap_or("?")).or_insert(0) += 1;
    }
    let paths = paths
        .iter()
        .map(|(p, n)| format!("{p} {n}"))
        .collect::<Vec<_>>()
        .join(", ");
    (
        [field("decode_us"), field("sync_us"), field("publish_us")],
        paths,
    )
}

pub(crate) fn med(v: &[f64]) -> f64 {
    median(v).unwrap_or(f64::NAN)
}

pub(crate) fn ms(v: f64) -> String {
    format!("{:.1}", v * 1e3)
}

/// Runs `ygg-bench hydra`.
///
/// # Errors
/// A process that does not start or answer, or a file that cannot be written.
pub fn run(args: &HydraArgs) -> Result<(), Box<dyn std::error::Error>> {
    let load_before = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let dir = tempfile::tempdir()?;
    let office = generate(OfficeParams {
        seed: 7,
        scale: args.scale,
    });
    let path = dir.path().join("office.sparkdsg");
    ygg_dsg::write_binary(&office, &path)?;
    let bytes = std::fs::metadata(&path)?.len();
    eprintln!("office: {} nodes, {bytes} bytes", office.nodes.len());
    let object = office
        .nodes
        .iter()
        .find(|n| n.kind == ygg_dsg::NodeKind::Object)
        .ok_or("the office has no object")?
        .id;
    drop(office);

    let mut sender = Sender::start(&args.python, &path, true)?;
    let endpoint = format!("tcp://127.0.0.1:{}", sender.port);
    let ygg_bin = ygg_testkit::binary("ygg");
    let me = std::env::current_exe()?;
    let mut results: Vec<(usize, &str, [Measured; 2])> = Vec::new();
    let mut bridge_phases: Vec<(usize, &str, Phases)> = Vec::new();
    for &n in &args.consumers {
        // Our side: the bridge and n readers.
        let scene = TestScene::for_run("hydra");
        let mut bridge = Proc::start(
            scene.command_for(
                &ygg_bin,
                &[
                    "bridge",
                    "zmq",
                    "--connect",
                    &endpoint,
                    "--scene",
                    &scene.name,
                    "--layout",
                    args.layout.name(),
                ],
            ),
            "bridge",
            Input::Null,
        )?;
        bridge
            .wait_line_after(0, STEP, |l| l.contains("\"connected\""))
            .ok_or_else(|| format!("bridge: {}", bridge.describe()))?;
        let until = Instant::now() + STEP;
        while bridge.count_lines(|l| l.contains("\"ready\"")) == 0 {
            if Instant::now() > until {
                return Err(format!("bridge never ready: {}", bridge.describe()).into());
            }
            sender.send(false)?;
            std::thread::sleep(Duration::from_millis(500));
        }
        let mut readers = Vec::new();
        for i in 0..n {
            let proc = Proc::start(
                scene.command_for(&me, &["hydra-reader", "--scene", &scene.name]),
                format!("reader {i}"),
                Input::Null,
            )?;
            let c = Consumer { proc };
            c.line_after(0)?; // the current snapshot
            readers.push(c);
        }
        let mut pids: Vec<u32> = readers.iter().map(|c| c.proc.pid()).collect();
        pids.push(bridge.pid());
        eprintln!("{n} consumers: Yggdrasil");
        let at = bridge.stdout().len();
        let ours_new = measure(
            &mut sender,
            &readers,
            &pids,
            args.messages,
            Case::New,
            object,
        )?;
        let mid = bridge.stdout().len();
        let ours_moved = measure(
            &mut sender,
            &readers,
            &pids,
            args.messages,
            Case::Moved,
            object,
        )?;
        let mid2 = bridge.stdout().len();
        let ours_edit = measure(&mut sender, &readers, &pids, args.edits, Case::Edit, object)?;
        let lines = bridge.stdout();
        bridge_phases.push((n, NEW, phases(&lines[at..mid], true)));
        bridge_phases.push((n, MOVED, phases(&lines[mid..mid2], false)));
        bridge_phases.push((n, EDIT, phases(&lines[mid2..], false)));
        for r in &readers {
            r.proc.signal(rustix::process::Signal::TERM);
        }
        for r in &mut readers {
            r.proc.wait_exit(STEP);
        }
        drop(readers);
        bridge.signal(rustix::process::Signal::TERM);
        bridge.wait_exit(STEP);
        if let Some(left) = scene.clean_up() {
            eprintln!("left behind: {left}");
        }

        // spark_dsg's side: n receivers.
        eprintln!("{n} consumers: spark_dsg");
        let mut receivers = Vec::new();
        for i in 0..n {
            let mut command = Command::new(&args.python);
            command.arg("-c").arg(SPARK_RECEIVER).arg(&endpoint);
            let proc = Proc::start(command, format!("receiver {i}"), Input::Null)?;
            proc.wait_line_after(0, STEP, |l| l == "ready")
                .ok_or_else(|| format!("receiver: {}", proc.describe()))?;
            receivers.push(Consumer { proc });
        }
        // Resend until every receiver has a graph (PUB drops before subscriptions land).
        let until = Instant::now() + STEP;
        while receivers.iter().any(|r| !r.has_graph()) {
            if Instant::now() > until {
                return Err("receivers never got a graph".into());
            }
            sender.send(false)?;
            std::thread::sleep(Duration::from_millis(1500));
        }
        let pids: Vec<u32> = receivers.iter().map(|c| c.proc.pid()).collect();
        let spark_new = measure(
            &mut sender,
            &receivers,
            &pids,
            args.messages,
            Case::New,
            object,
        )?;
        let spark_moved = measure(
            &mut sender,
            &receivers,
            &pids,
            args.messages,
            Case::Moved,
            object,
        )?;
        let spark_edit = measure(
            &mut sender,
            &receivers,
            &pids,
            args.edits,
            Case::Edit,
            object,
        )?;
        drop(receivers);
        results.push((n, NEW, [ours_new, spark_new]));
        results.push((n, MOVED, [ours_moved, spark_moved]));
        results.push((n, EDIT, [ours_edit, spark_edit]));
    }
    sender.proc.send("quit").ok();
    sender.proc.close_stdin();

    eprintln!("binary file import");
    let (ours_import, _) = crate::dsg_io::time_ours(&path, args.import_runs)?;
    let (spark_import, version) =
        crate::dsg_io::time_spark_dsg(&args.python, &path, args.import_runs)?;
    let load_after = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();

    let mut md = String::new();
    writeln!(
        md,
        "# Hydra's stream: `ygg bridge zmq` + Yggdrasil readers against spark_dsg DsgReceivers\n"
    )?;
    writeln!(
        md,
        "`ygg-bench hydra` (release build), one run. Sender: spark_dsg {version}'s `DsgSender` socket \
         (Python) publishing the office (scale {}, seed 7, with mesh: {bytes} B as a `.sparkdsg`) \
         as `to_binary(include_mesh=True)`; bridge layout {}. Medians of {} full-office \
         messages (each of the two full cases) and {} one-object edits per consumer count. \
         Send → visible: from just before the sender's socket send to a new validated \
         snapshot in a reader (ours) or the end of `update_from_binary` (spark_dsg); first \
         and last of the N consumers. CPU: user + system seconds per message of all \
         consumers together (ours: the bridge + N readers; spark_dsg: N receivers), the time \
         on a CPU of each of their threads (`/proc/PID/task/TID/schedstat`). The two sides run one after the other on the same \
         sender, never at once.\n",
        args.scale, args.layout, args.messages, args.edits
    )?;
    let machine = crate::ladder::report::machine();
    writeln!(
        md,
        "Machine: {}, {} cores; load average {} before and {} after.\n",
        machine["cpu"].as_str().unwrap_or("?"),
        machine["cores"],
        load_before
            .split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" "),
        load_after
            .split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" "),
    )?;
    writeln!(
        md,
        "| case | consumers | ours: send → first visible ms | ours: → last visible ms | spark_dsg: → first ms | spark_dsg: → last ms | spark_dsg `update_from_binary` ms | ours CPU ms / msg (median; mean) | spark_dsg CPU ms / msg (median; mean) | CPU ratio (means) |"
    )?;
    writeln!(md, "|---|---|---|---|---|---|---|---|---|---|")?;
    for (n, case, [ours, spark]) in &results {
        let ratio = spark.cpu_mean / ours.cpu_mean;
        writeln!(
            md,
            "| {case} | {n} | {} | {} | {} | {} | {} | {}; {} | {}; {} | {} |",
            ms(med(&ours.first)),
            ms(med(&ours.last)),
            ms(med(&spark.first)),
            ms(med(&spark.last)),
            ms(med(&spark.update)),
            ms(med(&ours.cpu)),
            ms(ours.cpu_mean),
            ms(med(&spark.cpu)),
            ms(spark.cpu_mean),
            if ratio.is_finite() {
                format!("{ratio:.1}x")
            } else {
                "ours: no tick in the batch".to_owned()
            },
        )?;
    }
    writeln!(
        md,
        "\nBinary file import of the same office (`.sparkdsg`, {bytes} B), median of {}: \
         ygg-dsg `read_file` {} ms, spark_dsg `DynamicSceneGraph.load` {} ms ({:.1}x).\n",
        args.import_runs,
        ms(med(&ours_import)),
        ms(med(&spark_import)),
        med(&spark_import) / med(&ours_import)
    )?;
    writeln!(
        md,
        "The bridge's own phases per message (medians from its `update` lines, ms): \
         decode (+ layout build on the build path) / sync_to or patch / publish, and the \
         paths the updates took (`patch`: node moves applied without building the layout; \
         `build`: the layout built and synced to):\n"
    )?;
    for (n, case, ([d, s, p], paths)) in &bridge_phases {
        writeln!(
            md,
            "- {case}, {n} readers: {} / {} / {} ({paths})",
            ms(*d),
            ms(*s),
            ms(*p)
        )?;
    }
    writeln!(
        md,
        "\nOur CPU per message by process (means over each batch, ms): the bridge; each reader.\n"
    )?;
    for (n, case, [ours, _]) in &results {
        // The bridge is measured last (see `run`).
        if let Some((bridge, readers)) = ours.cpu_mean_per_process.split_last() {
            let readers: Vec<String> = readers.iter().map(|&c| ms(c)).collect();
            writeln!(
                md,
                "- {case}, {n}: bridge {}; readers {}",
                ms(*bridge),
                readers.join(", ")
            )?;
        }
    }
    writeln!(md)?;
    writeln!(md, "Per-message samples (ms; CPU in ms):\n")?;
    for (n, case, [ours, spark]) in &results {
        let list = |v: &[f64], scale: f64| {
            v.iter()
                .map(|x| format!("{:.1}", x * scale))
                .collect::<Vec<_>>()
                .join(", ")
        };
        writeln!(
            md,
            "- {case}, {n}: ours last visible [{}], CPU [{}]; spark_dsg last [{}], CPU [{}]",
            list(&ours.last, 1e3),
            list(&ours.cpu, 1e3),
            list(&spark.last, 1e3),
            list(&spark.cpu, 1e3)
        )?;
    }
    print!("{md}");
    if let Some(out) = &args.out {
        std::fs::write(out, &md)?;
    }
    Ok(())
}
