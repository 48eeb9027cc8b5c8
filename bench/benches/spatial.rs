//! Spatial benchmarks (issue: live spatial indexes and spatial queries).
//!
//! For each size (points; one point per node in a `mesh` layer, every node nested under
//! one `room` node, layer index on `mesh`, node index on the room): nearest (m = 1, 10),
//! radius (about 10 and about 1,000 answers) and visible (a 30° cone with about 1,000
//! points in view) on the live graph (live kd-tree) and on its snapshot (kiddo's
//! archived tree, zero-copy), against a bare kiddo `ImmutableKdTree` over the same points
//! (the floor) and brute force; update latency (insert, move, remove one point) with no
//! index, with the layer index, and with both indexes; index bytes per point (and the
//! live indexes' shared handle table).
//!
//! Sizes: `YGG_SPATIAL_SIZES` (comma-separated point counts; default `10000,100000`;
//! the full run is `10000,100000,1000000,10000000`). Besides criterion's
//! estimates, each size prints a markdown table of per-call p50 / p99 (`Instant` around
//! each call, about 20 ns of timer overhead included) and the ratios to bare kiddo.
#![expect(clippy::unwrap_used, reason = "acceptable in benchmarks")]
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use kiddo::SquaredEuclidean;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::num::NonZeroUsize;
use std::time::{Duration, Instant};
use ygg_store::index::{KdTree, SpatialIndex};
use ygg_store::query::{ConeView, nearest_nodes, nodes_within_radius, visible};
use ygg_store::{LayerId, NodeId, Point, SceneGraph, SceneView, Scope, SnapshotFile};

/// Extent of the scene, metres: a building floor-like slab.
const EXTENT: [f32; 3] = [100.0, 100.0, 10.0];
/// First mesh node id (node i holds point i).
const BASE: u64 = 1_000;
/// Spare empty nodes used by the insert/remove benchmarks.
const SPARE: u64 = 1_000;
const HALF_ANGLE: f32 = std::f32::consts::FRAC_PI_6;

struct Scene {
    g: SceneGraph,
    mesh: LayerId,
    room: NodeId,
    points: Vec<Point>,
    snapshot: SnapshotFile,
    bare: KdTree,
    queries: Vec<Point>,
    r_small: f32,
    r_large: f32,
    cones: Vec<ConeView>,
}

fn random_point(rng: &mut ChaCha8Rng) -> Point {
    [0, 1, 2].map(|a| rng.gen_range(0.0..EXTENT[a]))
}

fn build(n: usize) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(n as u64);
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms").unwrap();
    let mesh = g.add_layer("mesh").unwrap();
    g.add_layer_edge(rooms, mesh).unwrap();
    let room = NodeId(1);
    g.add_node(room, rooms).unwrap();
    let points: Vec<Point> = (0..n).map(|_| random_point(&mut rng)).collect();
    for (i, p) in points.iter().enumerate() {
        let id = NodeId(BASE + i as u64);
        g.add_node(id, mesh).unwrap();
        g.set_geometry(id, vec![*p]).unwrap();
        g.nest(room, id).unwrap();
    }
    for s in 0..SPARE {
        let id = NodeId(BASE + n as u64 + s);
        g.add_node(id, mesh).unwrap();
        g.nest(room, id).unwrap();
    }
    g.enable_layer_index(mesh).unwrap();
    g.enable_node_index(room).unwrap();
    let snapshot = g.to_snapshot();
    let entries: Vec<(u32, Point)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| (i as u32, *p))
        .collect();
    let bare = KdTree::new_from_entries(&entries).unwrap();
    let queries: Vec<Point> = (0..1024).map(|_| random_point(&mut rng)).collect();
    let count_within = |r: f32| {
        let total: usize = queries[..64]
            .iter()
            .map(|q| {
                bare.query(q)
                    .within::<SquaredEuclidean<f32>>(r * r)
                    .unsorted()
                    .execute()
                    .len()
            })
            .sum();
        total as f32 / 64.0
    };
    let fit = |target: f32| {
        let mut r = (target * EXTENT.iter().product::<f32>() / n as f32 * 0.24).cbrt();
        for _ in 0..8 {
            let found = count_within(r).max(0.5);
            r *= (target / found).powf(0.4);
        }
        r
    };
    let r_small = fit(10.0);
    let r_large = fit(1000.0);
    // Cones from random eyes in random horizontal directions, their range fitted so that
    // about 1,000 points are in view (a 30° cone holds ~6.7% of its range's ball; small
    // scenes see fewer).
    let range = fit(15_000f32.min(n as f32 / 4.0));
    let cones: Vec<ConeView> = queries
        .iter()
        .map(|&eye| {
            let a: f32 = rng.gen_range(0.0..std::f32::consts::TAU);
            ConeView {
                eye,
                dir: [a.cos(), a.sin(), 0.0],
                half_angle: HALF_ANGLE,
                range,
            }
        })
        .collect();
    Scene {
        g,
        mesh,
        room,
        points,
        snapshot,
        bare,
        queries,
        r_small,
        r_large,
        cones,
    }
}

