//! `ygg-bench ladder --writer-ticks N`: the writer's cost per tick of the demo's stream,
//! in process, without the transport.
//!
//! The office in `mint` takes `N` ticks of [`SlamReplay`] (the stream `ygg serve`
//! and the demo replay); after each tick every changed layer's segment is brought up to
//! date through a [`SegmentCache`] (as [`ygg_writer::SceneWriter::publish`] does) and
//! archived into a buffer, then the manifest. Reported: the update (the stream's
//! mutations), the segment builds and the archiving per tick (means and medians; the
//! archiving includes the sizing pass, `archived_len`, also shown alone), and where the
//! build and archive time goes by layer role.

use std::collections::BTreeMap;
use std::time::Instant;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::replay::SlamReplay;
use ygg_store::snapshot::{SegmentBytes, SegmentCache};
use ygg_store::{SceneGraph, SceneView};

/// Per-tick costs, ns.
#[derive(Default)]
struct Ticks {
    update: Vec<f64>,
    build: Vec<f64>,
    sizing: Vec<f64>,
    archive: Vec<f64>,
    bytes: Vec<f64>,
}

/// The layer's role: its name without the room (`room:12/claimed-mesh` → `room/claimed-mesh`).
fn role_of(name: &str) -> String {
    match name.split_once('/') {
        Some((_, role)) => format!("room/{role}"),
        None => name.to_owned(),
    }
}

/// Archives `len` bytes into `buf` through `write` (the in-place path the writer uses
/// on a loaned sample): `buf` only grows, so no tick pays for zeroing it.
fn archive_len(len: usize, buf: &mut SegmentBytes, write: impl FnOnce(&mut [u8]) -> usize) {
    if buf.len() < len {
        buf.resize(len, 0);
    }
    let written = write(&mut buf[..len]);
    assert_eq!(written, len, "archived length");
}

/// Runs `ticks` ticks of the stream on the office (`scale`) and prints the costs.
///
/// # Errors
/// A mutation of the stream refused.
pub fn run(scale: f64, ticks: usize) -> Result<(), Box<dyn std::error::Error>> {
    let dsg = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams { seed: 7, scale });
    let mut g: SceneGraph = layout::build(&dsg, Layout::Mint)?;
    let mut replay = SlamReplay::new(&g, 7);
    let mut cache = SegmentCache::new();
    let mut published: BTreeMap<u32, u64> = BTreeMap::new();
    let mut buf = SegmentBytes::new();
    // Per role: build ns, archive ns, bytes (sums) and each send's build + archive ns.
    let mut by_role: BTreeMap<String, (f64, f64, usize, Vec<f64>)> = BTreeMap::new();
    let mut t = Ticks::default();
    for tick in 0..=ticks {
        let t0 = Instant::now();
        if tick > 0 {
            replay.step(&mut g)?;
        }
        let t1 = Instant::now();
        let (mut build_ns, mut sizing_ns, mut archive_ns, mut bytes) = (0.0, 0.0, 0.0, 0usize);
        let layers: Vec<_> = g.layers().collect();
        for l in layers {
            let generation = g.layer_generation(l).expect("listed layer");
            if published.get(&l.0) == Some(&generation) {
                continue;
            }
            published.insert(l.0, generation);
            let role = role_of(g.layer_name(l).unwrap_or(""));
            let a = Instant::now();
            let segment = cache.layer_segment(&mut g, l);
            let b = Instant::now();
            let len = segment.archived_len();
            let sized = Instant::now();
            archive_len(len, &mut buf, |out| {
                segment.archive_into(out).expect("sized")
            });
            let c = Instant::now();
            sizing_ns += (sized - b).as_nanos() as f64;
            let e = by_role.entry(role).or_default();
            e.0 += (b - a).as_nanos() as f64;
            e.1 += (c - b).as_nanos() as f64;
            e.2 += len;
            e.3.push((c - a).as_nanos() as f64);
            build_ns += (b - a).as_nanos() as f64;
            archive_ns += (c - b).as_nanos() as f64;
            bytes += len;
        }
        let a = Instant::now();
        let manifest = cache.manifest(&g, tick as u64 + 1);
        let len = manifest.archived_len();
        sizing_ns += a.elapsed().as_nanos() as f64;
        archive_len(len, &mut buf, |out| {
            manifest.archive_into(out).expect("sized")
        });
        archive_ns += a.elapsed().as_nanos() as f64;
        bytes += len;
        if tick == 0 {
            by_role.clear();
            continue;
        }
        t.update.push((t1 - t0).as_nanos() as f64);
        t.build.push(build_ns);
        t.sizing.push(sizing_ns);
        t.archive.push(archive_ns);
        t.bytes.push(bytes as f64);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let median = |v: &[f64]| {
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        s.get(s.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "writer per tick over {ticks} ticks of the demo stream (mint, scale {scale}), µs mean / median:"
    );
    for (name, v) in [
        ("update", &t.update),
        ("segment builds", &t.build),
        ("archiving", &t.archive),
        ("  of it sizing", &t.sizing),
    ] {
        println!(
            "  {name:<15} {:>8.1} / {:>8.1}",
            mean(v) / 1e3,
            median(v) / 1e3
        );
    }
    let total: Vec<f64> = (0..t.build.len())
        .map(|i| t.build[i] + t.archive[i])
        .collect();
    println!(
        "  {:<15} {:>8.1} / {:>8.1}",
        "build+archive",
        mean(&total) / 1e3,
        median(&total) / 1e3
    );
    println!("  bytes archived per tick: {:.0} mean", mean(&t.bytes));
    println!(
        "by layer role: µs per tick (build, archive), KB per tick, sends, µs per send (median, max):"
    );
    let mut roles: Vec<_> = by_role.into_iter().collect();
    roles.sort_by(|a, b| (b.1.0 + b.1.1).total_cmp(&(a.1.0 + a.1.1)));
    for (role, (b, a, n, sends)) in roles {
        let per = ticks as f64;
        let max = sends.iter().copied().fold(0.0, f64::max);
        println!(
            "  {role:<24} {:>7.1} {:>7.1} {:>8.1} {:>6} {:>8.1} {:>8.1}",
            b / per / 1e3,
            a / per / 1e3,
            n as f64 / per / 1e3,
            sends.len(),
            median(&sends) / 1e3,
            max / 1e3
        );
    }
    Ok(())
}
