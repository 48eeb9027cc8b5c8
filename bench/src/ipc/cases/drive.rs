//! The plumbing every case shares: a writer for a scene, reader arguments, publishing
//! with pauses and collecting what each reader saw, and turning that into latencies.

use super::super::child::{Readers, Scene};
use super::super::clock::unix_ns;
use super::super::error::Res;
use super::super::interrupt::check_interrupted;
use super::super::report::{Row, median, median_p99_us};
use super::plan::Plan;
use std::collections::HashMap;
use std::time::{Duration, Instant};
use ygg_store::SceneGraph;
use ygg_store::snapshot::POINT_CHUNK_LEN;
use ygg_writer::SceneWriter;

/// The layer the readers' nearest-node query runs on: the office's places (waypoints).
pub(super) const QUERY_LAYER: &str = "PLACES";
/// How long readers may take to attach and validate their first snapshot.
pub(crate) const ATTACH_TIMEOUT: Duration = Duration::from_secs(60);
/// How long readers may take to exit when told.
pub(crate) const EXIT_GRACE: Duration = Duration::from_secs(5);

/// A writer for `scene` owning `graph`, which it publishes once.
pub(crate) fn writer(
    scene: &Scene,
    graph: SceneGraph,
    max_readers: usize,
    segment_bytes: usize,
) -> Res<SceneWriter> {
    writer_chunked(scene, graph, max_readers, segment_bytes, POINT_CHUNK_LEN)
}

/// A [`writer`] whose layers of more than `point_chunk_len` points are published in
/// chunks of that many.
pub(crate) fn writer_chunked(
    scene: &Scene,
    graph: SceneGraph,
    max_readers: usize,
    segment_bytes: usize,
    point_chunk_len: usize,
) -> Res<SceneWriter> {
    let mut w = SceneWriter::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .max_readers(max_readers)
        .initial_segment_bytes(segment_bytes)
        .point_chunk_len(point_chunk_len)
        .create(graph)?;
    w.publish()?;
    Ok(w)
}

/// A case's writer and its reader processes.
pub(super) struct Case {
    /// The writer (its graph already published once).
    pub(super) w: SceneWriter,
    /// The readers, each holding its first snapshot.
    pub(super) readers: Readers,
}

impl Case {
    /// A [`writer`] for `scene` owning `graph` (room for `n` readers and one more, first
    /// segments of `segment_bytes`) and `n` readers in `mode`, querying `query` (a layer
    /// name) if given.
    pub(super) fn start(
        scene: &Scene,
        graph: SceneGraph,
        segment_bytes: usize,
        n: usize,
        mode: &str,
        query: Option<&str>,
    ) -> Res<Case> {
        Self::start_chunked(scene, graph, segment_bytes, n, mode, query, POINT_CHUNK_LEN)
    }

    /// [`Case::start`] with a writer that chunks layers of more than `point_chunk_len`
    /// points.
    pub(super) fn start_chunked(
        scene: &Scene,
        graph: SceneGraph,
        segment_bytes: usize,
        n: usize,
        mode: &str,
        query: Option<&str>,
        point_chunk_len: usize,
    ) -> Res<Case> {
        let w = writer_chunked(scene, graph, n + 1, segment_bytes, point_chunk_len)?;
        let readers = Readers::spawn(n, scene, &reader_args(mode, query), ATTACH_TIMEOUT)?;
        Ok(Case { w, readers })
    }

    /// [`drive`]s the case and [`observe`]s what the readers saw.
    pub(super) fn observe(
        &mut self,
        plan: &Plan,
        warmup: usize,
        n: usize,
        mutate: &mut dyn FnMut(&mut SceneGraph, u64) -> Res<()>,
    ) -> Res<Observed> {
        let (p, s) = drive(plan, &mut self.w, &mut self.readers, warmup, n, mutate)?;
        Ok(observe(&p, &s))
    }

    /// Tells the readers to exit, waits for them, then drops the writer.
    pub(super) fn finish(self) -> Res<()> {
        self.readers.finish(EXIT_GRACE)?;
        drop(self.w);
        Ok(())
    }
}

/// Arguments of `ygg-bench ipc reader` for `mode`, with a nearest-node query on `query`.
pub(crate) fn reader_args(mode: &str, query: Option<&str>) -> Vec<String> {
    let mut a = vec!["--mode".to_owned(), mode.to_owned()];
    if let Some(q) = query {
        a.extend(["--query-layer".to_owned(), q.to_owned()]);
    }
    a
}

/// One publish as the writer saw it.
pub(crate) struct Publish {
    /// The generation it published.
    pub(crate) generation: u64,
    /// Unix ns just before `publish()`.
    pub(crate) t0: u64,
    /// Unix ns just after.
    pub(crate) t1: u64,
    /// Layers it sent.
    pub(crate) layers_sent: usize,
    /// Layers of the cut.
    pub(crate) layers_total: usize,
    /// Bytes it archived into shared memory.
    pub(crate) bytes: usize,
}

