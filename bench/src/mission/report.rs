//! The mission report: medians over each build's runs, a table per window (baseline,
//! new, ratio), the targets, an SVG of the bins (ticks on x), and the JSON.

use super::args::{Config, FORMAT};
use super::spans::thousands;
use crate::ipc::report::{fmt_bytes, fmt_us, hand_written_section, median};
use plotters::prelude::*;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Heading of the report's hand-written section, kept when the report is written again.
pub const NOTES: &str = "## Notes";

/// The hand-written section of an earlier report, if it has one.
pub fn notes(md: &str) -> Option<String> {
    hand_written_section(md, NOTES)
}

/// The numbers of the tables, in order: key and label (with its unit).
const METRICS: [(&str, &str); 26] = [
    ("publish_median_us", "`publish()` per tick, median"),
    ("publish_mean_us", "`publish()` per tick, mean"),
    ("update_mean_us", "stream step per tick, mean"),
    ("bytes_median_bytes", "bytes published per tick, median"),
    ("bytes_mean_bytes", "bytes published per tick, mean"),
    ("layers_sent_mean", "segments (layers) sent per tick, mean"),
    ("segments_mean", "segments a cut names, mean"),
    ("visible_p50_us", "publish → visible p50, worst reader"),
    ("visible_p99_us", "publish → visible p99, worst reader"),
    ("slowest_p99_us", "publish → visible in every reader, p99"),
    ("reader_cpu_us", "reader CPU per update, thread, median"),
    ("reader_cpu_mean_us", "reader CPU per update, thread, mean"),
    ("reader_proc_cpu_us", "reader CPU per update, whole process"),
    (
        "skipped_share",
        "publishes a reader skipped (saw a newer one first)",
    ),
    ("attach_ms", "late reader: start → first answer (ms)"),
    (
        "attach_from_spawn_ms",
        "late reader: spawn → first answer (ms)",
    ),
    ("attach_cpu_ms", "late reader: CPU until its answer (ms)"),
    ("writer_rss_mb", "writer RSS (MB)"),
    ("writer_rss_anon_mb", "writer private RSS (MB)"),
    ("reader_rss_mb", "reader RSS, largest (MB)"),
    ("reader_rss_anon_mb", "reader private RSS, largest (MB)"),
    ("nodes", "nodes in the scene at the window's end"),
    (
        "bare_publish_us",
        "bare iceoryx2, same bytes: publish call, median",
    ),
    (
        "bare_visible_p50_us",
        "bare iceoryx2, same bytes: publish → subscriber holds them, p50",
    ),
    (
        "publish_vs_bare",
        "`publish()` median / bare publish call median",
    ),
    (
        "visible_vs_bare",
        "publish → visible p50, worst reader / bare p50",
    ),
];

/// One build's runs.
pub struct Side {
    /// `baseline`, `new` or `this build`.
    pub label: &'static str,
    /// Its `ygg-bench`.
    pub binary: PathBuf,
    /// Each run's result.
    pub runs: Vec<Value>,
}

impl Side {
    /// A build with no runs yet.
    pub fn new(label: &'static str, binary: PathBuf) -> Side {
        Side {
            label,
            binary,
            runs: Vec::new(),
        }
    }
}

/// A span's numbers: medians over a build's runs.
struct Agg {
    name: String,
    start: u64,
    end: u64,
    m: BTreeMap<String, f64>,
    /// Per reader: visible p50 and p99, thread CPU per update (µs).
    readers: Vec<[f64; 3]>,
}

