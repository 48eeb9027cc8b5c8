//! Rows, statistics, targets, and the JSON and markdown reports.

use serde_json::{Value, json};
use std::collections::BTreeMap;
use ygg_testkit::stats;

/// One measured case.
#[derive(Clone, Debug, Default)]
pub struct Row {
    /// Case name (`layer_update_office`, `size_1KB`, ...).
    pub case: String,
    /// What is measured, for the markdown table.
    pub what: String,
    /// Median, µs.
    pub median_us: f64,
    /// 99th percentile, µs.
    pub p99_us: f64,
    /// Samples behind median and p99 (summed over rounds).
    pub samples: usize,
    /// A rate (queries or updates per second), when the case measures one.
    pub value: Option<f64>,
    /// The rate's unit.
    pub unit: Option<&'static str>,
    /// Further numbers (named), reported as they are.
    pub extra: Vec<(String, f64)>,
    /// Free text (skipped snapshots, sizes).
    pub note: String,
    /// Per-round (median, p99, value), when there were several rounds.
    pub rounds: Vec<(f64, f64, Option<f64>)>,
}

impl Row {
    /// A latency row from nanosecond samples.
    pub fn latency(case: &str, what: &str, samples_ns: &[f64]) -> Row {
        let (median_us, p99_us) = median_p99_us(samples_ns);
        Row {
            case: case.into(),
            what: what.into(),
            median_us,
            p99_us,
            samples: samples_ns.len(),
            ..Row::default()
        }
    }

    /// Adds a named number.
    pub fn with(mut self, key: &str, value: f64) -> Row {
        self.extra.push((key.into(), value));
        self
    }

    /// The named number `key`.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.extra.iter().find(|(k, _)| k == key).map(|(_, v)| *v)
    }
}

pub use ygg_testkit::stats::median_p99_us;

/// [`stats::median`] of a list (NaN values ignored; NaN when there are none).
pub fn median(values: &[f64]) -> f64 {
    stats::median(values).unwrap_or(f64::NAN)
}

/// Merges the rows of several rounds: per case, the median over rounds of the median,
/// the p99, the rate and every extra number; samples add up.
pub fn aggregate(rounds: &[Vec<Row>]) -> Vec<Row> {
    let mut order: Vec<String> = Vec::new();
    let mut by_case: BTreeMap<String, Vec<&Row>> = BTreeMap::new();
    for round in rounds {
        for r in round {
            if !by_case.contains_key(&r.case) {
                order.push(r.case.clone());
            }
            by_case.entry(r.case.clone()).or_default().push(r);
        }
    }
    order
        .into_iter()
        .map(|case| {
            let rows = &by_case[&case];
            let first = rows[0];
            let pick =
                |f: &dyn Fn(&Row) -> f64| median(&rows.iter().map(|r| f(r)).collect::<Vec<_>>());
            let value = first
                .value
                .map(|_| pick(&|r: &Row| r.value.unwrap_or(f64::NAN)));
            let extra = first
                .extra
                .iter()
                .map(|(k, _)| (k.clone(), pick(&|r: &Row| r.get(k).unwrap_or(f64::NAN))))
                .collect();
            let mut notes: Vec<&str> = rows
                .iter()
                .map(|r| r.note.as_str())
                .filter(|n| !n.is_empty())
                .collect();
            notes.dedup();
            Row {
                case,
                what: first.what.clone(),
                median_us: pick(&|r: &Row| r.median_us),
                p99_us: pick(&|r: &Row| r.p99_us),
                samples: rows.iter().map(|r| r.samples).sum(),
                value,
                unit: first.unit,
                extra,
                note: notes.join("; "),
                rounds: if rows.len() > 1 {
                    rows.iter()
                        .map(|r| (r.median_us, r.p99_us, r.value))
                        .collect()
                } else {
                    Vec::new()
                },
            }
        })
        .collect()
}

/// A target of issue 5 and whether this run met it.
#[derive(Clone, Debug)]
pub struct Target {
    /// The target as the issue states it.
    pub text: String,
    /// Measured value(s), in words.
    pub measured: String,
    /// Met, missed, or not measured in this run.
    pub met: Option<bool>,
}

