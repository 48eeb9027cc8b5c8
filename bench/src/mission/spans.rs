//! The tick ranges a mission run reports on, and what is computed over each.
//!
//! *Windows* are the points of a mission (the first ticks, around 10,000, 36,000
//! and 100,000, and the last ticks), each `len` ticks; *bins* cut the whole run into
//! about 100 equal parts for the plots. Both are [`Span`]s; the run stops at every span
//! boundary (a *mark*) to let the readers catch up and to read `/proc`, so per-span
//! numbers never mix two spans' work.

use crate::ipc::cases::{Publish, Seen, observe};
use crate::ipc::report::median;
use serde_json::{Map, Value, json};
use std::collections::BTreeSet;
use ygg_testkit::stats::median_p99;

/// Centres of the windows after the first one (ticks; 30 Hz: 5.6, 20 and 55 min).
pub const CENTRES: [u64; 3] = [10_000, 36_000, 100_000];

/// Whether a span is one of the windows or a bin of the plots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A window: its numbers go to the tables, and a late reader attaches at its end.
    Window,
    /// A bin: its numbers go to the plots.
    Bin,
}

/// A range of ticks `[start, end)` (tick `i` is the `i`-th publish after the first).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Span {
    /// `first 1,000`, `around 10,000`, `last 1,000`; for bins, the range.
    pub name: String,
    /// First tick.
    pub start: u64,
    /// One past the last tick.
    pub end: u64,
    /// Window or bin.
    pub kind: Kind,
}

/// `12345` as `12,345`.
pub fn thousands(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// The windows of a run of `ticks` ticks, `len` ticks each: the first ticks; one around
/// each of [`CENTRES`] the run reaches (the last one ends with the run when the run ends
/// before its second half); the last ticks, when they overlap none of those.
pub fn windows(ticks: u64, len: u64) -> Vec<Span> {
    let len = len.clamp(1, ticks.max(1));
    let mut out = vec![Span {
        name: format!("first {}", thousands(len)),
        start: 0,
        end: len,
        kind: Kind::Window,
    }];
    for c in CENTRES.into_iter().filter(|&c| c <= ticks) {
        let end = (c + len / 2).min(ticks);
        let start = end - len;
        if start >= out.last().map_or(0, |w| w.end) {
            out.push(Span {
                name: format!("around {}", thousands(c)),
                start,
                end,
                kind: Kind::Window,
            });
        }
    }
    let last_end = out.last().map_or(0, |w| w.end);
    if ticks >= last_end + len {
        out.push(Span {
            name: format!("last {}", thousands(len)),
            start: ticks - len,
            end: ticks,
            kind: Kind::Window,
        });
    }
    out
}

/// Bins of `max(ticks / 100, 10)` ticks over the whole run (the last may be shorter).
pub fn bins(ticks: u64) -> Vec<Span> {
    let len = (ticks / 100).max(10);
    (0..ticks.div_ceil(len))
        .map(|i| {
            let (start, end) = (i * len, ((i + 1) * len).min(ticks));
            Span {
                name: format!("{start}-{end}"),
                start,
                end,
                kind: Kind::Bin,
            }
        })
        .collect()
}

/// The bare iceoryx2 floor over `ticks` (the first numbered `first`): each bare publish
/// call's duration and, for each one the subscriber recorded (`log`, by tick number), the
/// time from before the call to the subscriber holding the bytes; ns.
fn bare_floor(first: u64, ticks: &[Tick], log: &Log) -> (Vec<f64>, Vec<f64>) {
    let mut calls = Vec::with_capacity(ticks.len());
    let mut visible = Vec::with_capacity(ticks.len());
    for (n, t) in (first..).zip(ticks).filter(|(_, t)| t.bare_t0 > 0) {
        calls.push(t.bare_call_ns as f64);
        if let Ok(at) = log.binary_search_by_key(&n, |(seq, _)| *seq) {
            visible.push(log[at].1[0].saturating_sub(t.bare_t0) as f64);
        }
    }
    (calls, visible)
}

/// Every tick count at which some span starts or ends, ascending, with 0.
pub fn marks(spans: &[Span]) -> Vec<u64> {
    let set: BTreeSet<u64> = std::iter::once(0)
        .chain(spans.iter().flat_map(|s| [s.start, s.end]))
        .collect();
    set.into_iter().collect()
}

/// One tick as the writer measured it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Tick {
    /// The generation its publish made.
    pub generation: u64,
    /// Unix ns just before `publish()`.
    pub t0: u64,
    /// Unix ns just after.
    pub t1: u64,
    /// The stream's step (and the window's trim) before the publish, ns.
    pub update_ns: u64,
    /// `PublishReport::bytes_sent`.
    pub bytes: usize,
    /// `PublishReport::layers_sent`.
    pub layers_sent: usize,
    /// `PublishReport::chunks_sent`.
    pub chunks_sent: usize,
    /// `PublishReport::segments`: what a reader's join walks.
    pub segments: usize,
    /// With `--bare`: Unix ns just before the bare publish of as many bytes (0: none).
    pub bare_t0: u64,
    /// With `--bare`: how long that publish call took, ns.
    pub bare_call_ns: u64,
}

