//! Demo consumers (`ygg demo-role`): a planner, a visibility checker and a label
//! searcher, each attached to a live scene, querying every new snapshot (the planner and
//! the visibility checker through [`Objects`] over the current room's objects), checking
//! a sample of its answers against brute force on the same snapshot, and printing JSON
//! progress and summary lines.
//!
//! When the writer goes away a role prints a `warning` line, keeps querying its last
//! snapshot and picks up a restarted writer (DESIGN.md §5); progress lines name the
//! writer `session` of the snapshot queried, so a driver can see the pickup.

use std::time::{Duration, Instant};
use ygg_dsg::layout::{self, AgentPose, LayerRole, RoomScope};
use ygg_dsg::objects::{self, Objects};
use ygg_reader::{ReaderOpenError, SceneReader, SceneReceiveError, SceneSnapshot};
use ygg_store::query::{self, ConeView};
use ygg_store::snapshot::ArchivedScene;
use ygg_store::{NodeId, Point, SceneView, Scope};

use super::{child, stats};

/// Which consumer to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Role {
    /// Nearest object, objects within a radius, room of the current position.
    Planner,
    /// Objects in the field of view from the newest agent pose.
    Visibility,
    /// Objects by label.
    Labels,
}

/// Options of `ygg demo-role`.
#[derive(clap::Args, Debug)]
pub struct RoleArgs {
    /// Scene name.
    #[arg(long)]
    scene: String,
    /// The consumer to run.
    #[arg(long, value_enum)]
    role: Role,
    /// How long to run.
    #[arg(long, default_value_t = 20.0)]
    seconds: f64,
    /// Check every n-th batch of answers against brute force.
    #[arg(long, default_value_t = 5)]
    check_every: u64,
    /// How long to wait for the writer to appear.
    #[arg(long, default_value_t = 10.0)]
    wait_for_writer: f64,
}

const LABELS: [&str; 6] = ["light", "chair", "shelf", "bulletin", "person", "unicorn"];
/// The planner's radius, metres.
const RADIUS: f32 = 1.5;
/// The visibility checker's view: half-angle (degrees) and range (metres).
const HALF_ANGLE_DEG: f32 = 45.0;
const RANGE: f32 = 5.0;

