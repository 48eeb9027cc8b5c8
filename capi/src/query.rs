//! The paper's queries on a snapshot handle. Each calls the one Rust implementation:
//! the store's queries (`ygg_store::query`) and the object-query contract
//! (`ygg_dsg::objects::Objects`, as `ygg query` answers it).
//!
//! Every query fills a caller-provided `ygg_node_list`. Ownership: `*list` is
//! overwritten (not freed) with a list the caller frees with `ygg_node_list_free`; on
//! error it is the empty list. Thread-safety: as the snapshot (any number of threads at
//! once).

use crate::args::{Out, point_arg, str_arg, str_array_arg};
use crate::errors::{FfiError, YggStatus, guard};
use crate::lists::{YggNodeList, deliver_ids, deliver_ranked};
use crate::snapshot::{YggSnapshot, snapshot_arg, view_arg};
use std::ffi::c_char;
use ygg_dsg::objects::cone_view;
use ygg_store::query;
use ygg_store::{LayerId, NodeId, Scope};

/// The `layer` argument of a query that means the whole graph rather than one layer.
pub const YGG_ALL_LAYERS: u32 = u32::MAX;

fn scope(layer: u32) -> Scope {
    if layer == YGG_ALL_LAYERS {
        Scope::Graph
    } else {
        Scope::Layer(LayerId(layer))
    }
}

fn query_error(e: impl std::fmt::Display) -> FfiError {
    FfiError::invalid(format!("query refused: {e}"))
}

/// At most `m` nodes in `layer` (or `YGG_ALL_LAYERS`) closest to `point`, nearest first
/// with distances (ties to the smaller id). Uses a layer index when one covers the scope.
///
/// # Safety
/// `point` is null or holds 3 floats; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_nearest_nodes(
    snapshot: *const YggSnapshot,
    layer: u32,
    point: *const f32,
    m: usize,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_nearest_nodes", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `point`.
            let c = unsafe { point_arg(point, "point") }?;
            query::nearest_nodes(view_arg(snapshot)?, scope(layer), c, m).map_err(query_error)
        })();
        deliver_ranked(found, out)
    })
}

/// Nodes in `layer` (or `YGG_ALL_LAYERS`) with a point at distance `<= radius` from
/// `point`, ascending.
///
/// # Safety
/// `point` is null or holds 3 floats; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_nodes_within_radius(
    snapshot: *const YggSnapshot,
    layer: u32,
    point: *const f32,
    radius: f32,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_nodes_within_radius", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `point`.
            let c = unsafe { point_arg(point, "point") }?;
            query::nodes_within_radius(view_arg(snapshot)?, scope(layer), c, radius)
                .map_err(query_error)
        })();
        deliver_ids(found, out)
    })
}

/// At most `m` nodes of `root`'s sub-tree (root included) closest to `point`, nearest
/// first with distances. An unknown root gives the empty list.
///
/// # Safety
/// `point` is null or holds 3 floats; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_nearest_in_subtree(
    snapshot: *const YggSnapshot,
    root: u64,
    point: *const f32,
    m: usize,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_nearest_in_subtree", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `point`.
            let c = unsafe { point_arg(point, "point") }?;
            query::nearest_in_subtree(view_arg(snapshot)?, NodeId(root), c, m).map_err(query_error)
        })();
        deliver_ranked(found, out)
    })
}

/// Nodes of `root`'s sub-tree with a point inside the view cone (apex `eye`, direction
/// `dir`, half-angle `half_angle_deg` degrees in `[0, 180]` as everywhere in the C API,
/// `range` metres; inclusive), ascending.
///
/// # Safety
/// `eye` and `dir` are null or hold 3 floats each; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_visible(
    snapshot: *const YggSnapshot,
    root: u64,
    eye: *const f32,
    dir: *const f32,
    half_angle_deg: f32,
    range: f32,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_visible", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `eye` and `dir`.
            let (eye, dir) = unsafe { (point_arg(eye, "eye")?, point_arg(dir, "dir")?) };
            let cone = cone_view(eye, dir, half_angle_deg, range).map_err(query_error)?;
            query::visible(view_arg(snapshot)?, NodeId(root), &cone).map_err(query_error)
        })();
        deliver_ids(found, out)
    })
}

