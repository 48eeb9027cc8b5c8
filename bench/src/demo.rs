//! `ygg-bench demo`: the main job. A writer process serves the built-in office and
//! replays a SLAM-like stream (agent poses at 30 Hz, objects moving and appearing, the
//! mesh growing room by room); reader processes (planner, visibility checker, label
//! searcher) query every snapshot. Live progress per process, then a summary table.

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

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

/// A child process and the name it goes by.
struct Proc {
    name: String,
    child: Child,
    bar: ProgressBar,
    summary: Option<Value>,
}

/// Finds (building if needed) the `ygg-writer` and `ygg-reader` binaries.
fn binaries() -> Result<(PathBuf, PathBuf), Box<dyn std::error::Error>> {
    let exe = std::env::current_exe()?;
    let dir = exe
        .parent()
        .ok_or("cannot locate the binary directory")?
        .to_path_buf();
    if let Ok(cargo) = std::env::var("CARGO") {
        let release = dir.ends_with("release");
        let mut cmd = Command::new(cargo);
        cmd.args([
            "build",
            "-q",
            "-p",
            "ygg-writer",
            "-p",
            "ygg-reader",
            "--bins",
        ]);
        if release {
            cmd.arg("--release");
        }
        if !cmd.status()?.success() {
            return Err("building ygg-writer and ygg-reader failed".into());
        }
    }
    let (w, r) = (dir.join("ygg-writer"), dir.join("ygg-reader"));
    for b in [&w, &r] {
        if !b.exists() {
            return Err(format!(
                "{} not found: run `cargo build --release --workspace` first",
                b.display()
            )
            .into());
        }
    }
    Ok((w, r))
}

fn spawn(
    bin: &Path,
    args: &[String],
    prefix: &str,
    log: &Path,
    id: usize,
    tx: mpsc::Sender<(usize, Value)>,
) -> Result<Child, Box<dyn std::error::Error>> {
    let mut child = Command::new(bin)
        .args(args)
        .env("YGG_IOX2_PREFIX", prefix)
        .stdout(Stdio::piped())
        .stderr(Stdio::from(std::fs::File::create(log)?))
        .spawn()?;
    let out = child.stdout.take().ok_or("no stdout")?;
    std::thread::spawn(move || {
        for line in BufReader::new(out).lines().map_while(Result::ok) {
            let Ok(v) = serde_json::from_str::<Value>(&line) else {
                continue;
            };
            if tx.send((id, v)).is_err() {
                break;
            }
        }
    });
    Ok(child)
}

