//! `ygg-bench ladder`: the paper's ablation ladder (dsg, vanilla, chocolate, mint,
//! saffron) on the office workload, with answers checked identical before timing.

pub mod after_ipc;
pub mod answer_line;
pub mod flat_dsg;
pub mod harness;
pub mod kiddo_floor;
pub mod reader_cpu;
pub mod report;
pub mod update;
pub mod workload;
pub mod writer_ticks;
pub mod ygg;

use harness::{Row, Target, compare_answers, time_targets};
use report::{Report, StaticRow};
use std::path::{Path, PathBuf};
use std::time::Instant;
use update::{move_object, object_rooms};
use workload::{Answer, Workload};
use ygg_dsg::DsgGraph;
use ygg_dsg::layout::{self, Layout};
use ygg_store::{NodeId, SceneGraph, SceneView};
use ygg_testkit::stats::median_p99_us;

/// Options of `ygg-bench ladder`.
#[derive(clap::Args, Debug)]
pub struct LadderArgs {
    /// A Spark-DSG JSON file (.json or .json.gz) instead of the built-in office.
    #[arg(long)]
    pub dsg: Option<PathBuf>,
    /// Scale of the built-in office (1 = the uHumans2 office).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Reference points per room.
    #[arg(long, default_value_t = 64)]
    pub per_room: usize,
    /// Repetitions of every query.
    #[arg(long, default_value_t = 5)]
    pub reps: usize,
    /// Fewer repetitions and reference points: under a minute.
    #[arg(long)]
    pub quick: bool,
    /// Write the report as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the markdown table and SVG plot into this folder.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Skip the Spark-DSG Python anchor.
    #[arg(long)]
    pub no_spark_dsg: bool,
    /// Only measure the writer's cost per tick of the demo's stream in process, over
    /// this many ticks (see `writer_ticks`), and print it.
    #[arg(long)]
    pub writer_ticks: Option<usize>,
    /// Only measure a reader's CPU time per single-layer update, over this many
    /// updates (see `reader_cpu`), and print it.
    #[arg(long)]
    pub reader_cpu: Option<usize>,
    /// With `--reader-cpu`: the office split into this many rooms (103 is the ipc
    /// bench's many-layer office) instead of its 9.
    #[arg(long, requires = "reader_cpu")]
    pub rooms: Option<usize>,
}

