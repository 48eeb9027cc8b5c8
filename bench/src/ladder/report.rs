//! The ladder's report: JSON, a markdown table, and an SVG plot like the paper's figure
//! (log latency axis, one panel per query family, every target).

use super::harness::Row;
use plotters::prelude::*;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// Static cost of one target.
#[derive(Clone, Debug)]
pub struct StaticRow {
    /// Target name.
    pub target: String,
    /// Nodes in the graph.
    pub nodes: usize,
    /// Memory, MB (archive bytes for Yggdrasil targets, heap estimate for dsg).
    pub memory_mb: f64,
    /// Median update latency, microseconds.
    pub update_us: f64,
}

/// Everything one ladder run measured.
pub struct Report {
    /// Machine description.
    pub machine: Value,
    /// Input description.
    pub input: String,
    /// Query timings of the ladder's targets.
    pub rows: Vec<Row>,
    /// Static costs.
    pub statics: Vec<StaticRow>,
    /// Anchor timings (kiddo floor, Spark-DSG paths).
    pub anchors: Vec<Row>,
    /// Whether every target gave identical answers.
    pub answers_identical: bool,
    /// Notes (anchor unavailable, sampled paths, ...).
    pub notes: Vec<String>,
}

/// Machine facts for the report.
pub fn machine() -> Value {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| "unknown".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    json!({"cpu": cpu, "cores": cores, "loadavg": load.split_whitespace().take(3).collect::<Vec<_>>().join(" "), "os": std::env::consts::OS})
}

impl Report {
    /// The JSON the issue asks for.
    pub fn to_json(&self) -> Value {
        let row = |r: &Row| json!({"target": r.target, "query": r.query, "median_us": r.median_us, "p99_us": r.p99_us});
        json!({
            "machine": self.machine,
            "input": self.input,
            "rows": self.rows.iter().map(row).collect::<Vec<_>>(),
            "static": self.statics.iter().map(|s| json!({"target": s.target, "nodes": s.nodes, "memory_mb": s.memory_mb, "update_us": s.update_us})).collect::<Vec<_>>(),
            "anchors": self.anchors.iter().map(|r| json!({"name": r.target, "query": r.query, "median_us": r.median_us, "p99_us": r.p99_us})).collect::<Vec<_>>(),
            "answers_identical": self.answers_identical,
            "notes": self.notes,
        })
    }

    /// A markdown report: the latency table (median / p99), anchors, static table.
    pub fn to_markdown(&self) -> String {
        let mut targets: Vec<String> = Vec::new();
        let mut cells: BTreeMap<(String, String), &Row> = BTreeMap::new();
        let mut queries: Vec<String> = Vec::new();
        for r in self.rows.iter().chain(&self.anchors) {
            if !targets.contains(&r.target) {
                targets.push(r.target.clone());
            }
            if !queries.contains(&r.query) {
                queries.push(r.query.clone());
            }
            cells.insert((r.query.clone(), r.target.clone()), r);
        }
        let mut md = format!(
            "# Ablation ladder\n\nInput: {}. Machine: {}. Answers identical across targets: **{}**.\n\n\
             Latency in µs, median / p99 over every query of the family and repetition.\n\n| query |",
            self.input, self.machine, self.answers_identical
        );
        for t in &targets {
            md += &format!(" {t} |");
        }
        md += "\n|---|";
        md += &"---|".repeat(targets.len());
        md += "\n";
        for q in &queries {
            md += &format!("| {q} |");
            for t in &targets {
                match cells.get(&(q.clone(), t.clone())) {
                    Some(r) => md += &format!(" {} / {} |", fmt_us(r.median_us), fmt_us(r.p99_us)),
                    None => md += " – |",
                }
            }
            md += "\n";
        }
        md += "\n## Static cost\n\n| target | nodes | memory (MB) | update (µs, median) |\n|---|---|---|---|\n";
        for s in &self.statics {
            md += &format!(
                "| {} | {} | {:.1} | {} |\n",
                s.target,
                s.nodes,
                s.memory_mb,
                fmt_us(s.update_us)
            );
        }
        if !self.notes.is_empty() {
            md += "\n## Notes\n\n";
            for n in &self.notes {
                md += &format!("- {n}\n");
            }
        }
        md
    }

