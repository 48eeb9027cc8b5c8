//! `ygg demo`: the main job. A writer process (`ygg serve`) serves the built-in office
//! and replays a SLAM-like stream (agent poses at 30 Hz, objects moving and appearing, the
//! mesh growing room by room); reader processes (`ygg demo-role`: planner, visibility
//! checker, label searcher) query every snapshot. Live progress per process, then a
//! summary table. Every process is this executable, started again with another
//! subcommand.

mod child;
pub mod roles;
mod scene;
mod stats;
mod viewer;

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use rustix::process::Signal;
use serde_json::Value;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use self::child::Child;
use self::scene::DemoScene;
use self::viewer::DemoViewer;

/// Options of `ygg demo`.
#[derive(clap::Args, Debug)]
pub struct DemoArgs {
    /// How long the readers run, seconds.
    #[arg(long, default_value_t = 20.0)]
    pub seconds: f64,
    /// Number of reader processes (roles cycle: planner, visibility, labels).
    #[arg(long, default_value_t = 3)]
    pub readers: usize,
    /// Scale of the built-in office.
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Writer update ticks per second.
    #[arg(long, default_value_t = 30.0)]
    pub rate: f64,
    /// Points per chunk of the writer's chunked layers (its `--point-chunk-len`; 65536
    /// keeps the office's meshes in one piece, as before chunked layers).
    #[arg(long, default_value_t = ygg_store::snapshot::POINT_CHUNK_LEN as u64,
          value_parser = clap::value_parser!(u64).range(1..=65536))]
    pub point_chunk_len: u64,
    /// Also write the summary as JSON here (`readers`: per reader `visible_p50_us`,
    /// `visible_p99_us`, `checked`, `matched`; `writer`: `update_us_mean`,
    /// `publish_us_mean`, `updates_per_s`).
    #[arg(long)]
    pub json: Option<std::path::PathBuf>,
    /// Also show the scene in the browser (`ygg view --scene`; needs the Python package
    /// with its `view` extra), the page's address printed.
    #[arg(long)]
    pub view: bool,
    /// The viewer's port, with --view.
    #[arg(long, default_value_t = 8080)]
    pub view_port: u16,
}

/// The reader roles (`ygg demo-role --role ...`), in the order `--readers` cycles.
const ROLES: [&str; 3] = ["planner", "visibility", "labels"];

/// How long the writer may take to build the office and serve it.
const WRITER_READY: Duration = Duration::from_secs(120);

/// A flag that Ctrl-C (SIGINT) sets.
fn stop_on_ctrl_c() -> Result<Arc<AtomicBool>, ctrlc::Error> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))?;
    Ok(stop)
}

/// Starts `ygg serve` (this executable) on `scene`: the built-in office at `scale`,
/// updated `rate` times a second, exiting by itself after `seconds`, with `extra`
/// arguments.
fn start_writer(
    scene: &DemoScene,
    args: &DemoArgs,
    seconds: f64,
    extra: &[&str],
) -> std::io::Result<Child> {
    let (seconds, rate, scale) = (
        seconds.to_string(),
        args.rate.to_string(),
        args.scale.to_string(),
    );
    let mut all = vec![
        "serve",
        "--scene",
        &scene.name,
        "--seconds",
        &seconds,
        "--rate",
        &rate,
        "--scale",
        &scale,
    ];
    all.extend_from_slice(extra);
    Child::start(scene.command(&std::env::current_exe()?, &all), "writer")
}

/// Starts the reader role `role` (`ygg demo-role`, this executable) on `scene` for
/// `seconds`.
fn start_role(scene: &DemoScene, role: &str, seconds: f64, label: &str) -> std::io::Result<Child> {
    let seconds = seconds.to_string();
    let args = [
        "demo-role",
        "--scene",
        &scene.name,
        "--role",
        role,
        "--seconds",
        &seconds,
    ];
    Child::start(scene.command(&std::env::current_exe()?, &args), label)
}

/// Waits until `writer` prints its `ready` line and returns it parsed.
///
/// # Errors
/// When the writer exits first, `stop` is set, or it is not ready within
/// [`WRITER_READY`]: a message with the end of its stderr.
fn wait_ready(writer: &mut Child, stop: &AtomicBool) -> Result<Value, String> {
    let until = Instant::now() + WRITER_READY;
    loop {
        let seen = writer
            .next_line(Duration::from_millis(100))
            .filter(|l| l.contains("\"event\":\"ready\""));
        if let Some(v) = seen.and_then(|l| serde_json::from_str(&l).ok()) {
            return Ok(v);
        }
        let why = if stop.load(Ordering::SeqCst) {
            "interrupted"
        } else if writer.try_status().is_some() {
            "it exited"
        } else if Instant::now() >= until {
            "not ready in time"
        } else {
            continue;
        };
        return Err(format!(
            "{} did not start ({why}):\n{}",
            writer.label(),
            writer.stderr_tail()
        ));
    }
}

