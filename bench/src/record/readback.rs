//! Phase 3 and 4 of `ygg-bench record`: the recording read back (size, opening, a cut to
//! its first answer, Q1a on a past cut against the live scene, `changes`) and replayed,
//! and the Markdown report.

use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use ygg_dsg::layout::Layout;
use ygg_reader::SceneReader;
use ygg_store::SceneView;
use ygg_store::recording::Recording;
use ygg_testkit::TestScene;
use ygg_testkit::stats::median;

use crate::ladder::harness::Target;
use crate::ladder::workload::{Query, Workload};
use crate::ladder::ygg::YggTarget;

const REPEATS: usize = 7;

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn median_of(
    mut f: impl FnMut() -> Result<f64, Box<dyn std::error::Error>>,
) -> Result<f64, Box<dyn std::error::Error>> {
    let samples = (0..REPEATS).map(|_| f()).collect::<Result<Vec<_>, _>>()?;
    Ok(median(&samples).unwrap_or(f64::NAN))
}

/// Median ns per query of answering every query of `queries` on `view`, after a warm-up
/// pass.
fn q1a_ns<V: SceneView>(view: &V, queries: &[Query]) -> f64 {
    let target = YggTarget::new(String::new(), Layout::Mint, view);
    for q in queries {
        std::hint::black_box(target.answer(q));
    }
    let samples: Vec<f64> = (0..REPEATS * 3)
        .map(|_| {
            let t = Instant::now();
            for q in queries {
                std::hint::black_box(target.answer(q));
            }
            t.elapsed().as_nanos() as f64 / queries.len() as f64
        })
        .collect();
    median(&samples).unwrap_or(f64::NAN)
}

