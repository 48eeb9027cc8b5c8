//! One mission run (`ygg-bench mission --leaf`, started by [`super::paired`]): this
//! process is the writer, replaying the demo's SLAM stream on the built-in office (mint),
//! with reader processes of `ygg-bench ipc reader` following it. Prints `progress` lines
//! and, last, one `result <json>` line on stdout.

use super::args::{Config, FORMAT};
use super::procfs;
use super::spans::{self, Around, Kind, Log, ProcSample, Span, Tick};
use crate::ipc::bare::BarePublisher;
use crate::ipc::cases::{
    ATTACH_TIMEOUT, EXIT_GRACE, collect_seen, reader_args, spawn_attacher, writer,
};
use crate::ipc::child::{Readers, Scene};
use crate::ipc::clock::unix_ns;
use crate::ipc::error::Res;
use crate::ipc::interrupt::{check_interrupted, install_signal_handler};
use crate::ipc::report::median;
use crate::ipc::scenes;
use serde_json::{Value, json};
use std::io::Write;
use std::time::{Duration, Instant};
use ygg_dsg::layout::Layout;
use ygg_dsg::replay::SlamReplay;
use ygg_dsg::replay::window::{Keep, Window};
use ygg_writer::SceneWriter;

/// How long readers may take to catch up with the writer at a mark.
const CATCH_UP: Duration = Duration::from_secs(60);

/// Largest payload the bare iceoryx2 floor sends (a tick that sends more is floored at
/// this size).
const BARE_MAX_BYTES: usize = 8 << 20;

/// The bare iceoryx2 floor of `--bare`: a publisher in this process, a subscriber
/// process, and what the subscriber recorded (by tick number).
struct BareFloor {
    publisher: BarePublisher,
    subscriber: Readers,
    log: Log,
}

/// Runs one mission and prints its result.
pub fn main(cfg: &Config) -> Res<()> {
    // Die with the benchmark that started this run, even if it was SIGKILLed.
    ygg_testkit::die_with_parent().map_err(|e| format!("cannot die with the benchmark: {e}"))?;
    install_signal_handler();
    let _ = ygg_transport::limits::raise_open_file_limit();
    let scene = Scene::for_run("mission");
    let result = run(cfg, &scene);
    // Every process of the scene has exited (the readers were finished or dropped).
    let leftovers = scene.clean_up();
    let mut result = result?;
    result["leftovers"] = json!(leftovers);
    let mut out = std::io::stdout().lock();
    writeln!(out, "result {result}")?;
    out.flush()?;
    Ok(())
}

/// Prints a `progress` line (the benchmark echoes it).
fn progress(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "progress {text}");
    let _ = out.flush();
}

/// The writer, its readers and everything measured so far.
struct Mission<'a> {
    cfg: &'a Config,
    scene: &'a Scene,
    w: SceneWriter,
    readers: Readers,
    replay: SlamReplay,
    window: Window,
    /// Ticks from `base` on (older ones are dropped once no open span needs them).
    ticks: Vec<Tick>,
    base: u64,
    /// Each reader's snapshots not yet dropped.
    logs: Vec<Log>,
    /// Generation of the initial publish (before tick 0).
    initial_generation: u64,
    /// Readers at each mark after any attach, by mark: the start of the spans from there.
    starts: Vec<(u64, Vec<ProcSample>)>,
    /// With `--bare`: the floor beside the writer.
    bare: Option<BareFloor>,
}