/// Nodes in `layer` (or `YGG_ALL_LAYERS`) carrying `label`, ascending.
///
/// # Safety
/// `label` is null or NUL-terminated; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_nodes_with_label(
    snapshot: *const YggSnapshot,
    layer: u32,
    label: *const c_char,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_nodes_with_label", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `label`.
            let label = unsafe { str_arg(label, "label") }?;
            Ok(query::nodes_with_label(
                view_arg(snapshot)?,
                scope(layer),
                label,
            ))
        })();
        deliver_ids(found, out)
    })
}

/// Nodes in `layer` (or `YGG_ALL_LAYERS`) carrying every one of the `count` feature
/// keys in `keys`, ascending.
///
/// # Safety
/// `keys` is null or holds `count` NUL-terminated strings; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_nodes_having(
    snapshot: *const YggSnapshot,
    layer: u32,
    keys: *const *const c_char,
    count: usize,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_nodes_having", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `keys` and `count`.
            let keys = unsafe { str_array_arg(keys, count, "keys") }?;
            Ok(query::nodes_having(
                view_arg(snapshot)?,
                scope(layer),
                &keys,
            ))
        })();
        deliver_ids(found, out)
    })
}

/// `root` and every node nested under it, transitively, ascending (empty for an unknown
/// root).
///
/// # Safety
/// `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_subtree(
    snapshot: *const YggSnapshot,
    root: u64,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_subtree", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = view_arg(snapshot).map(|view| query::subtree(view, NodeId(root)));
        deliver_ids(found, out)
    })
}

/// Q1a, the object contract: the object with the vertex closest to `point` (ties to the
/// smaller id); `*found` says whether there is one, `*object` is its id (0 if none).
///
/// # Safety
/// `point` is null or holds 3 floats; `found` and `object` are null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_nearest_object(
    snapshot: *const YggSnapshot,
    point: *const f32,
    found: *mut bool,
    object: *mut u64,
) -> YggStatus {
    guard("ygg_snapshot_nearest_object", || {
        // SAFETY: the caller's contract for `point`, `found` and `object`.
        let (c, found, out) = unsafe {
            (
                point_arg(point, "point")?,
                Out::new(found, "found")?,
                Out::new(object, "object")?,
            )
        };
        let nearest = snapshot_arg(snapshot)?
            .with_objects(|o| o.nearest_object(c))
            .map_err(query_error)?;
        found.write(nearest.is_some());
        out.write(nearest.map_or(0, |n| n.0));
        Ok(())
    })
}

/// Q1b, the object contract: every object with a vertex at distance `<= radius` from
/// `point`, ascending.
///
/// # Safety
/// `point` is null or holds 3 floats; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_objects_within(
    snapshot: *const YggSnapshot,
    point: *const f32,
    radius: f32,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_objects_within", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `point`.
            let c = unsafe { point_arg(point, "point") }?;
            snapshot_arg(snapshot)?
                .with_objects(|o| o.objects_within(c, radius))
                .map_err(query_error)
        })();
        deliver_ids(found, out)
    })
}

/// Q2, the object contract: every object with a vertex in the view cone (apex `eye`,
/// direction `dir`, half-angle `half_angle_deg` degrees in `[0, 180]`, `range` metres),
/// ascending.
///
/// # Safety
/// `eye` and `dir` are null or hold 3 floats each; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_visible_objects(
    snapshot: *const YggSnapshot,
    eye: *const f32,
    dir: *const f32,
    half_angle_deg: f32,
    range: f32,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_visible_objects", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `eye` and `dir`.
            let (eye, dir) = unsafe { (point_arg(eye, "eye")?, point_arg(dir, "dir")?) };
            snapshot_arg(snapshot)?
                .with_objects(|o| o.visible_objects(eye, dir, half_angle_deg, range))
                .map_err(query_error)
        })();
        deliver_ids(found, out)
    })
}

/// Q3, the object contract: every object carrying `label` (its labelspace name or its
/// decimal semantic label), ascending.
///
/// # Safety
/// `label` is null or NUL-terminated; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_objects_with_label(
    snapshot: *const YggSnapshot,
    label: *const c_char,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_objects_with_label", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `label`.
            let label = unsafe { str_arg(label, "label") }?;
            Ok(snapshot_arg(snapshot)?.with_objects(|o| o.objects_with_label(label)))
        })();
        deliver_ids(found, out)
    })
}
