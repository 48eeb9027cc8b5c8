//! `ygg-bench record`: issue 41's targets, measured on the demo's stream (the built-in
//! office in mint layout with [`SlamReplay`], as `ygg serve` and `ygg demo` publish it).
//!
//! 1. **Paired publish cost**: the writer ticks at `--rate` for `--pair-minutes` while a
//!    `ygg record` process, a plain reader (`ygg watch`) or nothing is attached, in turn,
//!    per `--toggle-seconds` window; `publish()` per tick with a recorder against
//!    nothing and against a plain reader, from the same run.
//! 2. **A mission's recording**: the writer ticks for `--minutes` with a recorder
//!    attached throughout; the recording's size against the bytes the writer published
//!    for the cuts it holds.
//! 3. **Reading it back** ([`readback`]): opening the recording, then any cut to its
//!    first Q1a answer (the first, the middle and the last cut, from a fresh open each
//!    time); Q1a on the last recorded cut against the same query on the live scene;
//!    `changes` over the last 10 minutes.
//! 4. **Replay** at 1x of the last `--replay-seconds`: how far each interval between
//!    two published cuts strays from the recorded one.
//!
//! Writes `--out` (Markdown) and `--json`.

mod readback;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Parser;
use rustix::process::Signal;
use serde_json::{Value, json};
use ygg_dsg::layout::Layout;
use ygg_dsg::replay::SlamReplay;
use ygg_testkit::stats::median_p99;
use ygg_testkit::{Proc, TestScene, Watchdog};
use ygg_writer::SceneWriter;

/// Arguments of `ygg-bench record`.
#[derive(Parser, Debug)]
pub struct RecordArgs {
    /// Minutes of the recorded mission (phase 2).
    #[arg(long, default_value_t = 30.0)]
    minutes: f64,
    /// Minutes of the paired publish measurement (phase 1).
    #[arg(long, default_value_t = 10.0)]
    pair_minutes: f64,
    /// Seconds of each window of phase 1 (nothing, a recorder, a plain reader attached, in turn).
    #[arg(long, default_value_t = 30.0)]
    toggle_seconds: f64,
    /// Ticks per second.
    #[arg(long, default_value_t = 30.0)]
    rate: f64,
    /// Seconds of the recording replayed at 1x (phase 4).
    #[arg(long, default_value_t = 120.0)]
    replay_seconds: f64,
    /// Folder for the recordings (removed at the end).
    #[arg(long, default_value = "target/bench-record")]
    dir: PathBuf,
    /// Markdown report.
    #[arg(long, default_value = "bench/results/record.md")]
    out: PathBuf,
    /// JSON report.
    #[arg(long, default_value = "bench/results/record.json")]
    json: PathBuf,
}

/// One tick of the writer: its `publish()` time and what it sent.
struct Tick {
    publish_ns: f64,
    bytes: usize,
    generation: u64,
    attached: Attached,
    /// Whether the tick is within 2 s after a process was attached or detached.
    settling: bool,
}

/// What follows the scene during a window of phase 1.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Attached {
    /// No process: the baseline.
    Nothing,
    /// `ygg record`.
    Recorder,
    /// `ygg watch`: a reader that validates each snapshot and writes nothing, to tell
    /// what any subscriber costs the writer from what recording adds.
    Reader,
}

/// The demo's writer and stream, ticked at a fixed rate.
struct Stream {
    writer: SceneWriter,
    replay: SlamReplay,
    period: Duration,
    next: Instant,
}