/// Evaluates the targets on the aggregated rows.
pub fn targets(rows: &[Row]) -> Vec<Target> {
    let find = |c: &str| rows.iter().find(|r| r.case == c);
    let mut out = Vec::new();
    out.push(match find("layer_update_office") {
        Some(r) => Target {
            text: "single-layer update (one agent pose) visible in a reader ≤ 200 µs p50 on the office".into(),
            measured: format!(
                "p50 {} to the first query answered ({} to the validated snapshot); {}",
                fmt_us(r.median_us),
                fmt_us(r.get("visible_median_us").unwrap_or(f64::NAN)),
                split(r)
            ),
            met: Some(r.median_us <= 200.0),
        },
        None => not_measured("single-layer update visible ≤ 200 µs p50"),
    });
    out.push(match find("full_office") {
        Some(r) => {
            let mut measured = format!(
                "p50 {}, p99 {} (mint); {}",
                fmt_us(r.median_us),
                fmt_us(r.p99_us),
                split(r)
            );
            if let Some(c) = find("full_office_chocolate") {
                measured.push_str(&format!(
                    "; the same office in chocolate layout (no spatial indexes): p50 {}",
                    fmt_us(c.median_us)
                ));
            }
            Target {
                text: "full office visible ≤ 10 ms".into(),
                measured,
                met: Some(r.median_us <= 10_000.0),
            }
        }
        None => not_measured("full office visible ≤ 10 ms"),
    });
    out.push(match (find("shm_40MB"), find("socket_40MB")) {
        (Some(s), Some(k)) => {
            let ratio = k.median_us / s.median_us;
            let mut measured = format!(
                "{ratio:.1}× for the whole graph (shm p50 {}, socket p50 {}); shm {}; socket: serialize p50 {}",
                fmt_us(s.median_us),
                fmt_us(k.median_us),
                split(s),
                fmt_us(k.get("serialize_us").unwrap_or(f64::NAN))
            );
            if let Some(one) = find("shm_40MB_layer_update") {
                measured.push_str(&format!(
                    "; {:.0}× for one agent pose (shm p50 {}: only that layer is sent)",
                    k.median_us / one.median_us,
                    fmt_us(one.median_us)
                ));
            }
            Target {
                text: "≥ 20× faster than the socket baseline at 40 MB (the same graph both ways)"
                    .into(),
                measured,
                met: Some(ratio >= 20.0),
            }
        }
        _ => not_measured("≥ 20× faster than the socket baseline at 40 MB"),
    });
    out.push(match (find("readers_1"), find("readers_8")) {
        (Some(one), Some(eight)) => {
            let ratio = eight.p99_us / one.p99_us;
            Target {
                text: "p99 with 8 readers ≤ 1.5× that with 1 reader".into(),
                measured: format!(
                    "{ratio:.2}× (p99 until the slowest of 8 readers has it {}, with 1 reader {}; p50 {} and {})",
                    fmt_us(eight.p99_us),
                    fmt_us(one.p99_us),
                    fmt_us(eight.median_us),
                    fmt_us(one.median_us)
                ),
                met: Some(ratio <= 1.5),
            }
        }
        _ => not_measured("p99 with 8 readers ≤ 1.5× that with 1 reader"),
    });
    let zero = find("writer_throughput_0_readers");
    let four = find("writer_throughput_4_readers");
    match (zero, four) {
        (Some(z), Some(f)) => {
            let (zw, fw) = (z.value.unwrap_or(f64::NAN), f.value.unwrap_or(f64::NAN));
            let drop = 1.0 - fw / zw;
            out.push(Target {
                text: "writer throughput drop with 4 busy readers ≤ 10% (updates per wall-clock second)".into(),
                measured: format!(
                    "{:.1}% ({zw:.0} updates/s with 0 readers, {fw:.0} with 4)",
                    drop * 100.0
                ),
                met: Some(drop <= 0.10),
            });
            let zc = z.get("updates_per_writer_cpu_s").unwrap_or(f64::NAN);
            let fc = f.get("updates_per_writer_cpu_s").unwrap_or(f64::NAN);
            let drop = 1.0 - fc / zc;
            let mut measured = format!(
                "{:.1}% ({zc:.0} updates per CPU-second with 0 readers, {fc:.0} with 4 busy",
                drop * 100.0
            );
            if let Some(idle) = find("writer_throughput_4_idle_readers")
                .and_then(|r| r.get("updates_per_writer_cpu_s"))
            {
                measured.push_str(&format!(", {idle:.0} with 4 idle"));
            }
            measured.push(')');
            out.push(Target {
                text: "the same per second of writer CPU time (what an update costs, leaving out the CPU the readers take on 2 cores)".into(),
                measured,
                met: Some(drop <= 0.10),
            });
        }
        _ => out.push(not_measured(
            "writer throughput drop with 4 busy readers ≤ 10%",
        )),
    }
    out.extend(floor_targets(rows));
    out
}

