//! `ygg-bench ros2`: Hydra's `DsgUpdate` over ROS 2 (DDS) through `ygg bridge ros2`,
//! against the same bytes over ZeroMQ through `ygg bridge zmq`, in one run.
//!
//! Senders: Cyclone DDS with spark_dsg 1.1.3 (`tests/python/ros2_peer.py`) and spark_dsg's
//! own `DsgSender` (`tests/python/dsg_sender.py`), both loading the office written by
//! `write_binary` and sending `to_binary(include_mesh=True)`, stamped with
//! CLOCK_MONOTONIC just before the send. The ROS 2 side runs in a network namespace (one
//! end of a veth pair: RustDDS discovers by multicast, never on loopback), the ZeroMQ
//! side on loopback; readers (`ygg-bench hydra-reader`) attach to each bridge's scene.
//! Cases, each `--messages` times, medians reported:
//! * **full office**: the whole office translated by a centimetre, sent in full on both
//!   transports (every layer resent): send → visible in the last reader;
//! * **one-object incremental** (ROS 2 only): one object moved, sent as an incremental
//!   `DsgUpdate` (the object's node alone): send → visible in every reader, and the
//!   bridge's CPU per message against its CPU per full message.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use clap::Parser;
use ygg_dsg::office::{OfficeParams, generate};
use ygg_testkit::{Input, Proc, TestScene, VethLink};

use crate::hydra::{Consumer, STEP, Sender, cpu_seconds, med, ms};

/// Arguments of `ygg-bench ros2`.
#[derive(Parser, Debug)]
pub struct Ros2Args {
    /// Full-office messages per transport (medians are reported).
    #[arg(long, default_value_t = 5)]
    pub messages: usize,
    /// One-object incremental updates (medians are reported).
    #[arg(long, default_value_t = 20)]
    pub edits: usize,
    /// Reader processes per bridge.
    #[arg(long, default_value_t = 4)]
    pub readers: usize,
    /// Office scale (1.0: the full office).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Layout the bridges build.
    #[arg(long, default_value = "mint")]
    pub layout: ygg_dsg::layout::Layout,
    /// The Python interpreter with spark_dsg, pyzmq and cyclonedds installed.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Cyclone DDS's `Internal/Watermarks/WhcHigh` for the sender (bytes in flight
    /// before the writer waits for acknowledgements), e.g. `500kB`; default: Cyclone's.
    /// RustDDS leaves the socket's receive buffer at the system default (net.core.rmem_default,
    /// 208 KiB here), so a sender that bursts a 31 MB message loses fragments and repairs
    /// them heartbeat by heartbeat.
    #[arg(long)]
    pub cyclone_whc_high: Option<String>,
    /// More of Cyclone DDS's `General` settings for the sender, as XML (e.g.
    /// `<FragmentSize>8000B</FragmentSize>`); default: Cyclone's.
    #[arg(long)]
    pub cyclone_general: Option<String>,
    /// Send the graph without its mesh (as hydra_ros does unless `serialize_dsg_mesh`).
    #[arg(long)]
    pub no_mesh: bool,
    /// Also write the markdown report to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The Cyclone DDS peer in the namespace.
struct Peer {
    proc: Proc,
}

impl Peer {
    fn command(&mut self, line: &str) -> Result<String, Box<dyn std::error::Error>> {
        let skip = self.proc.stdout().len();
        self.proc.send(line)?;
        let (_, answer) = self
            .proc
            .wait_line_after(skip, STEP, |l| {
                l.starts_with("ok") || l.starts_with("error")
            })
            .ok_or_else(|| format!("peer did not answer {line:?}: {}", self.proc.describe()))?;
        if !answer.starts_with("ok") {
            return Err(format!("peer: {line:?}: {answer}").into());
        }
        Ok(answer)
    }

    /// Sends (`send` or `delta`); returns the send's CLOCK_MONOTONIC ns.
    fn send(&mut self, line: &str) -> Result<u64, Box<dyn std::error::Error>> {
        let answer = self.command(line)?;
        answer
            .split_whitespace()
            .find_map(|w| w.strip_prefix("t_ns="))
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| format!("no t_ns in {answer:?}").into())
    }
}

/// A bridge and its readers.
struct Side {
    bridge: Proc,
    readers: Vec<Consumer>,
    _scene: TestScene,
}