impl Stream {
    fn new(scene: &TestScene, rate: f64) -> Result<Stream, Box<dyn std::error::Error>> {
        let dsg = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams {
            seed: 7,
            scale: 1.0,
        });
        let graph = ygg_dsg::layout::build(&dsg, Layout::Mint)?;
        let mut writer = SceneWriter::builder(&scene.name)
            .iceoryx_prefix(&scene.prefix)
            .create(graph)?;
        writer.publish()?;
        let replay = SlamReplay::new(writer.graph(), 7);
        let period = Duration::from_secs_f64(1.0 / rate);
        Ok(Stream {
            writer,
            replay,
            period,
            next: Instant::now() + period,
        })
    }

    /// Waits for the next tick's time, applies one step of the stream and publishes it.
    fn tick(
        &mut self,
        attached: Attached,
        settling: bool,
    ) -> Result<Tick, Box<dyn std::error::Error>> {
        let now = Instant::now();
        if self.next > now {
            std::thread::sleep(self.next - now);
        }
        self.next = self.next.max(Instant::now() - self.period) + self.period;
        self.replay.step(self.writer.graph_mut())?;
        let t = Instant::now();
        let report = self.writer.publish()?;
        Ok(Tick {
            publish_ns: t.elapsed().as_nanos() as f64,
            bytes: report.bytes_sent,
            generation: report.generation,
            attached,
            settling,
        })
    }
}

/// Starts `ygg record` on `scene` into `dir` and waits for its ready line.
fn start_recorder(scene: &TestScene, dir: &std::path::Path, watchdog: &Watchdog) -> Proc {
    let recorder = Proc::spawn(
        scene.command(
            "ygg",
            &[
                "record",
                "--scene",
                &scene.name,
                "-o",
                &dir.display().to_string(),
            ],
        ),
        "recorder",
        watchdog,
    );
    recorder.expect_line(Duration::from_secs(30), |l| {
        l.contains("\"event\":\"ready\"")
    });
    recorder
}

/// Starts `ygg watch` on `scene` (a plain reader) and waits for its first snapshot line.
fn start_reader(scene: &TestScene, watchdog: &Watchdog) -> Proc {
    let reader = Proc::spawn(
        scene.command("ygg", &["watch", "--scene", &scene.name]),
        "reader",
        watchdog,
    );
    reader.expect_line(Duration::from_secs(30), |l| l.contains("generation"));
    reader
}

/// Stops a plain reader with SIGTERM.
fn stop_reader(mut reader: Proc) -> Result<(), String> {
    reader.signal(Signal::TERM);
    if reader.wait_exit(Duration::from_secs(30)).success() {
        Ok(())
    } else {
        Err(format!("the reader failed: {}", reader.stderr().join("\n")))
    }
}

/// Stops a window's follower, a recorder or a plain reader.
fn stop_follower((attached, proc): (Attached, Proc)) -> Result<(), String> {
    match attached {
        Attached::Recorder => stop_recorder(proc).map(drop),
        _ => stop_reader(proc),
    }
}

/// Stops a recorder with SIGTERM and returns its summary line.
fn stop_recorder(mut recorder: Proc) -> Result<String, String> {
    recorder.signal(Signal::TERM);
    if !recorder.wait_exit(Duration::from_secs(30)).success() {
        return Err(format!(
            "the recorder failed: {}",
            recorder.stderr().join("\n")
        ));
    }
    Ok(recorder
        .stdout()
        .into_iter()
        .rfind(|l| l.contains("\"event\":\"summary\""))
        .unwrap_or_default())
}

fn us(ns: &[f64]) -> (f64, f64) {
    median_p99(ns).map_or((f64::NAN, f64::NAN), |(m, p)| (m / 1e3, p / 1e3))
}