/// A process of the demo: its name, progress bar and summary line.
struct Member {
    name: String,
    proc: Child,
    bar: ProgressBar,
    summary: Option<Value>,
}

impl Member {
    /// Handles the JSON lines the process printed since the last call.
    fn poll(&mut self) {
        for line in self.proc.new_lines() {
            if let Ok(v) = serde_json::from_str::<Value>(&line) {
                handle(self, &v);
            }
        }
    }

    fn exited(&mut self) -> bool {
        self.proc.try_status().is_some()
    }
}

/// Runs the demo.
pub fn run(args: &DemoArgs) -> Result<(), Box<dyn std::error::Error>> {
    if !(args.seconds.is_finite() && args.seconds > 0.0) {
        return Err("--seconds must be a positive number".into());
    }
    if args.readers == 0 || args.readers > 16 {
        return Err("--readers must be between 1 and 16".into());
    }
    let stop = stop_on_ctrl_c()?;
    let removed = scene::remove_stale();
    if removed > 0 {
        eprintln!("removed {removed} files left by earlier, killed runs");
    }
    let scene = DemoScene::new("demo");
    let multi = MultiProgress::new();
    let style = ProgressStyle::with_template("{prefix:>12} [{elapsed_precise}] {bar:30} {msg}")?;
    let bar = |name: &str| {
        multi.add(
            ProgressBar::new((args.seconds * 10.0) as u64)
                .with_style(style.clone())
                .with_prefix(name.to_owned()),
        )
    };

    println!(
        "Yggdrasil demo: one writer, {} readers, scene {}, {:.0} s",
        args.readers, scene.name, args.seconds
    );
    let chunk_len = args.point_chunk_len.to_string();
    let writer = start_writer(
        &scene,
        args,
        args.seconds + 30.0,
        &["--point-chunk-len", &chunk_len],
    )?;
    let mut procs = vec![Member {
        name: "writer".into(),
        proc: writer,
        bar: bar("writer"),
        summary: None,
    }];
    procs[0].bar.set_message("building the office...");

    match wait_ready(&mut procs[0].proc, &stop) {
        Ok(ready) => handle(&mut procs[0], &ready),
        Err(why) => {
            drop(procs);
            scene.clean_up();
            return Err(why.into());
        }
    }
    procs[0].poll();
    let viewer = if args.view {
        match DemoViewer::start(&scene, args.view_port) {
            Ok((viewer, url)) => {
                println!("viewer: {url}");
                Some(viewer)
            }
            Err(why) => {
                drop(procs);
                scene.clean_up();
                return Err(why);
            }
        }
    } else {
        None
    };
    let start = Instant::now();
    for i in 0..args.readers {
        let role = ROLES[i % ROLES.len()];
        let name = format!("{role}-{i}");
        let proc = start_role(&scene, role, args.seconds, &name)?;
        procs.push(Member {
            bar: bar(&name),
            name,
            proc,
            summary: None,
        });
    }
    let mut interrupted = false;
    loop {
        if stop.load(Ordering::SeqCst) && !interrupted {
            interrupted = true;
            for p in &procs {
                p.proc.signal(Signal::INT);
            }
        }
        std::thread::sleep(Duration::from_millis(100));
        for p in &mut procs {
            p.poll();
        }
        procs[0]
            .bar
            .set_position((start.elapsed().as_secs_f64() * 10.0) as u64);
        let readers_done = procs[1..].iter_mut().all(Member::exited);
        if readers_done && procs[0].summary.is_none() && !procs[0].exited() {
            procs[0].proc.signal(Signal::TERM);
        }
        if procs.iter_mut().all(Member::exited) {
            for p in &mut procs {
                p.poll();
            }
            break;
        }
    }
    if let Some(viewer) = viewer {
        viewer.stop();
    }
    for p in &procs {
        p.bar.finish();
    }
    print_summary(&procs, interrupted);
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&summary_json(&procs, args))?;
        std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        println!("wrote {}", path.display());
    }
    let failed: Vec<String> = procs
        .iter_mut()
        .filter_map(|p| {
            let ok = p.summary.is_some() && p.proc.try_status().is_some_and(|s| s.success());
            (!ok).then(|| format!("{}:\n{}", p.name, p.proc.stderr_tail()))
        })
        .collect();
    let (checked, matched) = checks(&procs);
    drop(procs);
    match scene.clean_up() {
        None => println!("shared memory: nothing left in /dev/shm"),
        Some(left) => println!("shared memory left behind (now removed): {left}"),
    }
    if checked != matched {
        return Err(format!(
            "{} of {checked} checked answers differ from brute force",
            checked - matched
        )
        .into());
    }
    if !failed.is_empty() && !interrupted {
        return Err(format!(
            "a process failed or ended without a summary; its stderr:\n{}",
            failed.join("\n")
        )
        .into());
    }
    Ok(())
}