fn signal(child: &Child, sig: rustix::process::Signal) {
    if let Some(pid) = rustix::process::Pid::from_raw(child.id() as i32) {
        let _ = rustix::process::kill_process(pid, sig);
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
    let (writer_bin, reader_bin) = binaries()?;
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst))?;
    }
    let pid = std::process::id();
    // Children share one iceoryx2 prefix of their own, so the demo can tell its files
    // from anyone else's and remove them; a caller may choose it (tests do).
    let prefix = std::env::var("YGG_IOX2_PREFIX").unwrap_or_else(|_| format!("ygd{pid}_"));
    let scene = format!("demo-{pid}");
    let logs = std::env::temp_dir().join(format!("ygg-demo-{pid}"));
    std::fs::create_dir_all(&logs)?;
    let (tx, rx) = mpsc::channel::<(usize, Value)>();
    let multi = MultiProgress::new();
    let style = ProgressStyle::with_template("{prefix:>12} [{elapsed_precise}] {bar:30} {msg}")?;

    println!(
        "Yggdrasil demo: one writer, {} readers, scene {scene}, {:.0} s",
        args.readers, args.seconds
    );
    let writer_args: Vec<String> = vec![
        "serve".into(),
        "--scene".into(),
        scene.clone(),
        "--seconds".into(),
        format!("{}", args.seconds + 30.0),
        "--rate".into(),
        format!("{}", args.rate),
        "--scale".into(),
        format!("{}", args.scale),
    ];
    let writer = spawn(
        &writer_bin,
        &writer_args,
        &prefix,
        &logs.join("writer.log"),
        0,
        tx.clone(),
    )?;
    let bar = multi.add(
        ProgressBar::new((args.seconds * 10.0) as u64)
            .with_style(style.clone())
            .with_prefix("writer"),
    );
    bar.set_message("building the office...");
    let mut procs = vec![Proc {
        name: "writer".into(),
        child: writer,
        bar,
        summary: None,
    }];

    // Wait for the writer to serve.
    let ready = wait_for(&rx, &mut procs, &stop, Duration::from_secs(120), |id, v| {
        id == 0 && v["event"] == "ready"
    });
    if !ready {
        shutdown(&mut procs);
        return Err(format!(
            "the writer did not start; see {}",
            logs.join("writer.log").display()
        )
        .into());
    }
    let start = Instant::now();
    for i in 0..args.readers {
        let role = ROLES[i % ROLES.len()];
        let name = format!("{role}-{i}");
        let a: Vec<String> = vec![
            "role".into(),
            "--scene".into(),
            scene.clone(),
            "--role".into(),
            role.into(),
            "--seconds".into(),
            format!("{}", args.seconds),
        ];
        let child = spawn(
            &reader_bin,
            &a,
            &prefix,
            &logs.join(format!("{name}.log")),
            i + 1,
            tx.clone(),
        )?;
        let bar = multi.add(
            ProgressBar::new((args.seconds * 10.0) as u64)
                .with_style(style.clone())
                .with_prefix(name.clone()),
        );
        procs.push(Proc {
            name,
            child,
            bar,
            summary: None,
        });
    }
    drop(tx);
    let mut interrupted = false;
    loop {
        if stop.load(Ordering::SeqCst) && !interrupted {
            interrupted = true;
            for p in &procs {
                signal(&p.child, rustix::process::Signal::INT);
            }
        }
        match rx.recv_timeout(Duration::from_millis(100)) {
            Ok((id, v)) => handle(&mut procs[id], &v),
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
            Err(mpsc::RecvTimeoutError::Timeout) => {}
        }
        let elapsed = (start.elapsed().as_secs_f64() * 10.0) as u64;
        procs[0].bar.set_position(elapsed);
        let readers_done = procs[1..]
            .iter_mut()
            .all(|p| matches!(p.child.try_wait(), Ok(Some(_))));
        if readers_done
            && procs[0].summary.is_none()
            && matches!(procs[0].child.try_wait(), Ok(None))
        {
            signal(&procs[0].child, rustix::process::Signal::TERM);
        }
        if procs
            .iter_mut()
            .all(|p| matches!(p.child.try_wait(), Ok(Some(_))))
        {
            while let Ok((id, v)) = rx.try_recv() {
                handle(&mut procs[id], &v);
            }
            break;
        }
    }
    for p in &mut procs {
        let _ = p.child.wait();
        p.bar.finish();
    }
    print_summary(&procs, interrupted);
    let leftovers = clean_shared_memory(&prefix);
    if leftovers.is_empty() {
        println!("shared memory: nothing left in /dev/shm");
        let _ = std::fs::remove_dir_all(&logs);
    } else {
        println!(
            "shared memory left behind: {leftovers:?} (logs in {})",
            logs.display()
        );
    }
    let checked: u64 = procs
        .iter()
        .filter_map(|p| p.summary.as_ref()?["checked"].as_u64())
        .sum();
    let matched: u64 = procs
        .iter()
        .filter_map(|p| p.summary.as_ref()?["matched"].as_u64())
        .sum();
    if checked != matched {
        return Err(format!(
            "{} of {checked} checked answers differ from brute force",
            checked - matched
        )
        .into());
    }
    if procs.iter().any(|p| p.summary.is_none()) && !interrupted {
        return Err(format!(
            "a process ended without a summary; logs in {}",
            logs.display()
        )
        .into());
    }
    Ok(())
}

fn handle(p: &mut Proc, v: &Value) {
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

fn wait_for(
    rx: &mpsc::Receiver<(usize, Value)>,
    procs: &mut [Proc],
    stop: &AtomicBool,
    timeout: Duration,
    done: impl Fn(usize, &Value) -> bool,
) -> bool {
    let until = Instant::now() + timeout;
    while Instant::now() < until && !stop.load(Ordering::SeqCst) {
        if let Ok((id, v)) = rx.recv_timeout(Duration::from_millis(100)) {
            handle(&mut procs[id], &v);
            if done(id, &v) {
                return true;
            }
        }
        if matches!(procs[0].child.try_wait(), Ok(Some(_))) {
            return false;
        }
    }
    false
}

fn shutdown(procs: &mut [Proc]) {
    for p in procs.iter() {
        signal(&p.child, rustix::process::Signal::TERM);
    }
    for p in procs.iter_mut() {
        let _ = p.child.wait();
    }
}

fn num(v: &Value, k: &str) -> f64 {
    v[k].as_f64().unwrap_or(f64::NAN)
}

fn print_summary(procs: &[Proc], interrupted: bool) {
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
    let checked: u64 = procs
        .iter()
        .filter_map(|p| p.summary.as_ref()?["checked"].as_u64())
        .sum();
    let matched: u64 = procs
        .iter()
        .filter_map(|p| p.summary.as_ref()?["matched"].as_u64())
        .sum();
    println!("brute-force check: {matched} of {checked} sampled answers matched");
}

/// Removes iceoryx2's per-prefix management file and returns anything else left behind
/// with the demo's prefix.
fn clean_shared_memory(prefix: &str) -> Vec<String> {
    let mut left = Vec::new();
    for dir in ["/dev/shm", "/tmp/iceoryx2"] {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if !name.starts_with(prefix) {
                continue;
            }
            if name.ends_with("global_mgmt") {
                let _ = std::fs::remove_file(e.path());
            } else {
                left.push(format!("{dir}/{name}"));
            }
        }
    }
    left
}