/// Runs `ygg-bench record`.
///
/// # Errors
/// A recorder or writer that fails, a recording that does not open.
pub fn run(args: &RecordArgs) -> Result<(), Box<dyn std::error::Error>> {
    ygg_transport::init_iceoryx_logging();
    let scene = TestScene::for_run("bench-record");
    let watchdog = Watchdog::new(Duration::from_secs_f64(
        (args.minutes + args.pair_minutes) * 60.0 + args.replay_seconds + 1800.0,
    ));
    std::fs::create_dir_all(&args.dir)?;
    let mut stream = Stream::new(&scene, args.rate)?;
    let machine = crate::ladder::report::machine();
    eprintln!(
        "phase 1: paired publish() for {} minutes",
        args.pair_minutes
    );
    let mut pair = Vec::new();
    let start = Instant::now();
    let mut window = 0usize;
    let mut follower: Option<(Attached, Proc)> = None;
    let mut toggled = Instant::now();
    while start.elapsed().as_secs_f64() < args.pair_minutes * 60.0 {
        let w = (start.elapsed().as_secs_f64() / args.toggle_seconds) as usize;
        if w != window || (w == 0 && pair.is_empty()) {
            window = w;
            toggled = Instant::now();
            if let Some(f) = follower.take() {
                stop_follower(f)?;
            }
            follower = match w % 3 {
                1 => {
                    let dir = args.dir.join(format!("pair{w}.yggrec"));
                    Some((Attached::Recorder, start_recorder(&scene, &dir, &watchdog)))
                }
                2 => Some((Attached::Reader, start_reader(&scene, &watchdog))),
                _ => None,
            };
        }
        let settling = toggled.elapsed() < Duration::from_secs(2);
        let attached = follower.as_ref().map_or(Attached::Nothing, |(a, _)| *a);
        pair.push(stream.tick(attached, settling)?);
    }
    if let Some(f) = follower.take() {
        stop_follower(f)?;
    }
    for w in 0..=window {
        let _ = std::fs::remove_dir_all(args.dir.join(format!("pair{w}.yggrec")));
    }

    eprintln!("phase 2: a {}-minute mission with a recorder", args.minutes);
    let path = args.dir.join("mission.yggrec");
    let _ = std::fs::remove_dir_all(&path);
    let recorder = start_recorder(&scene, &path, &watchdog);
    let mut mission = Vec::new();
    let start = Instant::now();
    let mut last_note = start;
    while start.elapsed().as_secs_f64() < args.minutes * 60.0 {
        mission.push(stream.tick(Attached::Recorder, false)?);
        if last_note.elapsed() > Duration::from_secs(60) {
            last_note = Instant::now();
            eprintln!(
                "  {:.0} s, {} ticks",
                start.elapsed().as_secs_f64(),
                mission.len()
            );
        }
    }
    // The last cut published is recorded before the recorder stops.
    let final_generation = stream.writer.generation();
    ygg_testkit::poll_until(Duration::from_secs(30), || {
        ygg_store::recording::Recording::open(&path)
            .ok()
            .is_some_and(|r| {
                r.cuts()
                    .last()
                    .is_some_and(|c| c.generation >= final_generation)
            })
    });
    let summary = stop_recorder(recorder)?;
    eprintln!("phase 3: reading the recording back");
    let published: Vec<(u64, usize)> = mission.iter().map(|t| (t.generation, t.bytes)).collect();
    let read = readback::measure(&path, &scene, &published, args.replay_seconds)?;

    let settled = |which: Attached| -> Vec<f64> {
        pair.iter()
            .filter(|t| t.attached == which && !t.settling)
            .map(|t| t.publish_ns)
            .collect()
    };
    let (off, on, reader) = (
        us(&settled(Attached::Nothing)),
        us(&settled(Attached::Recorder)),
        us(&settled(Attached::Reader)),
    );
    let mission_publish = us(&mission.iter().map(|t| t.publish_ns).collect::<Vec<_>>());
    let report = json!({
        "machine": machine,
        "rate_hz": args.rate,
        "paired": {"minutes": args.pair_minutes, "toggle_seconds": args.toggle_seconds,
            "ticks_without": settled(Attached::Nothing).len(),
            "ticks_with": settled(Attached::Recorder).len(),
            "ticks_with_reader": settled(Attached::Reader).len(),
            "publish_us_without": {"median": off.0, "p99": off.1},
            "publish_us_with": {"median": on.0, "p99": on.1},
            "publish_us_with_reader": {"median": reader.0, "p99": reader.1},
            "median_ratio": on.0 / off.0,
            "median_ratio_to_reader": on.0 / reader.0},
        "mission": {"minutes": args.minutes, "ticks": mission.len(),
            "publish_us": {"median": mission_publish.0, "p99": mission_publish.1},
            "recorder_summary": serde_json::from_str::<Value>(&summary).unwrap_or(Value::Null)},
        "readback": read,
    });
    std::fs::write(&args.json, serde_json::to_string_pretty(&report)? + "\n")?;
    std::fs::write(&args.out, readback::markdown(&report))?;
    let _ = std::fs::remove_dir_all(&path);
    drop(stream);
    eprintln!("wrote {} and {}", args.out.display(), args.json.display());
    Ok(())
}