/// The cone test and enclosing ball the store uses, for the bare and brute baselines.
struct ConeTest {
    eye: [f64; 3],
    dir: [f64; 3],
    cos_half: f64,
    range2: f64,
    centre: Point,
    ball2: f32,
}

impl ConeTest {
    fn new(c: &ConeView) -> Self {
        let d = c.dir.map(f64::from);
        let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let dir = d.map(|v| v / norm);
        let eye = c.eye.map(f64::from);
        let cos_half = f64::from(c.half_angle).cos();
        let range = f64::from(c.range);
        let t = range / (2.0 * cos_half);
        let centre = [0, 1, 2].map(|a| (eye[a] + dir[a] * t) as f32);
        let r = t * 1.0001 + 1e-3;
        ConeTest {
            eye,
            dir,
            cos_half,
            range2: range * range,
            centre,
            ball2: (r * r) as f32,
        }
    }

    fn contains(&self, p: &Point) -> bool {
        let v = [0, 1, 2].map(|a| f64::from(p[a]) - self.eye[a]);
        let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        d2 <= self.range2
            && (d2 == 0.0
                || v[0] * self.dir[0] + v[1] * self.dir[1] + v[2] * self.dir[2]
                    >= self.cos_half * d2.sqrt())
    }
}

// ---- the operations measured ----------------------------------------------------------

fn brute_nearest(points: &[Point], c: &Point, m: usize) -> Vec<(f32, u32)> {
    let mut best: Vec<(f32, u32)> = Vec::with_capacity(m + 1);
    for (i, p) in points.iter().enumerate() {
        let d = ygg_store::distance_squared(p, c);
        if best.len() < m || d < best[m - 1].0 {
            let at = best.partition_point(|e| e.0 <= d);
            best.insert(at, (d, i as u32));
            best.truncate(m);
        }
    }
    best
}

fn brute_within(points: &[Point], c: &Point, r: f32) -> Vec<u32> {
    (0..points.len() as u32)
        .filter(|&i| ygg_store::distance_squared(&points[i as usize], c).sqrt() <= r)
        .collect()
}

fn bare_within(bare: &KdTree, c: &Point, r: f32) -> Vec<u32> {
    let mut v: Vec<u32> = bare
        .query(c)
        .within::<SquaredEuclidean<f32>>(r * r)
        .unsorted()
        .execute()
        .into_iter()
        .map(|x| x.item)
        .collect();
    v.sort_unstable();
    v
}

fn bare_visible(bare: &KdTree, cone: &ConeView) -> Vec<u32> {
    let t = ConeTest::new(cone);
    let mut v = Vec::new();
    bare.query(&t.centre)
        .within::<SquaredEuclidean<f32>>(t.ball2)
        .unsorted()
        .with_points()
        .visit(|r| {
            if t.contains(&r.point) {
                v.push(r.item);
            }
        });
    v.sort_unstable();
    v
}

fn brute_visible(points: &[Point], cone: &ConeView) -> Vec<u32> {
    let t = ConeTest::new(cone);
    (0..points.len() as u32)
        .filter(|&i| t.contains(&points[i as usize]))
        .collect()
}

