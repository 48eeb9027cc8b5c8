//! `size_*`: one layer of a given size republished, one reader.

use super::super::child::Readers;
use super::super::report::Row;
use super::super::{Res, scenes};
use super::drive::{ATTACH_TIMEOUT, EXIT_GRACE, drive, observe, reader_args, writer};
use super::{Ctx, in_scene};

pub(super) fn case_size(ctx: &mut Ctx, label: &str, bytes: usize, samples: usize) -> Res<Row> {
    let (graph, node) = scenes::sized_layer(bytes)?;
    in_scene(ctx, "size", |ctx, scene| {
        let mut w = writer(scene, graph, 2, bytes + 4096)?;
        let mut readers = Readers::spawn(1, scene, &reader_args("latency", None), ATTACH_TIMEOUT)?;
        let (p, s) = drive(&ctx.plan, &mut w, &mut readers, 3, samples, &mut |g, i| {
            scenes::nudge(g, node, i)
        })?;
        readers.finish(EXIT_GRACE)?;
        drop(w);
        let o = observe(&p, &s);
        Ok(o.annotate(Row::latency(
            &format!("size_{label}"),
            &format!("one layer of ~{label} republished → validated snapshot in 1 reader"),
            &o.visible,
        )))
    })
}