/// Measures the recording at `path` of the writer of `scene`, whose ticks published
/// `mission` (`(generation, bytes)` per tick), and replays its last `replay_seconds`.
pub fn measure(
    path: &Path,
    scene: &TestScene,
    mission: &[(u64, usize)],
    replay_seconds: f64,
) -> Result<Value, Box<dyn std::error::Error>> {
    let rec = Recording::open(path)?;
    let cuts = rec.cuts();
    let last = cuts.len() - 1;
    let file_bytes: usize = rec.files().map(|(_, b)| b).sum();
    let first = rec.raw_cut(0)?;
    let first_cut_bytes =
        first.manifest.len() + first.segments.iter().map(|s| s.bytes.len()).sum::<usize>();
    let (g0, gn) = (cuts[0].generation, cuts[last].generation);
    let published: usize = first_cut_bytes
        + mission
            .iter()
            .filter(|(g, _)| *g > g0 && *g <= gn)
            .map(|(_, bytes)| bytes)
            .sum::<usize>();
    let missed = mission.iter().filter(|(g, _)| *g > g0 && *g <= gn).count() + 1 - cuts.len();

    let open_ms = median_of(|| {
        let t = Instant::now();
        Recording::open(path)?;
        Ok(ms(t.elapsed()))
    })?;
    let dsg = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams {
        seed: 7,
        scale: 1.0,
    });
    let queries: Vec<Query> = Workload::generate(&dsg, 7, 4)
        .queries
        .into_iter()
        .filter(|q| matches!(q, Query::Nearest { .. }))
        .collect();
    let first_answer = |cut: usize| {
        median_of(|| {
            let fresh = Recording::open(path)?;
            let t = Instant::now();
            let scene = fresh.scene(cut)?;
            let view = scene.view();
            let target = YggTarget::new(String::new(), Layout::Mint, view);
            std::hint::black_box(target.answer(&queries[0]));
            Ok(ms(t.elapsed()))
        })
    };
    let warm_first_answer = |cut: usize| {
        let warm = Recording::open(path)?;
        drop(warm.scene(cut)?);
        median_of(|| {
            let t = Instant::now();
            let scene = warm.scene(cut)?;
            let target = YggTarget::new(String::new(), Layout::Mint, scene.view());
            std::hint::black_box(target.answer(&queries[0]));
            Ok(ms(t.elapsed()))
        })
    };
    let mid = last / 2;
    let opening = json!({
        "first_cut_ms": first_answer(0)?, "middle_cut_ms": first_answer(mid)?, "last_cut_ms": first_answer(last)?,
        "first_cut_warm_ms": warm_first_answer(0)?, "last_cut_warm_ms": warm_first_answer(last)?,
    });

    let mut reader = SceneReader::builder(&scene.name)
        .iceoryx_prefix(&scene.prefix)
        .wait_for_writer(Duration::from_secs(10))
        .open()?;
    let live = match reader.latest()? {
        Some(s) => s,
        None => reader
            .wait_next(Duration::from_secs(10))?
            .ok_or("no live snapshot within 10 s")?,
    };
    let past = rec.scene(last)?;
    let live_ns = q1a_ns(live.view(), &queries);
    let past_ns = q1a_ns(past.view(), &queries);
    let same_generation = live.generation() == cuts[last].generation;
    drop((live, reader));

    let window_ns = cuts[last].writer_unix_ns.saturating_sub(600_000_000_000);
    let from = rec.cut_at_time(window_ns).unwrap_or(0);
    let changes_cold_ms = median_of(|| {
        let fresh = Recording::open(path)?;
        let t = Instant::now();
        fresh.changes(from, last, 0.05)?;
        Ok(ms(t.elapsed()))
    })?;
    let changes_warm_ms = median_of(|| {
        let t = Instant::now();
        rec.changes(from, last, 0.05)?;
        Ok(ms(t.elapsed()))
    })?;
    let c = rec.changes(from, last, 0.05)?;

    let start_ns = cuts[last]
        .writer_unix_ns
        .saturating_sub((replay_seconds * 1e9) as u64);
    let from_cut = rec.cut_at_time(start_ns).unwrap_or(0);
    let after_first = (cuts[from_cut].writer_unix_ns - cuts[0].writer_unix_ns) as f64 / 1e9;
    let replay_default = replay(path, after_first, replay_seconds, false)?;
    // With real-time priority (root only): how much of the error is waiting for a CPU
    // that other processes hold.
    let replay_realtime = replay(path, after_first, replay_seconds, true)?;

    Ok(json!({
        "cuts": cuts.len(), "cuts_skipped_by_the_recorder": missed,
        "files": rec.files().count(), "file_bytes": file_bytes, "published_bytes": published,
        "first_cut_bytes": first_cut_bytes, "size_ratio": file_bytes as f64 / published as f64,
        "open_recording_ms": open_ms,
        "cut_to_first_answer": opening,
        "q1a_ns": {"live": live_ns, "past_cut": past_ns, "ratio": past_ns / live_ns,
            "same_generation": same_generation, "queries": queries.len()},
        "changes_10min": {"from_cut": from, "to_cut": last,
            "seconds": (cuts[last].writer_unix_ns - cuts[from].writer_unix_ns) as f64 / 1e9,
            "cold_ms": changes_cold_ms, "warm_ms": changes_warm_ms,
            "segments_compared": c.segments_compared, "nodes_added": c.nodes_added.len(),
            "nodes_moved": c.nodes_moved.len(), "edges_added": c.edges_added.len()},
        "replay": replay_default,
        "replay_realtime": replay_realtime,
    }))
}

