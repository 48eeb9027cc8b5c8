//! `ygg-bench dsg-io`: importing the full office, JSON and binary, against spark_dsg's
//! own `DynamicSceneGraph.load` of the same files, in one run.
//!
//! The office is generated in Rust (`office::generate(seed 7, scale 1.0)`) and written
//! with `write_json` and `write_binary`, so the benchmark needs no external file. With
//! `--data FILE` (the `gen_office_dsg.py` output, `.json` or `.json.gz`), that file is
//! unpacked and measured too, with its `.sparkdsg` made by `write_binary`, after
//! checking that it and the generated office agree (counts, claim statistics, labels,
//! layers). Each import is timed `--runs` times from the page cache (file read,
//! decompression of nothing, parse, checks), our side in this process, spark_dsg's in
//! one `python3` process per file (interpreter start excluded; a warm-up load first on
//! both sides). The report gives medians, ratios and the machine.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use clap::Parser;
use ygg_dsg::office::{OfficeParams, generate};
use ygg_dsg::{DsgGraph, ImportPhase};

/// Arguments of `ygg-bench dsg-io`.
#[derive(Parser, Debug)]
pub struct DsgIoArgs {
    /// Timed imports per file and tool (medians are reported).
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// The `gen_office_dsg.py` office (`.json` or `.json.gz`) to measure as well.
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// The Python interpreter with spark_dsg installed.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Skip spark_dsg (only our import, with its phases).
    #[arg(long)]
    pub no_spark_dsg: bool,
    /// Also write the markdown report to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// spark_dsg's side: load the file `runs + 1` times, print each time but the first.
const SPARK_DSG_LOAD: &str = r#"
import sys, time
import spark_dsg
path, runs = sys.argv[1], int(sys.argv[2])
spark_dsg.DynamicSceneGraph.load(path)
for _ in range(runs):
    t = time.perf_counter()
    g = spark_dsg.DynamicSceneGraph.load(path)
    print(time.perf_counter() - t, flush=True)
    del g
from importlib.metadata import version
print("version", version("spark_dsg"))
"#;

/// One file measured.
struct Row {
    what: String,
    bytes: u64,
    ours: Vec<f64>,
    /// Median seconds per phase of our import (read, parse, validate), last run.
    phases: [f64; 3],
    spark_dsg: Option<Vec<f64>>,
}

/// Runs `ygg-bench dsg-io`.
///
/// # Errors
/// A file that cannot be written or read, an office file that does not agree with the
/// generated one, or a spark_dsg process that fails.
pub fn run(args: &DsgIoArgs) -> Result<(), Box<dyn std::error::Error>> {
    let runs = args.runs.max(1);
    let load_before = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let dir = tempfile::tempdir()?;
    let t = Instant::now();
    let office = generate(OfficeParams {
        seed: 7,
        scale: 1.0,
    });
    eprintln!("generated the office in {:.2} s", t.elapsed().as_secs_f64());
    let mut files: Vec<(String, PathBuf)> = Vec::new();
    let json = dir.path().join("office_generated.json");
    let binary = dir.path().join("office_generated.sparkdsg");
    ygg_dsg::write_json(&office, &json)?;
    ygg_dsg::write_binary(&office, &binary)?;
    files.push(("generated office, JSON (`write_json`)".to_owned(), json));
    files.push((
        "generated office, binary (`write_binary`)".to_owned(),
        binary,
    ));
    if let Some(data) = &args.data {
        let unpacked = dir.path().join("office_seed7.json");
        let bytes = unpacked_bytes(data)?;
        std::fs::write(&unpacked, &bytes)?;
        let file_office = ygg_dsg::read_file(&unpacked)?;
        agree(&office, &file_office)?;
        eprintln!("{} agrees with the generated office", data.display());
        let binary = dir.path().join("office_seed7.sparkdsg");
        ygg_dsg::write_binary(&file_office, &binary)?;
        files.push((
            format!("`{}` unpacked, JSON (gen_office_dsg.py)", file_name(data)),
            unpacked,
        ));
        files.push((
            format!("`{}`, binary (`write_binary`)", file_name(data)),
            binary,
        ));
    }

    let mut rows = Vec::new();
    let mut version = None;
    for (what, path) in files {
        let bytes = std::fs::metadata(&path)?.len();
        eprintln!("{what}: {bytes} bytes");
        let (ours, phases) = time_ours(&path, runs)?;
        let spark_dsg = if args.no_spark_dsg {
            None
        } else {
            let (times, v) = time_spark_dsg(&args.python, &path, runs)?;
            version = Some(v);
            Some(times)
        };
        rows.push(Row {
            what,
            bytes,
            ours,
            phases,
            spark_dsg,
        });
    }
    let load_after = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let report = report(&rows, runs, version.as_deref(), &load_before, &load_after);
    print!("{report}");
    if let Some(out) = &args.out {
        std::fs::write(out, &report)?;
    }
    Ok(())
}

fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The bytes of a file, gunzipped when compressed.
fn unpacked_bytes(path: &Path) -> Result<Vec<u8>, Box<dyn std::error::Error>> {
    let raw = std::fs::read(path)?;
    if !raw.starts_with(&[0x1f, 0x8b]) {
        return Ok(raw);
    }
    let mut out = Vec::new();
    std::io::Read::read_to_end(&mut flate2::read::MultiGzDecoder::new(&raw[..]), &mut out)?;
    Ok(out)
}

/// Whether the shared office file and the generated office are the same office: counts,
/// claim statistics, layers, labelspaces and label histogram.
fn agree(generated: &DsgGraph, file: &DsgGraph) -> Result<(), String> {
    let checks = [
        ("counts", generated.counts() == file.counts()),
        (
            "claim statistics",
            generated.claim_stats() == file.claim_stats(),
        ),
        ("layers", generated.layers == file.layers),
        ("labelspaces", generated.labelspaces == file.labelspaces),
        (
            "object labels",
            generated.object_labels() == file.object_labels(),
        ),
    ];
    match checks.iter().find(|(_, ok)| !ok) {
        Some((what, _)) => Err(format!(
            "{}: the {what} differ from the generated office's",
            file.source
        )),
        None => Ok(()),
    }
}

/// Our import of `path`, `runs` times after a warm-up: seconds each, and the phases
/// (read, parse, validate) of the median run.
pub(crate) fn time_ours(
    path: &Path,
    runs: usize,
) -> Result<(Vec<f64>, [f64; 3]), Box<dyn std::error::Error>> {
    ygg_dsg::read_file(path)?;
    let mut times = Vec::with_capacity(runs);
    let mut phases = Vec::with_capacity(runs);
    for _ in 0..runs {
        let start = Instant::now();
        let mut marks: Vec<(ImportPhase, Instant)> = Vec::new();
        let g = ygg_dsg::read_file_with_progress(path, &mut |p| {
            if marks.last().is_none_or(|m| m.0 != p.phase) {
                marks.push((p.phase, Instant::now()));
            }
        })?;
        let end = Instant::now();
        drop(g);
        times.push((end - start).as_secs_f64());
        let at = |phase: ImportPhase| marks.iter().find(|m| m.0 == phase).map(|m| m.1);
        let span = |from: ImportPhase, to: Option<Instant>| {
            at(from).map_or(0.0, |s| (to.unwrap_or(end) - s).as_secs_f64())
        };
        phases.push([
            span(ImportPhase::Read, at(ImportPhase::Parse)),
            span(ImportPhase::Parse, at(ImportPhase::Validate)),
            span(ImportPhase::Validate, at(ImportPhase::Done)),
        ]);
    }
    let median_run = median_index(&times);
    Ok((times, phases[median_run]))
}

/// spark_dsg's `DynamicSceneGraph.load` of `path`, `runs` times after a warm-up, in one
/// Python process: seconds each, and spark_dsg's version.
pub(crate) fn time_spark_dsg(
    python: &str,
    path: &Path,
    runs: usize,
) -> Result<(Vec<f64>, String), Box<dyn std::error::Error>> {
    let out = Command::new(python)
        .arg("-c")
        .arg(SPARK_DSG_LOAD)
        .arg(path)
        .arg(runs.to_string())
        .output()?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!(
            "spark_dsg failed to load {}: {}",
            path.display(),
            String::from_utf8_lossy(&out.stderr)
        )
        .into());
    }
    let mut times = Vec::new();
    let mut version = String::from("?");
    for line in stdout.lines() {
        if let Some(v) = line.strip_prefix("version ") {
            version = v.to_owned();
        } else {
            times.push(line.trim().parse::<f64>()?);
        }
    }
    Ok((times, version))
}