    /// Draws the paper-style figure: one panel per query family, log latency axis.
    pub fn plot_svg(&self, path: &Path) -> Result<(), Box<dyn std::error::Error>> {
        let families = ["Q1a", "Q1b", "Q2", "Q3"];
        let mut targets: Vec<String> = Vec::new();
        for r in self.rows.iter().chain(&self.anchors) {
            if !targets.contains(&r.target) {
                targets.push(r.target.clone());
            }
        }
        let root = SVGBackend::new(path, (1400, 520)).into_drawing_area();
        root.fill(&WHITE)?;
        let panels = root.split_evenly((1, families.len()));
        let all: Vec<&Row> = self.rows.iter().chain(&self.anchors).collect();
        let (lo, hi) = all
            .iter()
            .map(|r| r.median_us)
            .filter(|v| v.is_finite() && *v > 0.0)
            .fold((f64::MAX, 0f64), |(a, b), v| (a.min(v), b.max(v)));
        let (lo, hi) = (lo.max(1e-3) / 2.0, hi.max(1.0) * 2.0);
        for (panel, family) in panels.iter().zip(families) {
            let queries: Vec<String> = {
                let mut q: Vec<String> = all
                    .iter()
                    .filter(|r| r.query.starts_with(family))
                    .map(|r| r.query.clone())
                    .collect();
                q.dedup();
                let mut seen = Vec::new();
                q.retain(|x| {
                    if seen.contains(x) {
                        false
                    } else {
                        seen.push(x.clone());
                        true
                    }
                });
                q
            };
            let n = queries.len().max(1) as f64;
            let mut chart = ChartBuilder::on(panel)
                .caption(family, ("sans-serif", 20))
                .margin(8)
                .x_label_area_size(40)
                .y_label_area_size(55)
                .build_cartesian_2d(0f64..n, (lo..hi).log_scale())?;
            chart
                .configure_mesh()
                .disable_x_mesh()
                .x_labels(queries.len().max(1))
                .x_label_formatter(&|x| {
                    queries
                        .get(x.floor() as usize)
                        .map(|q| {
                            q.trim_start_matches(family)
                                .trim_start_matches(['@', ':'])
                                .to_owned()
                        })
                        .unwrap_or_default()
                })
                .y_desc("µs (median, log)")
                .draw()?;
            let width = 0.8 / targets.len().max(1) as f64;
            for (ti, t) in targets.iter().enumerate() {
                let color = Palette99::pick(ti).to_rgba();
                let bars: Vec<Rectangle<(f64, f64)>> = queries
                    .iter()
                    .enumerate()
                    .filter_map(|(qi, q)| {
                        let r = all.iter().find(|r| &r.target == t && &r.query == q)?;
                        let x0 = qi as f64 + 0.1 + ti as f64 * width;
                        Some(Rectangle::new(
                            [(x0, lo), (x0 + width, r.median_us.max(lo))],
                            color.filled(),
                        ))
                    })
                    .collect();
                let series = chart.draw_series(bars)?;
                if *family == *"Q1a" {
                    series.label(t.as_str()).legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 10, y + 5)], color.filled())
                    });
                }
            }
            if family == "Q1a" {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()?;
            }
        }
        root.present()?;
        Ok(())
    }
}

/// Microseconds with sensible precision.
pub fn fmt_us(us: f64) -> String {
    if !us.is_finite() {
        "–".into()
    } else if us >= 100.0 {
        format!("{us:.0}")
    } else if us >= 1.0 {
        format!("{us:.2}")
    } else {
        format!("{us:.3}")
    }
}
