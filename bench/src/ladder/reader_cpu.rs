//! `ygg-bench ladder --reader-cpu N`: a reader's CPU time per single-layer update.
//!
//! One process: a [`SceneWriter`] serving the office in `mint`, and a [`SceneReader`] on
//! another thread. In lockstep, `N` times: the writer changes a feature of the newest
//! agent pose (only the AGENTS layer changes) and publishes; the reader's
//! `wait_next` wakes, receives, validates the one new layer and accepts the cut, and
//! the reader builds the view. The reader's thread CPU time (`CLOCK_THREAD_CPUTIME_ID`)
//! across `wait_next` and `view()` is one sample: blocked time costs no CPU, so it is
//! the wake-up, receive, validation and view. Each answer is checked to be the
//! generation just published.

use std::sync::mpsc;
use std::time::Duration;
use ygg_dsg::layout::{self, LayerRole, Layout};
use ygg_reader::SceneReader;
use ygg_store::{FeatureValue, SceneView};
use ygg_writer::SceneWriter;

/// How long one step may take.
const TIMEOUT: Duration = Duration::from_secs(10);

/// CPU time of the calling thread, ns.
fn thread_cpu_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    u64::try_from(t.tv_sec).unwrap_or(0) * 1_000_000_000 + u64::try_from(t.tv_nsec).unwrap_or(0)
}

/// The reader thread: attaches, then for each update records the CPU of `wait_next` +
/// `view()` and reports the generation it got. Returns the samples, ns.
fn read(scene: &str, updates: usize, got: &mpsc::Sender<u64>) -> Result<Vec<f64>, String> {
    let mut reader = SceneReader::builder(scene)
        .wait_for_writer(TIMEOUT)
        .open()
        .map_err(|e| e.to_string())?;
    let first = reader
        .wait_next(TIMEOUT)
        .map_err(|e| e.to_string())?
        .ok_or("no first snapshot")?;
    got.send(first.generation()).map_err(|e| e.to_string())?;
    let mut cpu = Vec::with_capacity(updates);
    for _ in 0..updates {
        let c0 = thread_cpu_ns();
        let snapshot = reader
            .wait_next(TIMEOUT)
            .map_err(|e| e.to_string())?
            .ok_or("no update")?;
        let layers = snapshot.view().layers().count();
        let c1 = thread_cpu_ns();
        std::hint::black_box(layers);
        cpu.push(c1.saturating_sub(c0) as f64);
        got.send(snapshot.generation()).map_err(|e| e.to_string())?;
    }
    Ok(cpu)
}

/// Runs `updates` single-layer updates on the office (`scale`, split into `rooms` rooms
/// if given) and prints the reader's CPU per update.
///
/// # Errors
/// The transport failing, the reader failing or answering a stale generation.
pub fn run(
    scale: f64,
    rooms: Option<usize>,
    updates: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut dsg = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams { seed: 7, scale });
    if let Some(rooms) = rooms {
        dsg = ygg_dsg::office::split_rooms(&dsg, rooms)?;
    }
    let g = layout::build(&dsg, Layout::Mint)?;
    let agents = layout::layer_with_role(&g, LayerRole::Agents).ok_or("no agents layer")?;
    let pose = g
        .layer_nodes(agents)
        .map(|n| g.node_id(n))
        .max()
        .ok_or("no agent pose")?;
    let layer_count = g.layers().count();
    let scene = format!("ladder-reader-cpu-{}", std::process::id());
    let mut writer = SceneWriter::builder(&scene).max_readers(2).create(g)?;
    writer.publish()?;
    let (tx, rx) = mpsc::channel();
    let reader = {
        let scene = scene.clone();
        std::thread::spawn(move || read(&scene, updates, &tx))
    };
    let wait = |rx: &mpsc::Receiver<u64>| rx.recv_timeout(TIMEOUT);
    let mut stale = None;
    let mut bytes = 0;
    if wait(&rx).is_ok() {
        for i in 0..updates {
            writer
                .graph_mut()
                .set_feature(pose, "ladder_tick", FeatureValue::Int(i as i64))?;
            let report = writer.publish()?;
            bytes = report.bytes_sent;
            match wait(&rx) {
                Ok(g) if g == report.generation && report.layers_sent == 1 => {}
                other => {
                    stale = Some(format!(
                        "update {i}: the reader got {other:?} after generation {} ({} layers sent)",
                        report.generation, report.layers_sent
                    ));
                    break;
                }
            }
        }
    }
    let samples = reader.join().map_err(|_| "the reader thread panicked")??;
    if let Some(e) = stale {
        return Err(e.into());
    }
    let (median, p99) = ygg_testkit::stats::median_p99_us(&samples);
    let mean = samples.iter().sum::<f64>() / samples.len().max(1) as f64 / 1e3;
    println!(
        "reader CPU per single-layer update ({} layers, AGENTS, {:.0} KB sent per update incl. manifest), {} updates: median {median:.1} µs, p99 {p99:.1} µs, mean {mean:.1} µs",
        layer_count,
        bytes as f64 / 1e3,
        samples.len()
    );
    Ok(())
}