/// Medians over `runs` of each span of `key` (`windows` or `bins`), matched by position.
fn aggregate(runs: &[Value], key: &str) -> Vec<Agg> {
    let Some(first) = runs.first().and_then(|r| r[key].as_array()) else {
        return Vec::new();
    };
    first
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let spans: Vec<&Value> = runs.iter().map(|r| &r[key][i]).collect();
            let over = |f: &dyn Fn(&Value) -> Option<f64>| -> f64 {
                median(&spans.iter().filter_map(|s| f(s)).collect::<Vec<_>>())
            };
            let m = s["m"]
                .as_object()
                .map(|o| {
                    o.keys()
                        .map(|k| (k.clone(), over(&|s| s["m"][k].as_f64())))
                        .collect()
                })
                .unwrap_or_default();
            let readers = (0..s["readers"].as_array().map_or(0, Vec::len))
                .map(|r| {
                    ["visible_p50_us", "visible_p99_us", "cpu_median_us"]
                        .map(|k| over(&|s| s["readers"][r][k].as_f64()))
                })
                .collect();
            Agg {
                name: s["name"].as_str().unwrap_or("").to_owned(),
                start: s["start"].as_u64().unwrap_or(0),
                end: s["end"].as_u64().unwrap_or(0),
                m,
                readers,
            }
        })
        .collect()
}

/// One build's medians.
struct SideAgg {
    side: Side,
    windows: Vec<Agg>,
    bins: Vec<Agg>,
}

impl SideAgg {
    fn run_median(&self, key: &str) -> f64 {
        median(
            &self
                .side
                .runs
                .iter()
                .filter_map(|r| r[key].as_f64())
                .collect::<Vec<_>>(),
        )
    }
}

/// Everything the benchmark measured.
pub struct Report {
    sides: Vec<SideAgg>,
    cfg: Config,
    command: String,
    elapsed: Duration,
}

impl Report {
    /// The report of `sides` (baseline first, if any).
    pub fn new(sides: Vec<Side>, cfg: &Config, command: String, elapsed: Duration) -> Report {
        let sides = sides
            .into_iter()
            .map(|side| SideAgg {
                windows: aggregate(&side.runs, "windows"),
                bins: aggregate(&side.runs, "bins"),
                side,
            })
            .collect();
        Report {
            sides,
            cfg: cfg.clone(),
            command,
            elapsed,
        }
    }

    /// Every run's result and the medians.
    pub fn to_json(&self) -> Value {
        let spans = |v: &[Agg]| -> Value {
            v.iter()
                .map(|a| json!({"name": a.name, "start": a.start, "end": a.end, "m": a.m, "readers": a.readers}))
                .collect()
        };
        json!({
            "format": FORMAT,
            "command": self.command,
            "config": self.cfg.to_json(),
            "elapsed_s": self.elapsed.as_secs_f64(),
            "sides": self.sides.iter().map(|s| json!({
                "label": s.side.label,
                "binary": s.side.binary.display().to_string(),
                "windows": spans(&s.windows),
                "bins": spans(&s.bins),
                "runs": s.side.runs,
            })).collect::<Vec<_>>(),
        })
    }

