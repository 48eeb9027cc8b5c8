//! `ygg import`: a Spark-DSG file (JSON or binary `.sparkdsg`, plain or gzip) to a
//! `.ygg` snapshot in one of the paper's layouts, with a progress bar.
//!
//! Phases: read (file bytes), decompress (gzip only; decompressed bytes), parse (a
//! spinner: the JSON parser reports no position; the binary decoder is fast enough not
//! to need one), validate (nodes and edges), build
//! (the layout), save (archive and write). The snapshot is written to a temporary file
//! next to the output and renamed into place, so a failed import never leaves a partial
//! `.ygg` behind. Errors name the file (and, from the importer, the node and field).
//!
//! Import is strict: a fault such as an edge to an absent node is an error that says
//! so and names `--lenient`. With `--lenient` the importer drops what it cannot import
//! and prints one `lenient import: dropped N <class> (first: ...)` line per class
//! ([`ygg_dsg::ImportReport`]), or `lenient import: nothing dropped`.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::Parser;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::{ImportOptions, ImportPhase, ImportProgress};
use ygg_store::{SceneGraph, SceneView};

/// Arguments of `ygg import`.
#[derive(Parser, Debug)]
pub struct ImportArgs {
    /// Spark-DSG file: JSON (`.json`, or gzip-compressed `.json.gz`) or binary
    /// (`.sparkdsg`); the format is detected from the content.
    pub input: PathBuf,
    /// The paper's layout to build: vanilla, chocolate, mint or saffron.
    #[arg(long, default_value = "mint")]
    pub layout: Layout,
    /// The `.ygg` snapshot to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// No progress bar (it is also hidden when stderr is not a terminal).
    #[arg(long, short)]
    pub quiet: bool,
    /// Import what can be imported: drop edges to absent nodes, duplicate and self
    /// edges, nodes of undeclared layers or unknown attribute types (JSON; binary files
    /// cannot skip an attribute layout spark_dsg does not register), repeated node ids
    /// and claims of absent mesh vertices, and print each class dropped with its count
    /// and first example. Without it, the first such fault is an error.
    #[arg(long)]
    pub lenient: bool,
}

/// Per-phase durations of one import.
#[derive(Default)]
struct Timings {
    read: Duration,
    parse: Duration,
    build: Duration,
    save: Duration,
}

/// Runs `ygg import`: prints a one-line summary on success.
///
/// # Errors
/// A message naming the file (and node and field for malformed content).
pub fn run(args: &ImportArgs) -> Result<(), String> {
    let start = Instant::now();
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr())
    };
    let mut timings = Timings::default();
    let mut phase_start = Instant::now();
    let mut phase = None;
    let options = ImportOptions {
        lenient: args.lenient,
    };
    let imported = ygg_dsg::import_file(&args.input, options, &mut |p: ImportProgress| {
        if phase != Some(p.phase) {
            let now = Instant::now();
            if phase == Some(ImportPhase::Decompress) || phase == Some(ImportPhase::Read) {
                timings.read += now - phase_start;
            } else if phase.is_some() {
                timings.parse += now - phase_start;
            }
            phase_start = now;
            phase = Some(p.phase);
            // The new phase's units first, so that no frame mixes two phases.
            bar.set_length(p.total.unwrap_or(0));
            bar.set_position(p.done);
            enter_phase(&bar, p);
        }
        if let Some(total) = p.total {
            bar.set_length(total);
        }
        bar.set_position(p.done);
    })
    .map_err(|e| {
        bar.finish_and_clear();
        e.to_string()
    })?;
    timings.parse += phase_start.elapsed();
    let ygg_dsg::Imported { graph: dsg, report } = imported;

    let t = Instant::now();
    spinner(&bar, format!("building the {} layout", args.layout));
    let graph = layout::build(&dsg, args.layout).map_err(|e| {
        bar.finish_and_clear();
        e.to_string()
    })?;
    timings.build = t.elapsed();
    let counts = dsg.counts();
    drop(dsg);

    let t = Instant::now();
    spinner(&bar, format!("saving {}", args.output.display()));
    let bytes = save(&graph, &args.output).inspect_err(|_| bar.finish_and_clear())?;
    timings.save = t.elapsed();
    bar.finish_and_clear();

    let summary = GraphSummary::of(&graph);
    println!(
        "imported {} ({} nodes, {} edges, {} mesh vertices) as {} -> {}: {} layers, {} nodes, {} points, {} edges, {} bytes in {:.2} s (read {:.2} s, parse {:.2} s, build {:.2} s, save {:.2} s)",
        args.input.display(),
        counts.nodes,
        counts.edges,
        counts.mesh_vertices,
        args.layout,
        args.output.display(),
        summary.layers,
        summary.nodes,
        summary.points,
        summary.edges,
        bytes,
        start.elapsed().as_secs_f64(),
        timings.read.as_secs_f64(),
        timings.parse.as_secs_f64(),
        timings.build.as_secs_f64(),
        timings.save.as_secs_f64(),
    );
    if args.lenient {
        for line in report.to_string().lines() {
            println!("lenient import: {line}");
        }
    }
    Ok(())
}

/// Switches the bar to a new importer phase.
fn enter_phase(bar: &ProgressBar, p: ImportProgress) {
    let bytes = |msg: &str| {
        let style = ProgressStyle::with_template(
            "{msg:>12} [{bar:40}] {bytes}/{total_bytes} ({bytes_per_sec}, {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        bar.disable_steady_tick();
        bar.set_style(style);
        bar.set_message(msg.to_owned());
    };
    match p.phase {
        ImportPhase::Read => bytes("reading"),
        ImportPhase::Decompress => bytes("decompressing"),
        ImportPhase::Parse => spinner(bar, "parsing".to_owned()),
        ImportPhase::Validate => {
            let style =
                ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} nodes and edges")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> ");
            bar.disable_steady_tick();
            bar.set_style(style);
            bar.set_message("validating");
        }
        ImportPhase::Done => {}
    }
}

/// Shows a spinner with `msg` (for phases without a position).
fn spinner(bar: &ProgressBar, msg: String) {
    let style = ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
        .unwrap_or_else(|_| ProgressStyle::default_spinner());
    bar.set_style(style);
    bar.set_message(msg);
    bar.enable_steady_tick(Duration::from_millis(100));
}

/// Writes the snapshot to `out` ([`SceneGraph::save`]: crash-safe, the old file stays
/// intact on failure). Returns the file size.
fn save(graph: &SceneGraph, out: &Path) -> Result<u64, String> {
    graph
        .save(out)
        .map_err(|e| format!("cannot write the snapshot: {e}"))?;
    std::fs::metadata(out)
        .map(|m| m.len())
        .map_err(|e| format!("{}: {e}", out.display()))
}

/// Counts of a built graph for the summary line.
struct GraphSummary {
    layers: usize,
    nodes: usize,
    points: usize,
    edges: usize,
}

impl GraphSummary {
    fn of<V: SceneView>(view: &V) -> Self {
        let mut s = GraphSummary {
            layers: 0,
            nodes: 0,
            points: 0,
            edges: 0,
        };
        for l in view.layers() {
            s.layers += 1;
            for n in view.layer_nodes(l) {
                s.nodes += 1;
                s.points += view.points(n).len();
                s.edges += view.out_edges(n).count();
            }
        }
        s
    }
}
