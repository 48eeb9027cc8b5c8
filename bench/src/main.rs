//! `ygg-bench`: Yggdrasil's benchmarks (the demo is `ygg demo`, the soak `ygg-soak`).

mod capi;
mod dsg_io;
mod hydra;
mod ipc;
mod ladder;
mod mission;
mod record;
mod remote;
mod ros2;

use clap::{Parser, Subcommand};
use ygg_store::{NodeId, SceneGraph};

#[derive(Parser)]
#[command(version, about = "Yggdrasil benchmarks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Archive size and bytes per node for feature-less graphs of 10k, 100k and 1M nodes.
    ArchiveSizes,
    /// The paper's ablation ladder on the office workload.
    Ladder(ladder::LadderArgs),
    /// Multi-process publish-to-visible latency: shared memory vs a Unix socket.
    Ipc(ipc::IpcArgs),
    /// A whole mission: the demo's SLAM stream for N ticks with reader processes;
    /// publish, bytes, latency, reader CPU, attach and memory per window of ticks,
    /// optionally against another build (bench/results/mission.md).
    Mission(mission::MissionArgs),
    /// Recording a live scene: a recorder's cost to the writer (paired), the recording's
    /// size, opening any cut, Q1a on a past cut, `changes`, replay timing
    /// (bench/results/record.md).
    Record(record::RecordArgs),
    /// Importing the full office (JSON and binary) against spark_dsg's own load.
    DsgIo(dsg_io::DsgIoArgs),
    /// Hydra's ZMQ stream through `ygg bridge zmq` and Yggdrasil readers, against
    /// the same number of spark_dsg DsgReceivers (latency, CPU), and the binary import.
    Hydra(hydra::HydraArgs),
    /// Hydra's DsgUpdate over ROS 2 (Cyclone DDS) through `ygg bridge ros2`, against the
    /// same bytes over ZeroMQ; one-object incremental updates (needs root: a network
    /// namespace).
    Ros2(ros2::Ros2Args),
    /// A consumer process of `hydra`: prints a JSON line per new snapshot of a scene.
    #[command(hide = true)]
    HydraReader(hydra::HydraReaderArgs),
    /// FFI overhead of the C API: the SLAM-style stream published from C++ (through the
    /// C API) and from Rust, side by side (bench/results/capi.md).
    Capi(capi::CapiArgs),
    /// Readers on another host: writer -> ygg-relay over a veth pair between two network
    /// namespaces -> remote reader, against spark_dsg's ZMQ full-graph stream (needs root).
    Remote(remote::RemoteArgs),
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    match Cli::parse().command {
        Command::ArchiveSizes => archive_sizes(),
        Command::Ladder(args) => ladder::run(&args),
        Command::Ipc(args) => ipc::run(&args),
        Command::Mission(args) => mission::run(&args),
        Command::Record(args) => record::run(&args),
        Command::DsgIo(args) => dsg_io::run(&args),
        Command::Capi(args) => capi::run(&args),
        Command::Hydra(args) => hydra::run(&args),
        Command::HydraReader(args) => hydra::run_reader(&args),
        Command::Ros2(args) => ros2::run(&args),
        Command::Remote(args) => remote::run(&args),
    }
}

/// Prints a markdown table: archive bytes per feature-less node (one point each, nested
/// under one of 9 rooms), and the same nodes without geometry.
fn archive_sizes() -> Result<(), Box<dyn std::error::Error>> {
    println!(
        "| nodes | points per node | archive bytes | bytes per node | bytes per node minus 12 per point |"
    );
    println!("|---|---|---|---|---|");
    for n in [10_000u64, 100_000, 1_000_000] {
        for points in [0usize, 1] {
            let mut g = SceneGraph::new();
            let layer = g.add_layer("points")?;
            for i in 0..n {
                g.add_node(NodeId(i), layer)?;
                if points > 0 {
                    g.set_geometry(NodeId(i), vec![[i as f32, 0.0, 1.0]])?;
                }
            }
            let bytes = g.to_segments().len();
            let per_node = bytes as f64 / n as f64;
            println!(
                "| {n} | {points} | {bytes} | {per_node:.1} | {:.1} |",
                per_node - 12.0 * points as f64
            );
        }
    }
    Ok(())
}