/// What one reader process looked like at a mark (`/proc`, the readers idle).
#[derive(Clone, Copy, Debug, Default)]
pub struct ProcSample {
    /// CPU time of the whole process, ns.
    pub cpu_ns: u64,
    /// Resident memory, bytes (`VmRSS`: private memory and the shared memory it touched).
    pub rss: u64,
    /// Resident private memory, bytes (`RssAnon`).
    pub rss_anon: u64,
}

/// One reader's snapshots, ascending by generation: (generation, [visible Unix ns,
/// answered Unix ns, thread CPU ns of the update]).
pub type Log = Vec<(u64, [u64; 3])>;

/// The numbers of one span that do not come from the readers' logs.
pub struct Around<'a> {
    /// The ticks of the span, in order.
    pub ticks: &'a [Tick],
    /// Each reader at the span's start and at its end.
    pub readers_start: &'a [ProcSample],
    /// Each reader at the span's end.
    pub readers_end: &'a [ProcSample],
    /// The writer (this process) at the span's end.
    pub writer_end: ProcSample,
    /// Nodes of the graph at the span's end.
    pub nodes: usize,
    /// With `--bare`: the bare subscriber's records, by tick number (ascending).
    pub bare: Option<&'a Log>,
}

/// Metrics of a span: a flat map of numbers (keys end in their unit: `_us`, `_ms`,
/// `_mb`, `_bytes`) and the per-reader details.
pub fn compute(span: &Span, around: &Around<'_>, logs: &[Log]) -> Value {
    let publishes: Vec<Publish> = around
        .ticks
        .iter()
        .map(|t| Publish {
            generation: t.generation,
            t0: t.t0,
            t1: t.t1,
            layers_sent: t.layers_sent,
            layers_total: 0,
            bytes: t.bytes,
        })
        .collect();
    let (first, last) = match (around.ticks.first(), around.ticks.last()) {
        (Some(f), Some(l)) => (f.generation, l.generation),
        _ => (0, 0),
    };
    let mut m = Map::new();
    let mut put = |k: &str, v: f64| {
        m.insert(k.to_owned(), json!(finite(v)));
    };
    let ns =
        |f: fn(&Tick) -> u64| -> Vec<f64> { around.ticks.iter().map(|t| f(t) as f64).collect() };
    let publish = ns(|t| t.t1.saturating_sub(t.t0));
    let bytes = ns(|t| t.bytes as u64);
    put("publish_median_us", median(&publish) / 1e3);
    put("publish_mean_us", mean(&publish) / 1e3);
    put("update_mean_us", mean(&ns(|t| t.update_ns)) / 1e3);
    put("bytes_median_bytes", median(&bytes));
    put("bytes_mean_bytes", mean(&bytes));
    put("layers_sent_mean", mean(&ns(|t| t.layers_sent as u64)));
    put("chunks_sent_mean", mean(&ns(|t| t.chunks_sent as u64)));
    put("segments_mean", mean(&ns(|t| t.segments as u64)));
    let mut readers = Vec::new();
    let mut seen_all = Vec::new();
    for (i, log) in logs.iter().enumerate() {
        // The snapshots that can show this span's publishes: from its first generation to
        // the first one at or past its last (a reader that skipped the last publish saw it
        // in a newer snapshot).
        let a = log.partition_point(|(g, _)| *g < first);
        let b = (log.partition_point(|(g, _)| *g < last) + 1).min(log.len());
        let seen: Seen = log[a..b].iter().copied().collect();
        let received = log[a..b].iter().filter(|(g, _)| *g <= last).count();
        let o = observe(&publishes, std::slice::from_ref(&seen));
        seen_all.push(seen);
        let (p50, p99) = median_p99(&o.visible).unwrap_or((f64::NAN, f64::NAN));
        let (start, end) = (around.readers_start[i], around.readers_end[i]);
        let proc_cpu = end.cpu_ns.saturating_sub(start.cpu_ns) as f64 / received.max(1) as f64;
        readers.push(json!({
            "visible_p50_us": finite(p50 / 1e3),
            "visible_p99_us": finite(p99 / 1e3),
            "returned_p50_us": finite(median(&o.returned) / 1e3),
            "cpu_median_us": finite(median(&o.reader_cpu) / 1e3),
            "cpu_mean_us": finite(mean(&o.reader_cpu) / 1e3),
            "proc_cpu_us": finite(proc_cpu / 1e3),
            "snapshots": received,
            "skipped": o.coalesced,
            "unseen": o.unseen,
            "rss_mb": end.rss as f64 / 1e6,
            "rss_anon_mb": end.rss_anon as f64 / 1e6,
        }));
    }
    let each = |k: &str| -> Vec<f64> {
        readers
            .iter()
            .filter_map(|r| r[k].as_f64())
            .collect::<Vec<_>>()
    };
    let max = |v: Vec<f64>| v.into_iter().fold(f64::NAN, f64::max);
    let worst_p50_us = max(each("visible_p50_us"));
    put("visible_p50_us", worst_p50_us);
    put("visible_p99_us", max(each("visible_p99_us")));
    let all = observe(&publishes, &seen_all);
    put(
        "slowest_p99_us",
        median_p99(&all.all_visible).map_or(f64::NAN, |(_, p)| p / 1e3),
    );
    put("reader_cpu_us", median(&each("cpu_median_us")));
    put("reader_cpu_mean_us", mean(&each("cpu_mean_us")));
    put("reader_proc_cpu_us", median(&each("proc_cpu_us")));
    let pairs = (publishes.len() * logs.len()).max(1) as f64;
    put("skipped_share", all.coalesced as f64 / pairs);
    put("reader_rss_mb", max(each("rss_mb")));
    put("reader_rss_anon_mb", max(each("rss_anon_mb")));
    put("writer_rss_mb", around.writer_end.rss as f64 / 1e6);
    put(
        "writer_rss_anon_mb",
        around.writer_end.rss_anon as f64 / 1e6,
    );
    put("nodes", around.nodes as f64);
    if let Some(log) = around.bare {
        let (calls, visible) = bare_floor(span.start, around.ticks, log);
        let call = median(&calls);
        let p50 = median(&visible);
        put("bare_publish_us", call / 1e3);
        put("bare_visible_p50_us", p50 / 1e3);
        put("publish_vs_bare", median(&publish) / call);
        put("visible_vs_bare", worst_p50_us * 1e3 / p50);
    }
    json!({
        "name": span.name,
        "start": span.start,
        "end": span.end,
        "m": m,
        "readers": readers,
    })
}

