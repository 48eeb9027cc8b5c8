//! `ygg query`: answers a stream of JSON-line object queries (the contract of
//! [`ygg_dsg::objects`]) on a `.ygg` snapshot or on a live scene.
//!
//! One JSON line out per line in, in order:
//!
//! | in | out |
//! |---|---|
//! | `{"op":"nearest_object","point":[x,y,z]}` | `{"ids":[id]}` (or `{"ids":[]}` without objects) |
//! | `{"op":"objects_within","point":[x,y,z],"radius":r}` | `{"ids":[...]}` |
//! | `{"op":"visible_objects","eye":[..],"dir":[..],"half_angle_deg":a,"range":m}` | `{"ids":[...]}` |
//! | `{"op":"objects_with_label","label":"light"}` | `{"ids":[...]}` |
//! | anything malformed | `{"error":"line N: ..."}` for that line alone |
//!
//! Ids are Spark-DSG node ids as JSON integers (u64, exact above 2^53), ascending.

use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Parser;
use ygg_dsg::objects::{ObjectQuery, Objects};
use ygg_reader::{SceneReader, SceneSnapshot};
use ygg_store::{SceneView, SnapshotFile};

/// Arguments of `ygg query`.
#[derive(Parser, Debug)]
pub struct QueryArgs {
    /// The `.ygg` snapshot or recording folder to query (or use --scene).
    #[arg(required_unless_present = "scene", conflicts_with = "scene")]
    pub snapshot: Option<PathBuf>,
    /// For a recording: query the cut of this generation (the last one at or before it).
    #[arg(long, conflicts_with = "time")]
    pub at: Option<u64>,
    /// For a recording: query the scene as it was at this time (the last cut published at
    /// or before it): seconds since the Unix epoch, +S after the first cut, -S before the
    /// last. Default: the last cut.
    #[arg(long, allow_hyphen_values = true)]
    pub time: Option<crate::moment::TimeSpec>,
    /// Query a live scene published under this name instead of a file.
    #[arg(long)]
    pub scene: Option<String>,
    /// JSON-lines file of queries; `-` or absent reads standard input.
    #[arg(long, short)]
    pub queries: Option<PathBuf>,
    /// Print to stderr how long opening took and how long the batch took after that.
    #[arg(long)]
    pub timing: bool,
    /// Seconds to wait for a live scene's writer and first snapshot.
    #[arg(long, default_value_t = 5.0)]
    pub timeout: f64,
}

/// Runs `ygg query`.
///
/// # Errors
/// A message naming the snapshot, scene or query file that could not be opened or read.
/// Malformed query lines are not errors: each is answered with `{"error":...}`.
pub fn run(args: &QueryArgs) -> Result<(), String> {
    let start = Instant::now();
    let input: Box<dyn Read> = match &args.queries {
        Some(p) if p.as_os_str() != "-" => Box::new(
            std::fs::File::open(p).map_err(|e| format!("{}: cannot read: {e}", p.display()))?,
        ),
        _ => Box::new(std::io::stdin().lock()),
    };
    let source = args
        .queries
        .as_ref()
        .filter(|p| p.as_os_str() != "-")
        .map_or_else(|| "<stdin>".to_owned(), |p| p.display().to_string());
    let interactive = args
        .queries
        .as_deref()
        .is_none_or(|p| p == std::path::Path::new("-"));
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let on_recording = args
        .snapshot
        .as_deref()
        .is_some_and(crate::moment::is_recording);
    if !on_recording && (args.at.is_some() || args.time.is_some()) {
        return Err(
            "--at and --time apply to a recording (a folder written by `ygg record`)".into(),
        );
    }
    let stats = match (&args.snapshot, &args.scene) {
        (Some(path), _) if on_recording => {
            let recording = crate::moment::open_recording(path)?;
            let cut = crate::moment::chosen_cut(&recording, args.at, args.time)?;
            let scene = recording.scene(cut).map_err(|e| e.to_string())?;
            let opened = start.elapsed();
            let stats = answer_lines(scene.view(), input, &source, &mut out, interactive)?;
            Stats { opened, ..stats }
        }
        (Some(path), _) => {
            let file = SnapshotFile::open(path).map_err(|e| e.to_string())?;
            let opened = start.elapsed();
            let view = file.view();
            let stats = answer_lines(&view, input, &source, &mut out, interactive)?;
            Stats { opened, ..stats }
        }
        (None, Some(scene)) => {
            let snapshot = live_snapshot(scene, seconds(args.timeout, "--timeout")?)?;
            let opened = start.elapsed();
            let view = snapshot.view();
            let stats = answer_lines(&view, input, &source, &mut out, interactive)?;
            Stats { opened, ..stats }
        }
        (None, None) => return Err("give a snapshot file or --scene NAME".to_owned()),
    };
    if args.timing {
        let per = stats.batch.as_secs_f64() * 1e6 / stats.lines.max(1) as f64;
        eprintln!(
            "timing: open {:.3} ms; {} queries ({} errors) in {:.3} ms after open ({per:.1} µs per query)",
            stats.opened.as_secs_f64() * 1e3,
            stats.lines,
            stats.errors,
            stats.batch.as_secs_f64() * 1e3,
        );
    }
    Ok(())
}

