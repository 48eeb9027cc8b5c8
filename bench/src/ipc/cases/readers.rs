//! `readers_N`: a small update, visible in every one of N reader processes.

use super::super::error::Res;
use super::super::report::{Row, median_p99_us};
use super::super::scenes;
use super::context::{Ctx, in_scene};
use super::drive::Case;

pub(super) fn case_readers(ctx: &mut Ctx, n: usize) -> Res<Row> {
    let (graph, node) = scenes::small()?;
    in_scene(ctx, "readers", |ctx, scene| {
        let mut case = Case::start(scene, graph, 64 * 1024, n, "latency", None)?;
        let samples = ctx.plan.small_samples;
        let o = case.observe(&ctx.plan, 5, samples, &mut |g, i| scenes::nudge(g, node, i))?;
        case.finish()?;
        let (any_med, any_p99) = median_p99_us(&o.visible);
        Ok(o.annotate(
            Row::latency(
                &format!("readers_{n}"),
                &format!("small update (~2 KB layer) → visible in every one of {n} reader(s) (the slowest)"),
                &o.all_visible,
            )
            .with("each_reader_median_us", any_med)
            .with("each_reader_p99_us", any_p99),
        ))
    })
}