    /// The markdown report; `name` is the files' base name, `notes` a hand-written
    /// section to keep.
    pub fn markdown(&self, name: &str, notes: Option<&str>) -> String {
        let cfg = &self.cfg;
        let first_run = self.sides.iter().find_map(|s| s.side.runs.first());
        let machine = first_run.map_or(Value::Null, |r| r["machine"].clone());
        let mut md = format!(
            "# Mission benchmark: the demo's SLAM stream for {} ticks\n\n",
            thousands(cfg.ticks)
        );
        md += "Written by `ygg-bench mission` (bench/src/mission/); see the method at the end.\n\n";
        md += &format!("- Command: `{}`\n", self.command);
        md += &format!(
            "- Machine: {}, {} cores; load average at the start {}\n",
            machine["cpu"].as_str().unwrap_or("?"),
            machine["cores"],
            machine["loadavg"].as_str().unwrap_or("?")
        );
        md += &format!(
            "- Stream: the built-in office (scale 1, mint), `SlamReplay` seed 7, {} ticks {}, {} reader process(es), {}\n",
            thousands(cfg.ticks),
            if cfg.rate > 0.0 {
                format!("at {} Hz", cfg.rate)
            } else {
                "as fast as the writer goes".to_owned()
            },
            cfg.readers,
            cfg.keep_poses
                .map_or("every pose kept".to_owned(), |k| format!(
                    "the newest {k} poses kept (--keep-poses)"
                ))
        );
        for s in &self.sides {
            md += &format!(
                "- `{}`: `{}`; {} run(s), {:.0} s each (median; {:.0} s of ticks), nodes {} → {}\n",
                s.side.label,
                s.side.binary.display(),
                s.side.runs.len(),
                s.run_median("duration_s"),
                s.run_median("ticks_s"),
                s.run_median("nodes_start"),
                s.run_median("nodes_end"),
            );
        }
        md += &format!(
            "- Whole benchmark: {:.0} s; numbers are medians over runs{}\n",
            self.elapsed.as_secs_f64(),
            if self.sides.len() > 1 {
                " (the builds' runs alternate ABBA)"
            } else {
                ""
            }
        );
        md += &self.window_tables();
        md += &self.targets();
        md += &format!(
            "\n## Plots\n\n![mission plots]({name}.svg)\n\nTicks on x (bins of about 1 % of the run; late readers at the end of each window); log scales.\n"
        );
        if let Some(n) = notes {
            md += "\n";
            md += n.trim_end();
            md += "\n";
        }
        md += "\n## Method\n\n";
        for n in method() {
            md += &format!("- {n}\n");
        }
        let leftovers: Vec<String> = self
            .sides
            .iter()
            .flat_map(|s| &s.side.runs)
            .filter_map(|r| r["leftovers"].as_str().map(str::to_owned))
            .collect();
        md += &format!(
            "- Shared-memory files left after the runs: {}.\n",
            if leftovers.is_empty() {
                "none".to_owned()
            } else {
                leftovers.join("; ")
            }
        );
        md
    }

    /// A table per window: each build's numbers and, with two, their ratio.
    fn window_tables(&self) -> String {
        let mut md = "\n## Windows\n".to_owned();
        let Some(first) = self.sides.first() else {
            return md;
        };
        let paired = self.sides.len() == 2;
        for (i, w) in first.windows.iter().enumerate() {
            md += &format!(
                "\n### {} (ticks {}–{})\n\n|  |",
                w.name,
                thousands(w.start),
                thousands(w.end)
            );
            for s in &self.sides {
                md += &format!(" {} |", s.side.label);
            }
            md += if paired {
                " new / baseline |\n|---|---|---|---|\n"
            } else {
                "\n|---|---|\n"
            };
            let at = |s: &SideAgg, k: &str| s.windows.get(i).and_then(|w| w.m.get(k)).copied();
            for (key, label) in METRICS {
                let values: Vec<Option<f64>> = self.sides.iter().map(|s| at(s, key)).collect();
                if values.iter().all(|v| v.is_none_or(f64::is_nan)) {
                    continue;
                }
                md += &format!("| {label} |");
                for v in &values {
                    md += &format!(" {} |", v.map_or("–".to_owned(), |v| fmt_value(key, v)));
                }
                if paired {
                    md += &format!(" {} |", fmt_ratio(values[0], values[1]));
                }
                md += "\n";
            }
            if self.cfg.readers > 1 {
                md += "| each reader: publish → visible p50 / p99 |";
                for s in &self.sides {
                    let each: Vec<String> = s
                        .windows
                        .get(i)
                        .map(|w| {
                            w.readers
                                .iter()
                                .map(|r| format!("{}/{}", fmt_us(r[0]), fmt_us(r[1])))
                                .collect()
                        })
                        .unwrap_or_default();
                    md += &format!(" {} |", each.join(", "));
                }
                md += if paired { " |\n" } else { "\n" };
            }
        }
        md
    }