/// Runs the ladder and writes its report.
pub fn run(args: &LadderArgs) -> Result<(), Box<dyn std::error::Error>> {
    if let Some(ticks) = args.writer_ticks {
        return writer_ticks::run(args.scale, ticks);
    }
    if let Some(updates) = args.reader_cpu {
        return reader_cpu::run(args.scale, args.rooms, updates);
    }
    let (per_room, reps) = if args.quick {
        (args.per_room.min(16), 1)
    } else {
        (args.per_room, args.reps.max(1))
    };
    let t = Instant::now();
    let (dsg, input) = match &args.dsg {
        Some(path) => (ygg_dsg::read_file(path)?, path.display().to_string()),
        None => {
            let p = ygg_dsg::office::OfficeParams {
                seed: 7,
                scale: args.scale,
            };
            (
                ygg_dsg::office::generate(p),
                format!("built-in office (seed 7, scale {})", args.scale),
            )
        }
    };
    eprintln!(
        "input: {input} ({} nodes) in {:.1?}",
        dsg.nodes.len(),
        t.elapsed()
    );
    let workload = Workload::generate(&dsg, 42, per_room);
    eprintln!(
        "workload: {} queries, {reps} repetition(s) each",
        workload.queries.len()
    );

    let flat = flat_dsg::FlatDsg::new(&dsg);
    let mut graphs: Vec<(Layout, SceneGraph)> = Vec::new();
    for l in Layout::ALL {
        let t = Instant::now();
        graphs.push((l, layout::build(&dsg, l)?));
        eprintln!("built {l} in {:.1?}", t.elapsed());
    }
    let room_of: rustc_hash::FxHashMap<u64, u64> = object_rooms(&dsg);
    let floor = kiddo_floor::KiddoFloor::new(&dsg, &room_of);

    let mut statics = vec![StaticRow {
        target: "dsg".into(),
        nodes: flat.node_count(),
        memory_mb: flat.memory_bytes() as f64 / 1e6,
        update_us: f64::NAN,
    }];
    for (l, g) in &mut graphs {
        let bytes = g.to_segments().len();
        statics.push(StaticRow {
            target: l.name().into(),
            nodes: g.node_count(),
            memory_mb: bytes as f64 / 1e6,
            update_us: update_latency(g, if args.quick { 200 } else { 2000 }),
        });
    }

    let snapshot = graphs
        .iter()
        .find(|(l, _)| *l == Layout::Mint)
        .map(|(_, g)| g.to_snapshot())
        .expect("mint built");
    let snapshot_view = snapshot.view();
    let targets: Vec<Box<dyn Target + '_>> = {
        let mut v: Vec<Box<dyn Target + '_>> = vec![Box::new(FlatTarget(&flat))];
        for (l, g) in &graphs {
            v.push(Box::new(ygg::YggTarget::new(l.name().into(), *l, g)));
        }
        v.push(Box::new(ygg::YggTarget::new(
            "mint-archived".into(),
            Layout::Mint,
            &snapshot_view,
        )));
        v
    };
    let refs: Vec<&dyn Target> = targets.iter().map(|t| t.as_ref()).collect();
    let answers = compare_answers(&refs, &workload)
        .map_err(|e| format!("answers differ, refusing to time: {e}"))?;
    eprintln!("answers identical on {} targets", refs.len());

    // The floor takes its turns with the targets; it answers Q1a and Q1b only.
    let t0 = Instant::now();
    let timed: Vec<&dyn Target> = refs
        .iter()
        .copied()
        .chain([&floor as &dyn Target])
        .collect();
    let (mut rows, mut anchors): (Vec<Row>, Vec<Row>) = time_targets(&timed, &workload, reps)
        .into_iter()
        .partition(|r| r.target != floor.name());
    anchors.retain(|r| r.query.starts_with("Q1"));
    eprintln!("timed {} targets in {:.1?}", timed.len(), t0.elapsed());
    let mut notes = Vec::new();
    drop(timed);
    drop(refs);
    drop(targets);
    rows.extend(after_update_local(
        &mut graphs,
        &workload,
        &dsg,
        if args.quick { 20 } else { 200 },
    ));
    let (ipc_rows, ipc_notes) = after_ipc::after_update_ipc(&graphs, &workload, &dsg, args.quick)?;
    rows.extend(ipc_rows);
    notes.extend(ipc_notes);

    if !args.no_spark_dsg {
        match spark_dsg_anchor(&dsg, args, &workload, &answers) {
            Ok((a, n)) => {
                anchors.extend(a);
                notes.extend(n);
            }
            Err(e) => notes.push(format!("Spark-DSG anchor unavailable: {e}")),
        }
    }
    let report = Report {
        machine: report::machine(),
        input,
        rows,
        statics,
        anchors,
        answers_identical: true,
        notes,
    };
    if let Some(path) = &args.json {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        std::fs::write(path, serde_json::to_string_pretty(&report.to_json())?)?;
        eprintln!("wrote {}", path.display());
    }
    let md = report.to_markdown();
    if let Some(dir) = &args.out_dir {
        std::fs::create_dir_all(dir)?;
        std::fs::write(dir.join("ladder.md"), &md)?;
        report.plot_svg(&dir.join("ladder.svg"))?;
        eprintln!("wrote {}/ladder.md and ladder.svg", dir.display());
    }
    println!("{md}");
    Ok(())
}

/// The flat baseline as a ladder target.
struct FlatTarget<'a>(&'a flat_dsg::FlatDsg);

impl Target for FlatTarget<'_> {
    fn name(&self) -> String {
        "dsg".into()
    }
    fn answer(&self, q: &workload::Query) -> Answer {
        self.0.answer(q)
    }
}

/// Median latency of moving one mesh point of an object (the mapping stack's most
/// frequent edit), with whatever boxes and indexes the layout keeps live. Each sample
/// moves a point and the next puts it back, so the graph ends as it started.
fn update_latency(g: &mut SceneGraph, n: usize) -> f64 {
    let mesh_nodes: Vec<NodeId> = layout::object_mesh_layers(&*g)
        .into_iter()
        .flat_map(|(l, _)| g.layer_nodes(l).map(|m| g.node_id(m)).collect::<Vec<_>>())
        .collect();
    if mesh_nodes.is_empty() {
        return f64::NAN;
    }
    let mut samples = Vec::with_capacity(n);
    for i in 0..n.div_ceil(2) {
        let id = mesh_nodes[(i * 7919) % mesh_nodes.len()];
        let original = g.node(id).map(|m| g.points(m).to_vec()).unwrap_or_default();
        let mut moved = original.clone();
        if let Some(p) = moved.get_mut(i % original.len().max(1)) {
            p[0] += 0.01;
        }
        for points in [moved, original] {
            let t = Instant::now();
            g.set_geometry(id, points)
                .expect("moving a point of an existing node");
            samples.push(t.elapsed().as_nanos() as f64);
        }
    }
    median_p99_us(&samples).0
}