fn run(cfg: &Config, scene: &Scene) -> Res<Value> {
    let started = Instant::now();
    let machine = crate::ladder::report::machine();
    let graph = scenes::office(&scenes::office_dsg(1.0), Layout::Mint)?;
    let nodes_start = graph.node_count();
    // Room for the readers, a late reader and one more.
    let w = writer(
        scene,
        graph,
        cfg.readers + 2,
        ygg_transport::DEFAULT_INITIAL_SEGMENT_BYTES,
    )?;
    let initial_generation = w.generation();
    let replay = SlamReplay::new(w.graph(), 7);
    let keep = Keep {
        poses: cfg.keep_poses,
        ..Keep::default()
    };
    let window = Window::new(w.graph(), keep);
    let readers = Readers::spawn(
        cfg.readers,
        scene,
        &reader_args("latency", None),
        ATTACH_TIMEOUT,
    )?;
    let bare = if cfg.bare {
        Some(BareFloor {
            publisher: BarePublisher::new(&scene.name, &scene.prefix, BARE_MAX_BYTES, 2)?,
            subscriber: Readers::spawn(1, scene, &reader_args("bare", None), ATTACH_TIMEOUT)?,
            log: Log::new(),
        })
    } else {
        None
    };
    progress(&format!(
        "office: {nodes_start} nodes; {} reader(s) attached{}",
        cfg.readers,
        if cfg.bare {
            "; bare iceoryx2 floor"
        } else {
            ""
        }
    ));
    let mut m = Mission {
        cfg,
        scene,
        w,
        readers,
        replay,
        window,
        ticks: Vec::new(),
        base: 0,
        logs: vec![Log::new(); cfg.readers],
        initial_generation,
        starts: Vec::new(),
        bare,
    };
    let windows = spans::windows(cfg.ticks, cfg.window);
    let bins = spans::bins(cfg.ticks);
    let all: Vec<Span> = windows.iter().chain(&bins).cloned().collect();
    let marks = spans::marks(&all);
    let (mut window_out, mut bin_out) = (Vec::new(), Vec::new());
    let mut tick = 0u64;
    let mut busy = Duration::ZERO;
    for mark in marks {
        let t = Instant::now();
        m.run_ticks(tick, mark)?;
        busy += t.elapsed();
        tick = mark;
        let window_ends = windows.iter().any(|w| w.end == mark);
        let end = m.at_mark(mark, window_ends)?;
        for span in all.iter().filter(|s| s.end == mark) {
            let out = m.span(span, &end)?;
            match span.kind {
                Kind::Window => window_out.push(out),
                Kind::Bin => bin_out.push(out),
            }
        }
        if let Some(b) = bin_out
            .last()
            .filter(|_| bins.iter().any(|b| b.end == mark))
        {
            progress(&format!(
                "tick {mark}/{}: publish {:.0} µs, {:.0} KB per tick, reader p50 {:.0} µs; {:.0} s",
                cfg.ticks,
                b["m"]["publish_mean_us"].as_f64().unwrap_or(f64::NAN),
                b["m"]["bytes_mean_bytes"].as_f64().unwrap_or(f64::NAN) / 1e3,
                b["m"]["visible_p50_us"].as_f64().unwrap_or(f64::NAN),
                started.elapsed().as_secs_f64()
            ));
        }
        let needed = all
            .iter()
            .filter(|s| s.end > mark)
            .map(|s| s.start)
            .min()
            .unwrap_or(mark);
        m.drop_before(needed);
    }
    let nodes_end = m.w.graph().node_count();
    m.readers.finish(EXIT_GRACE)?;
    if let Some(bare) = m.bare.take() {
        bare.subscriber.finish(EXIT_GRACE)?;
    }
    drop(m.w);
    Ok(json!({
        "format": FORMAT,
        "config": cfg.to_json(),
        "machine": machine,
        "machine_end": crate::ladder::report::machine(),
        "binary": std::env::current_exe().map(|p| p.display().to_string()).unwrap_or_default(),
        "duration_s": started.elapsed().as_secs_f64(),
        "ticks_s": busy.as_secs_f64(),
        "nodes_start": nodes_start,
        "nodes_end": nodes_end,
        "windows": window_out,
        "bins": bin_out,
    }))
}