fn median_index(v: &[f64]) -> usize {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    idx[idx.len() / 2]
}

fn median(v: &[f64]) -> f64 {
    v[median_index(v)]
}

fn report(
    rows: &[Row],
    runs: usize,
    version: Option<&str>,
    load_before: &str,
    load_after: &str,
) -> String {
    use std::fmt::Write as _;
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_owned())
        })
        .unwrap_or_else(|| "?".to_owned());
    let nproc = std::thread::available_parallelism().map_or(0, |n| n.get());
    let loadavg = |s: &str| s.split_whitespace().take(3).collect::<Vec<_>>().join(" ");
    let mut s = String::new();
    let _ = writeln!(s, "# Spark-DSG import: ygg-dsg against spark_dsg\n");
    let _ = writeln!(
        s,
        "`ygg-bench dsg-io` (release build): median of {runs} imports per file and tool, from the page cache, after one warm-up each. \
         ygg-dsg: `ygg_dsg::read_file` in the bench process (read, parse, checks, into `DsgGraph`). \
         spark_dsg {}: `DynamicSceneGraph.load` in one python3 process per file (interpreter start and `import` excluded).\n",
        version.unwrap_or("(not run)")
    );
    let _ = writeln!(
        s,
        "Targets: binary import at least 2x faster than spark_dsg's binary load, JSON import at least 5x faster than its JSON load. \
         Phases of the median ygg-dsg run: read = file to memory, parse = JSON parse or binary decode into the raw form, validate = the shared checks and conversion.\n"
    );
    let _ = writeln!(
        s,
        "Machine: {cpu}, {nproc} cores (shared with other jobs), load average {} before and {} after.\n",
        loadavg(load_before),
        loadavg(load_after)
    );
    let _ = writeln!(
        s,
        "| file | MB | ygg-dsg s (median) | spark_dsg s (median) | speed-up | ygg-dsg read / parse / validate s | ygg-dsg runs s | spark_dsg runs s |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.3}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for r in rows {
        let ours = median(&r.ours);
        let (theirs, ratio, theirs_list) = match &r.spark_dsg {
            Some(t) if !t.is_empty() => {
                let m = median(t);
                (format!("{m:.3}"), format!("{:.1}x", m / ours), list(t))
            }
            _ => ("–".to_owned(), "–".to_owned(), "–".to_owned()),
        };
        let _ = writeln!(
            s,
            "| {} | {:.1} | {ours:.3} | {theirs} | {ratio} | {:.3} / {:.3} / {:.3} | {} | {theirs_list} |",
            r.what,
            r.bytes as f64 / 1e6,
            r.phases[0],
            r.phases[1],
            r.phases[2],
            list(&r.ours),
        );
    }
    s
}
