//! `size_*`: one layer of a given size republished, one reader.

use super::super::error::Res;
use super::super::report::Row;
use super::super::scenes;
use super::context::{Ctx, in_scene};
use super::drive::Case;

pub(super) fn case_size(ctx: &mut Ctx, label: &str, bytes: usize, samples: usize) -> Res<Row> {
    let (graph, node) = scenes::sized_layer(bytes)?;
    in_scene(ctx, "size", |ctx, scene| {
        let mut case = Case::start(scene, graph, bytes + 4096, 1, "latency", None)?;
        let o = case.observe(&ctx.plan, 3, samples, &mut |g, i| scenes::nudge(g, node, i))?;
        case.finish()?;
        Ok(o.annotate(Row::latency(
            &format!("size_{label}"),
            &format!("one layer of ~{label} republished → validated snapshot in 1 reader"),
            &o.visible,
        )))
    })
}