/// Replays the recording at `path` from `after_first` seconds after its first cut to
/// its end (about `replay_seconds`) at 1x with `ygg serve --recording` (under `chrt -f 10` when `realtime`), and
/// reports how far each interval between two cuts strayed from the recorded one (the
/// player's own measurement, its summary line).
fn replay(
    path: &Path,
    after_first: f64,
    replay_seconds: f64,
    realtime: bool,
) -> Result<Value, Box<dyn std::error::Error>> {
    let scene = TestScene::for_run("bench-replay");
    let ygg = ygg_testkit::binary("ygg");
    let from = format!("+{after_first:.6}");
    let args = [
        "serve",
        "--scene",
        &scene.name,
        "--recording",
        path.to_str().ok_or("path")?,
        "--from",
        &from,
    ];
    let mut command = if realtime {
        let mut c = std::process::Command::new("chrt");
        c.args(["-f", "10"]).arg(&ygg).args(args);
        c
    } else {
        let mut c = std::process::Command::new(&ygg);
        c.args(args);
        c
    };
    scene.configure(&mut command);
    let watchdog =
        ygg_testkit::Watchdog::new(Duration::from_secs_f64(replay_seconds * 2.0 + 120.0));
    let mut player = ygg_testkit::Proc::spawn(command, "replay", &watchdog);
    // The player keeps serving the last cut after it: stop it once it says so.
    player.expect_line(Duration::from_secs_f64(replay_seconds * 2.0 + 60.0), |l| {
        l.contains("\"event\":\"end\"")
    });
    player.signal(rustix::process::Signal::INT);
    if !player.wait_exit(Duration::from_secs(30)).success() {
        return Ok(json!({"error": player.stderr().join("\n")}));
    }
    let summary: Value = player
        .stdout()
        .iter()
        .rfind(|l| l.contains("\"event\":\"summary\""))
        .map(|l| serde_json::from_str(l))
        .transpose()?
        .ok_or("the replay printed no summary")?;
    Ok(json!({"cuts": summary["cuts_played"], "realtime": realtime,
        "interval_error_ms": {"p50": summary["interval_error_ms_p50"], "p99": summary["interval_error_ms_p99"],
            "max": summary["interval_error_ms_max"]}}))
}