    /// The targets, on the last build (the new one): the last window against the
    /// first.
    fn targets(&self) -> String {
        let Some(s) = self.sides.last() else {
            return String::new();
        };
        let (Some(first), Some(last)) = (s.windows.first(), s.windows.last()) else {
            return String::new();
        };
        let mut md = format!(
            "\n## Targets of issue 38 (`{}`: {} against {})\n\n| target | first window | last window | ratio | met |\n|---|---|---|---|---|\n",
            s.side.label, last.name, first.name
        );
        let get = |w: &Agg, k: &str| w.m.get(k).copied().unwrap_or(f64::NAN);
        for (key, what, bound) in [
            ("publish_median_us", "`publish()` per tick ≤ 1.3×", 1.3),
            ("bytes_median_bytes", "bytes per tick ≤ 1.3×", 1.3),
            ("reader_cpu_us", "reader CPU per update ≤ 1.3×", 1.3),
            ("visible_p50_us", "publish → visible p50 ≤ 1.3×", 1.3),
            ("attach_ms", "attach to first answer ≤ 2×", 2.0),
        ] {
            let (a, b) = (get(first, key), get(last, key));
            let ratio = b / a;
            md += &format!(
                "| {what} | {} | {} | {} | {} |\n",
                fmt_value(key, a),
                fmt_value(key, b),
                fmt_ratio(Some(a), Some(b)),
                met(ratio.is_finite().then_some(ratio <= bound))
            );
        }
        let most = s
            .bins
            .iter()
            .map(|b| get(b, "bytes_median_bytes"))
            .fold(f64::NAN, f64::max);
        md += &format!(
            "| bytes per pose tick ≤ 24 KB at any point (largest bin median) | | {} | | {} |\n",
            fmt_bytes(most),
            met(most.is_finite().then_some(most <= 24e3))
        );
        // Against the bare iceoryx2 floor of the same run (`--bare`), in every window.
        for (key, what, bound) in [
            (
                "publish_vs_bare",
                "`publish()` ≤ 2× bare iceoryx2's publish call",
                2.0,
            ),
            (
                "visible_vs_bare",
                "publish → visible p50 (worst reader) ≤ 2.5× bare iceoryx2's",
                2.5,
            ),
        ] {
            let (a, b) = (get(first, key), get(last, key));
            if a.is_finite() || b.is_finite() {
                let worst = s
                    .windows
                    .iter()
                    .map(|w| get(w, key))
                    .fold(f64::NAN, f64::max);
                md += &format!(
                    "| {what}, every window (largest: {worst:.2}×) | {a:.2}× | {b:.2}× | | {} |\n",
                    met(worst.is_finite().then_some(worst <= bound))
                );
            }
        }
        md
    }

