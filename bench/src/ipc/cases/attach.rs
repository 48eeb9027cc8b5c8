//! `attach_*`: a new reader process's attach to its first answer, and what one scene costs in
//! descriptors and shared-memory files, on the office and on the 103-room office.

use super::super::child::ReaderProc;
use super::super::report::{Row, median};
use super::super::{Res, check_interrupted, unix_ns};
use super::drive::{ATTACH_TIMEOUT, EXIT_GRACE, QUERY_LAYER, reader_args, writer};
use super::{Ctx, in_scene};
use std::time::Instant;
use ygg_store::{SceneGraph, SceneView};

/// Open descriptors of process `pid` (`self` for this one).
fn descriptors(pid: &str) -> Res<usize> {
    Ok(std::fs::read_dir(format!("/proc/{pid}/fd"))?.count())
}

/// Files in /dev/shm with `prefix`.
fn shm_files(prefix: &str) -> Res<usize> {
    Ok(std::fs::read_dir("/dev/shm")?
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .count())
}

/// An idle writer publishes `graph` once; `samples` reader processes attach one after the
/// other, each timed from its start to its first nearest-node query answered.
pub(super) fn case_attach(
    ctx: &mut Ctx,
    case: &str,
    what: &str,
    graph: SceneGraph,
    samples: usize,
) -> Res<Row> {
    let layers = graph.layers().count();
    in_scene(ctx, case, |_, scene| {
        let before = descriptors("self")?;
        let w = writer(scene, graph, 2, 64 * 1024)?;
        let writer_fds = descriptors("self")?.saturating_sub(before);
        let mut attach = Vec::with_capacity(samples);
        let mut from_spawn = Vec::with_capacity(samples);
        let mut cpu = Vec::with_capacity(samples);
        let (mut reader_fds, mut files) = (Vec::new(), Vec::new());
        for _ in 0..samples {
            check_interrupted()?;
            let spawned = unix_ns();
            let mut p = ReaderProc::spawn(
                "attach reader".to_owned(),
                scene,
                &reader_args("attach", Some(QUERY_LAYER)),
            )?;
            let line = p.expect("ready", Instant::now() + ATTACH_TIMEOUT)?;
            let v: Vec<u64> = line
                .split_whitespace()
                .skip(1)
                .filter_map(|x| x.parse().ok())
                .collect();
            let [_, started, answered, cpu_ns] = v[..] else {
                return Err(format!("malformed attach line {line:?}").into());
            };
            attach.push(answered.saturating_sub(started) as f64);
            cpu.push(cpu_ns as f64);
            from_spawn.push(answered.saturating_sub(spawned) as f64);
            reader_fds.push(descriptors(&p.pid().to_string())? as f64);
            files.push(shm_files(&scene.prefix)? as f64);
            p.close_stdin();
            p.finish(EXIT_GRACE)?;
        }
        drop(w);
        Ok(Row::latency(case, what, &attach)
            .with("from_spawn_median_us", median(&from_spawn) / 1e3)
            .with("process_cpu_us", median(&cpu) / 1e3)
            .with("layers", layers as f64)
            .with("writer_fds", writer_fds as f64)
            .with("reader_fds", median(&reader_fds))
            .with("shm_files", median(&files)))
    })
}