/// Issue 19's transport targets: ratios to the bare iceoryx2 floor of the same run, reader
/// CPU, readers fanning out, attaching on a few layers and on many.
fn floor_targets(rows: &[Row]) -> Vec<Target> {
    let find = |c: &str| rows.iter().find(|r| r.case == c);
    let mut out = Vec::new();
    out.push(match (find("layer_update_office"), find("bare_iceoryx2")) {
        (Some(u), Some(b)) => {
            let ratio = u.median_us / b.median_us;
            Target {
                text: "`layer_update_office` p50 ≤ 1.5× `bare_iceoryx2` p50 (same run)".into(),
                measured: format!(
                    "{ratio:.2}× ({} against {}; validated snapshot {}; {}; bare publish call {})",
                    fmt_us(u.median_us),
                    fmt_us(b.median_us),
                    fmt_us(u.get("visible_median_us").unwrap_or(f64::NAN)),
                    split(u),
                    fmt_us(b.get("publish_call_us").unwrap_or(f64::NAN))
                ),
                met: Some(ratio <= 1.5),
            }
        }
        _ => not_measured("`layer_update_office` p50 ≤ 1.5× `bare_iceoryx2` p50"),
    });
    out.push(match find("layer_update_office") {
        Some(u) => {
            let cpu = u.get("reader_cpu_us").unwrap_or(f64::NAN);
            let bare = find("bare_iceoryx2").and_then(|b| b.get("reader_cpu_us"));
            Target {
                text: "per-reader CPU per single-layer update ≤ 15 µs (thread CPU time)".into(),
                measured: format!(
                    "{} per update (wake-up, receive, validation, view; the bare subscriber's wake-up and receive: {})",
                    fmt_us(cpu),
                    bare.map_or("–".into(), fmt_us)
                ),
                met: Some(cpu <= 15.0),
            }
        }
        None => not_measured("per-reader CPU per single-layer update ≤ 15 µs"),
    });
    out.push(match (find("readers_1"), find("readers_8")) {
        (Some(one), Some(eight)) => {
            let ratio = eight.median_us / one.median_us;
            Target {
                text: "8 readers: the slowest reader's p50 ≤ 2× the p50 with one".into(),
                measured: format!(
                    "{ratio:.2}× ({} against {})",
                    fmt_us(eight.median_us),
                    fmt_us(one.median_us)
                ),
                met: Some(ratio <= 2.0),
            }
        }
        _ => not_measured("8 readers: the slowest reader's p50 ≤ 2× the p50 with one"),
    });
    out.extend(match (find("attach_office"), find("attach_office103")) {
        (Some(a), Some(b)) => {
            let worst = a.median_us.max(b.median_us);
            let within = |k: &str| {
                let (x, y) = (a.get(k).unwrap_or(f64::NAN), b.get(k).unwrap_or(f64::NAN));
                x.max(y) / x.min(y)
            };
            let ratios = [within("writer_fds"), within("reader_fds"), within("shm_files")];
            let line = |r: &Row| {
                let reference = find(&format!("{}_bound512", r.case)).map_or(String::new(), |x| {
                    format!(
                        " against {} at the bound 512 ({:.1}x)",
                        fmt_us(x.median_us),
                        x.median_us / r.median_us
                    )
                });
                format!(
                    "{} layers, bound {}: attach p50 {}{reference} (from spawn {}; the reader process's CPU time to its answer {}), writer {} fds, reader {} fds, {} /dev/shm files",
                    r.get("layers").unwrap_or(f64::NAN),
                    r.get("max_layers").unwrap_or(f64::NAN),
                    fmt_us(r.median_us),
                    fmt_us(r.get("from_spawn_median_us").unwrap_or(f64::NAN)),
                    fmt_us(r.get("process_cpu_us").unwrap_or(f64::NAN)),
                    r.get("writer_fds").unwrap_or(f64::NAN),
                    r.get("reader_fds").unwrap_or(f64::NAN),
                    r.get("shm_files").unwrap_or(f64::NAN)
                )
            };
            vec![
                Target {
                    text: "attach to first answer ≤ 20 ms on the office and on the 103-room office".into(),
                    measured: format!("{}; {}", line(a), line(b)),
                    met: Some(worst <= 20_000.0),
                },
                Target {
                    text: "fds and /dev/shm files per process within 1.5× between the two offices".into(),
                    measured: format!(
                        "ratios writer fds {:.2}, reader fds {:.2}, files {:.2}",
                        ratios[0], ratios[1], ratios[2]
                    ),
                    met: Some(ratios.iter().all(|r| *r <= 1.5)),
                },
            ]
        }
        _ => vec![not_measured(
            "attach to first answer ≤ 20 ms on the office and on the 103-room office",
        )],
    });
    out
}