    /// The plots: one panel per measure, ticks on x, every build.
    pub fn plot_svg(&self, path: &Path) -> Result<(), Box<dyn std::error::Error>> {
        // Per panel: its title and its series (legend, from the windows rather than the
        // bins, metric, scale).
        let panels: [(&str, &[Series]); 6] = [
            (
                "publish() per tick, µs",
                &[
                    ("mean", false, "publish_mean_us", 1.0),
                    ("median", false, "publish_median_us", 1.0),
                ],
            ),
            (
                "bytes published per tick, KB",
                &[("mean", false, "bytes_mean_bytes", 1e-3)],
            ),
            (
                "publish → visible, worst reader, µs",
                &[
                    ("p50", false, "visible_p50_us", 1.0),
                    ("p99", false, "visible_p99_us", 1.0),
                ],
            ),
            (
                "reader CPU per update, µs",
                &[
                    ("thread median", false, "reader_cpu_us", 1.0),
                    ("process", false, "reader_proc_cpu_us", 1.0),
                ],
            ),
            (
                "late reader: start → first answer, ms",
                &[("attach", true, "attach_ms", 1.0)],
            ),
            (
                "RSS, MB",
                &[
                    ("writer", false, "writer_rss_mb", 1.0),
                    ("reader", false, "reader_rss_mb", 1.0),
                ],
            ),
        ];
        let root = SVGBackend::new(path, (1300, 1150)).into_drawing_area();
        root.fill(&WHITE)?;
        let areas = root.split_evenly((3, 2));
        let x_max = self.cfg.ticks.max(1) as f64;
        for (area, (title, series)) in areas.iter().zip(panels) {
            // (legend, points) of every series of every build.
            let mut lines: Vec<Line> = Vec::new();
            for s in &self.sides {
                for &(name, windows, key, scale) in series {
                    let spans = if windows { &s.windows } else { &s.bins };
                    let points: Vec<(f64, f64)> = spans
                        .iter()
                        .filter_map(|a| Some((a.end as f64, a.m.get(key)? * scale)))
                        .filter(|(_, y)| y.is_finite() && *y > 0.0)
                        .collect();
                    lines.push((format!("{} {name}", s.side.label), windows, points));
                }
            }
            let (lo, hi) = lines
                .iter()
                .flat_map(|(_, _, p)| p.iter().map(|(_, y)| *y))
                .fold((f64::MAX, 0f64), |(a, b), y| (a.min(y), b.max(y)));
            // A log axis labels its powers of ten only: a narrow range is widened to hold one.
            let pad = if hi < 10.0 * lo { 3.2 } else { 1.5 };
            let (lo, hi) = if hi > 0.0 {
                (lo / pad, hi * pad)
            } else {
                (0.1, 10.0)
            };
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 18))
                .margin(10)
                .x_label_area_size(35)
                .y_label_area_size(60)
                .build_cartesian_2d(0f64..x_max, (lo..hi).log_scale())?;
            chart
                .configure_mesh()
                .x_desc("tick")
                .x_label_formatter(&|x| thousands(*x as u64))
                .draw()?;
            for (i, (legend, windows, points)) in lines.into_iter().enumerate() {
                let color = Palette99::pick(i).to_rgba();
                let style = color.stroke_width(2);
                let series = chart.draw_series(LineSeries::new(points.clone(), style))?;
                series
                    .label(legend)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], style));
                if windows {
                    chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, color.filled())))?;
                }
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()?;
        }
        root.present()?;
        Ok(())
    }
}

/// A series of a plot panel: legend, from the windows (not the bins), metric, scale.
type Series = (&'static str, bool, &'static str, f64);
/// A line drawn: legend, from the windows, points.
type Line = (String, bool, Vec<(f64, f64)>);

/// How the numbers were measured.
fn method() -> [&'static str; 8] {
    [
        "Each run is a process of its own (`ygg-bench mission --leaf`): it builds the office, creates the writer (room for the readers and a late one), publishes it, starts the reader processes (`ygg-bench ipc reader --mode latency`, the ipc benchmark's reader, each on a fresh scene name and iceoryx2 prefix) and then runs the ticks. A tick is one `SlamReplay::step` (an agent pose appended every tick, an object moved every 30, a mesh patch every 15, a new object every 150), the `--keep-poses` window's trim, and one `SceneWriter::publish()`.",
        "`publish()` per tick: the call's wall time in the writer; bytes per tick: its `PublishReport::bytes_sent` (layer segments, chunks and the manifest archived into shared memory).",
        "Publish → visible: Unix ns taken in the writer just before `publish()` to Unix ns taken in the reader once `SceneReader::wait_next` returned the validated snapshot and its view was built (same host clock). A publish a reader skipped (it woke to a newer one) is timed to that newer snapshot. Reader CPU per update: the reader thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`) from the `wait_next` call that returned the snapshot to its view, per snapshot received; whole process: the reader process's CPU time over the window (the sum of its threads' `/proc/<pid>/task/*/schedstat`) divided by the snapshots it received.",
        "At every span boundary (windows and plot bins) the writer stops until every reader holds the newest snapshot (it asks for their records until they include it), then reads `/proc`: the numbers of a span are its own. RSS is `VmRSS` (it counts the shared memory a process touched) and `RssAnon` (private memory); the writer's includes the benchmark's own bookkeeping (the ticks and reader records of the open spans only).",
        "Late reader: at the end of each window, with the writer and the readers idle, a new reader process (`ygg-bench ipc reader --mode attach`) opens the scene, waits for its first snapshot and answers a nearest-node query on PLACES; start → answer is timed inside it from its `main`, spawn → answer from the benchmark. Several start one after the other; the table gives their median.",
        "Windows: the first `--window` ticks, `--window` ticks centred on 10,000, 36,000 and 100,000 (a window past the run's end is left out; one whose second half is past it ends with the run), and the last ticks when they overlap none of those. The targets compare the last window with the first.",
        "With `--against`, the other build's `ygg-bench` runs the same command (`mission --leaf` with the same options), so both builds run this benchmark's code and differ only in the store, writer and reader they link; runs alternate ABBA and every number is the median over a build's runs.",
        "A run that exceeds its watchdog (`--timeout-min`) is killed, its readers die with it (parent-death signal) and its shared-memory files are removed; Ctrl-C stops every process and removes them too.",
    ]
}