fn handle(p: &mut Member, v: &Value) {
    match v["event"].as_str() {
        Some("ready") => p.bar.set_message(format!("serving {} nodes", v["nodes"])),
        Some("progress") if p.name == "writer" => p.bar.set_message(format!(
            "generation {} | {} nodes | {} ticks",
            v["generation"], v["nodes"], v["ticks"]
        )),
        Some("progress") => {
            p.bar
                .set_position((v["seconds"].as_f64().unwrap_or(0.0) * 10.0) as u64);
            p.bar.set_message(format!(
                "{} batches | generation {} | checked {} matched {}",
                v["queries"], v["generation"], v["checked"], v["matched"]
            ));
        }
        Some("summary") => p.summary = Some(v.clone()),
        Some("warning") => p.bar.set_message(format!("warning: {}", v["message"])),
        _ => {}
    }
}

fn num(v: &Value, k: &str) -> f64 {
    v[k].as_f64().unwrap_or(f64::NAN)
}

fn print_summary(procs: &[Member], interrupted: bool) {
    println!();
    if interrupted {
        println!("interrupted: every process stopped cleanly");
    }
    println!(
        "| reader | batches | query p50 µs | query p99 µs | publish→visible p50 µs | p99 µs | staleness mean / max (generations) | checked | matched |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for p in &procs[1..] {
        let Some(s) = &p.summary else {
            println!("| {} | (no summary) | | | | | | | |", p.name);
            continue;
        };
        println!(
            "| {} | {} | {:.1} | {:.1} | {:.0} | {:.0} | {:.2} / {} | {} | {} |",
            p.name,
            s["batches"],
            num(s, "query_p50_us"),
            num(s, "query_p99_us"),
            num(s, "visible_p50_us"),
            num(s, "visible_p99_us"),
            num(s, "staleness_mean"),
            s["staleness_max"],
            s["checked"],
            s["matched"]
        );
    }
    if let Some(w) = &procs[0].summary {
        println!(
            "\nwriter: {:.1} updates/s (update {:.0} µs, publish {:.0} µs per tick), {} nodes at the end, generation {}, {:.1} MB published, {:.0} MB resident",
            num(w, "updates_per_s"),
            num(w, "update_us"),
            num(w, "publish_us"),
            w["nodes"],
            w["generation"],
            num(w, "bytes_published") / 1e6,
            num(w, "rss_mb")
        );
    }
    let (checked, matched) = checks(procs);
    println!("brute-force check: {matched} of {checked} sampled answers matched");
}

/// The summary as JSON: per reader its latencies and checks, the writer's means, and the
/// machine and options of the run.
fn summary_json(procs: &[Member], args: &DemoArgs) -> Value {
    let readers: Vec<Value> = procs[1..]
        .iter()
        .map(|p| {
            let s = p.summary.as_ref();
            let get = |k: &str| s.map_or(Value::Null, |s| s[k].clone());
            serde_json::json!({
                "name": p.name,
                "visible_p50_us": get("visible_p50_us"),
                "visible_p99_us": get("visible_p99_us"),
                "query_p50_us": get("query_p50_us"),
                "query_p99_us": get("query_p99_us"),
                "batches": get("batches"),
                "checked": get("checked"),
                "matched": get("matched"),
            })
        })
        .collect();
    let w = procs[0].summary.as_ref();
    let get = |k: &str| w.map_or(Value::Null, |w| w[k].clone());
    serde_json::json!({
        "readers": readers,
        "writer": {
            "update_us_mean": get("update_us"),
            "publish_us_mean": get("publish_us"),
            "updates_per_s": get("updates_per_s"),
            "rss_mb": get("rss_mb"),
            "nodes": get("nodes"),
        },
        "options": {
            "seconds": args.seconds,
            "readers": args.readers,
            "scale": args.scale,
            "rate": args.rate,
        },
        "machine": machine(),
    })
}

/// Answers checked against brute force and answers that matched, over every summary.
fn checks(procs: &[Member]) -> (u64, u64) {
    let sum = |key: &str| {
        procs
            .iter()
            .filter_map(|p| p.summary.as_ref()?[key].as_u64())
            .sum()
    };
    (sum("checked"), sum("matched"))
}

/// The machine the run took place on (CPU model, cores, load average, OS).
fn machine() -> Value {
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
    serde_json::json!({"cpu": cpu, "cores": cores,
        "loadavg": load.split_whitespace().take(3).collect::<Vec<_>>().join(" "),
        "os": std::env::consts::OS})
}
