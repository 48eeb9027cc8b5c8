//! `attach_*`: a new reader process's attach to its first answer, and what one scene costs in
//! descriptors and shared-memory files, on the office and on the 103-room office.

use super::super::child::ReaderProc;
use super::super::child::Scene;
use super::super::clock::unix_ns;
use super::super::error::Res;
use super::super::interrupt::check_interrupted;
use super::super::report::{Row, median};
use super::context::Ctx;
use super::drive::{ATTACH_TIMEOUT, EXIT_GRACE, QUERY_LAYER, reader_args};
use std::time::Instant;
use ygg_store::snapshot::POINT_CHUNK_LEN;
use ygg_store::{SceneGraph, SceneView};
use ygg_writer::SceneWriter;

/// Open descriptors of process `pid` (`self` for this one).
fn descriptors(pid: &str) -> Res<usize> {
    Ok(std::fs::read_dir(format!("/proc/{pid}/fd"))?.count())
}

/// Files in /dev/shm with `prefix`.
fn shm_files(prefix: &str) -> Res<usize> {
    Ok(std::fs::read_dir("/dev/shm")?
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .count())
}

/// The layer bound the reference rows use: the fixed bound every writer had before bounds
/// were sized from the scene.
const REFERENCE_MAX_LAYERS: usize = ygg_transport::service::DEFAULT_MAX_SEGMENTS;

/// What one late reader process measured of its attach.
pub(crate) struct AttachTimes {
    /// From the process's start to its first nearest-node query answered, ns.
    pub(crate) attach_ns: u64,
    /// From just before the spawn (in the benchmark) to the same answer, ns.
    pub(crate) from_spawn_ns: u64,
    /// The process's CPU time until the answer, ns.
    pub(crate) cpu_ns: u64,
}

/// Starts a reader process on `scene` that attaches, answers one nearest-node query (on
/// [`QUERY_LAYER`]) and reports its times; returns it (idle until its stdin closes) with
/// them.
pub(crate) fn spawn_attacher(scene: &Scene) -> Res<(ReaderProc, AttachTimes)> {
    let spawned = unix_ns();
    let mut p = ReaderProc::spawn(
        "attach reader".to_owned(),
        scene,
        &reader_args("attach", Some(QUERY_LAYER)),
    )?;
    let line = p.expect("ready", Instant::now() + ATTACH_TIMEOUT)?;
    let v: Vec<u64> = line
        .split_whitespace()
        .skip(1)
        .filter_map(|x| x.parse().ok())
        .collect();
    let [_, started, answered, cpu_ns] = v[..] else {
        return Err(format!("malformed attach line {line:?}").into());
    };
    let times = AttachTimes {
        attach_ns: answered.saturating_sub(started),
        from_spawn_ns: answered.saturating_sub(spawned),
        cpu_ns,
    };
    Ok((p, times))
}

/// One writer's scene and what its attaching readers measured.
struct Attached {
    scene: Scene,
    writer: SceneWriter,
    writer_fds: usize,
    attach: Vec<f64>,
    from_spawn: Vec<f64>,
    cpu: Vec<f64>,
    reader_fds: Vec<f64>,
    files: Vec<f64>,
}

impl Attached {
    /// An idle writer of `graph` (layer bound `max_layers`, default if `None`), published once.
    fn start(tag: &str, graph: SceneGraph, max_layers: Option<usize>) -> Res<Attached> {
        let scene = Scene::new(&format!("ipcb-{tag}"));
        let before = descriptors("self")?;
        let builder = SceneWriter::builder(&scene.name)
            .iceoryx_prefix(&scene.prefix)
            .max_readers(2)
            .initial_segment_bytes(64 * 1024);
        let mut writer = match max_layers {
            Some(n) => builder.max_layers(n),
            None => builder,
        }
        .create(graph)?;
        writer.publish()?;
        let writer_fds = descriptors("self")?.saturating_sub(before);
        Ok(Attached {
            scene,
            writer,
            writer_fds,
            attach: Vec::new(),
            from_spawn: Vec::new(),
            cpu: Vec::new(),
            reader_fds: Vec::new(),
            files: Vec::new(),
        })
    }

    /// One reader process attaches, answers and exits.
    fn sample(&mut self) -> Res<()> {
        let (mut p, t) = spawn_attacher(&self.scene)?;
        self.attach.push(t.attach_ns as f64);
        self.cpu.push(t.cpu_ns as f64);
        self.from_spawn.push(t.from_spawn_ns as f64);
        self.reader_fds
            .push(descriptors(&p.pid().to_string())? as f64);
        self.files.push(shm_files(&self.scene.prefix)? as f64);
        p.close_stdin();
        p.finish(EXIT_GRACE)?;
        Ok(())
    }

    /// The row, once the writer is gone and the scene's files are checked.
    fn finish(self, ctx: &mut Ctx, case: &str, what: &str, layers: usize) -> Row {
        let max_layers = self.writer.max_layers();
        drop(self.writer);
        if let Some(left) = self.scene.clean_up() {
            ctx.leftovers.push(left);
        }
        Row::latency(case, what, &self.attach)
            .with("from_spawn_median_us", median(&self.from_spawn) / 1e3)
            .with("process_cpu_us", median(&self.cpu) / 1e3)
            .with("layers", layers as f64)
            .with("max_layers", max_layers as f64)
            .with("writer_fds", self.writer_fds as f64)
            .with("reader_fds", median(&self.reader_fds))
            .with("shm_files", median(&self.files))
    }
}

/// Two idle writers publish `graph` once, one with the layer bound sized from the scene (the
/// default) and one with the fixed reference bound; `samples` reader processes attach to
/// each, alternating between the two (ABBA), each timed from its start to its first
/// nearest-node query answered. Rows `case` and `case_bound512` (the latter only for a
/// scene that fits the reference bound).
pub(super) fn case_attach(
    ctx: &mut Ctx,
    case: &str,
    what: &str,
    graph: SceneGraph,
    samples: usize,
) -> Res<Vec<Row>> {
    let layers = graph.layers().count();
    // A scene of more segments than the reference bound cannot be published under it.
    let fits_reference = graph.snapshot_segments(POINT_CHUNK_LEN) <= REFERENCE_MAX_LAYERS;
    let mut sized = Attached::start(case, graph.clone(), None)?;
    let mut reference = match fits_reference {
        true => Some(Attached::start(
            &format!("{case}-bound512"),
            graph,
            Some(REFERENCE_MAX_LAYERS),
        )?),
        false => None,
    };
    for i in 0..samples {
        check_interrupted()?;
        let Some(reference) = reference.as_mut() else {
            sized.sample()?;
            continue;
        };
        if i % 2 == 0 {
            sized.sample()?;
            reference.sample()?;
        } else {
            reference.sample()?;
            sized.sample()?;
        }
    }
    let reference_what = format!(
        "reference: the same with the writer's layer bound at {REFERENCE_MAX_LAYERS} (every writer's bound before it was sized from the scene); samples alternate with the row above"
    );
    let mut rows = vec![sized.finish(ctx, case, what, layers)];
    if let Some(reference) = reference {
        rows.push(reference.finish(ctx, &format!("{case}_bound512"), &reference_what, layers));
    }
    Ok(rows)
}
