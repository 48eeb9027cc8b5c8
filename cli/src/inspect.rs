//! `ygg inspect`: what a scene holds and what it costs.
//!
//! * `inspect scene.ygg` and `inspect --scene NAME` (a live scene): every layer (id,
//!   name, nodes, points, edges, nested nodes, generation, segment bytes, indexes), the
//!   layer DAG, totals, the objects of the query contract, the indexes and the memory.
//! * `inspect run.yggrec` (a recording): its files, cuts and time span, and a timeline
//!   of cuts (time, generation, bytes added, layers changed); with `--at`/`--time`, the
//!   scene at that cut as above.
//! * `inspect FILE.json[.gz]` or `inspect FILE.sparkdsg` (a Spark-DSG file): the object
//!   labels with their counts (label id, name, objects), then the paper's static table —
//!   for each layout (all four, or `--layouts mint,saffron`), layers, nodes, edges and
//!   memory.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::Parser;
use ygg_dsg::NodeSymbol;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::objects::Objects;
use ygg_store::index::SpatialIndex;
use ygg_store::snapshot::{STRUCTURE_SEGMENT_ID, segment_layer_part};
use ygg_store::{LayerId, NodeId, SceneView, SnapshotFile};

use crate::query::{live_snapshot, seconds};

/// Arguments of `ygg inspect`.
#[derive(Parser, Debug)]
pub struct InspectArgs {
    /// A `.ygg` snapshot, a recording folder (its timeline), or a Spark-DSG file
    /// (`.json`, `.json.gz`, `.sparkdsg`) whose layouts to tabulate.
    #[arg(required_unless_present = "scene", conflicts_with = "scene")]
    pub path: Option<PathBuf>,
    /// Inspect a live scene published under this name instead of a file.
    #[arg(long)]
    pub scene: Option<String>,
    /// For a Spark-DSG file: the layouts to tabulate, comma-separated (default: all four).
    #[arg(long, value_delimiter = ',')]
    pub layouts: Vec<Layout>,
    /// List every node that carries a node index (default: the first few).
    #[arg(long, short)]
    pub verbose: bool,
    /// Seconds to wait for a live scene's writer and first snapshot.
    #[arg(long, default_value_t = 5.0)]
    pub timeout: f64,
    /// For a recording: inspect the cut of this generation instead of the timeline.
    #[arg(long, conflicts_with = "time")]
    pub at: Option<u64>,
    /// For a recording: inspect the scene as it was at this time (see `ygg query --time`).
    #[arg(long, allow_hyphen_values = true)]
    pub time: Option<crate::moment::TimeSpec>,
    /// For a recording's timeline: how many cuts to list (the first and the last halves;
    /// 0 lists every cut).
    #[arg(long, default_value_t = 20)]
    pub cuts: usize,
}

/// Runs `ygg inspect` on a file or a live scene (a recording's folder goes to
/// [`crate::timeline::run`]).
///
/// # Errors
/// A message naming the file or scene that could not be read.
pub fn run(args: &InspectArgs) -> Result<(), String> {
    if args.at.is_some() || args.time.is_some() {
        return Err(
            "--at and --time apply to a recording (a folder written by `ygg record`)".into(),
        );
    }
    match (&args.path, &args.scene) {
        (Some(path), _) if is_spark_dsg(path)? => layouts_table(path, &args.layouts),
        (Some(path), _) => {
            if !args.layouts.is_empty() {
                return Err(format!(
                    "{}: --layouts applies to Spark-DSG files, not to snapshots",
                    path.display()
                ));
            }
            let file = SnapshotFile::open(path).map_err(|e| e.to_string())?;
            let (manifest, layers) = file.segment_sizes();
            let view = file.view();
            let bytes: BTreeMap<LayerId, usize> = view.layers().zip(layers).collect();
            let memory = Memory {
                manifest,
                layers: bytes,
                total: Some(file.len()),
            };
            print_scene(
                &format!("snapshot {}", path.display()),
                &view,
                view.generation(),
                &memory,
                args.verbose,
            );
            Ok(())
        }
        (None, Some(scene)) => {
            if !args.layouts.is_empty() {
                return Err("--layouts applies to Spark-DSG files".to_owned());
            }
            let snapshot = live_snapshot(scene, seconds(args.timeout, "--timeout")?)?;
            let raw = snapshot.raw();
            let memory = Memory::of_segments(
                raw.manifest_bytes().len(),
                raw.layers().map(|(e, b)| (e.layer_id, b.len())),
            );
            let view = snapshot.view();
            print_scene(
                &format!("live scene {scene}"),
                &view,
                snapshot.generation(),
                &memory,
                args.verbose,
            );
            Ok(())
        }
        (None, None) => Err("give a file or --scene NAME".to_owned()),
    }
}

