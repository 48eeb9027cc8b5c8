//! `ygg`: Yggdrasil's one command for users, in the idiom of cargo and git (`ygg <command>
//! [options]`, `ygg help <command>`). The libraries stay free of it: `ygg-writer` and
//! `ygg-reader` link only the store and the transport, and everything a command line needs
//! (clap, progress bars, Spark-DSG, ZeroMQ and its async runtime) lives here.
//!
//! | command | what it does | module |
//! |---|---|---|
//! | `ygg demo` | the main job: a writer serving the built-in office with a live update stream, and reader processes querying it (planner, visibility, labels), checked against brute force | [`demo`] |
//! | `ygg serve` | serve a scene (a `.ygg` file or the built-in office), optionally with a SLAM-like update stream | [`serve`] |
//! | `ygg import` | a Spark-DSG file (JSON or binary) to a `.ygg` snapshot in one of the paper's layouts | [`import`] |
//! | `ygg export` | a live scene's current snapshot to a `.ygg` file; `ygg export ros2`: a live scene to ROS 2 as Hydra's `DsgUpdate` | [`export`] |
//! | `ygg inspect` | a scene's layers, DAG, counts, indexes and memory; the layouts' static table of a Spark-DSG file | [`inspect`] |
//! | `ygg query` | JSON-line object queries on a `.ygg` file or a live scene | [`query`] |
//! | `ygg watch` | follow a live scene: a line per validated snapshot, writer exits and restarts | [`watch`] |
//! | `ygg bridge zmq` | follow a Spark-DSG ZeroMQ stream (Hydra) and publish what changes | [`bridge`] |
//! | `ygg view` | a scene in the browser: live, a file, or a timeline of files (runs the Python module `yggdrasil.view`) | [`view`] |
//! | `ygg bridge ros2` | follow Hydra's ROS 2 `DsgUpdate` topic (full and incremental updates) and publish what changes | [`bridge`] |
//!
//! `ygg demo-role` (hidden) is one of the demo's reader processes; the demo starts it, as
//! it starts `ygg serve`, from this same executable.
//!
//! Not here: the Zenoh relay stays its own binary, `ygg-relay` (crate `relay/`), so that
//! Zenoh's build (hundreds of crates) stays out of `ygg` and of every other crate;
//! `.ci/check-deps` keeps zenoh to `ygg-relay`. Test drivers (`ygg-test-writer`,
//! `ygg-test-reader`, `ygg-soak`) live in `ygg-testkit`, benchmarks in `ygg-bench`.

mod bridge;
mod changes;
mod demo;
mod error_chain;
mod export;
mod import;
mod inspect;
mod moment;
mod query;
mod record;
mod replay;
mod serve;
mod timeline;
mod view;
mod watch;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use error_chain::error_chain;

#[derive(Parser, Debug)]
#[command(
    name = "ygg",
    version,
    about = "Yggdrasil: a layered 3D scene graph in shared memory, for robots"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// The main job: a writer process serving the built-in office with a live update
    /// stream, and reader processes querying it (planner, visibility, labels).
    Demo(demo::DemoArgs),
    /// One of the demo's reader processes (planner, visibility, labels) on a live scene,
    /// printing JSON progress and a summary line.
    #[command(hide = true)]
    DemoRole(demo::roles::RoleArgs),
    /// Serve a scene (a `.ygg` file or the built-in office) under a scene name, and
    /// optionally replay a SLAM-like stream of updates at a given rate.
    ///
    /// Prints a `{"event":"ready",...}` line naming the writer session once the scene is
    /// published, one JSON line per second (`{"event":"progress",...}`) and a final
    /// `{"event":"summary",...}` line. Exits cleanly, removing its shared memory, on
    /// SIGINT/SIGTERM or after --seconds.
    Serve(serve::ServeArgs),
    /// Import a Spark-DSG file (JSON, .json.gz or binary) into a `.ygg` snapshot in one
    /// of the paper's layouts, with a progress bar.
    Import(import::ImportArgs),
    /// Write the current snapshot of a live scene to a `.ygg` file (`ygg export ros2`:
    /// publish a live scene to ROS 2 as hydra_msgs/msg/DsgUpdate).
    Export(export::ExportArgs),
    /// Show a scene's layers, DAG, counts, indexes and memory (a `.ygg` file or --scene),
    /// or the paper's static table of the layouts of a Spark-DSG JSON file.
    Inspect(inspect::InspectArgs),
    /// Answer JSON-line object queries on a `.ygg` file or a live scene (one line out per
    /// line in).
    Query(query::QueryArgs),
    /// Print every validated snapshot of a live scene as it arrives, and writer exits
    /// and restarts.
    Watch(watch::WatchArgs),
    /// Record a live scene: each cut it receives is appended to a recording (a folder),
    /// each changed segment once. Query it with `ygg query DIR --time T`, inspect its
    /// timeline with `ygg inspect DIR`, replay it with `ygg serve --recording DIR`.
    Record(record::RecordArgs),
    /// What changed in a recording between two moments: nodes added, removed, moved and
    /// relabelled, edges added and removed (one JSON object).
    Changes(changes::ChangesArgs),
    /// Bridge another system's scene-graph stream into a scene (`ygg bridge zmq`,
    /// `ygg bridge ros2`).
    #[command(subcommand)]
    Bridge(bridge::BridgeCommand),
    /// Show a scene in the browser (served locally, the address printed): a live scene
    /// (--scene NAME), a `.ygg` or Spark-DSG file, or several files as a timeline.
    /// Runs `python3 -m yggdrasil.view` (the Python package's `view` extra);
    /// `ygg view --help` lists its options.
    View(view::ViewArgs),
}

fn main() -> ExitCode {
    ygg_transport::init_iceoryx_logging();
    let cli = Cli::parse();
    // A process may attach to many scenes (about 40 descriptors each); do not stop at a soft limit of 1024.
    let _ = ygg_transport::limits::raise_open_file_limit();
    let result: Result<ExitCode, Box<dyn std::error::Error>> = match cli.command {
        Command::Demo(args) => demo::run(&args).map(|()| ExitCode::SUCCESS),
        Command::DemoRole(args) => demo::roles::run(&args).map(|()| ExitCode::SUCCESS),
        Command::Serve(args) => serve::run(&args).map(|()| ExitCode::SUCCESS),
        Command::Import(args) => import::run(&args)
            .map(|()| ExitCode::SUCCESS)
            .map_err(Into::into),
        Command::Export(args) => export::run(&args).map(|()| ExitCode::SUCCESS),
        Command::Inspect(args) => match args.path.as_deref() {
            Some(path) if moment::is_recording(path) => timeline::run(path, &args),
            _ => inspect::run(&args),
        }
        .map(|()| ExitCode::SUCCESS)
        .map_err(Into::into),
        Command::Query(args) => query::run(&args)
            .map(|()| ExitCode::SUCCESS)
            .map_err(Into::into),
        Command::Watch(args) => watch::run(&args),
        Command::Record(args) => record::run(&args)
            .map(|()| ExitCode::SUCCESS)
            .map_err(Into::into),
        Command::Changes(args) => changes::run(&args)
            .map(|()| ExitCode::SUCCESS)
            .map_err(Into::into),
        Command::Bridge(command) => bridge::run(&command).map(|()| ExitCode::SUCCESS),
        Command::View(args) => view::run(&args)
            .map(|()| ExitCode::SUCCESS)
            .map_err(Into::into),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("ygg: error: {}", error_chain(e.as_ref()));
            ExitCode::FAILURE
        }
    }
}