/// What one batch did.
#[derive(Default)]
struct Stats {
    opened: Duration,
    batch: Duration,
    lines: usize,
    errors: usize,
}

/// Answers every line of `input` on `view`, one output line each, and flushes.
fn answer_lines<V: SceneView>(
    view: &V,
    input: Box<dyn Read + '_>,
    source: &str,
    out: &mut impl Write,
    flush_each: bool,
) -> Result<Stats, String> {
    let start = Instant::now();
    let objects = Objects::new(view);
    let mut input = BufReader::new(input);
    let mut line = Vec::new();
    let mut stats = Stats::default();
    let write_err = |e: std::io::Error| format!("<stdout>: cannot write: {e}");
    loop {
        line.clear();
        let n = input
            .read_until(b'\n', &mut line)
            .map_err(|e| format!("{source}: cannot read: {e}"))?;
        if n == 0 {
            break;
        }
        stats.lines += 1;
        let answer = answer_line(&objects, &line, stats.lines);
        stats.errors += usize::from(answer.get("error").is_some());
        serde_json::to_writer(&mut *out, &answer).map_err(|e| write_err(e.into()))?;
        out.write_all(b"\n").map_err(write_err)?;
        if flush_each {
            out.flush().map_err(write_err)?;
        }
    }
    out.flush().map_err(write_err)?;
    stats.batch = start.elapsed();
    Ok(stats)
}

/// The answer to one input line (1-based `number`), as a JSON object.
fn answer_line<V: SceneView>(
    objects: &Objects<'_, V>,
    line: &[u8],
    number: usize,
) -> serde_json::Value {
    let error = |msg: String| serde_json::json!({ "error": format!("line {number}: {msg}") });
    let text = match std::str::from_utf8(line) {
        Ok(t) => t.trim_end_matches(['\n', '\r']),
        Err(e) => return error(format!("not UTF-8: {e}")),
    };
    if text.trim().is_empty() {
        return error("empty line (expected a JSON query)".to_owned());
    }
    let query = match ObjectQuery::from_json(text) {
        Ok(q) => q,
        Err(e) => return error(e),
    };
    match objects.answer(&query) {
        Ok(ids) => serde_json::json!({ "ids": ids.iter().map(|id| id.0).collect::<Vec<u64>>() }),
        Err(e) => error(e.to_string()),
    }
}

/// Parses a non-negative number of seconds.
pub fn seconds(value: f64, flag: &str) -> Result<Duration, String> {
    Duration::try_from_secs_f64(value)
        .map_err(|_| format!("{flag} must be a non-negative number of seconds"))
}

/// Attaches to a live scene and returns its first complete, validated snapshot, waiting
/// up to `timeout` for the writer and the snapshot.
///
/// # Errors
/// A message naming the scene: no writer within `timeout`, no snapshot within
/// `timeout`, or a snapshot that failed validation.
pub fn live_snapshot(scene: &str, timeout: Duration) -> Result<SceneSnapshot, String> {
    let start = Instant::now();
    let mut reader = SceneReader::builder(scene)
        .wait_for_writer(timeout)
        .open()
        .map_err(|e| format!("scene {scene}: {e}"))?;
    if let Some(s) = reader.latest().map_err(|e| format!("scene {scene}: {e}"))? {
        return Ok(s);
    }
    loop {
        let remaining = timeout.saturating_sub(start.elapsed());
        if remaining.is_zero() {
            return Err(format!(
                "scene {scene}: no complete snapshot within {:.1} s",
                timeout.as_secs_f64()
            ));
        }
        match reader.wait_next(remaining) {
            Ok(Some(s)) => return Ok(s),
            Ok(None) => {}
            Err(e) => return Err(format!("scene {scene}: {e}")),
        }
    }
}
