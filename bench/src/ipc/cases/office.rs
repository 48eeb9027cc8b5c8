//! The office cases: one agent pose against every layer republished, mint and chocolate.

use super::super::error::Res;
use super::super::report::{Row, median, median_p99_us};
use super::super::scenes;
use super::context::{Ctx, in_scene};
use super::drive::{Case, Observed, QUERY_LAYER};
use ygg_dsg::layout::Layout;
use ygg_store::snapshot::{MAX_POINT_CHUNK_LEN, POINT_CHUNK_LEN};

pub(super) fn case_office(ctx: &mut Ctx) -> Res<Vec<Row>> {
    let agents = scenes::agents_segment_bytes(&ctx.office()?.1)?;
    let samples = ctx.plan.office_samples;
    let mut rows = vec![super::bare::case_bare(ctx, agents, samples)?];
    rows.extend(case_office_mint(ctx)?);
    rows.push(case_layer_update_office103(ctx)?);
    for (name, what, chunk_len) in [
        (
            "mesh_append_office",
            "office (mint): 64 vertices appended to (or taken off) the largest unclaimed mesh node; its layer's point column in chunks of 32,768 points (the default), only the last chunk and the small layer segment republished → first query answered",
            POINT_CHUNK_LEN,
        ),
        (
            "mesh_append_office_unchunked",
            "reference: the same with the layer in one piece (as before chunked layers): the whole mesh layer republished",
            MAX_POINT_CHUNK_LEN,
        ),
    ] {
        rows.push(case_mesh_append(ctx, name, what, chunk_len)?);
    }
    let samples = ctx.plan.attach_samples;
    let graph = ctx.office_mint()?;
    rows.extend(super::attach::case_attach(
        ctx,
        "attach_office",
        "a new reader process attaches to the office (mint) and answers a nearest-node query: from its start to the answer; descriptors and /dev/shm files with one writer and this reader",
        graph,
        samples,
    )?);
    let graph = ctx.office_many_rooms()?;
    rows.extend(super::attach::case_attach(
        ctx,
        "attach_office103",
        "the same on the office split into 103 rooms (mint)",
        graph,
        samples,
    )?);
    let graph = scenes::office(&ctx.office()?.0, Layout::Chocolate)?;
    rows.push(in_scene(ctx, "office-chocolate", |ctx, scene| {
        let mut case = Case::start(scene, graph, 64 * 1024, 1, "latency", Some(QUERY_LAYER))?;
        let samples = ctx.plan.full_samples;
        let o = case.observe(&ctx.plan, 3, samples, &mut |g, i| {
            scenes::touch_all_layers(g, i)
        })?;
        case.finish()?;
        let (vm, vp) = median_p99_us(&o.visible);
        Ok(o.annotate(
            Row::latency(
                "full_office_chocolate",
                "reference: the same office in chocolate layout (no spatial indexes to rebuild), every layer republished → first query answered",
                &o.all_answered,
            )
            .with("visible_median_us", vm)
            .with("visible_p99_us", vp)
            .with("layers_sent", median(&o.layers_sent))
            .with("layers_total", o.layers_total as f64),
        ))
    })?);
    Ok(rows)
}

/// A mesh growing at its end, published with layers chunked at `chunk_len` points.
fn case_mesh_append(ctx: &mut Ctx, name: &str, what: &str, chunk_len: usize) -> Res<Row> {
    let graph = ctx.office_mint()?;
    in_scene(ctx, "office-mesh", |ctx, scene| {
        let mut grower = scenes::MeshGrower::new(&graph)?;
        let base = grower.base_points();
        let mut case = Case::start_chunked(
            scene,
            graph,
            64 * 1024,
            1,
            "latency",
            Some(QUERY_LAYER),
            chunk_len,
        )?;
        let samples = ctx.plan.office_samples;
        let o = case.observe(&ctx.plan, 5, samples, &mut |g, i| grower.step(g, i))?;
        case.finish()?;
        let (vm, vp) = median_p99_us(&o.visible);
        Ok(o.annotate(
            Row::latency(name, what, &o.all_answered)
                .with("visible_median_us", vm)
                .with("visible_p99_us", vp)
                .with("layers_sent", median(&o.layers_sent))
                .with("mesh_points", base as f64),
        ))
    })
}

fn case_office_mint(ctx: &mut Ctx) -> Res<Vec<Row>> {
    let graph = ctx.office_mint()?;
    in_scene(ctx, "office", |ctx, scene| {
        let mut mover = scenes::AgentMover::new(&graph)?;
        let mut case = Case::start(scene, graph, 64 * 1024, 1, "latency", Some(QUERY_LAYER))?;
        let samples = ctx.plan.office_samples;
        let single = case.observe(&ctx.plan, 5, samples, &mut |g, _| mover.step(g))?;
        let samples = ctx.plan.full_samples;
        let full = case.observe(&ctx.plan, 3, samples, &mut |g, i| {
            scenes::touch_all_layers(g, i)
        })?;
        case.finish()?;
        Ok(vec![
            layers_row(
                &single,
                "layer_update_office",
                "office (mint): one agent pose moved, only AGENTS republished → first query answered in the reader",
            ),
            layers_row(
                &full,
                "full_office",
                "office (mint): every layer changed and republished → first query answered in the reader",
            ),
        ])
    })
}

/// The update of `layer_update_office` in the 103-room office (418 layers): a publish
/// costs what changed, whatever the layer count.
fn case_layer_update_office103(ctx: &mut Ctx) -> Res<Row> {
    let graph = ctx.office_many_rooms()?;
    in_scene(ctx, "office103", |ctx, scene| {
        let mut mover = scenes::AgentMover::new(&graph)?;
        let mut case = Case::start(scene, graph, 64 * 1024, 1, "latency", Some(QUERY_LAYER))?;
        let samples = ctx.plan.office_samples;
        let o = case.observe(&ctx.plan, 5, samples, &mut |g, _| mover.step(g))?;
        case.finish()?;
        Ok(layers_row(
            &o,
            "layer_update_office103",
            "the same on the office split into 103 rooms (mint, 418 layers): only AGENTS republished → first query answered",
        ))
    })
}

/// A latency row with the time to the validated snapshot and the layers sent per publish.
fn layers_row(o: &Observed, case: &str, what: &str) -> Row {
    let (vm, vp) = median_p99_us(&o.visible);
    o.annotate(
        Row::latency(case, what, &o.all_answered)
            .with("visible_median_us", vm)
            .with("visible_p99_us", vp)
            .with("layers_sent", median(&o.layers_sent))
            .with("layers_total", o.layers_total as f64),
    )
}