/// Where a publish-to-visible latency goes: the writer's `publish()` call against the
/// part after it returned (transport, wake-up, validation).
fn split(r: &Row) -> String {
    format!(
        "writer publish() call p50 {}, publish() returned → visible p50 {}",
        fmt_us(r.get("publish_call_us").unwrap_or(f64::NAN)),
        fmt_us(r.get("returned_median_us").unwrap_or(f64::NAN))
    )
}

fn not_measured(text: &str) -> Target {
    Target {
        text: text.into(),
        measured: "not measured in this run".into(),
        met: None,
    }
}

/// A duration in µs, printed with a sensible unit.
pub fn fmt_us(us: f64) -> String {
    if us.is_nan() {
        "–".into()
    } else if us >= 10_000.0 {
        format!("{:.1} ms", us / 1e3)
    } else if us >= 1_000.0 {
        format!("{:.2} ms", us / 1e3)
    } else {
        format!("{us:.0} µs")
    }
}

fn num(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// The JSON report: `{"machine", "rows": [{"case", "median_us", "p99_us", ...}], ...}`.
pub fn to_json(meta: &Meta, rows: &[Row], targets: &[Target]) -> Value {
    let rows: Vec<Value> = rows
        .iter()
        .map(|r| {
            let mut o = json!({
                "case": r.case,
                "median_us": num(r.median_us),
                "p99_us": num(r.p99_us),
                "samples": r.samples,
            });
            let m = o.as_object_mut().expect("an object");
            if let Some(v) = r.value {
                m.insert("value".into(), num(v));
                m.insert("unit".into(), json!(r.unit.unwrap_or("")));
            }
            for (k, v) in &r.extra {
                m.insert(k.clone(), num(*v));
            }
            if !r.note.is_empty() {
                m.insert("note".into(), json!(r.note));
            }
            if !r.rounds.is_empty() {
                m.insert(
                    "rounds".into(),
                    json!(
                        r.rounds
                            .iter()
                            .map(|(a, b, v)| json!({"median_us": num(*a), "p99_us": num(*b), "value": v.map(num)}))
                            .collect::<Vec<_>>()
                    ),
                );
            }
            o
        })
        .collect();
    json!({
        "machine": meta.machine,
        "machine_at_end": meta.machine_end,
        "mode": if meta.quick { "quick" } else { "full" },
        "rounds": meta.rounds,
        "duration_s": meta.duration_s,
        "rows": rows,
        "targets": targets.iter().map(|t| json!({"target": t.text, "measured": t.measured, "met": t.met})).collect::<Vec<_>>(),
        "leftover_shm_files": meta.leftovers,
        "notes": meta.notes,
    })
}

/// What the report says about the run itself.
pub struct Meta {
    /// Machine description at the start (cores, CPU, load average).
    pub machine: Value,
    /// The same at the end (load average again).
    pub machine_end: Value,
    /// Quick mode.
    pub quick: bool,
    /// Rounds per case.
    pub rounds: usize,
    /// Wall time of the run.
    pub duration_s: f64,
    /// Files left below /dev/shm (iceoryx2's node files included) after a case (should be
    /// empty).
    pub leftovers: Vec<String>,
    /// Method notes.
    pub notes: Vec<String>,
    /// The hand-written section of an earlier `ipc.md` ([`hand_written`]), kept as it is.
    pub hand_written: Option<String>,
    /// The command line.
    pub command: String,
}

/// The markdown report.
pub fn to_markdown(meta: &Meta, rows: &[Row], targets: &[Target]) -> String {
    let m = &meta.machine;
    let s = |v: &Value, k: &str| {
        v.get(k).map_or(String::new(), |x| {
            x.to_string().trim_matches('"').to_owned()
        })
    };
    let mut md = String::new();
    md.push_str("# IPC latency benchmark (issue 5, item 4)\n\n");
    md.push_str(&format!(
        "Machine: {} cores, {}; load average {} at the start, {} at the end (a shared, noisy host). \
         Mode: {}, {} round(s) per case, {:.0} s in all.\n\nCommand: `{}`\n\n",
        s(m, "cores"),
        s(m, "cpu"),
        s(m, "loadavg"),
        s(&meta.machine_end, "loadavg"),
        if meta.quick { "quick" } else { "full" },
        meta.rounds,
        meta.duration_s,
        meta.command,
    ));
    md.push_str("## Targets\n\n| target | measured | met |\n|---|---|---|\n");
    for t in targets {
        let met = match t.met {
            Some(true) => "yes",
            Some(false) => "**no**",
            None => "–",
        };
        md.push_str(&format!("| {} | {} | {met} |\n", t.text, t.measured));
    }
    md.push_str("\n## Results\n\nLatencies from the writer's `publish()` call unless the row says otherwise; ");
    md.push_str("\"returned→visible\" is from the writer's `publish()` call returning to the validated snapshot in the reader: transport plus validation alone.\n\n");
    md.push_str("| case | what | median | p99 | samples | rate | returned→visible p50 | notes |\n|---|---|---|---|---|---|---|---|\n");
    for r in rows {
        let rate = match (r.value, r.unit) {
            (Some(v), Some(u)) => format!("{v:.0} {u}"),
            _ => String::new(),
        };
        let returned = r.get("returned_median_us").map(fmt_us).unwrap_or_default();
        let mut notes = Vec::new();
        for (k, v) in &r.extra {
            if k == "returned_median_us" {
                continue;
            }
            notes.push(format!("{k} {}", fmt_extra(k, *v)));
        }
        if !r.note.is_empty() {
            notes.push(r.note.clone());
        }
        md.push_str(&format!(
            "| `{}` | {} | {} | {} | {} | {} | {} | {} |\n",
            r.case,
            r.what,
            fmt_us(r.median_us),
            fmt_us(r.p99_us),
            r.samples,
            rate,
            returned,
            notes.join(", ")
        ));
    }
    let with_rounds: Vec<&Row> = rows.iter().filter(|r| !r.rounds.is_empty()).collect();
    if !with_rounds.is_empty() {
        md.push_str("\n## Per round (median / p99, rate)\n\nThe tables above give the median over rounds.\n\n| case | rounds |\n|---|---|\n");
        for r in with_rounds {
            let cells: Vec<String> = r
                .rounds
                .iter()
                .map(|(a, b, v)| match v {
                    Some(v) => format!("{} / {} ({v:.0})", fmt_us(*a), fmt_us(*b)),
                    None => format!("{} / {}", fmt_us(*a), fmt_us(*b)),
                })
                .collect();
            md.push_str(&format!("| `{}` | {} |\n", r.case, cells.join("; ")));
        }
    }
    if let Some(section) = &meta.hand_written {
        md.push('\n');
        md.push_str(section.trim_end());
        md.push('\n');
    }
    md.push_str("\n## Method\n\n");
    for n in &meta.notes {
        md.push_str(&format!("- {n}\n"));
    }
    md.push_str(&format!(
        "- Shared-memory files left after the cases: {}.\n",
        if meta.leftovers.is_empty() {
            "none".to_owned()
        } else {
            meta.leftovers.join("; ")
        }
    ));
    md
}

/// Heading of the report's hand-written section: findings from profiling, written into
/// `ipc.md` by hand and carried over when the report is regenerated.
pub const HAND_WRITTEN: &str = "## Where the time goes";

/// The hand-written section of a report (from its [`HAND_WRITTEN`] heading to the next
/// `## ` heading), if it has one.
pub fn hand_written(md: &str) -> Option<String> {
    hand_written_section(md, HAND_WRITTEN)
}

/// The section of `md` under `heading` (a `## ` line), up to the next `## ` heading, if
/// it has one: a report's hand-written part, carried over when it is written again.
pub fn hand_written_section(md: &str, heading: &str) -> Option<String> {
    let start = md.find(&format!("\n{heading}\n"))? + 1;
    let rest = &md[start..];
    let end = rest[heading.len()..]
        .find("\n## ")
        .map_or(rest.len(), |i| i + heading.len() + 1);
    Some(rest[..end].to_owned())
}

fn fmt_extra(key: &str, v: f64) -> String {
    if key.ends_with("_us") {
        fmt_us(v)
    } else if key.ends_with("bytes") {
        fmt_bytes(v)
    } else if v.fract() == 0.0 || v.abs() >= 100.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    }
}