/// Per-call latency percentiles (p50, p99) in nanoseconds over `iters` calls.
fn percentiles(iters: usize, mut f: impl FnMut(usize) -> Duration) -> (f64, f64) {
    let ns: Vec<f64> = (0..iters).map(|i| f(i).as_nanos() as f64).collect();
    summarize(&ns)
}

/// p50 and p99 (nearest rank, [`ygg_testkit::stats`]) of nanosecond samples; 0 when none.
fn summarize(ns: &[f64]) -> (f64, f64) {
    ygg_testkit::stats::median_p99(ns).unwrap_or((0.0, 0.0))
}

/// Per-call p50 / p99 of several variants of one query, called in turn for each query
/// point so that a noisy machine disturbs every variant alike.
fn interleaved(
    iters: usize,
    variants: &mut [(&str, &mut dyn FnMut(usize))],
) -> Vec<(String, f64, f64)> {
    let mut samples: Vec<Vec<f64>> = vec![Vec::with_capacity(iters); variants.len()];
    for i in 0..iters {
        for (v, (_, f)) in variants.iter_mut().enumerate() {
            let t = Instant::now();
            f(i);
            samples[v].push(t.elapsed().as_nanos() as f64);
        }
    }
    variants
        .iter()
        .zip(&samples)
        .map(|((name, _), ns)| {
            let (p50, p99) = summarize(ns);
            (name.to_string(), p50, p99)
        })
        .collect()
}

fn timed(f: impl FnOnce()) -> Duration {
    let t = Instant::now();
    f();
    t.elapsed()
}

/// Update operations on a spare node `s` of the scene's mesh layer.
#[derive(Clone, Copy)]
enum Update {
    Insert,
    Move,
    Remove,
}

/// One timed update (untimed setup / restore around it).
fn update(s: &mut Scene, op: Update, i: usize, rng: &mut ChaCha8Rng) -> Duration {
    let n = s.points.len() as u64;
    let spare = NodeId(BASE + n + i as u64 % SPARE);
    let p = random_point(rng);
    match op {
        Update::Insert => {
            let d = timed(|| s.g.set_geometry(spare, vec![p]).unwrap());
            s.g.set_geometry(spare, Vec::new()).unwrap();
            d
        }
        Update::Move => {
            let id = NodeId(BASE + (i as u64).wrapping_mul(0x9E37_79B9) % n);
            timed(|| s.g.set_geometry(id, vec![p]).unwrap())
        }
        Update::Remove => {
            s.g.set_geometry(spare, vec![p]).unwrap();
            timed(|| s.g.set_geometry(spare, Vec::new()).unwrap())
        }
    }
}

// ---- the report -----------------------------------------------------------------------

struct Row {
    case: String,
    p50: f64,
    p99: f64,
}

fn fmt_ns(ns: f64) -> String {
    if ns >= 1e6 {
        format!("{:.2} ms", ns / 1e6)
    } else if ns >= 1e3 {
        format!("{:.2} µs", ns / 1e3)
    } else {
        format!("{ns:.0} ns")
    }
}