/// Runs a role until `--seconds` pass or a signal arrives.
pub fn run(args: &RoleArgs) -> Result<(), Box<dyn std::error::Error>> {
    // Started by the demo: stop when it dies.
    child::die_with_parent()?;
    let mut reader = match attach(&args.scene, args.wait_for_writer) {
        Err(ReaderOpenError::Terminated) => {
            // Stopped while waiting for a writer: a clean stop with nothing to report.
            println!(
                "{}",
                serde_json::json!({"event": "summary", "role": format!("{:?}", args.role).to_lowercase(),
                    "attached": false, "batches": 0, "checked": 0, "matched": 0})
            );
            return Ok(());
        }
        reader => reader?,
    };
    let start = Instant::now();
    let deadline = start + Duration::from_secs_f64(args.seconds.max(0.0));
    let (mut query_ns, mut visible_ns, mut staleness) = (Vec::new(), Vec::new(), Vec::new());
    let (mut batches, mut snapshots) = (0u64, 0u64);
    let (checks, checker) = Checker::spawn();
    let mut current: Option<SceneSnapshot> = None;
    let mut last_progress = start;
    // Times the writer went away, and whether a receive error is unanswered by a snapshot.
    let (mut writer_gone, mut away) = (0u64, false);
    while Instant::now() < deadline && !reader.termination_requested() {
        match reader.wait_next(Duration::from_millis(20)) {
            Ok(Some(s)) => {
                let fresh = current
                    .as_ref()
                    .is_none_or(|c| c.generation() != s.generation());
                if fresh {
                    let published = s.raw().published_unix_ns();
                    let now = ygg_transport::protocol::unix_ns();
                    if published > 0 && now >= published {
                        visible_ns.push((now - published) as f64);
                    }
                    if let Some(c) = &current {
                        staleness.push(s.generation().saturating_sub(c.generation() + 1) as f64);
                    }
                    snapshots += 1;
                    current = Some(s);
                    away = false;
                }
            }
            Ok(None) => {}
            Err(SceneReceiveError::Receive(ygg_reader::ReceiveError::Terminated)) => break,
            Err(e) => {
                if !away {
                    println!(
                        "{}",
                        serde_json::json!({"event": "warning", "role": format!("{:?}", args.role), "message": e.to_string()})
                    );
                }
                if matches!(
                    e,
                    SceneReceiveError::Receive(ygg_reader::ReceiveError::WriterGone { .. })
                ) {
                    writer_gone += 1;
                }
                away = true;
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        let Some(snap) = &current else { continue };
        let view = snap.view();
        batches += 1;
        let check = batches % args.check_every.max(1) == 0;
        let t = Instant::now();
        let answers = answer(args.role, view, batches);
        query_ns.push(t.elapsed().as_nanos() as f64 / answers.len().max(1) as f64);
        if check {
            // Sampled: a batch the checker has no room for is not checked.
            let _ = checks.try_send((snap.clone(), answers));
        }
        if last_progress.elapsed() >= Duration::from_millis(500) {
            last_progress = Instant::now();
            println!(
                "{}",
                serde_json::json!({"event": "progress", "queries": query_ns.len(), "generation": snap.generation(),
                    "session": snap.raw().session(), "seconds": start.elapsed().as_secs_f64(), "checked": checker.checked(), "matched": checker.matched()})
            );
        }
    }
    drop(checks);
    let (checked, matched) = checker.finish()?;
    let us = |ns: &[f64]| stats::median_p99(ns).map_or((0.0, 0.0), |(m, p)| (m / 1e3, p / 1e3));
    let q = us(&query_ns);
    let v = us(&visible_ns);
    let stale_mean = if staleness.is_empty() {
        0.0
    } else {
        staleness.iter().sum::<f64>() / staleness.len() as f64
    };
    let stale_max = staleness.iter().copied().fold(0.0, f64::max);
    println!(
        "{}",
        serde_json::json!({"event": "summary", "role": format!("{:?}", args.role).to_lowercase(),
            "batches": query_ns.len(), "query_p50_us": q.0, "query_p99_us": q.1,
            "visible_p50_us": v.0, "visible_p99_us": v.1, "snapshots": snapshots,
            "staleness_mean": stale_mean, "staleness_max": stale_max,
            "checked": checked, "matched": matched, "validations": reader.validations(),
            "writer_gone": writer_gone})
    );
    Ok(())
}

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Sampled answers, with the snapshot they were given on, for the brute-force checker.
type CheckRequest = (SceneSnapshot, Vec<(Query, Vec<u64>)>);

/// The brute-force checker: a thread at the lowest CPU priority (so that checking, which
/// scans whole layers, does not delay noticing the next snapshot) that re-answers each
/// sampled batch by brute force on the same snapshot.
struct Checker {
    /// Answers checked and answers that matched, so far.
    counts: Arc<[AtomicU64; 2]>,
    thread: std::thread::JoinHandle<()>,
}

impl Checker {
    /// Starts the thread; it ends when the returned sender is dropped.
    fn spawn() -> (std::sync::mpsc::SyncSender<CheckRequest>, Checker) {
        let (tx, rx) = std::sync::mpsc::sync_channel::<CheckRequest>(1);
        let counts = Arc::new([AtomicU64::new(0), AtomicU64::new(0)]);
        let shared = Arc::clone(&counts);
        let thread = std::thread::spawn(move || {
            // Best effort: at normal priority the checks only cost latency.
            let _ = rustix::process::setpriority_process(Some(rustix::thread::gettid()), 19);
            for (snapshot, answers) in rx {
                let view = snapshot.view();
                for (q, got) in &answers {
                    let same = brute_force(view, q) == *got;
                    shared[1].fetch_add(u64::from(same), Ordering::Relaxed);
                    shared[0].fetch_add(1, Ordering::Relaxed);
                }
            }
        });
        (tx, Checker { counts, thread })
    }

    fn checked(&self) -> u64 {
        self.counts[0].load(Ordering::Relaxed)
    }

    fn matched(&self) -> u64 {
        self.counts[1].load(Ordering::Relaxed)
    }

    /// Waits for the last check (drop the sender first): (checked, matched).
    fn finish(self) -> Result<(u64, u64), Box<dyn std::error::Error>> {
        let Checker { counts, thread } = self;
        thread
            .join()
            .map_err(|_| "the brute-force checker panicked")?;
        Ok((
            counts[0].load(Ordering::Relaxed),
            counts[1].load(Ordering::Relaxed),
        ))
    }
}

fn attach(scene: &str, wait_secs: f64) -> Result<SceneReader, ReaderOpenError> {
    SceneReader::builder(scene)
        .handle_termination_signals(true)
        .wait_for_writer(Duration::from_secs_f64(wait_secs.max(0.0)))
        .open()
}

/// One query of a role, kept so the answer can be re-checked by brute force.
#[derive(Clone, Debug)]
enum Query {
    Room(Point),
    Nearest {
        mesh_layer: ygg_store::LayerId,
        point: Point,
    },
    Within {
        mesh_layer: ygg_store::LayerId,
        point: Point,
        radius: f32,
    },
    Visible {
        mesh_layer: ygg_store::LayerId,
        cone: ConeView,
    },
    Label(&'static str),
}

/// Runs one batch of the role's queries with the indexed APIs ([`Objects`] for the
/// planner and the visibility checker).
fn answer(role: Role, view: &ArchivedScene<'_>, batch: u64) -> Vec<(Query, Vec<u64>)> {
    let mut out = Vec::new();
    match role {
        Role::Labels => {
            let label = LABELS[batch as usize % LABELS.len()];
            let ids = query::nodes_with_label(view, Scope::Graph, label)
                .into_iter()
                .map(|n| n.0)
                .collect();
            out.push((Query::Label(label), ids));
        }
        Role::Planner | Role::Visibility => {
            let Some(AgentPose {
                position: pose,
                previous: prev,
                ..
            }) = layout::newest_pose(view)
            else {
                return out;
            };
            let room = layout::room_of(view, &pose);
            out.push((Query::Room(pose), room.map(|r| r.0).into_iter().collect()));
            let Some(RoomScope {
                mesh_layer,
                claimed,
            }) = room.and_then(|r| layout::room_scope(view, r))
            else {
                return out;
            };
            // The room's objects answer (the claimed node holds them).
            let room_objects = Objects::in_subtree(view, claimed);
            if role == Role::Planner {
                let nearest = room_objects.nearest_object(pose).ok().flatten();
                out.push((
                    Query::Nearest {
                        mesh_layer,
                        point: pose,
                    },
                    nearest.map(|n| n.0).into_iter().collect(),
                ));
                let within = room_objects
                    .objects_within(pose, RADIUS)
                    .unwrap_or_default();
                out.push((
                    Query::Within {
                        mesh_layer,
                        point: pose,
                        radius: RADIUS,
                    },
                    within.into_iter().map(|n| n.0).collect(),
                ));
            } else {
                // A level view along the direction of travel.
                let d = [pose[0] - prev[0], pose[1] - prev[1], 0.0];
                let dir = if d[0] == 0.0 && d[1] == 0.0 {
                    [1.0, 0.0, 0.0]
                } else {
                    d
                };
                let Ok(cone) = objects::cone_view(pose, dir, HALF_ANGLE_DEG, RANGE) else {
                    return out;
                };
                let seen = room_objects
                    .visible_objects(pose, dir, HALF_ANGLE_DEG, RANGE)
                    .unwrap_or_default();
                out.push((
                    Query::Visible { mesh_layer, cone },
                    seen.into_iter().map(|n| n.0).collect(),
                ));
            }
        }
    }
    out
}

/// The same query answered by scanning every candidate, no index.
fn brute_force(view: &ArchivedScene<'_>, q: &Query) -> Vec<u64> {
    match q {
        Query::Room(p) => room_of_brute(view, p).into_iter().collect(),
        Query::Nearest { mesh_layer, point } => {
            let mut best: Option<(f32, u64)> = None;
            for n in view.layer_nodes(*mesh_layer) {
                let Some(owner) = view.parent(n) else {
                    continue;
                };
                for p in view.points(n) {
                    let d = ygg_store::distance_squared(p, point);
                    if best.is_none_or(|(bd, bo)| d < bd || (d == bd && owner.0 < bo)) {
                        best = Some((d, owner.0));
                    }
                }
            }
            best.map(|b| b.1).into_iter().collect()
        }
        Query::Within {
            mesh_layer,
            point,
            radius,
        } => owners_of_points(view, *mesh_layer, |p| {
            query::within_radius(p, point, *radius)
        }),
        Query::Visible { mesh_layer, cone } => {
            owners_of_points(view, *mesh_layer, |p| cone.contains(p).unwrap_or(false))
        }
        Query::Label(label) => {
            let mut ids: Vec<u64> = view
                .layers()
                .flat_map(|l| {
                    view.layer_nodes(l)
                        .filter(|&n| view.has_label(n, label))
                        .map(|n| view.node_id(n).0)
                        .collect::<Vec<_>>()
                })
                .collect();
            ids.sort_unstable();
            ids
        }
    }
}

/// The owners of the nodes of `mesh_layer` with a point that `hit` accepts, by scanning.
fn owners_of_points(
    view: &ArchivedScene<'_>,
    mesh_layer: ygg_store::LayerId,
    hit: impl Fn(&Point) -> bool,
) -> Vec<u64> {
    let hits: Vec<NodeId> = view
        .layer_nodes(mesh_layer)
        .filter(|&n| view.points(n).iter().any(&hit))
        .map(|n| view.node_id(n))
        .collect();
    layout::owners(view, hits)
        .into_iter()
        .map(|n| n.0)
        .collect()
}

/// The room by recomputing each room's box from its sub-tree's points.
fn room_of_brute(view: &ArchivedScene<'_>, p: &Point) -> Option<u64> {
    let rooms = layout::layer_with_role(view, LayerRole::Rooms)?;
    let mut found: Vec<u64> = Vec::new();
    for r in view.layer_nodes(rooms) {
        let id = view.node_id(r);
        let mut b: Option<ygg_store::Aabb> = None;
        for n in query::subtree(view, id) {
            for q in view.node(n).map(|x| view.points(x)).unwrap_or_default() {
                b = Some(b.map_or(ygg_store::Aabb::from_point(*q), |mut bb| {
                    bb.grow(q);
                    bb
                }));
            }
        }
        if b.is_some_and(|b| (0..2).all(|a| b.min[a] <= p[a] && p[a] <= b.max[a])) {
            found.push(id.0);
        }
    }
    found.sort_unstable();
    found.first().copied()
}