/// The Markdown report of `r` (the JSON written beside it).
pub fn markdown(r: &Value) -> String {
    let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    let m = &r["machine"];
    let p = &r["paired"];
    let b = &r["readback"];
    let o = &b["cut_to_first_answer"];
    let yes = |ok: bool| if ok { "yes" } else { "**no**" };
    let mut s = String::new();
    s += "# Recording a live scene: issue 41's targets (`ygg-bench record`)\n\n";
    s += &format!(
        "Machine: {} ({} cores), load average at the start {}. Other builds and tests ran on \
         this machine during the run (noisy: medians, and the paired windows alternate in \
         the same run).\n\n",
        m["cpu"].as_str().unwrap_or("?"),
        m["cores"],
        m["loadavg"].as_str().unwrap_or("?")
    );
    s += &format!(
        "Stream: the demo's (built-in office, mint layout, `SlamReplay`) at {} Hz.\n\n",
        r["rate_hz"]
    );
    s += "| target | measured | met |\n|---|---|---|\n";
    let ratio = f(&b["size_ratio"]);
    s += &format!(
        "| recording size ≤ 1.2× the bytes published for its cuts ({:.1} min) | {:.1} MB / {:.1} MB = {:.3}× | {} |\n",
        f(&r["mission"]["minutes"]),
        f(&b["file_bytes"]) / 1e6,
        f(&b["published_bytes"]) / 1e6,
        ratio,
        yes(ratio <= 1.2)
    );
    let pr = f(&p["median_ratio"]);
    s += &format!(
        "| `publish()` per tick with a recorder within noise of without (paired windows) | {:.1} µs vs {:.1} µs median ({:.3}×); p99 {:.1} vs {:.1} µs | {} |\n",
        f(&p["publish_us_with"]["median"]),
        f(&p["publish_us_without"]["median"]),
        pr,
        f(&p["publish_us_with"]["p99"]),
        f(&p["publish_us_without"]["p99"]),
        yes(pr <= 1.1)
    );
    if p.get("publish_us_with_reader").is_some() {
        s += &format!(
            "| (the same, a recorder against a plain reader, `ygg watch`, attached: what recording adds to what any subscriber costs) | {:.1} µs vs {:.1} µs median ({:.3}×); p99 {:.1} vs {:.1} µs | {} |\n",
            f(&p["publish_us_with"]["median"]),
            f(&p["publish_us_with_reader"]["median"]),
            f(&p["median_ratio_to_reader"]),
            f(&p["publish_us_with"]["p99"]),
            f(&p["publish_us_with_reader"]["p99"]),
            yes(f(&p["median_ratio_to_reader"]) <= 1.1)
        );
    }
    let worst = f(&o["first_cut_ms"])
        .max(f(&o["last_cut_ms"]))
        .max(f(&o["middle_cut_ms"]));
    s += &format!(
        "| any cut to its first Q1a answer ≤ 5 ms, first = last (fresh open: every segment validated) | first {:.2} ms, middle {:.2} ms, last {:.2} ms | {} |\n",
        f(&o["first_cut_ms"]),
        f(&o["middle_cut_ms"]),
        f(&o["last_cut_ms"]),
        yes(worst <= 5.0)
    );
    s += &format!(
        "| the same, segments validated by an earlier open of a cut | first {:.3} ms, last {:.3} ms | {} |\n",
        f(&o["first_cut_warm_ms"]),
        f(&o["last_cut_warm_ms"]),
        yes(f(&o["first_cut_warm_ms"]).max(f(&o["last_cut_warm_ms"])) <= 5.0)
    );
    let q = &b["q1a_ns"];
    s += &format!(
        "| Q1a on a past cut within 1.2× of the live scene | {:.2} µs vs {:.2} µs per query ({:.3}×) | {} |\n",
        f(&q["past_cut"]) / 1e3,
        f(&q["live"]) / 1e3,
        f(&q["ratio"]),
        yes(f(&q["ratio"]) <= 1.2)
    );
    let c = &b["changes_10min"];
    s += &format!(
        "| `changes(t0, t1)` over 10 minutes ≤ 50 ms | {:.1} ms cold (fresh open), {:.1} ms warm; {:.0} s, {} segments compared, {} nodes added, {} moved | {} |\n",
        f(&c["cold_ms"]),
        f(&c["warm_ms"]),
        f(&c["seconds"]),
        c["segments_compared"],
        c["nodes_added"],
        c["nodes_moved"],
        yes(f(&c["cold_ms"]) <= 50.0)
    );
    for (key, how) in [
        ("replay", "`ygg serve --recording`"),
        ("replay_realtime", "the same under `chrt -f 10`"),
    ] {
        let e = &b[key]["interval_error_ms"];
        s += &format!(
            "| replay at 1× ({how}): inter-cut timing within 1 ms p99 | p50 {:.3} ms, p99 {:.3} ms, max {:.3} ms over {} cuts | {} |\n",
            f(&e["p50"]),
            f(&e["p99"]),
            f(&e["max"]),
            b[key]["cuts"],
            yes(f(&e["p99"]) <= 1.0)
        );
    }
    s += &format!(
        "\nOther numbers: opening the recording (scanning {} files, {} cuts) {:.1} ms; the \
         first cut (the whole scene) {:.1} MB; the recorder skipped {} of the writer's cuts \
         (it records the newest when it falls behind); `publish()` over the whole mission \
         {:.1} µs median, {:.1} µs p99.\n",
        b["files"],
        b["cuts"],
        f(&b["open_recording_ms"]),
        f(&b["first_cut_bytes"]) / 1e6,
        b["cuts_skipped_by_the_recorder"],
        f(&r["mission"]["publish_us"]["median"]),
        f(&r["mission"]["publish_us"]["p99"])
    );
    s += "\nHow: `cargo build --release -p ygg-cli -p ygg-bench && target/release/ygg-bench record` \
          (phases in `bench/src/record/mod.rs`). Raw numbers: `record.json`.\n";
    s
}