fn report(n: usize, s: &mut Scene) {
    let view = s.snapshot.view();
    let q = |i: usize| s.queries[i % s.queries.len()];
    let scope = Scope::Layer(s.mesh);
    let iters = if n > 2_000_000 { 3_000 } else { 20_000 };
    let brute_iters = (2_000_000_000 / n.max(1)).clamp(20, 2_000);
    let mut rows = Vec::new();
    let mut family = |name: &str, iters: usize, variants: &mut [(&str, &mut dyn FnMut(usize))]| {
        for (variant, p50, p99) in interleaved(iters, variants) {
            rows.push(Row {
                case: format!("{name} / {variant}"),
                p50,
                p99,
            });
        }
    };
    let (g, bare, points) = (&s.g, &s.bare, &s.points);
    let k10 = NonZeroUsize::new(10).unwrap();
    family(
        "nearest m=1",
        iters,
        &mut [
            ("bare kiddo", &mut |i| {
                black_box(
                    bare.query(&q(i))
                        .nearest_one::<SquaredEuclidean<f32>>()
                        .execute(),
                );
            }),
            ("archived", &mut |i| {
                black_box(nearest_nodes(&view, scope, q(i), 1).unwrap());
            }),
            ("live", &mut |i| {
                black_box(nearest_nodes(g, scope, q(i), 1).unwrap());
            }),
        ],
    );
    family(
        "nearest m=10",
        iters,
        &mut [
            ("bare kiddo", &mut |i| {
                black_box(
                    bare.query(&q(i))
                        .nearest_n::<SquaredEuclidean<f32>>(k10)
                        .execute(),
                );
            }),
            ("archived", &mut |i| {
                black_box(nearest_nodes(&view, scope, q(i), 10).unwrap());
            }),
            ("live", &mut |i| {
                black_box(nearest_nodes(g, scope, q(i), 10).unwrap());
            }),
        ],
    );
    for (name, r) in [("radius small", s.r_small), ("radius large", s.r_large)] {
        family(
            name,
            iters / 4,
            &mut [
                ("bare kiddo", &mut |i| {
                    black_box(bare_within(bare, &q(i), r));
                }),
                ("archived", &mut |i| {
                    black_box(nodes_within_radius(&view, scope, q(i), r).unwrap());
                }),
                ("live", &mut |i| {
                    black_box(nodes_within_radius(g, scope, q(i), r).unwrap());
                }),
            ],
        );
    }
    let cone = |i: usize| s.cones[i % s.cones.len()];
    family(
        "visible",
        iters / 4,
        &mut [
            ("bare kiddo", &mut |i| {
                black_box(bare_visible(bare, &cone(i)));
            }),
            ("archived", &mut |i| {
                black_box(visible(&view, s.room, &cone(i)).unwrap());
            }),
            ("live", &mut |i| {
                black_box(visible(g, s.room, &cone(i)).unwrap());
            }),
        ],
    );
    for (name, m) in [("nearest m=1", 1), ("nearest m=10", 10)] {
        family(
            name,
            brute_iters,
            &mut [("brute force", &mut |i| {
                black_box(brute_nearest(points, &q(i), m));
            })],
        );
    }
    for (name, r) in [("radius small", s.r_small), ("radius large", s.r_large)] {
        family(
            name,
            brute_iters,
            &mut [("brute force", &mut |i| {
                black_box(brute_within(points, &q(i), r));
            })],
        );
    }
    family(
        "visible",
        brute_iters,
        &mut [("brute force", &mut |i| {
            black_box(brute_visible(points, &cone(i)));
        })],
    );
    let live_bytes = g.layer_index(s.mesh).unwrap().memory_bytes();
    let archived_bytes = view.layer_index(s.mesh).unwrap().memory_bytes();
    drop(view);
    // Validated open of the scene's `.ygg` file (mapped; the page cache is warm), with
    // its two kd-trees (layer index and node index), and the same without indexes.
    let open_ms = |g: &SceneGraph| {
        let dir = std::env::temp_dir().join(format!("ygg-spatial-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scene.ygg");
        g.save(&path).unwrap();
        let bytes = std::fs::metadata(&path).unwrap().len();
        let mut ms: Vec<f64> = (0..5)
            .map(|_| {
                let t = Instant::now();
                black_box(SnapshotFile::open(&path).unwrap());
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        std::fs::remove_dir_all(&dir).unwrap();
        (ms[2], bytes as f64 / 1e6)
    };
    let (open_indexed, mb_indexed) = open_ms(&s.g);
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    let update_iters = iters.min(20_000);
    for (label, layer_index, node_index) in [
        ("layer + node index", true, true),
        ("layer index", true, false),
        ("no index", false, false),
    ] {
        if !node_index {
            s.g.disable_node_index(s.room).unwrap();
        }
        if !layer_index {
            s.g.disable_layer_index(s.mesh).unwrap();
        }
        for (name, op) in [
            ("insert", Update::Insert),
            ("move", Update::Move),
            ("remove", Update::Remove),
        ] {
            let (p50, p99) = percentiles(update_iters, |i| update(s, op, i, &mut rng));
            rows.push(Row {
                case: format!("update {name} / {label}"),
                p50,
                p99,
            });
        }
    }
    let (open_plain, mb_plain) = open_ms(&s.g);
    s.g.enable_layer_index(s.mesh).unwrap();
    s.g.enable_node_index(s.room).unwrap();

    println!(
        "\n### {n} points (r_small {:.2} m, r_large {:.2} m, cone range {:.2} m)\n",
        s.r_small, s.r_large, s.cones[0].range
    );
    println!("| case | p50 | p99 | p50 / bare kiddo |");
    println!("|---|---|---|---|");
    let floor = |case: &str| {
        let family = case.split(" / ").next().unwrap();
        rows.iter()
            .find(|r| r.case == format!("{family} / bare kiddo"))
            .map(|r| r.p50)
    };
    let family_of = |case: &str| case.split(" / ").next().unwrap().to_owned();
    let mut families: Vec<String> = Vec::new();
    for r in &rows {
        if !families.contains(&family_of(&r.case)) {
            families.push(family_of(&r.case));
        }
    }
    let ordered = families
        .iter()
        .flat_map(|f| rows.iter().filter(move |r| family_of(&r.case) == *f));
    for r in ordered {
        let ratio = floor(&r.case).map_or(String::new(), |f| format!("{:.2}×", r.p50 / f));
        println!(
            "| {} | {} | {} | {ratio} |",
            r.case,
            fmt_ns(r.p50),
            fmt_ns(r.p99)
        );
    }
    println!(
        "\nindex bytes per point: live {:.2}, archived {:.2} (12 of them are the point's coordinates); \
         live handle table {:.2} (item to node id, one per indexed node, shared by the graph's live indexes)\n",
        live_bytes as f64 / n as f64,
        archived_bytes as f64 / n as f64,
        s.g.index_handle_bytes() as f64 / n as f64
    );
    println!(
        "validated open: {open_indexed:.2} ms for {mb_indexed:.1} MB with both indexes, {open_plain:.2} ms for {mb_plain:.1} MB without\n"
    );
}

// ---- criterion --------------------------------------------------------------------------

fn sizes() -> Vec<usize> {
    std::env::var("YGG_SPATIAL_SIZES")
        .unwrap_or_else(|_| "10000,100000".into())
        .split(',')
        .map(|s| {
            s.trim()
                .parse()
                .expect("YGG_SPATIAL_SIZES: comma-separated point counts")
        })
        .collect()
}

fn spatial(c: &mut Criterion) {
    for n in sizes() {
        let t = Instant::now();
        let mut s = build(n);
        println!("built {n} points in {:.1} s", t.elapsed().as_secs_f64());
        check_answers(&s);
        report(n, &mut s);
        let view = s.snapshot.view();
        let scope = Scope::Layer(s.mesh);
        let k10 = NonZeroUsize::new(10).unwrap();
        let mut group = c.benchmark_group(format!("spatial/{n}"));
        group.throughput(Throughput::Elements(1));
        group
            .sample_size(30)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(1));
        let mut i = 0usize;
        let mut next = || {
            i = i.wrapping_add(1);
            i
        };
        let q = |i: usize| s.queries[i % s.queries.len()];
        group.bench_function(BenchmarkId::new("nearest_m1", "bare_kiddo"), |b| {
            b.iter(|| {
                s.bare
                    .query(&q(next()))
                    .nearest_one::<SquaredEuclidean<f32>>()
                    .execute()
            })
        });
        group.bench_function(BenchmarkId::new("nearest_m1", "archived"), |b| {
            b.iter(|| nearest_nodes(&view, scope, q(next()), 1).unwrap())
        });
        group.bench_function(BenchmarkId::new("nearest_m1", "live"), |b| {
            b.iter(|| nearest_nodes(&s.g, scope, q(next()), 1).unwrap())
        });
        group.bench_function(BenchmarkId::new("nearest_m10", "bare_kiddo"), |b| {
            b.iter(|| {
                s.bare
                    .query(&q(next()))
                    .nearest_n::<SquaredEuclidean<f32>>(k10)
                    .execute()
            })
        });
        group.bench_function(BenchmarkId::new("nearest_m10", "archived"), |b| {
            b.iter(|| nearest_nodes(&view, scope, q(next()), 10).unwrap())
        });
        group.bench_function(BenchmarkId::new("nearest_m10", "live"), |b| {
            b.iter(|| nearest_nodes(&s.g, scope, q(next()), 10).unwrap())
        });
        for (name, r) in [("radius_small", s.r_small), ("radius_large", s.r_large)] {
            group.bench_function(BenchmarkId::new(name, "bare_kiddo"), |b| {
                b.iter(|| bare_within(&s.bare, &q(next()), r))
            });
            group.bench_function(BenchmarkId::new(name, "archived"), |b| {
                b.iter(|| nodes_within_radius(&view, scope, q(next()), r).unwrap())
            });
            group.bench_function(BenchmarkId::new(name, "live"), |b| {
                b.iter(|| nodes_within_radius(&s.g, scope, q(next()), r).unwrap())
            });
        }
        let cone = |i: usize| s.cones[i % s.cones.len()];
        group.bench_function(BenchmarkId::new("visible", "bare_kiddo"), |b| {
            b.iter(|| bare_visible(&s.bare, &cone(next())))
        });
        group.bench_function(BenchmarkId::new("visible", "archived"), |b| {
            b.iter(|| visible(&view, s.room, &cone(next())).unwrap())
        });
        group.bench_function(BenchmarkId::new("visible", "live"), |b| {
            b.iter(|| visible(&s.g, s.room, &cone(next())).unwrap())
        });
        group.finish();
        drop(view);
        let mut group = c.benchmark_group(format!("spatial_update/{n}"));
        group
            .sample_size(30)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(1));
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for (name, op) in [
            ("insert", Update::Insert),
            ("move", Update::Move),
            ("remove", Update::Remove),
        ] {
            group.bench_function(BenchmarkId::new(name, "layer_and_node_index"), |b| {
                b.iter_custom(|iters| {
                    (0..iters)
                        .map(|k| update(&mut s, op, k as usize, &mut rng))
                        .sum()
                })
            });
        }
        group.finish();
    }
}

/// Before timing: every backend gives the brute-force answer on a sample of queries.
fn check_answers(s: &Scene) {
    let view = s.snapshot.view();
    let scope = Scope::Layer(s.mesh);
    let id = |i: u32| NodeId(BASE + u64::from(i));
    for i in 0..16 {
        let c = s.queries[i];
        for m in [1, 10] {
            let want: Vec<NodeId> = brute_nearest(&s.points, &c, m)
                .into_iter()
                .map(|e| id(e.1))
                .collect();
            for got in [
                nearest_nodes(&view, scope, c, m).unwrap(),
                nearest_nodes(&s.g, scope, c, m).unwrap(),
            ] {
                assert_eq!(got.into_iter().map(|e| e.0).collect::<Vec<_>>(), want);
            }
        }
        for r in [s.r_small, s.r_large] {
            let want: Vec<NodeId> = brute_within(&s.points, &c, r).into_iter().map(id).collect();
            assert_eq!(nodes_within_radius(&view, scope, c, r).unwrap(), want);
            assert_eq!(nodes_within_radius(&s.g, scope, c, r).unwrap(), want);
        }
        let cone = s.cones[i];
        let want: Vec<NodeId> = brute_visible(&s.points, &cone)
            .into_iter()
            .map(id)
            .collect();
        assert_eq!(
            bare_visible(&s.bare, &cone)
                .into_iter()
                .map(id)
                .collect::<Vec<_>>(),
            want
        );
        assert_eq!(visible(&view, s.room, &cone).unwrap(), want);
        assert_eq!(visible(&s.g, s.room, &cone).unwrap(), want);
    }
}

criterion_group!(benches, spatial);
criterion_main!(benches);