impl Side {
    /// Starts `command` (a bridge), waits for `ready` while `kick` sends, then the readers.
    fn start(
        scene: TestScene,
        command: Command,
        readers: usize,
        mut kick: impl FnMut() -> Result<(), Box<dyn std::error::Error>>,
    ) -> Result<Self, Box<dyn std::error::Error>> {
        let bridge = Proc::start(command, "bridge", Input::Null)?;
        let until = std::time::Instant::now() + STEP;
        while bridge.count_lines(|l| l.contains("\"ready\"")) == 0 {
            if std::time::Instant::now() > until {
                return Err(format!("bridge never ready: {}", bridge.describe()).into());
            }
            kick()?;
            bridge.wait_line_after(0, Duration::from_secs(2), |l| l.contains("\"ready\""));
        }
        let me = std::env::current_exe()?;
        let mut out = Vec::new();
        for i in 0..readers {
            let proc = Proc::start(
                scene.command_for(&me, &["hydra-reader", "--scene", &scene.name]),
                format!("reader {i}"),
                Input::Null,
            )?;
            let c = Consumer { proc };
            c.line_after(0)?;
            out.push(c);
        }
        Ok(Self {
            bridge,
            readers: out,
            _scene: scene,
        })
    }

    /// Sends with `send` (returning the send's ns) and measures: send → visible in the
    /// last reader (s), and the bridge's CPU seconds for the message.
    fn measure(
        &self,
        send: impl FnOnce() -> Result<u64, Box<dyn std::error::Error>>,
    ) -> Result<(f64, f64), Box<dyn std::error::Error>> {
        let seen: Vec<usize> = self.readers.iter().map(Consumer::lines).collect();
        let before = self.bridge.stdout().len();
        let cpu0 = cpu_seconds(self.bridge.pid());
        let t_send = send()?;
        let mut last = 0f64;
        for (c, &s) in self.readers.iter().zip(&seen) {
            let v = c.line_after(s)?;
            let t = v["t_ns"].as_u64().ok_or("no t_ns")?;
            last = last.max(t.saturating_sub(t_send) as f64 / 1e9);
        }
        // The bridge prints its update line after publishing: its work is done.
        self.bridge
            .wait_line_after(before, STEP, |l| l.contains("\"update\""))
            .ok_or("no update line")?;
        Ok((last, cpu_seconds(self.bridge.pid()) - cpu0))
    }
}