/// Per reader: generation -> (visible, answered: Unix ns; the reader thread's CPU ns for
/// the update).
pub(crate) type Seen = HashMap<u64, [u64; 3]>;

/// A tiny deterministic jitter source (±25 %) so publishes do not lock into phase with
/// periodic activity (liveness checks, timers).
pub(crate) struct Jitter(pub(crate) u64);

impl Jitter {
    /// `d` scaled by a factor between 0.75 and 1.25 (the next in the sequence).
    pub(crate) fn apply(&mut self, d: Duration) -> Duration {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        let f = 0.75 + (self.0 % 1000) as f64 / 2000.0;
        d.mul_f64(f)
    }
}

/// Publishes `warmup + n` times (mutating before each), pausing between publishes, then
/// collects what every reader recorded.
fn drive(
    plan: &Plan,
    w: &mut SceneWriter,
    readers: &mut Readers,
    warmup: usize,
    n: usize,
    mutate: &mut dyn FnMut(&mut SceneGraph, u64) -> Res<()>,
) -> Res<(Vec<Publish>, Vec<Seen>)> {
    let mut publishes = Vec::with_capacity(n);
    let mut jitter = Jitter(0x2545_F491_4F6C_DD1D);
    let mut gap = plan.gap;
    for i in 0..(warmup + n) as u64 {
        check_interrupted()?;
        mutate(w.graph_mut(), i)?;
        std::thread::sleep(jitter.apply(gap));
        let t0 = unix_ns();
        let report = w.publish()?;
        let t1 = unix_ns();
        if i >= warmup as u64 {
            publishes.push(Publish {
                generation: report.generation,
                t0,
                t1,
                layers_sent: report.layers_sent,
                layers_total: report.layers_sent + report.layers_unchanged,
                bytes: report.bytes_sent,
            });
        }
        gap = plan
            .gap
            .max(Duration::from_nanos(2 * t1.saturating_sub(t0)));
    }
    std::thread::sleep(gap * 4);
    let seen = collect_seen(readers)?;
    Ok((publishes, seen))
}

/// Asks every reader for its records and reads them (`seen` lines up to `end`).
pub(crate) fn collect_seen(readers: &mut Readers) -> Res<Vec<Seen>> {
    readers.send_all("report")?;
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut seen = Vec::with_capacity(readers.procs.len());
    for p in &mut readers.procs {
        let mut map = Seen::new();
        loop {
            let line = p.line(deadline)?;
            let mut it = line.split_whitespace();
            match it.next() {
                Some("end") => break,
                Some("seen") => {
                    let v: Vec<u64> = it.filter_map(|x| x.parse().ok()).collect();
                    let [g, vis, ans, cpu] = v[..] else {
                        return Err(format!("malformed reader line {line:?}").into());
                    };
                    map.insert(g, [vis, ans, cpu]);
                }
                _ => return Err(format!("unexpected reader line {line:?}").into()),
            }
        }
        seen.push(map);
    }
    Ok(seen)
}

/// Latencies of one driven case, ns.
#[derive(Default)]
pub(crate) struct Observed {
    /// Publish call -> visible, every reader and publish.
    pub(crate) visible: Vec<f64>,
    /// Publish call -> visible in every reader (the slowest), per publish.
    pub(crate) all_visible: Vec<f64>,
    /// Publish call -> first query answered in every reader, per publish.
    pub(crate) all_answered: Vec<f64>,
    /// `publish()` returned -> visible (transport, wake-up, validation), every reader
    /// and publish.
    pub(crate) returned: Vec<f64>,
    /// Duration of `publish()`.
    pub(crate) publish: Vec<f64>,
    /// (reader, publish) pairs a slow reader skipped: timed to the newer snapshot that
    /// first showed the publish to it.
    pub(crate) coalesced: usize,
    /// (reader, publish) pairs no snapshot showed (not timed; should not happen).
    pub(crate) unseen: usize,
    pub(crate) layers_sent: Vec<f64>,
    pub(crate) layers_total: usize,
    pub(crate) bytes: Vec<f64>,
    /// Reader thread CPU per snapshot received, ns, every reader.
    pub(crate) reader_cpu: Vec<f64>,
}