/// Mean (NaN when empty).
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// `v`, or JSON's null for NaN and infinities.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_beyond_the_run_are_left_out_and_the_last_one_ends_with_it() {
        let at = |ticks| -> Vec<(String, u64, u64)> {
            windows(ticks, 1_000)
                .into_iter()
                .map(|w| (w.name, w.start, w.end))
                .collect()
        };
        assert_eq!(
            at(100_000),
            [
                ("first 1,000".into(), 0, 1_000),
                ("around 10,000".into(), 9_500, 10_500),
                ("around 36,000".into(), 35_500, 36_500),
                ("around 100,000".into(), 99_000, 100_000),
            ]
        );
        assert_eq!(
            at(10_000),
            [
                ("first 1,000".into(), 0, 1_000),
                ("around 10,000".into(), 9_000, 10_000)
            ]
        );
        assert_eq!(
            at(3_000),
            [
                ("first 1,000".into(), 0, 1_000),
                ("last 1,000".into(), 2_000, 3_000)
            ]
        );
        assert_eq!(at(300), [("first 300".into(), 0, 300)]);
        assert_eq!(at(1_500), [("first 1,000".into(), 0, 1_000)]);
    }

    #[test]
    fn bins_cover_the_run_and_marks_every_boundary() {
        let b = bins(1_005);
        assert_eq!(b.len(), 101);
        assert_eq!(
            (b[0].start, b[0].end, b[100].start, b[100].end),
            (0, 10, 1_000, 1_005)
        );
        let mut spans = windows(1_005, 100);
        spans.extend(b);
        let m = marks(&spans);
        assert_eq!(m.first(), Some(&0));
        assert_eq!(m.last(), Some(&1_005));
        assert!(m.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(thousands(1_234_567), "1,234,567");
        assert_eq!(thousands(999), "999");
    }

    #[test]
    fn a_span_reports_publish_bytes_latency_and_cpu() {
        let ticks: Vec<Tick> = (1..=4u64)
            .map(|g| Tick {
                generation: g,
                t0: g * 1_000_000,
                t1: g * 1_000_000 + 2_000,
                update_ns: 500,
                bytes: 100 * g as usize,
                layers_sent: 1,
                chunks_sent: 0,
                segments: 40,
                // A bare publish half a millisecond after each tick, 1 µs long.
                bare_t0: g * 1_000_000 + 500_000,
                bare_call_ns: 1_000,
            })
            .collect();
        // The bare subscriber held ticks 0, 1 and 3 (numbered from the span's start) 4 µs
        // after their calls; tick 2 it never saw.
        let bare: Log = [0u64, 1, 3]
            .iter()
            .map(|&n| (n, [(n + 1) * 1_000_000 + 504_000, 0, 2_000]))
            .collect();
        // The reader saw generations 1, 2 and 4 (3 in 4), 10 µs after each publish call,
        // and generation 5 of the next span.
        let log: Log = [1u64, 2, 4, 5]
            .iter()
            .map(|&g| (g, [g * 1_000_000 + 10_000, 0, 3_000]))
            .collect();
        let sample = |cpu_ns| ProcSample {
            cpu_ns,
            rss: 2_000_000,
            rss_anon: 1_000_000,
        };
        let span = Span {
            name: "t".into(),
            start: 0,
            end: 4,
            kind: Kind::Window,
        };
        let v = compute(
            &span,
            &Around {
                ticks: &ticks,
                readers_start: &[sample(0)],
                readers_end: &[sample(30_000)],
                writer_end: sample(0),
                nodes: 7,
                bare: Some(&bare),
            },
            &[log],
        );
        let m = &v["m"];
        assert_eq!(m["publish_median_us"], 2.0);
        assert_eq!(m["bytes_mean_bytes"], 250.0);
        // Publish 3 became visible with generation 4: 1,010 µs after its call.
        assert_eq!(m["visible_p50_us"], 10.0);
        assert_eq!(m["visible_p99_us"], 1_010.0);
        assert_eq!(m["reader_cpu_us"], 3.0);
        // 30 µs of process CPU over the 3 snapshots of this span.
        assert_eq!(m["reader_proc_cpu_us"], 10.0);
        assert_eq!(v["readers"][0]["skipped"], 1);
        assert_eq!(m["skipped_share"], 0.25);
        assert_eq!(m["reader_rss_mb"], 2.0);
        assert_eq!(m["bare_publish_us"], 1.0);
        assert_eq!(m["bare_visible_p50_us"], 4.0);
        assert_eq!(m["publish_vs_bare"], 2.0);
        assert_eq!(m["visible_vs_bare"], 2.5);
    }
}