/// Runs `ygg-bench ros2`.
///
/// # Errors
/// A namespace that cannot be made (root and `ip` needed), a process that does not start
/// or answer, or a file that cannot be written.
pub fn run(args: &Ros2Args) -> Result<(), Box<dyn std::error::Error>> {
    let load_before = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let link = VethLink::create("yb")?;
    let dir = tempfile::tempdir()?;
    let config = dir.path().join("cyclonedds.xml");
    let internal = args.cyclone_whc_high.as_ref().map_or(String::new(), |w| {
        format!("<Internal><Watermarks><WhcHigh>{w}</WhcHigh></Watermarks></Internal>")
    });
    std::fs::write(
        &config,
        link.cyclone_unicast_config(
            0,
            &[link.address(0)],
            args.cyclone_general.as_deref().unwrap_or_default(),
            &internal,
        ),
    )?;
    let office = generate(OfficeParams {
        seed: 7,
        scale: args.scale,
    });
    let path = dir.path().join("office.sparkdsg");
    ygg_dsg::write_binary(&office, &path)?;
    let object = office
        .nodes
        .iter()
        .find(|n| n.kind == ygg_dsg::NodeKind::Object)
        .ok_or("the office has no object")?
        .id;
    let nodes = office.nodes.len();
    drop(office);
    let ygg = ygg_testkit::binary("ygg");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/python/ros2_peer.py");
    let path_str = path.to_str().ok_or("non-UTF-8 path")?;
    let script_str = script.to_str().ok_or("non-UTF-8 path")?;

    // ROS 2: Cyclone DDS -> ygg bridge ros2, in the namespace.
    let mut peer_cmd = link.command(
        0,
        args.python.as_ref(),
        &[
            script_str,
            "send",
            "7",
            "/hydra/backend/dsg",
            path_str,
            "--mesh",
        ],
    );
    peer_cmd.env("CYCLONEDDS_URI", format!("file://{}", config.display()));
    let peer_proc = Proc::start(peer_cmd, "peer", Input::Lines)?;
    peer_proc
        .wait_line_after(0, STEP, |l| l.starts_with("ready"))
        .ok_or_else(|| format!("peer: {}", peer_proc.describe()))?;
    let mut peer = Peer { proc: peer_proc };
    let ros_scene = TestScene::for_run("ros2");
    let mut bridge_cmd = link.command(
        0,
        &ygg,
        &[
            "bridge",
            "ros2",
            "--domain-id",
            "7",
            "--scene",
            &ros_scene.name,
            "--layout",
            args.layout.name(),
        ],
    );
    ros_scene.configure(&mut bridge_cmd);
    let mut sent_first = false;
    let ros = Side::start(ros_scene, bridge_cmd, args.readers, || {
        if !sent_first {
            peer.command("matched 1")?;
            peer.send("send")?;
            sent_first = true;
        }
        Ok(())
    })?;

    // ZeroMQ: spark_dsg's DsgSender -> ygg bridge zmq, on loopback.
    let mut zmq_sender = Sender::start(&args.python, &path, !args.no_mesh)?;
    let endpoint = format!("tcp://127.0.0.1:{}", zmq_sender.port);
    let zmq_scene = TestScene::for_run("zmq");
    let zmq_cmd = zmq_scene.command_for(
        &ygg,
        &[
            "bridge",
            "zmq",
            "--connect",
            &endpoint,
            "--scene",
            &zmq_scene.name,
            "--layout",
            args.layout.name(),
        ],
    );
    let zmq = Side::start(zmq_scene, zmq_cmd, args.readers, || {
        zmq_sender.send(false).map(drop)
    })?;

    // Full office, both transports, alternating.
    let (mut full_ros, mut full_zmq, mut cpu_full_ros) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..args.messages {
        let dx = if k % 2 == 0 { 0.01 } else { -0.01 };
        peer.command(&format!("shift {dx} 0 0"))?;
        zmq_sender.command(&format!("shift {dx} 0 0"))?;
        let (t, cpu) = ros.measure(|| peer.send("send"))?;
        full_ros.push(t);
        cpu_full_ros.push(cpu);
        let (t, _) = zmq.measure(|| zmq_sender.send(false))?;
        full_zmq.push(t);
        eprintln!(
            "full {k}: ros2 {} ms, zmq {} ms",
            ms(*full_ros.last().unwrap()),
            ms(*full_zmq.last().unwrap())
        );
    }
    // One-object incremental updates (ROS 2).
    let (mut edit, mut cpu_edit) = (Vec::new(), Vec::new());
    for k in 0..args.edits {
        let dx = if k % 2 == 0 { 0.05 } else { -0.05 };
        peer.command(&format!("move {object} {dx} 0.03 0"))?;
        let (t, cpu) = ros.measure(|| peer.send("delta"))?;
        edit.push(t);
        cpu_edit.push(cpu);
    }
    let paths: Vec<String> = ros
        .bridge
        .stdout()
        .iter()
        .filter(|l| l.contains("\"full_update\":false"))
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter_map(|v| v["path"].as_str().map(str::to_owned))
        .collect();
    let patched = paths.iter().filter(|p| *p == "patch").count();

    let (r, z) = (med(&full_ros), med(&full_zmq));
    let (ce, cf) = (med(&cpu_edit), med(&cpu_full_ros));
    let mut md = String::new();
    writeln!(md, "# ROS 2 bridge (`ygg-bench ros2`)\n")?;
    writeln!(
        md,
        "The office (seed 7, scale {}, {nodes} nodes, {}), layout {}, {} reader \
         processes per bridge; medians of {} full messages and {} incremental ones; Cyclone \
         DDS WhcHigh: {}, General: {}. Machine: {} cores; load average before: {}.\n",
        args.scale,
        if args.no_mesh {
            "sent without its mesh"
        } else {
            "sent with its mesh"
        },
        args.layout.name(),
        args.readers,
        args.messages,
        args.edits,
        args.cyclone_whc_high
            .as_deref()
            .unwrap_or("Cyclone's default"),
        args.cyclone_general
            .as_deref()
            .unwrap_or("Cyclone's defaults"),
        std::thread::available_parallelism().map_or(0, usize::from),
        load_before.trim()
    )?;
    writeln!(md, "| measure | value | target |\n|---|---|---|")?;
    writeln!(
        md,
        "| full office: send → visible in the last reader, ROS 2 (Cyclone DDS → RustDDS) | {} ms | |",
        ms(r)
    )?;
    writeln!(
        md,
        "| full office: send → visible in the last reader, ZeroMQ (same bytes) | {} ms | |",
        ms(z)
    )?;
    writeln!(md, "| ratio ROS 2 / ZeroMQ | {:.2} | ≤ 1.2 |", r / z)?;
    writeln!(
        md,
        "| one-object incremental: send → visible in all {} readers | {} ms (max {} ms) | ≤ 20 ms |",
        args.readers,
        ms(med(&edit)),
        ms(edit.iter().copied().fold(0.0, f64::max))
    )?;
    writeln!(
        md,
        "| bridge CPU per incremental / per full message | {} ms / {} ms = {:.3} | ≤ 0.1 |",
        ms(ce),
        ms(cf),
        ce / cf
    )?;
    writeln!(
        md,
        "| incremental updates patched (no layout build) | {patched} of {} | |",
        paths.len()
    )?;
    print!("{md}");
    if let Some(out) = &args.out {
        std::fs::write(out, &md)?;
    }
    peer.proc.send("quit").ok();
    Ok(())
}