/// What was sampled at a mark before any attach.
struct AtMark {
    readers: Vec<ProcSample>,
    writer: ProcSample,
    nodes: usize,
    /// Late readers' (attach, from spawn, CPU) times, ns, when a window ended here.
    attach: Vec<[f64; 3]>,
}

impl Mission<'_> {
    /// Runs ticks `from..to`: a step of the stream (and the window's trim), then a
    /// publish, paced at the rate if there is one.
    fn run_ticks(&mut self, from: u64, to: u64) -> Res<()> {
        let period = (self.cfg.rate > 0.0).then(|| Duration::from_secs_f64(1.0 / self.cfg.rate));
        let mut next = Instant::now();
        for i in from..to {
            if i.is_multiple_of(64) {
                check_interrupted()?;
            }
            if let Some(p) = period {
                // Pacing at the rate (as `ygg serve` does): a timer, not a stand-in for an
                // event.
                let now = Instant::now();
                let wait = next.saturating_duration_since(now);
                next = next.max(now) + p;
                std::thread::sleep(wait);
            }
            let u = Instant::now();
            let report = self.replay.step(self.w.graph_mut())?;
            self.window.trim(self.w.graph_mut(), &self.replay, report)?;
            let update_ns = u.elapsed().as_nanos() as u64;
            let started = Instant::now();
            let t0 = unix_ns();
            let r = self.w.publish()?;
            let t1 = unix_ns();
            let (mut bare_t0, mut bare_call_ns) = (0, 0);
            if let Some(bare) = &self.bare {
                // Half a tick later at a rate, so that the floor and the readers do not
                // queue for the same cores; at once otherwise.
                if let Some(p) = period {
                    std::thread::sleep((p / 2).saturating_sub(started.elapsed()));
                }
                bare_t0 = unix_ns();
                bare.publisher.publish_bytes(i, r.bytes_sent)?;
                bare_call_ns = unix_ns() - bare_t0;
            }
            self.ticks.push(Tick {
                generation: r.generation,
                t0,
                t1,
                update_ns,
                bytes: r.bytes_sent,
                layers_sent: r.layers_sent,
                chunks_sent: r.chunks_sent,
                segments: r.segments,
                bare_t0,
                bare_call_ns,
            });
        }
        Ok(())
    }

    /// The generation of the last publish before tick `mark`.
    fn generation_before(&self, mark: u64) -> u64 {
        mark.checked_sub(1)
            .and_then(|t| t.checked_sub(self.base))
            .and_then(|i| self.ticks.get(i as usize))
            .map_or(self.initial_generation, |t| t.generation)
    }

    /// At a mark: waits for every reader to hold the newest snapshot (collecting what they
    /// recorded), samples `/proc`, lets late readers attach if a window ends here, and
    /// samples the readers again for the spans starting here.
    fn at_mark(&mut self, mark: u64, window_ends: bool) -> Res<AtMark> {
        // At mark 0 each reader holds the first publish: it said `ready` with it.
        if mark > 0 {
            self.catch_up(self.generation_before(mark))?;
            self.bare_catch_up(mark)?;
        }
        let readers = self.sample_readers();
        let writer = procfs::sample(None);
        let nodes = self.w.graph().node_count();
        let mut attach = Vec::new();
        if window_ends {
            for _ in 0..self.cfg.attach_samples {
                check_interrupted()?;
                let (mut p, t) = spawn_attacher(self.scene)?;
                p.close_stdin();
                p.finish(EXIT_GRACE)?;
                attach.push([t.attach_ns as f64, t.from_spawn_ns as f64, t.cpu_ns as f64]);
            }
        }
        let after = if window_ends {
            self.sample_readers()
        } else {
            readers.clone()
        };
        self.starts.push((mark, after));
        Ok(AtMark {
            readers,
            writer,
            nodes,
            attach,
        })
    }

    fn sample_readers(&self) -> Vec<ProcSample> {
        self.readers
            .procs
            .iter()
            .map(|p| procfs::sample(Some(p.pid())))
            .collect()
    }

    /// Collects the readers' records until each holds `generation`.
    fn catch_up(&mut self, generation: u64) -> Res<()> {
        let deadline = Instant::now() + CATCH_UP;
        loop {
            let seen = collect_seen(&mut self.readers)?;
            for (log, s) in self.logs.iter_mut().zip(seen) {
                let mut new: Log = s.into_iter().collect();
                new.sort_unstable_by_key(|(g, _)| *g);
                log.extend(new);
            }
            let behind = self
                .logs
                .iter()
                .position(|l| l.last().is_none_or(|(g, _)| *g < generation));
            match behind {
                None => return Ok(()),
                Some(i) if Instant::now() > deadline => {
                    return Err(format!(
                        "reader {i} did not see generation {generation} within {CATCH_UP:?}"
                    )
                    .into());
                }
                Some(_) => {}
            }
        }
    }

    /// With `--bare`: collects the bare subscriber's records until it holds tick
    /// `mark - 1` (it always gets the newest sample; one it missed is left out of the
    /// floor's latencies).
    fn bare_catch_up(&mut self, mark: u64) -> Res<()> {
        let Some(bare) = &mut self.bare else {
            return Ok(());
        };
        let deadline = Instant::now() + CATCH_UP;
        loop {
            let seen = collect_seen(&mut bare.subscriber)?;
            let mut new: Log = seen.into_iter().flatten().collect();
            new.sort_unstable_by_key(|(n, _)| *n);
            bare.log.extend(new);
            if bare.log.last().is_some_and(|(n, _)| *n + 1 >= mark) {
                return Ok(());
            }
            if Instant::now() > deadline {
                return Err(format!(
                    "the bare subscriber did not see tick {} within {CATCH_UP:?}",
                    mark - 1
                )
                .into());
            }
        }
    }

    /// The metrics of `span`, which ends at this mark.
    fn span(&self, span: &Span, end: &AtMark) -> Res<Value> {
        let start = self
            .starts
            .iter()
            .find(|(m, _)| *m == span.start)
            .map(|(_, s)| s.as_slice())
            .ok_or_else(|| format!("no sample at the start of span {}", span.name))?;
        let from = usize::try_from(span.start - self.base)?;
        let to = usize::try_from(span.end - self.base)?;
        let mut v = spans::compute(
            span,
            &Around {
                ticks: &self.ticks[from..to],
                readers_start: start,
                readers_end: &end.readers,
                writer_end: end.writer,
                nodes: end.nodes,
                bare: self.bare.as_ref().map(|b| &b.log),
            },
            &self.logs,
        );
        if span.kind == Kind::Window {
            let col = |k: usize| -> Vec<f64> { end.attach.iter().map(|a| a[k]).collect() };
            let ms = |k: usize| Some(median(&col(k)) / 1e6).filter(|v| v.is_finite());
            v["m"]["attach_ms"] = json!(ms(0));
            v["m"]["attach_from_spawn_ms"] = json!(ms(1));
            v["m"]["attach_cpu_ms"] = json!(ms(2));
        }
        Ok(v)
    }

    /// Forgets ticks, records and samples from before tick `tick`.
    fn drop_before(&mut self, tick: u64) {
        // Snapshots up to the last publish before `tick` show no tick from `tick` on.
        let older = self.generation_before(tick);
        for log in &mut self.logs {
            let k = log.partition_point(|(g, _)| *g <= older);
            log.drain(..k);
        }
        if let Some(bare) = &mut self.bare {
            let k = bare.log.partition_point(|(n, _)| *n < tick);
            bare.log.drain(..k);
        }
        let n = usize::try_from(tick.saturating_sub(self.base)).unwrap_or(0);
        self.ticks.drain(..n.min(self.ticks.len()));
        self.base += n as u64;
        self.starts.retain(|(m, _)| *m >= tick);
    }
}