/// What the readers saw of `publishes` (each reader's snapshots by generation).
pub(crate) fn observe(publishes: &[Publish], seen: &[Seen]) -> Observed {
    // Per reader, the snapshots it held, by generation.
    let sorted: Vec<Vec<(u64, [u64; 3])>> = seen
        .iter()
        .map(|s| {
            let mut v: Vec<(u64, [u64; 3])> = s.iter().map(|(g, t)| (*g, *t)).collect();
            v.sort_unstable_by_key(|(g, _)| *g);
            v
        })
        .collect();
    let mut o = Observed::default();
    for p in publishes {
        o.publish.push(p.t1.saturating_sub(p.t0) as f64);
        o.layers_sent.push(p.layers_sent as f64);
        o.layers_total = p.layers_total;
        o.bytes.push(p.bytes as f64);
        let mut slowest: Option<(u64, u64)> = Some((0, 0));
        for s in &sorted {
            // The first snapshot the reader held that contains this publish: its own, or
            // (when a slow reader skipped it) the next newer one.
            let i = s.partition_point(|(g, _)| *g < p.generation);
            match s.get(i) {
                Some(&(g, [vis, ans, cpu])) => {
                    if g != p.generation {
                        o.coalesced += 1;
                    } else {
                        o.reader_cpu.push(cpu as f64);
                    }
                    o.visible.push(vis.saturating_sub(p.t0) as f64);
                    o.returned.push(vis.saturating_sub(p.t1) as f64);
                    slowest = slowest.map(|(v, a)| {
                        (
                            v.max(vis.saturating_sub(p.t0)),
                            a.max(ans.saturating_sub(p.t0)),
                        )
                    });
                }
                None => {
                    o.unseen += 1;
                    slowest = None;
                }
            }
        }
        if let Some((v, a)) = slowest {
            o.all_visible.push(v as f64);
            o.all_answered.push(a as f64);
        }
    }
    o
}

impl Observed {
    /// Adds the common extra numbers to `row`.
    pub(super) fn annotate(&self, mut row: Row) -> Row {
        let (sm, sp) = median_p99_us(&self.returned);
        row = row
            .with("returned_median_us", sm)
            .with("returned_p99_us", sp)
            .with("publish_call_us", median_p99_us(&self.publish).0)
            .with("bytes_per_publish", median(&self.bytes))
            .with("reader_cpu_us", median(&self.reader_cpu) / 1e3)
            .with("skipped_by_slow_reader", self.coalesced as f64);
        if self.unseen > 0 {
            row.note = format!(
                "{} publish(es) never seen by a reader, not timed",
                self.unseen
            );
        }
        row
    }
}

/// What a reader in qps mode reports after `stop`.
pub(super) struct QpsReport {
    pub(super) queries: f64,
    pub(super) elapsed_ns: f64,
    pub(super) median_ns: f64,
    pub(super) p99_ns: f64,
    pub(super) snapshots: f64,
}

impl QpsReport {
    pub(super) fn per_second(&self) -> f64 {
        self.queries / (self.elapsed_ns / 1e9)
    }
}

/// Reads one `qps` line per reader.
pub(super) fn qps_lines(readers: &mut Readers) -> Res<Vec<QpsReport>> {
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut out = Vec::new();
    for p in &mut readers.procs {
        let line = p.expect("qps", deadline)?;
        let v: Vec<f64> = line
            .split_whitespace()
            .skip(1)
            .filter_map(|x| x.parse().ok())
            .collect();
        let [queries, elapsed_ns, median_ns, p99_ns, snapshots] = v[..] else {
            return Err(format!("malformed qps line {line:?}").into());
        };
        out.push(QpsReport {
            queries,
            elapsed_ns,
            median_ns,
            p99_ns,
            snapshots,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_skipped_publish_is_timed_to_the_newer_snapshot() {
        let publish = |generation, t0| Publish {
            generation,
            t0,
            t1: t0 + 10,
            layers_sent: 1,
            layers_total: 1,
            bytes: 100,
        };
        let publishes = [publish(1, 1_000), publish(2, 2_000), publish(3, 3_000)];
        // Reader 0 saw every publish; reader 1 skipped generation 2.
        let r0: Seen = [
            (1, [1_100, 1_200, 7]),
            (2, [2_100, 2_200, 7]),
            (3, [3_100, 3_200, 7]),
        ]
        .into_iter()
        .collect();
        let r1: Seen = [(1, [1_300, 1_400, 9]), (3, [3_500, 3_600, 9])]
            .into_iter()
            .collect();
        let o = observe(&publishes, &[r0, r1]);
        assert_eq!((o.coalesced, o.unseen), (1, 0));
        // Generation 2 became visible to reader 1 with generation 3, at 3_500.
        assert_eq!(o.all_visible, vec![300.0, 1_500.0, 500.0]);
        assert_eq!(o.all_answered, vec![400.0, 1_600.0, 600.0]);
        assert_eq!(o.visible.len(), 6);
        // CPU of the snapshots that were the publish's own, not of a skipped one.
        assert_eq!(o.reader_cpu.len(), 5);
        // After publish() returned (t0 + 10): reader 0's first snapshot at 1_100.
        assert_eq!(o.returned[0], 90.0);
    }
}