/// Whether `path` holds a Spark-DSG file (JSON, plain or gzip, or binary with its
/// header) rather than a snapshot.
fn is_spark_dsg(path: &Path) -> Result<bool, String> {
    if path.extension().is_some_and(|e| e == "ygg") {
        return Ok(false);
    }
    let mut head = [0u8; 64];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let head = &head[..n];
    Ok(head.starts_with(&[0x1f, 0x8b])
        || ygg_dsg::is_binary(head)
        || head
            .iter()
            .find(|b| !b.is_ascii_whitespace())
            .is_some_and(|&b| b == b'{'))
}

/// Segment sizes of a scene.
pub(crate) struct Memory {
    manifest: usize,
    layers: BTreeMap<LayerId, usize>,
    /// The file size, for a file (header and padding included).
    total: Option<usize>,
}

impl Memory {
    /// The memory of a cut of segments (`(segment id, bytes)`): the structure counts with
    /// the manifest, a layer's parts and chunks with their layer.
    pub(crate) fn of_segments(
        manifest: usize,
        segments: impl Iterator<Item = (u64, usize)>,
    ) -> Memory {
        let mut memory = Memory {
            manifest,
            layers: BTreeMap::new(),
            total: None,
        };
        for (id, len) in segments {
            if id == STRUCTURE_SEGMENT_ID {
                memory.manifest += len;
            } else if let Some((layer, _)) = segment_layer_part(id) {
                *memory.layers.entry(layer).or_default() += len;
            }
        }
        memory
    }
}

/// One layer's line.
struct LayerRow {
    id: LayerId,
    name: String,
    nodes: usize,
    points: usize,
    edges: usize,
    nested: usize,
    generation: u64,
    /// Points and bytes of the layer index.
    layer_index: Option<(usize, usize)>,
    /// Roots, points and bytes of the node indexes rooted in this layer.
    node_indexes: Vec<(NodeId, usize, usize)>,
}

fn layer_rows<V: SceneView>(view: &V) -> Vec<LayerRow> {
    view.layers()
        .map(|l| {
            let mut row = LayerRow {
                id: l,
                name: view.layer_name(l).unwrap_or("?").to_owned(),
                nodes: 0,
                points: 0,
                edges: 0,
                nested: 0,
                generation: view.layer_generation(l).unwrap_or(0),
                layer_index: view.layer_index(l).map(|i| (i.len(), i.memory_bytes())),
                node_indexes: Vec::new(),
            };
            for n in view.layer_nodes(l) {
                row.nodes += 1;
                row.points += view.points(n).len();
                row.edges += view.out_edges(n).count();
                row.nested += usize::from(view.parent(n).is_some());
                let id = view.node_id(n);
                if view.has_node_index(id) {
                    let (points, bytes) = match view.node_index(id) {
                        Some(i) => (i.len(), i.memory_bytes()),
                        // A publish withholds small trees: readers walk the sub-tree.
                        None => (subtree_points(view, id), 0),
                    };
                    row.node_indexes.push((id, points, bytes));
                }
            }
            row.node_indexes.sort_unstable_by_key(|r| r.0);
            row
        })
        .collect()
}

/// Points in `root`'s sub-tree.
fn subtree_points<V: SceneView>(view: &V, root: NodeId) -> usize {
    ygg_store::query::subtree(view, root)
        .into_iter()
        .filter_map(|m| view.node(m))
        .map(|m| view.points(m).len())
        .sum()
}

