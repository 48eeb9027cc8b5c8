//! [`Ctx`]: what the cases of a run share (the plan, the scenes built once, the files
//! scenes left behind), and [`in_scene`], which runs a case in a fresh scene.

use super::super::child::Scene;
use super::super::error::Res;
use super::super::report::fmt_bytes;
use super::super::scenes;
use super::plan::Plan;
use std::time::Instant;
use ygg_dsg::DsgGraph;
use ygg_dsg::layout::Layout;
use ygg_store::{SceneGraph, SceneView};

/// State shared by the cases of a run.
pub(super) struct Ctx {
    pub(super) plan: Plan,
    /// The built-in office (scale 1) and its mint layout, built on first use.
    pub(super) office: Option<(DsgGraph, SceneGraph)>,
    /// The office split into 103 rooms, mint layout, built on first use.
    pub(super) office103: Option<SceneGraph>,
    /// The ~40 MB graph (the office in chocolate layout at a larger scale), built on first use.
    pub(super) big: Option<(SceneGraph, f64)>,
    pub(super) leftovers: Vec<String>,
}

impl Ctx {
    /// The built-in office and its mint layout.
    pub(super) fn office(&mut self) -> Res<&(DsgGraph, SceneGraph)> {
        if self.office.is_none() {
            let t = Instant::now();
            let dsg = scenes::office_dsg(1.0);
            let mint = scenes::office(&dsg, Layout::Mint)?;
            eprintln!(
                "office: {} nodes, {} layers, {} archived (mint), built in {:.1?}",
                mint.node_count(),
                mint.layers().count(),
                fmt_bytes(scenes::archived_bytes(&mint) as f64),
                t.elapsed()
            );
            self.office = Some((dsg, mint));
        }
        Ok(self.office.as_ref().expect("just built"))
    }

    /// A copy of the office in mint layout.
    pub(super) fn office_mint(&mut self) -> Res<SceneGraph> {
        Ok(self.office()?.1.clone())
    }

    /// A copy of the office split into [`scenes::MANY_ROOMS`] rooms, in mint layout.
    pub(super) fn office_many_rooms(&mut self) -> Res<SceneGraph> {
        if self.office103.is_none() {
            let t = Instant::now();
            let dsg = ygg_dsg::office::split_rooms(&self.office()?.0, scenes::MANY_ROOMS)?;
            let mint = scenes::office(&dsg, Layout::Mint)?;
            eprintln!(
                "office with {} rooms: {} nodes, {} layers, {} archived (mint), built in {:.1?}",
                scenes::MANY_ROOMS,
                mint.node_count(),
                mint.layers().count(),
                fmt_bytes(scenes::archived_bytes(&mint) as f64),
                t.elapsed()
            );
            self.office103 = Some(mint);
        }
        Ok(self.office103.clone().expect("just built"))
    }
}

/// Runs `f` in a fresh scene; afterwards (every process of the scene has exited) records
/// files the scene left behind and removes them.
pub(super) fn in_scene<T>(
    ctx: &mut Ctx,
    tag: &str,
    f: impl FnOnce(&mut Ctx, &Scene) -> Res<T>,
) -> Res<T> {
    let scene = Scene::new(&format!("ipcb-{tag}"));
    let result = f(ctx, &scene);
    if let Some(left) = scene.clean_up()
        && result.is_ok()
    {
        ctx.leftovers.push(left);
    }
    result
}
