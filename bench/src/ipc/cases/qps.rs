//! `qps_*`: reader queries per second while the writer publishes at 0, 10 and 100 Hz.

use super::super::error::Res;
use super::super::interrupt::check_interrupted;
use super::super::report::Row;
use super::super::scenes;
use super::context::{Ctx, in_scene};
use super::drive::{Case, QUERY_LAYER, qps_lines};
use std::time::{Duration, Instant};

pub(super) fn case_qps(ctx: &mut Ctx) -> Res<Vec<Row>> {
    let graph = ctx.office_mint()?;
    let secs = ctx.plan.qps_secs;
    in_scene(ctx, "qps", |_ctx, scene| {
        let mut mover = scenes::AgentMover::new(&graph)?;
        let mut case = Case::start(scene, graph, 64 * 1024, 1, "qps", Some(QUERY_LAYER))?;
        let Case { w, readers } = &mut case;
        let mut rows = Vec::new();
        for (case, rate) in [("qps_idle", 0.0), ("qps_10Hz", 10.0), ("qps_100Hz", 100.0)] {
            readers.send_all("start")?;
            let start = Instant::now();
            let mut publishes = 0u64;
            let mut next = start;
            let end = start + Duration::from_secs_f64(secs);
            loop {
                check_interrupted()?;
                let now = Instant::now();
                if now >= end {
                    break;
                }
                if rate > 0.0 && now >= next {
                    mover.step(w.graph_mut())?;
                    w.publish()?;
                    publishes += 1;
                    next += Duration::from_secs_f64(1.0 / rate);
                }
                let wake = if rate > 0.0 { next.min(end) } else { end };
                std::thread::sleep(
                    wake.saturating_duration_since(Instant::now())
                        .min(Duration::from_millis(50)),
                );
            }
            readers.send_all("stop")?;
            let q = qps_lines(readers)?;
            let q = q.first().ok_or("no qps report")?;
            let what = if rate > 0.0 {
                format!(
                    "1 reader: latest() + nearest place on the newest snapshot, in a loop; writer moves an agent and publishes at {rate:.0} Hz"
                )
            } else {
                "1 reader: latest() + nearest place, in a loop; writer idle (reference)".to_owned()
            };
            rows.push(Row {
                case: case.into(),
                what,
                median_us: q.median_ns / 1e3,
                p99_us: q.p99_ns / 1e3,
                samples: q.queries as usize,
                value: Some(q.per_second()),
                unit: Some("queries/s"),
                extra: vec![
                    ("publishes".into(), publishes as f64),
                    ("snapshots_seen".into(), q.snapshots),
                ],
                ..Row::default()
            });
        }
        case.finish()?;
        Ok(rows)
    })
}