/// Query after an update, in process: translate an object's mesh, then answer a Q1a in
/// its room; time from the mutation to the answer.
fn after_update_local(
    graphs: &mut [(Layout, SceneGraph)],
    w: &Workload,
    dsg: &DsgGraph,
    n: usize,
) -> Vec<Row> {
    let rooms = object_rooms(dsg);
    let Some(room) = rooms.get(&w.update_object).copied() else {
        return Vec::new();
    };
    let Some(q) = w
        .queries
        .iter()
        .find(|q| matches!(q, workload::Query::Nearest { room: r, .. } if *r == room))
        .cloned()
    else {
        return Vec::new();
    };
    let mut rows = Vec::new();
    for (l, g) in graphs.iter_mut() {
        let mesh: Vec<(NodeId, Vec<[f32; 3]>)> =
            ygg_store::query::children(&*g, NodeId(w.update_object))
                .into_iter()
                .map(|m| {
                    (
                        m,
                        g.node(m).map(|x| g.points(x).to_vec()).unwrap_or_default(),
                    )
                })
                .collect();
        let scopes = ygg::Scopes::new(&*g);
        let mut samples = Vec::with_capacity(n);
        for i in 0..n {
            let t = Instant::now();
            move_object(g, &mesh, w, i).expect("moving an existing mesh node");
            let target = ygg::YggTarget::with_scopes(String::new(), *l, &*g, &scopes);
            std::hint::black_box(target.answer(&q));
            samples.push(t.elapsed().as_nanos() as f64);
        }
        let (median_us, p99_us) = median_p99_us(&samples);
        rows.push(Row {
            target: l.name().into(),
            query: "after_update_local".into(),
            median_us,
            p99_us,
        });
    }
    rows
}

/// Runs the Spark-DSG Python anchor on the same input and workload.
fn spark_dsg_anchor(
    dsg: &DsgGraph,
    args: &LadderArgs,
    w: &Workload,
    answers: &[Answer],
) -> Result<(Vec<Row>, Vec<String>), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let script = root.join("bench/spark_dsg/run.sh");
    let dir = std::env::temp_dir().join(format!("ygg-ladder-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let input = match &args.dsg {
        Some(p) => p.clone(),
        None => {
            let p = dir.join("office.json");
            ygg_dsg::write_json(dsg, &p)?;
            p
        }
    };
    let wpath = dir.join("workload.json");
    std::fs::write(&wpath, serde_json::to_string(&w.to_json())?)?;
    let out = dir.join("rows.json");
    let mut cmd = std::process::Command::new("bash");
    cmd.arg(&script)
        .arg("--dsg")
        .arg(&input)
        .arg("--workload")
        .arg(&wpath)
        .arg("--out")
        .arg(&out)
        .current_dir(&root);
    if args.quick {
        cmd.arg("--quick");
    }
    eprintln!("running the Spark-DSG anchor (first run installs spark-dsg into a venv)...");
    let status = cmd.status()?;
    if !status.success() {
        return Err(format!("{} exited with {status}", script.display()).into());
    }
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out)?)?;
    let mut rows = Vec::new();
    for a in v["anchors"].as_array().into_iter().flatten() {
        rows.push(Row {
            target: a["name"].as_str().unwrap_or("spark-dsg").to_owned(),
            query: a["query"].as_str().unwrap_or("").to_owned(),
            median_us: a["median_us"].as_f64().unwrap_or(f64::NAN),
            p99_us: a["p99_us"].as_f64().unwrap_or(f64::NAN),
        });
    }
    let mut notes = Vec::new();
    let mut differ = 0;
    if let Some(map) = v["answers"].as_object() {
        for (id, ids) in map {
            let Ok(i) = id.parse::<usize>() else { continue };
            let theirs: Vec<u64> = ids
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|x| x.as_u64())
                .collect();
            if answers.get(i).is_some_and(|ours| *ours != theirs) {
                differ += 1;
            }
        }
        notes.push(format!(
            "Spark-DSG answers compared on {} queries: {differ} differ",
            map.len()
        ));
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok((rows, notes))
}
