//! `writer_throughput_*`: writer updates per second with no reader, 4 idle and 4 busy readers.

use super::super::child::Readers;
use super::super::error::Res;
use super::super::interrupt::check_interrupted;
use super::super::report::{Row, median};
use super::super::scenes;
use super::context::{Ctx, in_scene};
use super::drive::{ATTACH_TIMEOUT, EXIT_GRACE, QUERY_LAYER, qps_lines, reader_args, writer};
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// CPU time of the calling thread, ns.
fn thread_cpu_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    u64::try_from(t.tv_sec).unwrap_or(0) * 1_000_000_000 + u64::try_from(t.tv_nsec).unwrap_or(0)
}

/// Readers during a writer-throughput run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Load {
    /// No reader.
    None,
    /// 4 readers attached, not reading.
    Idle,
    /// 4 readers querying the newest snapshot in a loop.
    Busy,
}

pub(super) fn case_throughput(ctx: &mut Ctx) -> Res<Vec<Row>> {
    let graph = ctx.office_mint()?;
    let secs = ctx.plan.throughput_secs;
    let reps = ctx.plan.throughput_reps;
    in_scene(ctx, "throughput", |_ctx, scene| {
        let mut mover = scenes::AgentMover::new(&graph)?;
        let mut w = writer(scene, graph, 5, 64 * 1024)?;
        // Per variant: updates per wall second and per writer CPU second (one entry per
        // repetition), per-update latencies, and the busy readers' queries per second.
        let mut wall: HashMap<Load, Vec<f64>> = HashMap::new();
        let mut cpu: HashMap<Load, Vec<f64>> = HashMap::new();
        let mut lat: HashMap<Load, Vec<f64>> = HashMap::new();
        let mut reader_qps: Vec<f64> = Vec::new();
        for rep in 0..reps {
            let mut order = [Load::None, Load::Idle, Load::Busy];
            if rep % 2 == 1 {
                order.reverse();
            }
            for load in order {
                let mut readers = if load == Load::None {
                    None
                } else {
                    let mut r = Readers::spawn(
                        4,
                        scene,
                        &reader_args("qps", Some(QUERY_LAYER)),
                        ATTACH_TIMEOUT,
                    )?;
                    if load == Load::Busy {
                        r.send_all("start")?;
                    }
                    // Let them settle (and get busy).
                    std::thread::sleep(Duration::from_millis(100));
                    Some(r)
                };
                let start = Instant::now();
                let cpu0 = thread_cpu_ns();
                let end = start + Duration::from_secs_f64(secs);
                let mut ops = 0u64;
                let l = lat.entry(load).or_default();
                while Instant::now() < end {
                    if ops.is_multiple_of(256) {
                        check_interrupted()?;
                    }
                    let t = Instant::now();
                    mover.step(w.graph_mut())?;
                    w.publish()?;
                    l.push(t.elapsed().as_nanos() as f64);
                    ops += 1;
                }
                let elapsed = start.elapsed().as_secs_f64();
                let cpu_s = thread_cpu_ns().saturating_sub(cpu0) as f64 / 1e9;
                wall.entry(load).or_default().push(ops as f64 / elapsed);
                cpu.entry(load).or_default().push(ops as f64 / cpu_s);
                if let Some(mut r) = readers.take() {
                    if load == Load::Busy {
                        r.send_all("stop")?;
                        for q in qps_lines(&mut r)? {
                            reader_qps.push(q.per_second());
                        }
                    }
                    r.finish(EXIT_GRACE)?;
                }
            }
        }
        drop(w);
        let mut rows = Vec::new();
        for (load, case, what) in [
            (
                Load::None,
                "writer_throughput_0_readers",
                "office (mint): move an agent + publish, back to back, no readers; latency per update",
            ),
            (
                Load::Idle,
                "writer_throughput_4_idle_readers",
                "the same with 4 readers attached but not reading (delivery and wake-up events only)",
            ),
            (
                Load::Busy,
                "writer_throughput_4_readers",
                "the same while 4 readers run latest() + nearest place in a loop",
            ),
        ] {
            let mut row = Row::latency(case, what, &lat[&load]);
            row.value = Some(median(&wall[&load]));
            row.unit = Some("updates/s");
            row = row.with("updates_per_writer_cpu_s", median(&cpu[&load]));
            if load == Load::Busy {
                row = row.with("reader_queries_per_s", median(&reader_qps));
            }
            rows.push(row);
        }
        Ok(rows)
    })
}
