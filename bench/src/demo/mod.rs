//! `ygg-bench demo`: the main job. A writer process serves the built-in office and
//! replays a SLAM-like stream (agent poses at 30 Hz, objects moving and appearing, the
//! mesh growing room by room); reader processes (planner, visibility checker, label
//! searcher) query every snapshot. Live progress per process, then a summary table.

pub mod roles;

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use rustix::process::Signal;
use serde_json::Value;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use ygg_testkit::{Input, Proc, TestScene};
use ygg_transport::protocol::ENV_IOX2_PREFIX;

/// Options of `ygg-bench demo`.
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
}

const ROLES: [&str; 3] = ["planner", "visibility", "labels"];

/// How long the writer may take to build the office and serve it.
const WRITER_READY: Duration = Duration::from_secs(120);

/// A process of the demo: its name, progress bar and summary line.
struct Member {
    name: String,
    proc: Proc,
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

    /// The end of its stderr, for an error message.
    fn stderr_tail(&self) -> String {
        let lines = self.proc.stderr();
        lines[lines.len().saturating_sub(20)..].join("\n")
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
    let writer_bin = ygg_testkit::binary("ygg-writer");
    // The reader roles run in this executable (`ygg-bench role`).
    let roles_bin = std::env::current_exe()?;
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst))?;
    }
    let removed = ygg_testkit::remove_stale();
    if removed > 0 {
        eprintln!("removed {removed} files left by earlier, killed runs");
    }
    // Children share one iceoryx2 prefix of their own, so the demo can tell its files
    // from anyone else's and remove them; a caller may choose it (tests do).
    let mut scene = TestScene::new("demo");
    if let Ok(prefix) = std::env::var(ENV_IOX2_PREFIX) {
        scene.prefix = prefix;
    }
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
    let writer_args = [
        "serve".to_owned(),
        "--scene".to_owned(),
        scene.name.clone(),
        "--seconds".to_owned(),
        format!("{}", args.seconds + 30.0),
        "--rate".to_owned(),
        format!("{}", args.rate),
        "--scale".to_owned(),
        format!("{}", args.scale),
    ];
    let writer_args: Vec<&str> = writer_args.iter().map(String::as_str).collect();
    let writer = Proc::start(
        scene.command_for(&writer_bin, &writer_args),
        "writer",
        Input::Null,
    )?;
    let mut procs = vec![Member {
        name: "writer".into(),
        proc: writer,
        bar: bar("writer"),
        summary: None,
    }];
    procs[0].bar.set_message("building the office...");

    // Wait for the writer to serve.
    let until = Instant::now() + WRITER_READY;
    let ready = loop {
        let seen = procs[0]
            .proc
            .wait_line_after(0, Duration::from_millis(100), |l| {
                l.contains("\"event\":\"ready\"")
            });
        procs[0].poll();
        if seen.is_some() {
            break true;
        }
        if stop.load(Ordering::SeqCst) || procs[0].exited() || Instant::now() >= until {
            break false;
        }
    };
    if !ready {
        let why = procs[0].stderr_tail();
        drop(procs);
        scene.clean_up();
        return Err(format!("the writer did not start:\n{why}").into());
    }
    let start = Instant::now();
    for i in 0..args.readers {
        let role = ROLES[i % ROLES.len()];
        let name = format!("{role}-{i}");
        let seconds = format!("{}", args.seconds);
        let command = scene.command_for(
            &roles_bin,
            &[
                "role",
                "--scene",
                &scene.name,
                "--role",
                role,
                "--seconds",
                &seconds,
            ],
        );
        let proc = Proc::start(command, name.clone(), Input::Null)?;
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
    for p in &procs {
        p.bar.finish();
    }
    print_summary(&procs, interrupted);
    let failed: Vec<String> = procs
        .iter_mut()
        .filter_map(|p| {
            let ok = p.summary.is_some() && p.proc.try_status().is_some_and(|s| s.success());
            (!ok).then(|| format!("{}:\n{}", p.name, p.stderr_tail()))
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