/// Bytes with a decimal unit.
pub fn fmt_bytes(b: f64) -> String {
    if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else if b >= 1e3 {
        format!("{:.1} KB", b / 1e3)
    } else {
        format!("{b:.0} B")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_p99_use_nearest_rank() {
        let ns: Vec<f64> = (1..=100).map(f64::from).collect();
        let (m, p) = median_p99_us(&ns);
        assert_eq!((m, p), (0.05, 0.099));
        assert!(median_p99_us(&[]).0.is_nan());
        assert_eq!(median_p99_us(&[7000.0]), (7.0, 7.0));
    }

    #[test]
    fn rounds_merge_by_median_and_add_samples() {
        let row = |m: f64, v: f64| Row {
            case: "c".into(),
            median_us: m,
            p99_us: 2.0 * m,
            samples: 10,
            value: Some(v),
            extra: vec![("x".into(), m)],
            ..Row::default()
        };
        let merged = aggregate(&[
            vec![row(1.0, 5.0)],
            vec![row(3.0, 7.0)],
            vec![row(2.0, 9.0)],
        ]);
        assert_eq!(merged.len(), 1);
        let r = &merged[0];
        assert_eq!(
            (r.median_us, r.p99_us, r.value, r.samples),
            (2.0, 4.0, Some(7.0), 30)
        );
        assert_eq!(r.get("x"), Some(2.0));
        assert_eq!(r.rounds.len(), 3);
    }

    #[test]
    fn the_hand_written_section_is_carried_over() {
        let md = "# Report\n\n## Results\n\nold numbers\n\n## Where the time goes\n\n- by hand\n\n## Method\n\n- m\n";
        assert_eq!(
            hand_written(md).as_deref(),
            Some("## Where the time goes\n\n- by hand\n\n")
        );
        assert_eq!(hand_written("# Report\n\n## Method\n"), None);
    }

    #[test]
    fn json_has_the_required_fields() {
        let meta = Meta {
            machine: json!({"cores": 2}),
            machine_end: json!({}),
            quick: true,
            rounds: 1,
            duration_s: 1.0,
            leftovers: Vec::new(),
            notes: Vec::new(),
            hand_written: None,
            command: String::new(),
        };
        let rows = [Row::latency("readers_1", "", &[1000.0, 2000.0])];
        let v = to_json(&meta, &rows, &targets(&rows));
        assert_eq!(v["machine"]["cores"], 2);
        assert_eq!(v["rows"][0]["case"], "readers_1");
        assert!(v["rows"][0]["median_us"].is_number());
        assert!(v["rows"][0]["p99_us"].is_number());
    }
}
