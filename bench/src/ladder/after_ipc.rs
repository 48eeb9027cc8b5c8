//! Query after an update, across processes (the `after_update_ipc` rows).
//!
//! The ladder process is the writer: a [`ygg_writer::SceneWriter`] owning a clone of the
//! target's graph moves one object's mesh (the mutation of `after_update_local`) and
//! publishes. A separate reader process (`ygg-bench ipc reader --mode q1a`, spawned
//! through [`crate::ipc::child`]) blocks for the next snapshot, answers the same Q1a on
//! it through [`YggTarget`] and prints an [`AnswerLine`] at once (with a checksum of the
//! moved object's mesh in the snapshot, computed after the answer).
//!
//! Writer and reader run in lockstep: the writer waits for the answer to each publish and
//! checks generation, answer and checksum against its live graph (a wrong or stale
//! answer fails the run; the office's Q1a answer is the same object before and after the
//! move, so the checksum is what shows the snapshot holds the moved mesh), then pauses a
//! few ms before the next mutation, so the reader is back to waiting. Latency: Unix ns
//! just before the mutation (writer) to Unix ns once the reader has the answer (same host
//! clock).

use super::answer_line::{AnswerLine, TAG, mesh_checksum};
use super::harness::{Row, Target};
use super::report::fmt_us;
use super::update::{move_object, object_rooms};
use super::workload::{Query, Workload};
use super::ygg::YggTarget;
use crate::ipc::cases::{ATTACH_TIMEOUT, EXIT_GRACE, Jitter, writer};
use crate::ipc::child::{ReaderProc, Scene, remove_stale};
use crate::ipc::clock::unix_ns;
use crate::ipc::error::Res;
use crate::ipc::interrupt::{check_interrupted, install_signal_handler};
use std::time::{Duration, Instant};
use ygg_dsg::DsgGraph;
use ygg_dsg::layout::Layout;
use ygg_store::{NodeId, Point, SceneGraph, SceneView};
use ygg_testkit::stats::median_p99_us;

/// Samples per target that are checked but not timed.
const WARMUP: usize = 3;
/// How long one answer may take.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(30);

/// The room and point of the Q1a `after_update_local` times: the workload's first Q1a in
/// the moved object's room.
fn update_query(w: &Workload, dsg: &DsgGraph) -> Option<(u64, Point)> {
    let room = object_rooms(dsg).get(&w.update_object).copied()?;
    w.queries.iter().find_map(|q| match q {
        Query::Nearest { room: r, point } if *r == room => Some((room, *point)),
        _ => None,
    })
}

/// Timings of one target, ns per sample.
#[derive(Default)]
struct Samples {
    /// Mutation start (writer) → answer (reader).
    total: Vec<f64>,
    /// The mutation.
    mutate: Vec<f64>,
    /// `publish()`.
    publish: Vec<f64>,
    /// `publish()` called → the reader held the view.
    visible: Vec<f64>,
    /// View → answer in the reader.
    query: Vec<f64>,
    layers_sent: usize,
    layers_total: usize,
    bytes_sent: usize,
}

/// The `after_update_ipc` rows of every graph (each graph's layout is its target name),
/// and notes on how they were taken.
///
/// # Errors
/// A reader answering wrong or stale, or failing, or the transport failing; every child
/// is stopped and every shared-memory file removed first.
pub fn after_update_ipc(
    graphs: &[(Layout, SceneGraph)],
    w: &Workload,
    dsg: &DsgGraph,
    quick: bool,
) -> Res<(Vec<Row>, Vec<String>)> {
    let Some((room, point)) = update_query(w, dsg) else {
        return Ok((Vec::new(), Vec::new()));
    };
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    install_signal_handler();
    let stale = remove_stale();
    if stale > 0 {
        eprintln!("removed {stale} files left by earlier, killed runs");
    }
    let (n, gap) = if quick {
        (20, Duration::from_millis(3))
    } else {
        (200, Duration::from_millis(4))
    };
    let mut rows = Vec::new();
    let mut details = Vec::new();
    let mut leftovers = Vec::new();
    for (layout, graph) in graphs {
        let t = Instant::now();
        let scene = Scene::new(&format!("ladder-{layout}"));
        let result = measure(&scene, *layout, graph.clone(), w, (room, point), n, gap);
        leftovers.extend(scene.clean_up());
        let s = result?;
        let (median_us, p99_us) = median_p99_us(&s.total);
        eprintln!(
            "after_update_ipc {layout}: {} / {} µs in {:.1?}",
            fmt_us(median_us),
            fmt_us(p99_us),
            t.elapsed()
        );
        rows.push(Row {
            target: layout.name().into(),
            query: "after_update_ipc".into(),
            median_us,
            p99_us,
        });
        details.push(format!(
            "{layout} {} + {} ({} of {} layers, {:.0} KB; the call {}) + {}",
            fmt_us(median_p99_us(&s.mutate).0),
            fmt_us(median_p99_us(&s.visible).0),
            s.layers_sent,
            s.layers_total,
            s.bytes_sent as f64 / 1e3,
            fmt_us(median_p99_us(&s.publish).0),
            fmt_us(median_p99_us(&s.query).0),
        ));
    }
    check_interrupted()?;
    let left = if leftovers.is_empty() {
        "nothing was left in /dev/shm".to_owned()
    } else {
        eprintln!("files left in /dev/shm: {}", leftovers.join("; "));
        format!(
            "files were left in /dev/shm (removed): {}",
            leftovers.join("; ")
        )
    };
    let notes = vec![
        format!(
            "`after_update_ipc`: the mutation of `after_update_local`, with the ladder process as the writer (a `SceneWriter` owning a clone of the target's graph) and a separate reader process (`ygg-bench ipc reader --mode q1a`) that blocks for the next snapshot and answers the same Q1a on it. Time from just before the mutation (writer clock) to the answer in the reader (reader clock, same host): mutation + `publish()` of the changed layers + wake-up + validation of the changed layers + view + query in another process. Writer and reader in lockstep, one publish every ~{} ms; every answer (warm-up included) is checked against the writer's live graph: generation just published, answer ids, and a checksum of the moved object's mesh in the snapshot (computed after the answer, not timed; the ids alone do not change with this move); a wrong or stale answer fails the run. {n} samples per target after {WARMUP} warm-up; each target in a fresh scene, {left}.",
            gap.as_millis()
        ),
        format!(
            "`after_update_ipc` split, medians in µs: mutation + `publish()` called → the reader holds the new snapshot's view (layers and bytes republished; the `publish()` call alone) + view → answer (includes finding the room's query scope on the new snapshot, `YggTarget::new`, which `after_update_local` does once): {}.",
            details.join("; ")
        ),
    ];
    Ok((rows, notes))
}