/// `12,345,678`.
fn thousands(n: usize) -> String {
    let s = n.to_string();
    let mut out = String::with_capacity(s.len() + s.len() / 3);
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn mb(bytes: usize) -> String {
    format!("{:.2} MB", bytes as f64 / 1e6)
}

fn describe_node(id: NodeId) -> String {
    let s = NodeSymbol::from_id(id.0);
    if s.prefix().is_ascii_graphic() {
        format!("{s} [{}]", id.0)
    } else {
        id.0.to_string()
    }
}

pub(crate) fn print_scene<V: SceneView>(
    title: &str,
    view: &V,
    generation: u64,
    memory: &Memory,
    verbose: bool,
) {
    let rows = layer_rows(view);
    let sum = |f: fn(&LayerRow) -> usize| rows.iter().map(f).sum::<usize>();
    let objects = Objects::new(view);
    println!("{title}");
    println!(
        "  generation {generation}; {} layers, {} nodes, {} points, {} edges, {} nested nodes",
        rows.len(),
        thousands(sum(|r| r.nodes)),
        thousands(sum(|r| r.points)),
        thousands(sum(|r| r.edges)),
        thousands(sum(|r| r.nested)),
    );
    println!(
        "  objects: {} in {} object layers, {} with geometry in {} mesh layers",
        thousands(objects.objects().len()),
        objects
            .object_layers()
            .iter()
            .filter(|&&l| view.layer_len(l) > 0)
            .count(),
        thousands(objects.objects_with_geometry().count()),
        objects.mesh_layers().len(),
    );

    println!();
    println!("layers:");
    let w = rows.iter().map(|r| r.name.len()).max().unwrap_or(4).max(4);
    println!(
        "  {:>4}  {:<w$}  {:>9}  {:>9}  {:>7}  {:>7}  {:>5}  {:>11}  {:>16}  {:>16}",
        "id",
        "name",
        "nodes",
        "points",
        "edges",
        "nested",
        "gen",
        "bytes",
        "layer index",
        "node indexes"
    );
    for r in &rows {
        let bytes = memory
            .layers
            .get(&r.id)
            .map_or("?".to_owned(), |b| thousands(*b));
        let layer_index = r
            .layer_index
            .map_or("-".to_owned(), |(p, _)| format!("{} pts", thousands(p)));
        let node_indexes = if r.node_indexes.is_empty() {
            "-".to_owned()
        } else {
            format!("{} roots", thousands(r.node_indexes.len()))
        };
        println!(
            "  {:>4}  {:<w$}  {:>9}  {:>9}  {:>7}  {:>7}  {:>5}  {:>11}  {:>16}  {:>16}",
            r.id.0,
            r.name,
            thousands(r.nodes),
            thousands(r.points),
            thousands(r.edges),
            thousands(r.nested),
            r.generation,
            bytes,
            layer_index,
            node_indexes
        );
    }

    println!();
    println!("layer DAG (parent -> children):");
    let name = |l: LayerId| view.layer_name(l).unwrap_or("?").to_owned();
    let roots: Vec<String> = rows
        .iter()
        .filter(|r| view.layer_parents(r.id).is_empty())
        .map(|r| r.name.clone())
        .collect();
    println!("  roots: {}", roots.join(", "));
    for r in &rows {
        let children = view.layer_children(r.id);
        if !children.is_empty() {
            let names: Vec<String> = children.into_iter().map(name).collect();
            println!("  {} -> {}", r.name, names.join(", "));
        }
    }

    println!();
    println!("indexes:");
    let indexed: Vec<&LayerRow> = rows.iter().filter(|r| r.layer_index.is_some()).collect();
    let (li_points, li_bytes) = indexed.iter().fold((0, 0), |(p, b), r| {
        let (rp, rb) = r.layer_index.unwrap_or((0, 0));
        (p + rp, b + rb)
    });
    if indexed.is_empty() {
        println!("  layer indexes: none");
    } else {
        println!(
            "  layer indexes: {} layers, {} points, {}: {}",
            indexed.len(),
            thousands(li_points),
            mb(li_bytes),
            indexed
                .iter()
                .map(|r| r.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let roots: Vec<(NodeId, usize, usize)> = rows
        .iter()
        .flat_map(|r| r.node_indexes.iter().copied())
        .collect();
    if roots.is_empty() {
        println!("  node indexes: none");
    } else {
        let layers = rows.iter().filter(|r| !r.node_indexes.is_empty()).count();
        println!(
            "  node indexes: {} nodes in {} layers, {} points, {}",
            thousands(roots.len()),
            layers,
            thousands(roots.iter().map(|r| r.1).sum()),
            mb(roots.iter().map(|r| r.2).sum()),
        );
        let shown = if verbose { roots.len() } else { 8 };
        for (id, points, bytes) in roots.iter().take(shown) {
            println!(
                "    {} ({} points, {} bytes)",
                describe_node(*id),
                thousands(*points),
                thousands(*bytes)
            );
        }
        if roots.len() > shown {
            println!(
                "    ... {} more (--verbose lists them)",
                roots.len() - shown
            );
        }
    }

    println!();
    let layer_bytes: usize = memory.layers.values().sum();
    let total = memory.manifest + layer_bytes;
    print!(
        "memory: manifest {} B + {} layer segments {} B = {} B ({})",
        thousands(memory.manifest),
        memory.layers.len(),
        thousands(layer_bytes),
        thousands(total),
        mb(total)
    );
    match memory.total {
        Some(file) => println!("; file {} B with header and padding", thousands(file)),
        None => println!(),
    }
}

/// The paper's static table: each layout of a Spark-DSG file.
/// The object labels of a Spark-DSG graph with their counts.
fn print_labels(d: &ygg_dsg::DsgGraph) {
    let labels = d.object_labels();
    println!();
    println!(
        "object labels: {} distinct over {} objects (objects_with_label finds an object under its name and under its label id)",
        labels.len(),
        thousands(d.counts().kind(ygg_dsg::NodeKind::Object))
    );
    println!("{:>10}  {:<20} {:>7}", "label id", "name", "objects");
    for l in labels {
        println!(
            "{:>10}  {:<20} {:>7}",
            l.semantic_label
                .map_or_else(|| "-".to_owned(), |s| s.to_string()),
            l.name.as_deref().unwrap_or("-"),
            thousands(l.objects)
        );
    }
}

fn layouts_table(path: &Path, layouts: &[Layout]) -> Result<(), String> {
    let layouts = if layouts.is_empty() {
        Layout::ALL.to_vec()
    } else {
        layouts.to_vec()
    };
    let t = Instant::now();
    let d = ygg_dsg::read_file(path).map_err(|e| e.to_string())?;
    let imported = t.elapsed();
    let c = d.counts();
    println!(
        "Spark-DSG {} (version {}): {} nodes, {} edges, {} mesh vertices, {} faces; imported in {:.2} s",
        path.display(),
        d.version,
        thousands(c.nodes),
        thousands(c.edges),
        thousands(c.mesh_vertices),
        thousands(c.mesh_faces),
        imported.as_secs_f64()
    );
    print_labels(&d);
    println!();
    println!(
        "{:<10} {:>7} {:>10} {:>10} {:>8} {:>8} {:>10} {:>9} {:>11} {:>8}",
        "layout",
        "layers",
        "nodes",
        "points",
        "edges",
        "nested",
        "layer idx",
        "node idx",
        "memory MB",
        "build s"
    );
    for l in layouts {
        let t = Instant::now();
        let g = layout::build(&d, l).map_err(|e| e.to_string())?;
        let built: Duration = t.elapsed();
        let rows = layer_rows(&g);
        let sum = |f: fn(&LayerRow) -> usize| rows.iter().map(f).sum::<usize>();
        let bytes = g.to_segments().len();
        println!(
            "{:<10} {:>7} {:>10} {:>10} {:>8} {:>8} {:>10} {:>9} {:>11.2} {:>8.2}",
            l.name(),
            rows.len(),
            thousands(sum(|r| r.nodes)),
            thousands(sum(|r| r.points)),
            thousands(sum(|r| r.edges)),
            thousands(sum(|r| r.nested)),
            rows.iter().filter(|r| r.layer_index.is_some()).count(),
            thousands(sum(|r| r.node_indexes.len())),
            bytes as f64 / 1e6,
            built.as_secs_f64()
        );
    }
    println!();
    println!(
        "memory: bytes of the archived scene (manifest and layer segments, indexes included) — what a .ygg file or shared memory holds"
    );
    Ok(())
}