/// A value of metric `key` for the tables.
fn fmt_value(key: &str, v: f64) -> String {
    if !v.is_finite() {
        "–".to_owned()
    } else if key.ends_with("_us") {
        fmt_us(v)
    } else if key.ends_with("_bytes") {
        fmt_bytes(v)
    } else if key.ends_with("_share") {
        format!("{:.1} %", v * 100.0)
    } else if key.ends_with("_vs_bare") {
        format!("{v:.2}×")
    } else if key.ends_with("_ms") || key.ends_with("_mb") || key.ends_with("_mean") {
        format!("{v:.1}")
    } else {
        format!("{v:.0}")
    }
}

/// `b / a` as `1.23×`.
fn fmt_ratio(a: Option<f64>, b: Option<f64>) -> String {
    match (a, b) {
        (Some(a), Some(b)) if a > 0.0 && (b / a).is_finite() => format!("{:.2}×", b / a),
        _ => "–".to_owned(),
    }
}

fn met(ok: Option<bool>) -> &'static str {
    match ok {
        Some(true) => "yes",
        Some(false) => "**no**",
        None => "–",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(publish: f64, attach: Option<f64>) -> Value {
        let span = |name: &str, start: u64, end: u64| {
            json!({"name": name, "start": start, "end": end,
                "m": {"publish_median_us": publish, "bytes_median_bytes": 1000.0, "attach_ms": attach},
                "readers": [{"visible_p50_us": 5.0, "visible_p99_us": 9.0, "cpu_median_us": 2.0}]})
        };
        json!({"format": FORMAT, "duration_s": 3.0,
            "windows": [span("first 10", 0, 10), span("last 10", 90, 100)],
            "bins": [span("0-50", 0, 50), span("50-100", 50, 100)]})
    }

    #[test]
    fn builds_are_set_side_by_side_with_medians_over_runs() {
        let mut base = Side::new("baseline", "old".into());
        base.runs = vec![run(10.0, Some(1.0)), run(30.0, Some(3.0)), run(20.0, None)];
        let mut new = Side::new("new", "new".into());
        new.runs = vec![run(5.0, Some(1.0))];
        let cfg = Config {
            ticks: 100,
            readers: 1,
            rate: 0.0,
            keep_poses: None,
            window: 10,
            attach_samples: 1,
            bare: false,
        };
        let r = Report::new(
            vec![base, new],
            &cfg,
            "ygg-bench mission".into(),
            Duration::ZERO,
        );
        assert_eq!(r.sides[0].windows[0].m["publish_median_us"], 20.0);
        assert_eq!(r.sides[0].windows[0].m["attach_ms"], 1.0);
        let md = r.markdown("mission", Some("## Notes\n\nby hand\n"));
        assert!(
            md.contains("| `publish()` per tick, median | 20 µs | 5 µs | 0.25× |"),
            "{md}"
        );
        assert!(md.contains("### last 10 (ticks 90–100)"), "{md}");
        assert!(md.contains("\n## Notes\n\nby hand\n"), "{md}");
        assert_eq!(notes(&md).as_deref(), Some("## Notes\n\nby hand\n\n"));
        let dir = tempfile::tempdir().unwrap();
        r.plot_svg(&dir.path().join("m.svg")).unwrap();
        assert_eq!(r.to_json()["sides"][1]["label"], "new");
    }
}