/// Times one target: spawns the reader, then mutates, publishes and checks the answer
/// `WARMUP + n` times.
fn measure(
    scene: &Scene,
    layout: Layout,
    graph: SceneGraph,
    w: &Workload,
    (room, point): (u64, Point),
    n: usize,
    gap: Duration,
) -> Res<Samples> {
    let mesh: Vec<(NodeId, Vec<Point>)> =
        ygg_store::query::children(&graph, NodeId(w.update_object))
            .into_iter()
            .map(|m| {
                let points = graph.node(m).map(|x| graph.points(x).to_vec());
                (m, points.unwrap_or_default())
            })
            .collect();
    let query = Query::Nearest { room, point };
    let mut writer = writer(scene, graph, 2, 64 * 1024)?;
    let args: Vec<String> = vec![
        "--mode".into(),
        "q1a".into(),
        "--layout".into(),
        layout.name().into(),
        "--room".into(),
        room.to_string(),
        format!("--point={},{},{}", point[0], point[1], point[2]),
        "--object".into(),
        w.update_object.to_string(),
    ];
    let mut reader = ReaderProc::spawn(format!("{layout} q1a reader"), scene, &args)?;
    reader.expect("ready", Instant::now() + ATTACH_TIMEOUT)?;
    let mut jitter = Jitter(0x2545_F491_4F6C_DD1D);
    let mut s = Samples::default();
    for i in 0..WARMUP + n {
        check_interrupted()?;
        std::thread::sleep(jitter.apply(gap));
        let t0 = unix_ns();
        move_object(writer.graph_mut(), &mesh, w, i)?;
        let t1 = unix_ns();
        let report = writer.publish()?;
        let t2 = unix_ns();
        let got: AnswerLine = reader
            .expect(TAG, Instant::now() + ANSWER_TIMEOUT)?
            .parse()?;
        let want = YggTarget::new(String::new(), layout, writer.graph()).answer(&query);
        let checksum = mesh_checksum(writer.graph(), NodeId(w.update_object));
        if got.generation != report.generation
            || got.ids != want
            || got.mesh_checksum.to_bits() != checksum.to_bits()
        {
            return Err(format!(
                "{layout}: wrong or stale answer after an update: the reader answered {:?} (mesh checksum {}) on generation {}, the writer's live graph answers {want:?} (mesh checksum {checksum}) after publishing generation {}",
                got.ids, got.mesh_checksum, got.generation, report.generation
            )
            .into());
        }
        if i >= WARMUP {
            s.total.push(got.answered_ns.saturating_sub(t0) as f64);
            s.mutate.push(t1.saturating_sub(t0) as f64);
            s.publish.push(t2.saturating_sub(t1) as f64);
            s.visible.push(got.visible_ns.saturating_sub(t1) as f64);
            s.query
                .push(got.answered_ns.saturating_sub(got.visible_ns) as f64);
            s.layers_sent = report.layers_sent;
            s.layers_total = report.layers_sent + report.layers_unchanged;
            s.bytes_sent = report.bytes_sent;
        }
    }
    reader.finish(EXIT_GRACE)?;
    drop(writer);
    Ok(s)
}
